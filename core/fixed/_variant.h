/* One SIMD variant of the filter: the generated lane functions and four block drivers.
 *
 * Included by _filter_<variant>.c after it chose the instruction set (a target pragma) and
 * defined VARIANT; defines classify{3,4}_{f64,f32}_<VARIANT> (rule ids, -1 undecided).
 */
#include "_kernels.h"

/* Block sizes, measured on a Sapphire Rapids core (bench/throughput.py; ELLIPSOID_* macros
 * only for experiments): small blocks keep the memory requests for the next block spread
 * between short bursts of compute, so reading the inputs overlaps the filter's arithmetic;
 * 64-pair blocks were ~15 % slower on 3D pairs streamed from memory, 8 and 16 the same. */
#ifndef CHUNK3
#define CHUNK3 16 /* pairs per block of ellipses: the stage buffers stay in the L1 cache */
#endif
#ifndef CHUNK4
/* pairs per block of ellipsoids: 8. Measured 2026-12-02 on an AMD EPYC VM with AVX-512, 1 M random
 * 3D pairs from memory, one core, best of 9: float64 26.7-26.9 ms against 28.5-29.4 ms with 16
 * pairs (AVX2 31.6 against 34.3 ms; float32 the same); 32 pairs 35 ms. Ellipses keep 16 (8 was
 * 18.6 against 17.8 ms). On the Xeon VM 8 and 16 measured the same. */
#define CHUNK4 8
#endif
#ifndef LANES
#define LANES 8   /* pairs between two rounds of prefetching the next block */
#endif
#ifndef PF_DIST
/* blocks ahead: 3 (was 2). Measured 2026-12-02 on a 2-core Xeon VM (48 KB L1d, 2 MB L2 per core), 1 M random
 * 3D pairs streamed from memory, one core, interleaved runs of the two builds: 1 block ahead
 * 28.1-28.2 ms, 2 blocks 25.6-26.6 ms, 4 blocks 24.8-26.6 ms (the same runs: the one-core ratio to the
 * C tree 1.54-1.64x against 1.71-1.76x); 8 and 16 blocks no better than 2, nor L2/L3 hints.
 * 2026-12-04, the same kind of Xeon, AVX-512 variant after the kernel became faster (a block of 8
 * pairs in ~460 cycles): bench.stage_cycles' driver on random 3D pairs on huge pages (as numpy
 * allocates large arrays) 57.4-57.9 cycles per pair with 2 blocks ahead, 56.5-56.7 with 3, 56.7-57.1
 * with 4, 57.9-58.5 with 6 (on 4 KB pages 61.5-62.4 against 62.0-64.4); the extension as built, old
 * and new alternating, one pinned core, CPU time: random 3D 43.6-45.1 -> 44.9-45.6 M pairs/s, float32
 * 33.7-34.8 -> 35.3-35.4, 2D and the AVX2 variant unchanged. (In the L2 cache the same driver takes
 * 52.1 cycles per pair: the stream from memory still costs ~10 %.) */
#define PF_DIST 3
#endif
#ifndef PF_HINT
#define PF_HINT 3 /* __builtin_prefetch locality: into L1 */
#endif

/* Pairs (and entries) per transpose when a block is turned to structure of arrays: TP_F64 4 (a
 * 4 x 4 transpose of doubles), TP_F32 8 (an 8 x 8 transpose of floats), both in 32-byte
 * registers with their lane-crossing step riding on the loads (AVX: the variant that sets them
 * includes immintrin.h), or 0 (element by element, the default and the baseline's). Measured on
 * an AMD EPYC (Zen 4, which executes a 64-byte shuffle as two 32-byte halves), 1 M random 3D pairs
 * on one core: an 8 x 8 network of 64-byte shuffles for the doubles was ~30 % of the AVX-512
 * filter's time (35.2 M/s, the 4 x 4 transpose 40.0 M/s); in the AVX2 variant that network went
 * through memory (77 ms per 1 M pairs, element by element 35 ms); see the variants' files. */
/* F64_BEGIN / F64_END: what a variant puts around its float64 functions (GCC option pragmas, as
 * _Pragma); nothing by default. */
#ifndef F64_BEGIN
#define F64_BEGIN
#define F64_END
#endif
#ifndef TP_F64
#define TP_F64 0
#endif
#ifndef TP_F32
#define TP_F32 0
#endif
#if TP_F64 == 4
/* dst[k * ld_dst + p] = src[p * ld_src + k] for p, k < 4: rows p and p + 2 are loaded as 16-byte
 * halves into one 32-byte register (the lane-crossing step done by the loads), then 4 in-lane
 * unpacks. */
static inline void transpose4_f64(const double *restrict src, int64_t ld_src, double *restrict dst, int64_t ld_dst) {
    const __m256d r0 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(src)), _mm_loadu_pd(src + 2 * ld_src), 1);
    const __m256d r1 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(src + ld_src)), _mm_loadu_pd(src + 3 * ld_src), 1);
    const __m256d r2 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(src + 2)), _mm_loadu_pd(src + 2 * ld_src + 2), 1);
    const __m256d r3 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(src + ld_src + 2)), _mm_loadu_pd(src + 3 * ld_src + 2), 1);
    _mm256_storeu_pd(dst, _mm256_unpacklo_pd(r0, r1));
    _mm256_storeu_pd(dst + ld_dst, _mm256_unpackhi_pd(r0, r1));
    _mm256_storeu_pd(dst + 2 * ld_dst, _mm256_unpacklo_pd(r2, r3));
    _mm256_storeu_pd(dst + 3 * ld_dst, _mm256_unpackhi_pd(r2, r3));
}
#endif
#if TP_F32 == 8
/* dst[k * ld_dst + p] = src[p * ld_src + k] for p, k < 8: rows p and p + 4 as 16-byte halves of
 * one 32-byte register, then 16 in-lane shuffles (a network of 32-byte shuffles takes 24, 8 of
 * them lane-crossing). */
static inline void transpose8_f32(const float *restrict src, int64_t ld_src, float *restrict dst, int64_t ld_dst) {
    for (int h = 0; h < 8; h += 4) { /* entries h..h+3 */
        __m256 r[4], t[4];
        for (int p = 0; p < 4; p++)
            r[p] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(src + p * ld_src + h)), _mm_loadu_ps(src + (p + 4) * ld_src + h), 1);
        t[0] = _mm256_unpacklo_ps(r[0], r[1]);
        t[1] = _mm256_unpackhi_ps(r[0], r[1]);
        t[2] = _mm256_unpacklo_ps(r[2], r[3]);
        t[3] = _mm256_unpackhi_ps(r[2], r[3]);
        _mm256_storeu_ps(dst + h * ld_dst, _mm256_shuffle_ps(t[0], t[2], 0x44));
        _mm256_storeu_ps(dst + (h + 1) * ld_dst, _mm256_shuffle_ps(t[0], t[2], 0xEE));
        _mm256_storeu_ps(dst + (h + 2) * ld_dst, _mm256_shuffle_ps(t[1], t[3], 0x44));
        _mm256_storeu_ps(dst + (h + 3) * ld_dst, _mm256_shuffle_ps(t[1], t[3], 0xEE));
    }
}
#endif
#define TRANSPOSE_NAME_(tp, type) transpose##tp##_##type
#define TRANSPOSE_NAME(tp, type) TRANSPOSE_NAME_(tp, type)
#define TRANSPOSE_F64 TRANSPOSE_NAME(TP_F64, f64)
#define TRANSPOSE_F32 TRANSPOSE_NAME(TP_F32, f32)
#define GLUE_(a, b) a##_##b
#define GLUE(a, b) GLUE_(a, b)

#define N 3
#define CHUNK CHUNK3
#define T double
#define FIRST first3_f64
#define FIRST_NOSCALE first3_noscale_f64
#define TP TP_F64
#define TRANSPOSE_T TRANSPOSE_F64
#define FULL full3_f64
#define SECOND second3
#define FOURTH fourth3
#define THIRD third3_f64
#define THIRD_FAST third3_fast_f64
#define THIRD_SEP third_sep3_f64
#define THIRD_SEP_FAST third_sep3_fast_f64
#define THIRD_SEP_NOSCALE third_sep3_noscale_f64
#define CLASSIFY GLUE(classify3_f64, VARIANT)
F64_BEGIN
#include "_blocks.h"
F64_END
#undef T
#undef FIRST
#undef FIRST_NOSCALE
#undef TP
#undef TRANSPOSE_T
#undef FULL
#undef THIRD
#undef THIRD_FAST
#undef THIRD_SEP
#undef THIRD_SEP_FAST
#undef THIRD_SEP_NOSCALE
#undef CLASSIFY
#define T float
#define FIRST first3_f32
#define FIRST_NOSCALE first3_noscale_f32
#define TP TP_F32
#define TRANSPOSE_T TRANSPOSE_F32
#define FULL full3_f32
#define THIRD third3_f32
#define THIRD_FAST third3_fast_f32
#define THIRD_SEP third_sep3_f32
#define THIRD_SEP_FAST third_sep3_fast_f32
#define THIRD_SEP_NOSCALE third_sep3_noscale_f32
#define CLASSIFY GLUE(classify3_f32, VARIANT)
#include "_blocks.h"
#undef N
#undef CHUNK
#undef T
#undef FIRST
#undef FIRST_NOSCALE
#undef TP
#undef TRANSPOSE_T
#undef FULL
#undef SECOND
#undef FOURTH
#undef THIRD
#undef THIRD_FAST
#undef THIRD_SEP
#undef THIRD_SEP_FAST
#undef THIRD_SEP_NOSCALE
#undef CLASSIFY

#define N 4
#define CHUNK CHUNK4
#define T double
#define FIRST first4_f64
#define FIRST_NOSCALE first4_noscale_f64
#define TP TP_F64
#define TRANSPOSE_T TRANSPOSE_F64
#define FULL full4_f64
#define SECOND second4
#define FOURTH fourth4
#define THIRD third4_f64
#define THIRD_FAST third4_fast_f64
#define THIRD_SEP third_sep4_f64
#define THIRD_SEP_FAST third_sep4_fast_f64
#define THIRD_SEP_NOSCALE third_sep4_noscale_f64
#define SKIP_S0 skip_s04_f64
#define CLASSIFY GLUE(classify4_f64, VARIANT)
F64_BEGIN
#include "_blocks.h"
F64_END
#undef T
#undef FIRST
#undef FIRST_NOSCALE
#undef TP
#undef TRANSPOSE_T
#undef FULL
#undef THIRD
#undef THIRD_FAST
#undef THIRD_SEP
#undef THIRD_SEP_FAST
#undef THIRD_SEP_NOSCALE
#undef SKIP_S0
#undef CLASSIFY
#define T float
#define FIRST first4_f32
#define FIRST_NOSCALE first4_noscale_f32
#define TP TP_F32
#define TRANSPOSE_T TRANSPOSE_F32
#define FULL full4_f32
#define THIRD third4_f32
#define THIRD_FAST third4_fast_f32
#define THIRD_SEP third_sep4_f32
#define THIRD_SEP_FAST third_sep4_fast_f32
#define THIRD_SEP_NOSCALE third_sep4_noscale_f32
#define SKIP_S0 skip_s04_f32
#define CLASSIFY GLUE(classify4_f32, VARIANT)
#include "_blocks.h"
#undef N
#undef CHUNK
#undef T
#undef FIRST
#undef FIRST_NOSCALE
#undef TP
#undef TRANSPOSE_T
#undef FULL
#undef SECOND
#undef FOURTH
#undef THIRD
#undef THIRD_FAST
#undef THIRD_SEP
#undef THIRD_SEP_FAST
#undef THIRD_SEP_NOSCALE
#undef SKIP_S0
#undef CLASSIFY
