/* AVX-512 variant (x86-64 only): 8 float64 lanes per instruction, mask registers for the selects.
 * No FMA: the error bounds count one rounding per operation, and contraction is off
 * (-ffp-contract=off) in every variant. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h> /* the transposes of _variant.h whose lane-crossing step rides on the loads */
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx512f,avx512dq,avx512vl,avx512bw,avx512cd"))), apply_to = function)
#else
#pragma GCC target("avx512f,avx512dq,avx512vl,avx512bw,avx512cd,prefer-vector-width=512")
#endif
#define VARIANT avx512
/* doubles: the 4 x 4 transpose (TP_F64 4 in _variant.h): 1 M random 3D pairs on one core (AMD EPYC,
 * Zen 4, 2026-12-03, interleaved runs) 35.2 M/s with the 8 x 8 network of 64-byte shuffles, 40.0
 * M/s with it (the network was ~30 % of the filter's time) */
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
