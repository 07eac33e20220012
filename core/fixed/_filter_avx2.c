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
#include "_variant.h"
#if defined(__clang__)
#pragma clang attribute pop
#endif
#endif
