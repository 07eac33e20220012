/* Baseline variant: the compiler's default instruction set (x86-64: SSE2; elsewhere: portable). */
#include <math.h>
#include <stdint.h>
#include <string.h>

#define VARIANT baseline
#include "_variant.h"
