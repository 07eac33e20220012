/* AVX2 variant (x86-64 only): 4 float64 lanes. No FMA: the error bounds count one rounding per
 * operation, and contraction is off (-ffp-contract=off) in every variant. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h> /* the transposes of _variant.h whose lane-crossing step rides on the loads */
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#else
#pragma GCC target("avx2")
#endif
#define VARIANT avx2
/* doubles: the 4 x 4 transpose whose lane-crossing step rides on the loads (TP_F64 4 in
 * _variant.h): 1 M random 3D pairs on one core 27-31 against 36-37 M/s element by element
 * (2026-12-03; earlier: 77 ms per 1 M pairs with the 8 x 8 network, 35 ms element by element, 52 ms
 * with a 4 x 4 network of four 32-byte shuffles) */
#define TP_F64 4
/* floats: the 8 x 8 transpose whose lane-crossing step rides on the loads (TP_F32 8 in _variant.h):
 * 1 M random pairs, one core, interleaved runs (2026-12-03): AVX-512 3D 32.7-33.8 -> 34.9-36.0 M/s,
 * 2D 62.6-65.6 -> 65.5-69.9 M/s; AVX2 2D 40-54 -> 62-63 M/s (3D within the host's noise) */
#define TP_F32 8
#include "_variant.h"
#if defined(__clang__)
#pragma clang attribute pop
#endif
#endif
