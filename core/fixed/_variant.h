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
/* blocks ahead: 2. Measured 2026-12-02 on a 2-core Xeon VM (48 KB L1d, 2 MB L2 per core), 1 M random
 * 3D pairs streamed from memory, one core, interleaved runs of the two builds: 1 block ahead
 * 28.1-28.2 ms, 2 blocks 25.6-26.6 ms, 4 blocks 24.8-26.6 ms (the same runs: the one-core ratio to the
 * C tree 1.54-1.64x against 1.71-1.76x); 8 and 16 blocks no better than 2, nor L2/L3 hints. */
#define PF_DIST 2
#endif
#ifndef PF_HINT
#define PF_HINT 3 /* __builtin_prefetch locality: into L1 */
#endif

#if defined(__GNUC__) && !defined(__clang__)
#define SHUFFLE 1
#define SHUFFLE_D(a, b, ...) __builtin_shuffle(a, b, (v8i){__VA_ARGS__})
#define SHUFFLE_F(a, b, ...) __builtin_shuffle(a, b, (v8i32){__VA_ARGS__})
#elif defined(__clang__)
#define SHUFFLE 1
#define SHUFFLE_D(a, b, ...) __builtin_shufflevector(a, b, __VA_ARGS__)
#define SHUFFLE_F(a, b, ...) __builtin_shufflevector(a, b, __VA_ARGS__)
#endif
/* Pairs (and entries) per transpose when a block is turned to structure of arrays: 8 (an 8 x 8
 * shuffle network), 4 (doubles only: a 4 x 4 transpose in 32-byte registers whose lane-crossing
 * step rides on the loads, AVX) or 0 (element by element). Each variant picks what its registers
 * hold: a network wider than the registers goes through memory (measured 2026-12-02 on an AMD
 * EPYC with AVX-512, 1 M random 3D pairs on one core: the AVX2 variant 77 ms with the 64-byte
 * network of doubles, 35 ms element by element; see _filter_avx2.c and _filter_base.c). */
#ifndef TP_F64
#define TP_F64 8
#endif
#ifndef TP_F32
#define TP_F32 8
#endif
#ifndef SHUFFLE
#undef TP_F64
#undef TP_F32
#define TP_F64 0
#define TP_F32 0
#endif
#ifdef SHUFFLE
typedef double v8d __attribute__((vector_size(64)));
typedef float v8f __attribute__((vector_size(32)));
typedef long long v8i __attribute__((vector_size(64)));
typedef int v8i32 __attribute__((vector_size(32)));

/* dst[k * ld_dst + p] = src[p * ld_src + k] for p, k < 8: an 8 x 8 transpose in 24 shuffles
 * (pairs of rows, then quads, then halves), in whatever vector width the variant has. */
#define TRANSPOSE8(name, E, V, MASK)                                                                    \
    static inline void name(const E *restrict src, int64_t ld_src, E *restrict dst, int64_t ld_dst) { \
        V r[8], t[8], u[8];                                                                           \
        for (int p = 0; p < 8; p++) memcpy(&r[p], src + p * ld_src, sizeof(V));                       \
        for (int p = 0; p < 8; p += 2) {                                                              \
            t[p] = SHUFFLE_##MASK(r[p], r[p + 1], 0, 8, 2, 10, 4, 12, 6, 14);                         \
            t[p + 1] = SHUFFLE_##MASK(r[p], r[p + 1], 1, 9, 3, 11, 5, 13, 7, 15);                     \
        }                                                                                             \
        for (int p = 0; p < 8; p += 4)                                                                \
            for (int q = 0; q < 2; q++) {                                                             \
                u[p + q] = SHUFFLE_##MASK(t[p + q], t[p + q + 2], 0, 1, 8, 9, 4, 5, 12, 13);          \
                u[p + q + 2] = SHUFFLE_##MASK(t[p + q], t[p + q + 2], 2, 3, 10, 11, 6, 7, 14, 15);    \
            }                                                                                         \
        for (int k = 0; k < 4; k++) {                                                                 \
            const V lo = SHUFFLE_##MASK(u[k], u[k + 4], 0, 1, 2, 3, 8, 9, 10, 11);                    \
            const V hi = SHUFFLE_##MASK(u[k], u[k + 4], 4, 5, 6, 7, 12, 13, 14, 15);                  \
            memcpy(dst + k * ld_dst, &lo, sizeof(V));                                                 \
            memcpy(dst + (k + 4) * ld_dst, &hi, sizeof(V));                                           \
        }                                                                                             \
    }
TRANSPOSE8(transpose8_f64, double, v8d, D)
TRANSPOSE8(transpose8_f32, float, v8f, F)
#endif
#if TP_F64 == 4
/* dst[k * ld_dst + p] = src[p * ld_src + k] for p, k < 4: rows p and p + 2 are loaded as 16-byte
 * halves into one 32-byte register (the lane-crossing step done by the loads), then 4 in-lane
 * unpacks. 2 shuffles per 4 doubles where the 8 x 8 network of 64-byte registers takes 3, and
 * in-lane ones (a 64-byte shuffle costs two 32-byte ones on AMD Zen 4). */
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
#ifdef F32_LOAD_HALVES
/* The 8 x 8 transpose of floats (dst[k * ld_dst + p] = src[p * ld_src + k] for p, k < 8) whose
 * lane-crossing step rides on the loads: rows p and p + 4 as 16-byte halves of one register,
 * then 16 in-lane shuffles (the network above: 24, 8 of them lane-crossing). AVX. */
static inline void transpose8h_f32(const float *restrict src, int64_t ld_src, float *restrict dst, int64_t ld_dst) {
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
#ifdef F32_LOAD_HALVES
#define TRANSPOSE_F32 transpose8h_f32
#else
#define TRANSPOSE_F32 TRANSPOSE_NAME(TP_F32, f32)
#endif
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
#define CLASSIFY GLUE(classify3_f64, VARIANT)
#include "_blocks.h"
#undef T
#undef FIRST
#undef FIRST_NOSCALE
#undef TP
#undef TRANSPOSE_T
#undef FULL
#undef THIRD
#undef THIRD_FAST
#undef CLASSIFY
#define T float
#define FIRST first3_f32
#define FIRST_NOSCALE first3_noscale_f32
#define TP TP_F32
#define TRANSPOSE_T TRANSPOSE_F32
#define FULL full3_f32
#define THIRD third3_f32
#define THIRD_FAST third3_fast_f32
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
#define CLASSIFY GLUE(classify4_f64, VARIANT)
#include "_blocks.h"
#undef T
#undef FIRST
#undef FIRST_NOSCALE
#undef TP
#undef TRANSPOSE_T
#undef FULL
#undef THIRD
#undef THIRD_FAST
#undef CLASSIFY
#define T float
#define FIRST first4_f32
#define FIRST_NOSCALE first4_noscale_f32
#define TP TP_F32
#define TRANSPOSE_T TRANSPOSE_F32
#define FULL full4_f32
#define THIRD third4_f32
#define THIRD_FAST third4_fast_f32
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
#undef CLASSIFY
