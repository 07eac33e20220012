/* One new body asked of the grid of core.bodies.index (BodyIndex._query_one), in C.
 *
 * A Monte Carlo code asks the index about one trial body per move; in numpy that lookup is some
 * fifteen array operations on a few dozen bodies, each costing more in call overhead than in
 * work. Here it is one loop, with the steps of BodyIndex._near_one and _place_one:
 *
 * place_one: the body's cell u, from its centre c: open space floor((c - origin) / cell), kept
 * off the grid's empty margin; periodic floor(f n) mod n, f the fractional coordinates by the
 * triangular solve of core.bodies.periodic._solve (the same operations, so the same cell as
 * the numpy path) with its error bound, which must stay below 2^-30 with |f| <= 2^20.
 *
 * near_one: the cells within m[a] cells of the body's own cell
 * u (periodic: modulo the cell counts n, every cell of an axis once when 2 m + 1 >= n; open
 * space: the cells on the grid), the ids each cell holds (a row of the table, its filled slots
 * first, -1 after), all but `exclude`, and of those the bodies whose sphere (cr: centre, radius)
 * meets the new body's: |c_j - c|^2 <= (r_j + rpad)^2, rpad = r + the padding of the index's
 * sphere test. In a periodic box the indexed body's centre is first moved by the lattice image
 * that brings it nearest (k = -rint of the difference in fractional coordinates, as the index
 * finds it: diff / L per axis in an orthogonal box, frac_j - f through the cell in a tilted one).
 *
 * The sphere test only prunes: a pair it keeps is classified, a pair it drops has disjoint
 * spheres (padded far beyond the roundings of this test and of the lattice vector, which is
 * the float sum k1 a1 + k2 a2 + k3 a3 here), so the answers do not depend on its last bits.
 */

#define NEAR_TOO_FAR (-1) /* an image beyond 127 boxes (int8) */

/* The cell of centre c (place_one above); 0, or NEAR_FAR_BOX where the fractional coordinates are
 * not accurate enough (a centre too far from the box). H: the box vectors as columns (row-major
 * d x d, upper triangular), n: cells per axis; open space: origin o and cell sizes h. */
#define NEAR_FAR_BOX (-4)
static int place_one(int d, int periodic, const double *H, const int64_t *n, const double *o, const double *h, double gamma, double tiny,
                     double eps_max, double far, const double *c, int64_t *u, double *f) {
    if (!periodic) {
        for (int a = 0; a < d; a++) {
            double w = floor((c[a] - o[a]) / h[a]);
            w = w < 1.0 ? 1.0 : w;
            w = w > (double)(n[a] - 2) ? (double)(n[a] - 2) : w;
            u[a] = (int64_t)w;
        }
        return 0;
    }
    double e[3] = {0.0, 0.0, 0.0};
    for (int a = d - 1; a >= 0; a--) {
        double acc = c[a], mag = fabs(c[a]), err = 0.0;
        for (int b = a + 1; b < d; b++)
            if (H[a * d + b] != 0.0) {
                acc = acc - H[a * d + b] * f[b];
                mag = mag + fabs(H[a * d + b]) * fabs(f[b]);
                err = err + fabs(H[a * d + b]) * e[b];
            }
        f[a] = acc / H[a * d + a];
        e[a] = ((gamma * mag + err) / H[a * d + a]) * (1 + gamma) + tiny;
    }
    for (int a = 0; a < d; a++)
        if (!(e[a] < eps_max && fabs(f[a]) <= far)) return NEAR_FAR_BOX;
    for (int a = 0; a < d; a++) {
        const int64_t w = (int64_t)floor(f[a] * (double)n[a]);
        u[a] = ((w % n[a]) + n[a]) % n[a];
    }
    return 0;
}
#define NEAR_MOVED (-3)   /* code of a pair with a lattice image: not classified here (the caller moves B exactly) */

static int64_t near_one(int d, const int32_t *table, int64_t cap, int64_t nbody, const int64_t *n, const int64_t *stride, int periodic, int tilted,
                        const double *L, const double *H, const double *cr, const double *frac, const int64_t *u, const int64_t *m,
                        const double *c, const double *f, double rpad, int64_t exclude, int64_t *out, signed char *kout) {
    int64_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}; /* offsets per axis, or every cell (periodic, 2 m + 1 >= n) */
    int every[3] = {0, 0, 0};
    for (int a = 0; a < d; a++) {
        every[a] = periodic && 2 * m[a] + 1 >= n[a];
        lo[a] = every[a] ? 0 : -m[a];
        hi[a] = every[a] ? n[a] - 1 : m[a];
    }
    int64_t found = 0;
    int64_t v[3];
    for (v[0] = lo[0]; v[0] <= hi[0]; v[0]++)
        for (v[1] = lo[1]; v[1] <= hi[1]; v[1]++)
            for (v[2] = d == 3 ? lo[2] : 0; v[2] <= (d == 3 ? hi[2] : 0); v[2]++) {
                int64_t cell = 0, off = 0;
                for (int a = 0; a < d && !off; a++) {
                    int64_t w = every[a] ? v[a] : u[a] + v[a];
                    if (periodic)
                        w = ((w % n[a]) + n[a]) % n[a];
                    else if (w < 0 || w >= n[a])
                        off = 1; /* off the grid: no cell */
                    cell += w * stride[a];
                }
                if (off) continue;
                const int32_t *row = table + cell * cap;
                for (int64_t s = 0; s < cap && row[s] >= 0; s++) {
                    const int64_t j = row[s];
                    if (j == exclude || j >= nbody) continue; /* (ids come from the index: always < nbody) */
                    const double *p = cr + j * (d + 1);
                    double diff[3], k[3] = {0.0, 0.0, 0.0};
                    for (int a = 0; a < d; a++) diff[a] = p[a] - c[a];
                    if (periodic) {
                        for (int a = 0; a < d; a++) {
                            k[a] = nearbyint(tilted ? frac[j * d + a] - f[a] : diff[a] / L[a]);
                            if (!(fabs(k[a]) <= 127.0)) return NEAR_TOO_FAR;
                        }
                        for (int a = 0; a < d; a++) {
                            double shift = 0.0;
                            if (tilted)
                                for (int b = 0; b < d; b++) shift += H[a * d + b] * k[b];
                            else
                                shift = k[a] * L[a];
                            diff[a] -= shift;
                        }
                    }
                    double d2 = 0.0;
                    for (int a = 0; a < d; a++) d2 += diff[a] * diff[a];
                    const double rr = p[d] + rpad;
                    if (d2 <= rr * rr) {
                        out[found] = j;
                        if (periodic)
                            for (int a = 0; a < d; a++) kout[found * d + a] = (signed char)(-k[a]);
                        found++;
                    }
                }
            }
    return found;
}
