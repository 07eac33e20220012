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
/* GCC, float64 input: schedule before register allocation, aware of register pressure. The lane
 * functions are long straight-line code over 16 vector registers; GCC's default (no first
 * scheduling pass on x86) leaves the loads of spilled values next to their uses. 1 M random 3D
 * pairs, one core, AMD EPYC (Zen 3), 7-8 interleaved runs each (2026-12-03): best 22.7-23.5 ->
 * 27.9-28.5 M/s. float32 input slowed (20.7 -> 15.3 M/s) and keeps the default. Scheduling changes
 * no value: the operations and their order of evaluation stay as written. Keep these the only
 * option change of the file: an extra file-wide optimize pragma (live-range-shrinkage) made GCC
 * stop inlining the lane functions into these (7.9 M/s); the float64 functions call nothing. */
#define F64_BEGIN _Pragma("GCC push_options") _Pragma("GCC optimize(\"schedule-insns\", \"sched-pressure\")")
#define F64_END _Pragma("GCC pop_options")
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
