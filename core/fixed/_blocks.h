/* The block driver of the certified float filter: the generated lane functions over many pairs.
 *
 * Included by _variant.h once per (dimension, input type), with these macros defined:
 *   N          3 (ellipses) or 4 (ellipsoids)
 *   T          double or float (float is widened exactly: certified for the float values given)
 *   FIRST, FULL, SECOND, THIRD   the lane functions of _kernels.h for this N and T
 *   CLASSIFY   the name of the function defined here
 *
 * The pairs of a block are first transposed to structure of arrays (entry k of every pair in
 * one row). Each stage is then a loop over pairs whose body is a branch-free lane function, so
 * the compiler turns it into SIMD across pairs, a vector load reading one entry of several pairs. Stage 2 (s0) and stage 3 (the certificates) run only on the pairs
 * the stage before left open: packed first so that the SIMD lanes stay full, or, when most pairs
 * of the block are open, run on every lane in place and selected.
 */

void CLASSIFY(const T *restrict A, const T *restrict B, signed char *restrict out, int64_t count) {
    int full_run = 0; /* the last block tried was mostly symmetric only up to rounding */
    for (int64_t i0 = 0; i0 < count; i0 += CHUNK) {
        const int64_t m = count - i0 < CHUNK ? count - i0 : CHUNK;
        T a[N * N * CHUNK], b[N * N * CHUNK]; /* entry k of pair p at [k * CHUNK + p] */
        double c[2 * (N + 1) * CHUNK];        /* a_0..a_n, then their radii: the same layout */
        int64_t code[CHUNK], idx[CHUNK];
        int32_t open[CHUNK];
        int64_t done = 0;
#ifdef HAVE_TRANSPOSE8
        for (; done + 8 <= m; done += 8) { /* 8 pairs at a time, 8 entries per shuffle network */
                for (int k = 0; k + 8 <= N * N; k += 8) {
                    TRANSPOSE8_T(A + (i0 + done) * N * N + k, N * N, a + k * CHUNK + done, CHUNK);
                    TRANSPOSE8_T(B + (i0 + done) * N * N + k, N * N, b + k * CHUNK + done, CHUNK);
                }
                for (int64_t p = done; p < done + 8; p++)
                    for (int k = N * N / 8 * 8; k < N * N; k++) {
                        a[k * CHUNK + p] = A[(i0 + p) * N * N + k];
                        b[k * CHUNK + p] = B[(i0 + p) * N * N + k];
                    }
            }
#endif
        for (int64_t p = done; p < m; p++)
            for (int k = 0; k < N * N; k++) {
                a[k * CHUNK + p] = A[(i0 + p) * N * N + k];
                b[k * CHUNK + p] = B[(i0 + p) * N * N + k];
            }
        /* stage 1, every pair: prepare (exactly symmetric matrices), pencil with bounds, validity,
         * the tree with s0 pending; where the previous block was mostly symmetric only up to
         * rounding (numpy-built matrices come in whole arrays), the full prepare directly (it
         * takes the same decisions on an exactly symmetric matrix, so the route changes no
         * answer; every 16th block tries the fast pass again) */
        const int use_full = full_run && (i0 / CHUNK) % 16 != 0;
        int64_t k = 0;
        for (int64_t p0 = 0; p0 < m; p0 += LANES) {
            const int64_t p1 = p0 + LANES < m ? p0 + LANES : m;
            /* the block PF_DIST ahead streams in while this one computes (the transpose above is
             * the only reader of A and B; small blocks keep the requests spread out) */
#if PF_DIST > 0
            const char *na = (const char *)(A + (i0 + PF_DIST * CHUNK + p0) * N * N), *nb = (const char *)(B + (i0 + PF_DIST * CHUNK + p0) * N * N);
            for (int64_t off = 0; off < (p1 - p0) * N * N * (int64_t)sizeof(T); off += 64) {
                __builtin_prefetch(na + off, 0, PF_HINT);
                __builtin_prefetch(nb + off, 0, PF_HINT);
            }
#endif
            if (use_full)
                for (int64_t p = p0; p < p1; p++) code[p] = FULL(a + p, b + p, c + p, CHUNK, idx + p);
            else
                for (int64_t p = p0; p < p1; p++) code[p] = FIRST(a + p, b + p, c + p, CHUNK, idx + p);
        }
        /* stage 1 again with the full prepare, where a matrix is symmetric only up to rounding */
        if (!use_full) {
            for (int64_t p = 0; p < m; p++) {
                open[k] = (int32_t)p;
                k += code[p] == NEEDS_FULL;
            }
            full_run = 2 * k > m;
        }
        if (2 * k > m) { /* most pairs: every lane in place, then select */
            double d[2 * (N + 1) * CHUNK];
            int64_t di[CHUNK];
            for (int64_t p = 0; p < m; p++) {
                const int64_t full = FULL(a + p, b + p, d + p, CHUNK, di + p);
                const int64_t take = code[p] == NEEDS_FULL;
                for (int r = 0; r < 2 * (N + 1); r++) c[r * CHUNK + p] = take ? d[r * CHUNK + p] : c[r * CHUNK + p];
                idx[p] = take ? di[p] : idx[p];
                code[p] = take ? full : code[p];
            }
        } else if (k) {
            T pa[N * N * CHUNK], pb[N * N * CHUNK];
            double d[2 * (N + 1) * CHUNK];
            int64_t di[CHUNK], dc[CHUNK];
            for (int64_t q = 0; q < k; q++)
                for (int r = 0; r < N * N; r++) {
                    pa[r * CHUNK + q] = a[r * CHUNK + open[q]];
                    pb[r * CHUNK + q] = b[r * CHUNK + open[q]];
                }
            for (int64_t q = 0; q < k; q++) dc[q] = FULL(pa + q, pb + q, d + q, CHUNK, di + q);
            for (int64_t q = 0; q < k; q++) {
                for (int r = 0; r < 2 * (N + 1); r++) c[r * CHUNK + open[q]] = d[r * CHUNK + q];
                idx[open[q]] = di[q];
                code[open[q]] = dc[q];
            }
        }
        /* stage 2, where the tree asks for s0 */
        k = 0;
        for (int64_t p = 0; p < m; p++) {
            open[k] = (int32_t)p;
            k += code[p] == NEEDS_S0;
        }
        if (2 * k > m) { /* most pairs (random pairs: Var = 2 is common): every lane, then select */
            for (int64_t p = 0; p < m; p++) {
                const int64_t s0 = SECOND(c + p, CHUNK, idx[p]);
                code[p] = code[p] == NEEDS_S0 ? s0 : code[p];
            }
        } else if (k) {
            double d[2 * (N + 1) * CHUNK];
            int64_t di[CHUNK], dc[CHUNK];
            for (int64_t q = 0; q < k; q++) {
                for (int r = 0; r < 2 * (N + 1); r++) d[r * CHUNK + q] = c[r * CHUNK + open[q]];
                di[q] = idx[open[q]];
            }
            for (int64_t q = 0; q < k; q++) dc[q] = SECOND(d + q, CHUNK, di[q]);
            for (int64_t q = 0; q < k; q++) code[open[q]] = dc[q];
        }
        /* stage 3, valid pairs still open (spheres, translated and homothetic copies) */
        k = 0;
        for (int64_t p = 0; p < m; p++) {
            open[k] = (int32_t)p;
            k += code[p] == NEEDS_CERT;
        }
        if (2 * k > m) { /* most pairs (spheres, copies): every lane in place, then select */
            for (int64_t p = 0; p < m; p++) {
                const int64_t cert = THIRD(a + p, b + p, c + p, CHUNK);
                code[p] = code[p] == NEEDS_CERT ? cert : code[p];
            }
        } else if (k) {
            T pa[N * N * CHUNK], pb[N * N * CHUNK];
            double d[2 * (N + 1) * CHUNK];
            int64_t dc[CHUNK];
            for (int64_t q = 0; q < k; q++) {
                for (int r = 0; r < N * N; r++) {
                    pa[r * CHUNK + q] = a[r * CHUNK + open[q]];
                    pb[r * CHUNK + q] = b[r * CHUNK + open[q]];
                }
                for (int r = 0; r < 2 * (N + 1); r++) d[r * CHUNK + q] = c[r * CHUNK + open[q]];
            }
            for (int64_t q = 0; q < k; q++) dc[q] = THIRD(pa + q, pb + q, d + q, CHUNK);
            for (int64_t q = 0; q < k; q++) code[open[q]] = dc[q];
        }
        for (int64_t p = 0; p < m; p++) out[i0 + p] = (signed char)code[p];
    }
}
