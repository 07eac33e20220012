/* The block driver of the certified float filter: the generated lane functions over many pairs.
 *
 * Included by _variant.h once per (dimension, input type), with these macros defined:
 *   N          3 (ellipses) or 4 (ellipsoids)
 *   T          double or float (float is widened exactly: certified for the float values given)
 *   FIRST_NOSCALE, FIRST, FULL, SECOND, THIRD_SEP_NOSCALE, THIRD_SEP_FAST, THIRD_SEP, THIRD_FAST, THIRD, FOURTH   the lane functions of _kernels.h for this N and T
 *   SKIP_S0    (N 4 only) the lane function of driver.skips_s0
 *   CHUNK      pairs per block (CHUNK3 or CHUNK4 of _variant.h)
 *   TP, TRANSPOSE_T   pairs per transpose for T (4 for doubles, 8 for floats, or 0: element by element) and the TP x TP transpose
 *   CLASSIFY   the name of the function defined here: CLASSIFY(A, B, out, count, table) writes the
 *              rule id of each pair (-1 undecided) to out, or table[rule id as a byte] when table
 *              is not NULL (the relation codes: no second pass over the output in Python), and
 *              returns how many pairs are undecided
 *
 * The pairs of a block are first transposed to structure of arrays (entry k of every pair in
 * one row). Each stage is then a loop over pairs whose body is a branch-free lane function, so
 * the compiler turns it into SIMD across pairs, a vector load reading one entry of several
 * pairs. The stages (core/fixed/driver.py): 1 prepare, pencil, validity, the tree with s0
 * pending (first without the scaling, where every largest entry is already in [2^-8, 2^24]; then
 * scaled where one is not; then the full prepare where a matrix is symmetric only up to rounding); 2 the semi-static s0 test where the tree asks for s0; 3 the certificates where a
 * valid pair is still open (spheres, translated and homothetic copies): 3a the cheap separation
 * certificate, 3b the full ones; 4 the running-error s0 test where s0 is still needed (near
 * tangency). Stages 1 to 3a run per block, each only on the pairs the stages before left to it:
 * packed first so that the SIMD lanes stay full, or, when most pairs of the block need it, on
 * every lane in place and selected. The few pairs 3a leaves open are copied, with all their
 * block columns, to a queue that runs 3b and 4 (LATE) when it holds a block of them, and once
 * more at the end: a mixed block (spheres: ~5 % of the pairs reach 3b) would otherwise run the
 * costliest stage on a whole SIMD vector for one pair. Every stage is a function of the pair
 * alone, so where a pair runs changes no answer.
 */

/* k = how many pairs p < m of the block COND holds for (a vector count, cheap when no pair
 * needs the stage), and, when they are few enough to be packed (F k <= m), their indices in
 * open[0..k); when more pairs need the stage it runs in place and open[] is not read. */
#define SUBSET_AT(COND, F)                     \
    k = 0;                                     \
    for (int64_t p = 0; p < m; p++) k += (COND); \
    if (k && (F) * k <= m) {                   \
        int64_t j_ = 0;                        \
        for (int64_t p = 0; p < m; p++) {      \
            open[j_] = (int32_t)p;             \
            j_ += (COND);                      \
        }                                      \
    }
#define SUBSET(COND) SUBSET_AT(COND, 2) /* packed when at most half the pairs need the stage */

/* Rows r < ROWS of the block buffer SRC (T or double) for the subset, packed into DST. */
#define PACK(DST, SRC, ROWS)                                                       \
    for (int64_t q = 0; q < k; q++)                                                \
        for (int r = 0; r < (ROWS); r++) (DST)[r * CHUNK + q] = (SRC)[r * CHUNK + open[q]];

/* An s0 stage (LANE(c, stride, idx) -> code) on the pairs whose code is WHICH. */
#define S0_STAGE(LANE, WHICH)                                                                 \
    SUBSET(code[p] == (WHICH))                                                                \
    if (2 * k > m) {                                                                          \
        for (int64_t p = 0; p < m; p++) {                                                     \
            const int64_t r = LANE(c + p, CHUNK, idx[p]);                                     \
            code[p] = code[p] == (WHICH) ? r : code[p];                                       \
        }                                                                                     \
    } else if (k) {                                                                           \
        double d[2 * (N + 1) * CHUNK];                                                        \
        int64_t di[CHUNK], dc[CHUNK];                                                         \
        PACK(d, c, 2 * (N + 1))                                                               \
        for (int64_t q = 0; q < k; q++) di[q] = idx[open[q]];                                 \
        for (int64_t q = 0; q < k; q++) dc[q] = LANE(d + q, CHUNK, di[q]);                    \
        for (int64_t q = 0; q < k; q++) code[open[q]] = dc[q];                                \
    }

/* A certificate (LANE(a, b, c, stride) -> rule or -1) on the open pairs whose first pass ROUTE
 * holds for (an expression of route[p]: 0 unscaled, 1 scaled, 2 the full prepare); where it
 * fails a pair keeps its code when KEEP (stage 3a: the full certificates follow), else keeps
 * NEEDS_S0_RADIUS if its s0 is still unknown and is left undecided (-1) otherwise. The pairs
 * are packed when F k <= m (F 2: at most half of them), else the stage runs in place. */
#define CERT_STAGE(LANE, ROUTE, KEEP, F)                                                                          \
    SUBSET_AT((code[p] == NEEDS_CERT || code[p] == NEEDS_S0_RADIUS) && (ROUTE), F)                                \
    if ((F) * k > m) {                                                                                            \
        for (int64_t p = 0; p < m; p++) {                                                                         \
            const int64_t cert = LANE(a + p, b + p, c + p, CHUNK);                                                \
            const int64_t open_ = (code[p] == NEEDS_CERT || code[p] == NEEDS_S0_RADIUS) && (ROUTE);              \
            const int64_t left = (KEEP) || code[p] == NEEDS_S0_RADIUS ? code[p] : -1;                             \
            code[p] = open_ ? (cert >= 0 ? cert : left) : code[p];                                                \
        }                                                                                                         \
    } else if (k) {                                                                                               \
        T pa[N * N * CHUNK], pb[N * N * CHUNK];                                                                   \
        double d[2 * (N + 1) * CHUNK];                                                                            \
        int64_t dc[CHUNK];                                                                                        \
        PACK(pa, a, N * N)                                                                                        \
        PACK(pb, b, N * N)                                                                                        \
        PACK(d, c, 2 * (N + 1))                                                                                   \
        for (int64_t q = 0; q < k; q++) dc[q] = LANE(pa + q, pb + q, d + q, CHUNK);                               \
        for (int64_t q = 0; q < k; q++) {                                                                         \
            const int64_t p = open[q];                                                                            \
            code[p] = dc[q] >= 0 ? dc[q] : ((KEEP) || code[p] == NEEDS_S0_RADIUS ? code[p] : -1);                 \
        }                                                                                                         \
    }

/* Stage 1 again with LANE on the pairs whose code is WHICH (k and open[] from SUBSET): when most
 * pairs need it every lane in place, then select; else the pairs packed. */
#define AGAIN(LANE, WHICH)                                                                                  \
    if (2 * k > m) {                                                                                        \
        double d[2 * (N + 1) * CHUNK];                                                                      \
        int64_t di[CHUNK];                                                                                  \
        for (int64_t p = 0; p < m; p++) {                                                                   \
            const int64_t again = LANE(a + p, b + p, d + p, CHUNK, di + p);                                 \
            const int64_t take = code[p] == (WHICH);                                                        \
            for (int r = 0; r < 2 * (N + 1); r++) c[r * CHUNK + p] = take ? d[r * CHUNK + p] : c[r * CHUNK + p]; \
            idx[p] = take ? di[p] : idx[p];                                                                 \
            code[p] = take ? again : code[p];                                                               \
        }                                                                                                   \
    } else if (k) {                                                                                         \
        T pa[N * N * CHUNK], pb[N * N * CHUNK];                                                             \
        double d[2 * (N + 1) * CHUNK];                                                                      \
        int64_t di[CHUNK], dc[CHUNK];                                                                       \
        PACK(pa, a, N * N)                                                                                  \
        PACK(pb, b, N * N)                                                                                  \
        for (int64_t q = 0; q < k; q++) dc[q] = LANE(pa + q, pb + q, d + q, CHUNK, di + q);                 \
        for (int64_t q = 0; q < k; q++) {                                                                   \
            for (int r = 0; r < 2 * (N + 1); r++) c[r * CHUNK + open[q]] = d[r * CHUNK + q];                \
            idx[open[q]] = di[q];                                                                           \
            code[open[q]] = dc[q];                                                                          \
        }                                                                                                   \
    }

/* Part J (of 8) of the block PF_DIST ahead, of A and of B, into the cache. The parts are
 * requested at eight points spread over the work on this block (transpose, the two rounds of
 * stage 1, stages 2 to 4, output) a few lines at a time, so that the stream from memory overlaps
 * the arithmetic: one burst of requests per block stalls on the core's few line-fill buffers
 * (measured on 3D pairs streamed from memory: one burst per round of LANES pairs ~20 % slower).
 * (A loop over a running line index measured ~8 % slower.) */
#if PF_DIST > 0
#define PF_BYTES (CHUNK * N * N * (int64_t)sizeof(T))
#define PREFETCH(J)                                                                             \
    for (int64_t off_ = (J) * PF_BYTES / 8; off_ < ((J) + 1) * PF_BYTES / 8; off_ += 64) { \
        __builtin_prefetch(pf_a + off_, 0, PF_HINT);                                            \
        __builtin_prefetch(pf_b + off_, 0, PF_HINT);                                            \
    }
#else
#define PREFETCH(J)
#endif

/* Stage 3a packs the pairs it runs on only when one pair in SEP_PACK of the block needs it: the
 * lane reads 16 of the 42 rows a packed pair copies, so in place on every lane costs less than
 * packing for all but a lone pair. 400,000 3D pairs, AVX2 on an AMD EPYC, one pinned core, CPU
 * time, 9 interleaved rounds (with the queue of 3b): spheres 52.1 -> 49.6 ns per pair with 8
 * against 2, homothetic copies 52.8 -> 50.1, random 40.4 -> 40.7 (unchanged). */
#ifndef SEP_PACK
#define SEP_PACK 8
#endif
#define LATE GLUE(CLASSIFY, late)
#define DEFERRED (-12) /* a pair's code once it is in the queue: its output is the queue's */

/* Stages 3b and 4 and the output on m <= CHUNK pairs in block layout (the queue: columns of
 * several blocks), pair p going to out[at[p]]; returns how many are undecided. */
static __attribute__((noinline)) int64_t LATE(T *restrict a, T *restrict b, double *restrict c, int64_t *restrict code, int64_t *restrict idx,
                                              const int64_t *restrict route, const int64_t *restrict at, const int64_t m,
                                              signed char *restrict out, const signed char *restrict table) {
    int64_t k = 0, undecided = 0;
    int32_t open[CHUNK];
    CERT_STAGE(THIRD_FAST, route[p] != 2, 0, 2)
    CERT_STAGE(THIRD, route[p] == 2, 0, 2)
    S0_STAGE(FOURTH, NEEDS_S0_RADIUS)
    for (int64_t p = 0; p < m; p++) {
        const int64_t rule = code[p] >= 0 ? code[p] : -1; /* NEEDS_CERT: undecided */
        undecided += rule < 0;
        out[at[p]] = table ? table[(uint8_t)rule] : (signed char)rule;
    }
    return undecided;
}

int64_t CLASSIFY(const T *restrict A, const T *restrict B, signed char *restrict out, int64_t count, const signed char *restrict table) {
    int64_t undecided = 0;
    /* the queue of pairs for stages 3b and 4: block columns, and each pair's place in out */
    T qa[N * N * CHUNK], qb[N * N * CHUNK];
    double qc[2 * (N + 1) * CHUNK];
    int64_t qcode[CHUNK], qidx[CHUNK], qroute[CHUNK], qat[CHUNK], qn = 0;
    int full_run = 0;   /* the last block tried was mostly symmetric only up to rounding */
    int scaled_run = 0; /* the last block tried had mostly entries outside [2^-8, 2^24] */
    for (int64_t i0 = 0; i0 < count; i0 += CHUNK) {
        const int64_t m = count - i0 < CHUNK ? count - i0 : CHUNK;
        T a[N * N * CHUNK], b[N * N * CHUNK]; /* entry k of pair p at [k * CHUNK + p] */
        double c[2 * (N + 1) * CHUNK];        /* a_0..a_n, then their radii: the same layout */
        int64_t code[CHUNK], idx[CHUNK];
        int32_t open[CHUNK];
        int64_t route[CHUNK]; /* the first pass that gave the pair's a_i: 0 unscaled, 1 scaled, 2 the full prepare */
        int64_t done = 0, k = 0;
#if PF_DIST > 0
        const char *pf_a = (const char *)(A + (i0 + PF_DIST * CHUNK) * N * N), *pf_b = (const char *)(B + (i0 + PF_DIST * CHUNK) * N * N);
#endif
        PREFETCH(0)
#if TP > 0
        for (; done + TP <= m; done += TP) { /* TP pairs at a time, TP entries per shuffle network */
            for (int e = 0; e + TP <= N * N; e += TP) {
                TRANSPOSE_T(A + (i0 + done) * N * N + e, N * N, a + e * CHUNK + done, CHUNK);
                TRANSPOSE_T(B + (i0 + done) * N * N + e, N * N, b + e * CHUNK + done, CHUNK);
            }
            for (int64_t p = done; p < done + TP; p++)
                for (int e = N * N / TP * TP; e < N * N; e++) {
                    a[e * CHUNK + p] = A[(i0 + p) * N * N + e];
                    b[e * CHUNK + p] = B[(i0 + p) * N * N + e];
                }
        }
#endif
        PREFETCH(1)
        for (int64_t p = done; p < m; p++)
            for (int e = 0; e < N * N; e++) {
                a[e * CHUNK + p] = A[(i0 + p) * N * N + e];
                b[e * CHUNK + p] = B[(i0 + p) * N * N + e];
            }
        /* stage 1, every pair: prepare (exactly symmetric matrices), pencil with bounds, validity,
         * the tree with s0 pending; where the previous block was mostly symmetric only up to
         * rounding (numpy-built matrices come in whole arrays), the full prepare directly (it
         * takes the same decisions on an exactly symmetric matrix, so the route changes no
         * answer; every 16th block tries the fast pass again) */
        const int use_full = full_run && (i0 / CHUNK) % 16 != 0;
        /* the same for inputs whose entries are mostly outside [2^-8, 2^24] (the scaled pass directly) */
        const int use_scaled = !use_full && scaled_run && (i0 / CHUNK) % 16 != 0;
        for (int64_t p0 = 0; p0 < m; p0 += LANES) {
            const int64_t p1 = p0 + LANES < m ? p0 + LANES : m;
            PREFETCH(p0 ? 3 : 2)
            if (use_full)
                for (int64_t p = p0; p < p1; p++) code[p] = FULL(a + p, b + p, c + p, CHUNK, idx + p);
            else if (use_scaled)
                for (int64_t p = p0; p < p1; p++) code[p] = FIRST(a + p, b + p, c + p, CHUNK, idx + p);
            else
                for (int64_t p = p0; p < p1; p++) code[p] = FIRST_NOSCALE(a + p, b + p, c + p, CHUNK, idx + p);
        }
#if LANES >= CHUNK
        PREFETCH(3) /* one round per block: part 3 here */
#endif
        /* stage 1 again with the scaling, where a largest entry is outside [2^-8, 2^24] (and where
         * a matrix is not exactly symmetric: the scaled pass sends those on to the full prepare) */
        for (int64_t p = 0; p < m; p++) route[p] = use_scaled || code[p] == NEEDS_SCALE;
        if (!use_full && !use_scaled) {
            SUBSET(code[p] == NEEDS_SCALE)
            scaled_run = 2 * k > m;
            AGAIN(FIRST, NEEDS_SCALE)
        }
        for (int64_t p = 0; p < m; p++) route[p] = use_full || code[p] == NEEDS_FULL ? 2 : route[p];
        /* stage 1 again with the full prepare, where a matrix is symmetric only up to rounding */
        if (!use_full) {
            SUBSET(code[p] == NEEDS_FULL)
            full_run = 2 * k > m;
            AGAIN(FULL, NEEDS_FULL)
        }
        PREFETCH(4)
#ifdef SKIP_S0
        /* ellipsoids whose quadratic blocks look proportional (spheres, copies: s0 vanishes) go
         * past stage 2 as if it had failed (driver.skips_s0; every lane, then selected) */
        for (int64_t p = 0; p < m; p++) {
            const int64_t skip = SKIP_S0(a + p, b + p, CHUNK);
            code[p] = code[p] == NEEDS_S0 && skip ? NEEDS_S0_RADIUS : code[p];
        }
#endif
        /* stage 2, where the tree asks for s0: the semi-static test */
        S0_STAGE(SECOND, NEEDS_S0)
        PREFETCH(5)
        /* stage 3, valid pairs still open: the certificates, on the prepare each pair took; first
         * the cheap separation certificate (T* from the a_i and the traces: spheres, translated and
         * homothetic copies that are separate), then the full ones on the pairs it left */
        CERT_STAGE(THIRD_SEP_NOSCALE, route[p] == 0, 1, SEP_PACK)
        CERT_STAGE(THIRD_SEP_FAST, route[p] == 1, 1, SEP_PACK)
        CERT_STAGE(THIRD_SEP, route[p] == 2, 1, SEP_PACK)
        PREFETCH(6)
        /* the pairs still open: 3b, then stage 4 (s0 still needed, the running-error test); in
         * the block when most of its pairs need them (near-contact data: copying would only add
         * to the cost), else to the queue, which runs when it holds a block of them */
        SUBSET((code[p] == NEEDS_CERT || code[p] == NEEDS_S0_RADIUS))
        if (2 * k > m) { /* the stages of LATE, inline: LATE called on the block measured 8 % slower on tangent pairs */
            CERT_STAGE(THIRD_FAST, route[p] != 2, 0, 2)
            CERT_STAGE(THIRD, route[p] == 2, 0, 2)
            S0_STAGE(FOURTH, NEEDS_S0_RADIUS)
        } else {
            for (int64_t q = 0; q < k; q++) { /* open[] from SUBSET */
                const int64_t p = open[q];
                for (int r = 0; r < N * N; r++) {
                    qa[r * CHUNK + qn] = a[r * CHUNK + p];
                    qb[r * CHUNK + qn] = b[r * CHUNK + p];
                }
                for (int r = 0; r < 2 * (N + 1); r++) qc[r * CHUNK + qn] = c[r * CHUNK + p];
                qcode[qn] = code[p];
                qidx[qn] = idx[p];
                qroute[qn] = route[p];
                qat[qn] = i0 + p;
                code[p] = DEFERRED;
                if (++qn == CHUNK) {
                    undecided += LATE(qa, qb, qc, qcode, qidx, qroute, qat, qn, out, table);
                    qn = 0;
                }
            }
        }
        for (int64_t p = 0; p < m; p++) {
            if (code[p] == DEFERRED) continue;
            const int64_t rule = code[p] >= 0 ? code[p] : -1; /* NEEDS_CERT: undecided */
            undecided += rule < 0;
            out[i0 + p] = table ? table[(uint8_t)rule] : (signed char)rule;
        }
        PREFETCH(7)
    }
    if (qn) undecided += LATE(qa, qb, qc, qcode, qidx, qroute, qat, qn, out, table);
    return undecided;
}

#undef SUBSET
#undef SUBSET_AT
#undef LATE
#undef DEFERRED
#undef AGAIN
#undef PREFETCH
#undef PF_BYTES
#undef PACK
#undef S0_STAGE
#undef CERT_STAGE
