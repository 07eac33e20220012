/* AVX2 variant (x86-64 only): 4 float64 lanes. No FMA: the error bounds count one rounding per
 * operation, and contraction is off (-ffp-contract=off) in every variant. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#else
#pragma GCC target("avx2")
#endif
#define VARIANT avx2
/* doubles element by element (3D 77 ms per 1 M pairs with the 8 x 8 network, 35 ms without;
 * a 4 x 4 network of 32-byte shuffles 52 ms); floats: the 8 x 8 network fits the 32-byte registers (37 against 40 ms) */
#define TP_F64 0
#include "_variant.h"
#if defined(__clang__)
#pragma clang attribute pop
#endif
#endif
