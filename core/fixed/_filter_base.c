/* Baseline variant: the compiler's default instruction set (x86-64: SSE2; elsewhere: portable). */
#include <math.h>
#include <stdint.h>
#include <string.h>

#define VARIANT baseline
/* element-by-element transposes: a 32- or 64-byte shuffle network in 16-byte registers goes
 * through memory (3D 124 ms per 1 M pairs with the 8 x 8 network, 79 ms without; float32 117 / 76) */
#define TP_F64 0
#define TP_F32 0
#include "_variant.h"
