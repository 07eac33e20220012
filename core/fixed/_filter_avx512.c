/* AVX-512 variant (x86-64 only): 8 float64 lanes per instruction, mask registers for the selects.
 * No FMA: the error bounds count one rounding per operation, and contraction is off
 * (-ffp-contract=off) in every variant. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx512f,avx512dq,avx512vl,avx512bw,avx512cd"))), apply_to = function)
#else
#pragma GCC target("avx512f,avx512dq,avx512vl,avx512bw,avx512cd,prefer-vector-width=512")
#endif
#define VARIANT avx512
#include "_variant.h"
#if defined(__clang__)
#pragma clang attribute pop
#endif
#endif
