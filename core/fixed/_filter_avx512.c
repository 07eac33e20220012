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
/* tune=icelake-server: GCC's scheduling and instruction costs of an AVX-512 server core, not the
 * generic tuning (an ISA choice it is not: the variant runs on every CPU with these extensions; no
 * value changes). 1 M random 3D pairs on one pinned core of the Xeon VM (Sapphire Rapids class),
 * 2026-12-05, builds alternating: generic 50.0-51.6 M/s (1.95-1.98x the C tree), icelake-server
 * 52.5-52.8 (2.04-2.05x), sapphirerapids 51.7-53.4 (2.01-2.03x), skylake-avx512 51.3-52.2 (2.01-2.02x). */
#pragma GCC target("avx512f,avx512dq,avx512vl,avx512bw,avx512cd,prefer-vector-width=512,tune=icelake-server")
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
