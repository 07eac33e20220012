/* Certified float filter for the first contact of two ellipsoids (ellipses) in linear motion.
 *
 * Hand-written C, driven by core/moving/sweep_filter.py (the proofs are there and here), built
 * when the package is installed (setup.py: the extension core.moving._sweep_filter, this kernel
 * and its Python face _sweep_module.c) with the project's flags: no -ffast-math, no contraction
 * into FMA (-ffp-contract=off): every operation rounds once, to nearest, as the bounds assume.
 *
 * Body k: semi-axes r, centre c(t) = c0 + t (c1 - c0), orientation R(q(t) / |q(t)|) with
 * q(t) = (1 - t) q0 + t q1 (3D quaternion wxyz; 2D half-angle number (w, s)). For a pair (A, B)
 * the origin moves with A's centre (a common translation keeps P(T) = det(T A + B)), so A is
 * centred at 0 and B at d(t) = c_B(t) + shift - c_A(t). With R~(q) the rotation numerator
 * (R = R~ / N, N = |q|^2) each matrix is scaled by N^2 > 0:
 *     A~ = [[R~_A D_A R~_A^T, 0], [0, -N_A^2]],
 *     B~ = [[Q~_B, -Q~_B d], [-d^T Q~_B, d^T Q~_B d - N_B^2]],   Q~_B = R~_B D_B R~_B^T,
 * D = diag(1 / r^2). det(T A~ + B~) = N_B^(2(d+1)) P(t, T (N_A / N_B)^2): the same sign as the
 * true pencil P at a positive T, so every certificate below holds for the exact bodies.
 *
 * Polynomials in t are homogeneous forms in (1 - t, t) ("scaled Bernstein": p = sum c_k
 * (1-t)^(n-k) t^k), so products are plain convolutions, and the linear inputs are their own
 * coefficients (c(t) = c0 (1-t) + c1 t). Every coefficient carries a radius: |exact - value|
 * <= radius (midpoint-radius arithmetic). The pencil's coefficients a_i(t) are then divided by
 * the binomials into Bernstein coefficients on [0, 1], which are subdivided by de Casteljau's
 * algorithm (convex combinations) and bound the polynomial on each piece.
 *
 * Certificates (paper: P has two distinct positive roots iff separate):
 *   separate on [a, b]: one T > 0 with every Bernstein coefficient of P(., T) on [a, b] > its
 *     radius: P(t, T) > 0 for all t in [a, b];
 *   overlap at t: a point x with f_A(x) < 0 and f_B(x) < 0 (certified): inside both.
 * Search: separate at 0 (or overlap at 0: t* = 0), then advance t_a (separate on [0, t_a])
 * with T re-optimised at t_a and the next float root of P(., T) as target (a Newton-like step:
 * quadratic convergence to a transversal contact), until a point of both is certified at t_h
 * <= t_a + 9.5e-10: then t* is in (t_a, t_h]. Touching without crossing, tangency at 0,
 * degenerate or extreme pairs: the filter abstains and exact arithmetic decides.
 *
 * Speed: the forms of LANES = 8 pairs of the same shape (which bodies rotate, whether they
 * move) are built at once, one pair per vector lane (each lane performs one pair's operations
 * in the same order, so the results are those of one pair at a time); the search that follows
 * runs pair by pair.
 *
 * Radii: each operation's rounding (<= U |result|, U = 2^-52 >= u / (1 - u)) and underflow
 * (<= 2^-1075 per product or quotient; ETA = 2^-1022, 2^53 times that, is added, generously: a
 * normal number, so no operation ever runs on subnormals, which are slow) is added; the radius
 * formulas are themselves evaluated in floats on non-negative terms, so each computed radius is
 * at least (1 - u)^k times its formula's value after k dependent operations (a product's
 * underflow loss is covered by the ETAs added): comparisons use radius * RF, RF = 1 + 2^-30,
 * which covers k < 2^22, far more than any chain here. Each constant a radius formula adds is a
 * named allowance below, checked against a trace of the operations it covers.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define U 2.220446049250313e-16          /* 2^-52 */
#define ETA 0x1p-1022                    /* 2^-1022 >= any underflow loss (2^-1075); normal, so never slow */
#define RF (1.0 + 9.313225746154785e-10) /* 1 + 2^-30 */

/* Error allowances: every constant a radius formula adds is one of these names (nothing else below
 * uses U or ETA). core/moving/sweepbounds.py reads them from this file, re-derives from a trace of
 * the operations each one covers (core.fixed.errorbound's rounding counts and constants) what it
 * must be at least, and fails naming any that is smaller, any unused, and any use of U or ETA
 * outside them: `python -m core.moving.sweepbounds` prints the table, `python -m core.generated
 * --check` (run by the tests) checks it with the generated files. Several are generous (U is
 * twice u; one ETA covers 2^53 underflows): the table shows by how much. */
#define ADD_U U                          /* z = x +- y (badd, bsub, lf_addsub, lf_elevate): U |z| */
#define ADD_ETA ETA
#define MUL_U U                          /* z = x y of two balls (bmul, lf_scale): U |z| */
#define MUL_ETA (5 * ETA)
#define TIMES_ETA ETA                    /* z = c x, c in {-2, -1, 2} (lf_times): exact */
#define DIV_U U                          /* z = x / C(n, k) (lf_bernstein): U |z| */
#define DIV_ETA ETA
#define INV_SQUARE_U (3 * U)             /* D = 1 / (s s) (load_body): on D; s >= 2^-60, no underflow */
#define RESCALE_ETA ETA                  /* x 2^-e (load_pair): exact unless it underflows */
#define LERP_MAG_U (4 * U)               /* (1 - t) x0 + t x1 (blerp): on its magnitude ... */
#define LERP_Z_U (4 * U)                 /* ... and on |z| */
#define LERP_ETA (6 * ETA)
#define SPLIT_MAG_U (4 * U)              /* a de Casteljau step (f_split): on its magnitude */
#define SPLIT_ETA (6 * ETA)
#define DOT_U(m) ((m) * U)               /* a sum of m products in order (lf_mul): on sum |x_i y_i| */
#define DOT_ETA(m) ((8 * (m) + 2) * ETA)
#define COMBINE_U(m) ((m) * U)           /* P(t, T) = sum of m = n + 1 terms T^k b_k (combine) */
#define COMBINE_ETA(m) ((4 * (m) + 4) * ETA)
#define CERTIFY_STEPS_UP 4               /* nextafter steps making a computed (tb - ta) / (1 - ta) >= the exact one */
#define MAXF 20                          /* coefficients per form: degree <= 19 (3D: 18) */
#define MAXIT 100                        /* advancement steps before the filter abstains */
#define STEP_MARGIN 0.99609375           /* target 1 - 2^-8 of the way to the predicted root */
#define NEAR 5e-10                       /* predicted root this close: test a point of both */
#define BRACKET 9.5e-10                  /* t_h - t_a (< 1e-9 with the rounding of t_a + 9.5e-10) */
#define IN_RANGE(x) (fabs(x) <= 1.0 && (fabs(x) >= 0x1p-100 || (x) == 0.0))

enum { NEVER = 0, CONTACT = 1, OVERLAP_AT_START = 2, UNDECIDED = -1 };
const int8_t SWEEP_STATUS_CODES[4] = {NEVER, CONTACT, OVERLAP_AT_START, UNDECIDED}; /* the module's constants (_sweep_module.c) */

typedef struct { double v, r; } ball;
typedef struct { int n; double v[MAXF]; double r[MAXF]; } form;

/* ---------------------------------------------------------------- balls (midpoint, radius) */

static inline ball bx(double x) { ball o = {x, 0.0}; return o; }
static inline ball badd(ball x, ball y) { double z = x.v + y.v; ball o = {z, x.r + y.r + ADD_U * fabs(z) + ADD_ETA}; return o; }
static inline ball bsub(ball x, ball y) { double z = x.v - y.v; ball o = {z, x.r + y.r + ADD_U * fabs(z) + ADD_ETA}; return o; }
static inline ball bmul(ball x, ball y) {
    double z = x.v * y.v;
    ball o = {z, fabs(x.v) * y.r + x.r * (fabs(y.v) + y.r) + MUL_U * fabs(z) + MUL_ETA};
    return o;
}
/* (1 - t) x0 + t x1 for a float t in [0, 1]: 1 - t is exact for t >= 1/2, else within u (1 - t) */
static inline ball blerp(ball x0, ball x1, double t) {
    double al = 1.0 - t;
    double z = al * x0.v + t * x1.v;
    double mag = al * (fabs(x0.v) + x0.r) + t * fabs(x1.v);
    ball o = {z, al * x0.r + t * x1.r + LERP_MAG_U * mag + LERP_Z_U * fabs(z) + LERP_ETA};
    return o;
}
static inline int bneg(ball x) { return isfinite(x.v) && isfinite(x.r) && x.v < -x.r * RF; }

/* ------------------------------------------------------------ forms in (1 - t, t), with radii */

/* The construction runs on LANES pairs at once ("lane forms": the same degree, one coefficient
 * per pair in each lane), so that every loop below runs over lanes and vectorises; each lane
 * performs exactly the operations of one pair, in the same order (so the bounds are per lane). */
#define LANES 8
typedef struct { int n; double v[MAXF][LANES]; double r[MAXF][LANES]; } lform;
typedef struct { double v[LANES], r[LANES]; } lball;

static void lf_const(lform *f, const lball *b) {
    f->n = 0;
    for (int l = 0; l < LANES; l++) { f->v[0][l] = b->v[l]; f->r[0][l] = b->r[l]; }
}
static void lf_line(lform *f, const lball *b0, const lball *b1) {
    f->n = 1;
    for (int l = 0; l < LANES; l++) { f->v[0][l] = b0->v[l]; f->r[0][l] = b0->r[l]; f->v[1][l] = b1->v[l]; f->r[1][l] = b1->r[l]; }
}

/* z = a (1 - t + t)^(n - a.n): the same polynomial as a form of degree n (z may be a) */
static void lf_elevate(lform *z, const lform *a, int n) {
    int m = a->n;
    if (z != a) {
        z->n = m;
        memcpy(z->v, a->v, sizeof(double) * LANES * (m + 1));
        memcpy(z->r, a->r, sizeof(double) * LANES * (m + 1));
    }
    for (; m < n; m++) {  /* degree m -> m + 1, in place from the top */
        for (int l = 0; l < LANES; l++) { z->v[m + 1][l] = z->v[m][l]; z->r[m + 1][l] = z->r[m][l]; }
        for (int k = m; k >= 1; k--)
            for (int l = 0; l < LANES; l++) {
                double x = z->v[k][l] + z->v[k - 1][l];
                z->r[k][l] = z->r[k][l] + z->r[k - 1][l] + ADD_U * fabs(x) + ADD_ETA;
                z->v[k][l] = x;
            }
        z->n = m + 1;
    }
}

/* z = a + sa * b, sa = +1 or -1 (degrees raised to the larger; z may be a or b) */
static void lf_addsub(lform *z, const lform *a, const lform *b, double sa) {
    lform tmp;
    if (a->n < b->n) { lf_elevate(&tmp, a, b->n); a = &tmp; }
    else if (b->n < a->n) { lf_elevate(&tmp, b, a->n); b = &tmp; }
    int n = a->n;
    for (int k = 0; k <= n; k++)
        for (int l = 0; l < LANES; l++) {
            double x = a->v[k][l] + sa * b->v[k][l];
            z->r[k][l] = a->r[k][l] + b->r[k][l] + ADD_U * fabs(x) + ADD_ETA;
            z->v[k][l] = x;
        }
    z->n = n;
}
static void lf_add(lform *z, const lform *a, const lform *b) { lf_addsub(z, a, b, 1.0); }
static void lf_sub(lform *z, const lform *a, const lform *b) { lf_addsub(z, a, b, -1.0); }

/* z = c a for an exact c in {-2, -1, 2} */
static void lf_times(lform *z, const lform *a, double c) {
    z->n = a->n;
    for (int k = 0; k <= a->n; k++)
        for (int l = 0; l < LANES; l++) { z->v[k][l] = c * a->v[k][l]; z->r[k][l] = fabs(c) * a->r[k][l] + TIMES_ETA; }
}

/* z = a b for a ball b per lane (each coefficient times the lane's ball, as bmul) */
static void lf_scale(lform *z, const lform *a, const lball *b) {
    z->n = a->n;
    for (int k = 0; k <= a->n; k++)
        for (int l = 0; l < LANES; l++) {
            double x = a->v[k][l], rx = a->r[k][l], y = b->v[l], ry = b->r[l], p = x * y;
            z->r[k][l] = fabs(x) * ry + rx * (fabs(y) + ry) + MUL_U * fabs(p) + MUL_ETA;
            z->v[k][l] = p;
        }
}

/* z = a b: convolution. Coefficient k is a sum of m products, accumulated in order of i: it
 * rounds by <= m U sum|a_i b_j| (plus underflow, <= ETA per product); the inputs' radii add
 * sum |a_i| rb_j + ra_i (|b_j| + rb_j). z must not be a or b. */
static void lf_mul(lform *z, const lform *a, const lform *b) {
    int na = a->n, nb = b->n, n = na + nb;
    for (int k = 0; k <= n; k++) {
        int lo = k > nb ? k - nb : 0, hi = k < na ? k : na, m = hi - lo + 1;
        double sv[LANES] = {0}, S[LANES] = {0}, R[LANES] = {0};
        for (int i = lo; i <= hi; i++) {
            int j = k - i;
            for (int l = 0; l < LANES; l++) {
                double x = a->v[i][l], y = b->v[j][l], ax = fabs(x), ay = fabs(y);
                sv[l] += x * y;
                S[l] += ax * ay;
                R[l] += ax * b->r[j][l] + a->r[i][l] * (ay + b->r[j][l]);
            }
        }
        for (int l = 0; l < LANES; l++) {
            z->v[k][l] = sv[l];
            z->r[k][l] = R[l] + DOT_U(m) * S[l] + DOT_ETA(m);
        }
    }
    z->n = n;
}

/* lane l of a, divided by the binomials: Bernstein coefficients on [0, 1] (C(n, k) exact) */
static void lf_bernstein(form *z, const lform *a, int l) {
    double C = 1.0;
    z->n = a->n;
    for (int k = 0; k <= a->n; k++) {
        double x = a->v[k][l] / C;
        z->v[k] = x;
        z->r[k] = a->r[k][l] / C + DIV_U * fabs(x) + DIV_ETA;
        C = C * (a->n - k) / (k + 1);
    }
}

static int lf_finite(const lform *b, int l) {
    for (int k = 0; k <= b->n; k++)
        if (!(isfinite(b->v[k][l]) && isfinite(b->r[k][l]) && fabs(b->v[k][l]) < 0x1p+900 && b->r[k][l] < 0x1p+900)) return 0;
    return 1;
}

/* de Casteljau at tau (Bernstein form b on [0,1]): left = b on [0, tau], right = b on [tau, 1]
 * (either may be NULL). Each step x' = (1 - tau) x_i + tau x_{i+1}, 1 - tau within u. */
static void f_split(const form *b, double tau, form *left, form *right) {
    double v[MAXF], r[MAXF], al = 1.0 - tau;
    int n = b->n;
    memcpy(v, b->v, sizeof(double) * (n + 1));
    memcpy(r, b->r, sizeof(double) * (n + 1));
    if (left) { left->n = n; left->v[0] = v[0]; left->r[0] = r[0]; }
    if (right) { right->n = n; right->v[n] = v[n]; right->r[n] = r[n]; }
    for (int lev = 1; lev <= n; lev++) {
        for (int i = 0; i <= n - lev; i++) {
            double x = al * v[i] + tau * v[i + 1];
            double mag = al * (fabs(v[i]) + r[i]) + tau * fabs(v[i + 1]);
            r[i] = al * r[i] + tau * r[i + 1] + SPLIT_MAG_U * mag + SPLIT_ETA;
            v[i] = x;
        }
        if (left) { left->v[lev] = v[0]; left->r[lev] = r[0]; }
        if (right) { right->v[n - lev] = v[n - lev]; right->r[n - lev] = r[n - lev]; }
    }
}

static int f_positive(const form *b) {
    for (int k = 0; k <= b->n; k++)
        if (!(isfinite(b->v[k]) && isfinite(b->r[k]) && b->v[k] > b->r[k] * RF)) return 0;
    return 1;
}

/* ------------------------------------------------------------------------ one moving body */

typedef struct {
    int d, nq;
    double q0[4], q1[4];     /* scaled by a power of two (the same for both: the same path) */
    ball D[3];               /* 1 / r^2 (lengths scaled) */
    int rotates;
} body;

static int load_body(body *b, const double *row, int d, double inv_len) {
    int nq = d == 3 ? 4 : 2;
    const double *r = row + 2 * d, *q0 = row + 3 * d, *q1 = row + 3 * d + nq;
    double big = 0.0;
    b->d = d; b->nq = nq; b->rotates = 0;
    for (int c = 0; c < nq; c++) {
        big = fmax(big, fmax(fabs(q0[c]), fabs(q1[c])));
        if (q0[c] != q1[c]) b->rotates = 1;
    }
    int e;
    frexp(big, &e);
    for (int c = 0; c < nq; c++) {
        b->q0[c] = ldexp(q0[c], -e);
        b->q1[c] = ldexp(q1[c], -e);
        if (!IN_RANGE(b->q0[c]) || !IN_RANGE(b->q1[c])) return 0;
    }
    for (int a = 0; a < d; a++) {
        double s = r[a] * inv_len;          /* exact: a power of two */
        if (!(s >= 0x1p-60 && s <= 1.0)) return 0;
        double s2 = s * s, D = 1.0 / s2;    /* two roundings: |D - 1/s^2| <= INV_SQUARE_U D */
        b->D[a].v = D;
        b->D[a].r = INV_SQUARE_U * D;
    }
    return 1;
}

/* Temporaries of the construction, per batch (heap: a lane form is 2.5 KB) */
typedef struct {
    lform q[4], R[3][3], RD[3][3], N, sq[10], t1, t2, tmp;
    lform QA[3][3], QB[3][3], NA2, NB2, dd[3], X[3][3][2], y[3], z[2], dQd, acc, yy;
    lform adj[3][3][3], m1[3], m2[3], part[4], detX[4], w[3], zd[5], ak;
} workspace;

/* rotation numerator R~(q) (d x d lane forms) and N = |q|^2, for the lane forms q */
static void rotation_forms(workspace *ws, int d, lform R[3][3], lform *N) {
    lform *q = ws->q, *sq = ws->sq, *t1 = &ws->t1, *t2 = &ws->t2;
    if (d == 2) {
        lf_mul(&sq[0], &q[0], &q[0]); lf_mul(&sq[1], &q[1], &q[1]); lf_mul(&sq[2], &q[0], &q[1]);
        lf_sub(&R[0][0], &sq[0], &sq[1]); R[1][1] = R[0][0];
        lf_times(&R[1][0], &sq[2], 2.0); lf_times(&R[0][1], &sq[2], -2.0);
        lf_add(N, &sq[0], &sq[1]);
        return;
    }
    /* ww xx yy zz xy wz xz wy yz wx */
    const int f[10][2] = {{0, 0}, {1, 1}, {2, 2}, {3, 3}, {1, 2}, {0, 3}, {1, 3}, {0, 2}, {2, 3}, {0, 1}};
    for (int k = 0; k < 10; k++) lf_mul(&sq[k], &q[f[k][0]], &q[f[k][1]]);
    lform *ww = &sq[0], *xx = &sq[1], *yy = &sq[2], *zz = &sq[3], *xy = &sq[4], *wz = &sq[5], *xz = &sq[6], *wy = &sq[7], *yz = &sq[8], *wx = &sq[9];
    /* R00 = w2 + x2 - y2 - z2, R11 = w2 - x2 + y2 - z2, R22 = w2 - x2 - y2 + z2 */
    lf_add(t1, ww, xx); lf_add(t2, yy, zz); lf_sub(&R[0][0], t1, t2);
    lf_sub(t1, ww, xx); lf_sub(t2, yy, zz); lf_add(&R[1][1], t1, t2);
    lf_sub(t1, ww, xx); lf_sub(t2, zz, yy); lf_add(&R[2][2], t1, t2);
    lf_sub(t1, xy, wz); lf_times(&R[0][1], t1, 2.0);
    lf_add(t1, xz, wy); lf_times(&R[0][2], t1, 2.0);
    lf_add(t1, xy, wz); lf_times(&R[1][0], t1, 2.0);
    lf_sub(t1, yz, wx); lf_times(&R[1][2], t1, 2.0);
    lf_sub(t1, xz, wy); lf_times(&R[2][0], t1, 2.0);
    lf_add(t1, yz, wx); lf_times(&R[2][1], t1, 2.0);
    lf_add(t1, ww, xx); lf_add(t2, yy, zz); lf_add(N, t1, t2);
}

/* Q~ = R~ D R~^T (lane forms, symmetric) and N^2 of one body of every lane's pair (A or B) */
static void body_forms(workspace *ws, const body *const bodies[LANES], lform Q[3][3], lform *N2) {
    const body *b0 = bodies[0];
    int d = b0->d;
    lball x0, x1;
    for (int c = 0; c < b0->nq; c++) {
        for (int l = 0; l < LANES; l++) { x0.v[l] = bodies[l]->q0[c]; x1.v[l] = bodies[l]->q1[c]; x0.r[l] = x1.r[l] = 0.0; }
        if (b0->rotates) lf_line(&ws->q[c], &x0, &x1);
        else lf_const(&ws->q[c], &x0);
    }
    rotation_forms(ws, d, ws->R, &ws->N);
    for (int k = 0; k < d; k++) {
        lball D;
        for (int l = 0; l < LANES; l++) { D.v[l] = bodies[l]->D[k].v; D.r[l] = bodies[l]->D[k].r; }
        for (int i = 0; i < d; i++) lf_scale(&ws->RD[i][k], &ws->R[i][k], &D);
    }
    for (int i = 0; i < d; i++)
        for (int j = i; j < d; j++) {
            lf_mul(&Q[i][j], &ws->RD[i][0], &ws->R[j][0]);
            for (int k = 1; k < d; k++) { lf_mul(&ws->tmp, &ws->RD[i][k], &ws->R[j][k]); lf_add(&Q[i][j], &Q[i][j], &ws->tmp); }
            if (j != i) Q[j][i] = Q[i][j];
        }
    lf_mul(N2, &ws->N, &ws->N);
}

/* The same at one time t, as balls: Q~(t) (full, symmetric) and N(t)^2 */
static void body_at(const body *b, double t, ball Q[3][3], ball *N2) {
    int d = b->d;
    ball q[4], R[3][3], N;
    for (int c = 0; c < b->nq; c++) q[c] = b->rotates ? blerp(bx(b->q0[c]), bx(b->q1[c]), t) : bx(b->q0[c]);
    if (d == 2) {
        ball ww = bmul(q[0], q[0]), ss = bmul(q[1], q[1]), ws = bmul(q[0], q[1]);
        R[0][0] = R[1][1] = bsub(ww, ss);
        R[1][0] = (ball){2 * ws.v, 2 * ws.r};
        R[0][1] = (ball){-2 * ws.v, 2 * ws.r};
        N = badd(ww, ss);
    } else {
        ball w = q[0], x = q[1], y = q[2], z = q[3];
        ball ww = bmul(w, w), xx = bmul(x, x), yy = bmul(y, y), zz = bmul(z, z);
        ball xy = bmul(x, y), wz = bmul(w, z), xz = bmul(x, z), wy = bmul(w, y), yz = bmul(y, z), wx = bmul(w, x);
        R[0][0] = bsub(badd(ww, xx), badd(yy, zz));
        R[1][1] = badd(bsub(ww, xx), bsub(yy, zz));
        R[2][2] = badd(bsub(ww, xx), bsub(zz, yy));
        ball t1;
        t1 = bsub(xy, wz); R[0][1] = (ball){2 * t1.v, 2 * t1.r};
        t1 = badd(xz, wy); R[0][2] = (ball){2 * t1.v, 2 * t1.r};
        t1 = badd(xy, wz); R[1][0] = (ball){2 * t1.v, 2 * t1.r};
        t1 = bsub(yz, wx); R[1][2] = (ball){2 * t1.v, 2 * t1.r};
        t1 = bsub(xz, wy); R[2][0] = (ball){2 * t1.v, 2 * t1.r};
        t1 = badd(yz, wx); R[2][1] = (ball){2 * t1.v, 2 * t1.r};
        N = badd(badd(ww, xx), badd(yy, zz));
    }
    for (int i = 0; i < d; i++)
        for (int j = i; j < d; j++) {
            ball acc = bmul(bmul(R[i][0], b->D[0]), R[j][0]);
            for (int k = 1; k < d; k++) acc = badd(acc, bmul(bmul(R[i][k], b->D[k]), R[j][k]));
            Q[i][j] = Q[j][i] = acc;
        }
    *N2 = bmul(N, N);
}

/* ------------------------------------------------------------------------- one moving pair */

typedef struct {
    int d, n;                /* dimension; degree of P in T (d + 1) */
    body A, B;
    ball d0[3], d1[3];       /* B's centre relative to A's at t = 0, 1 (lengths scaled) */
    int moves;               /* d(t) not constant */
    form b[5];               /* Bernstein coefficients of a_i(t) on [0, 1] */
    double c[5][MAXF];       /* their homogeneous (scaled) coefficients: float evaluations only */
    int deg;
} pair;

/* x * inv (inv a power of two) is exact: finite, normal unless x is 0 (a subnormal product may
 * drop bits), and x again when divided back (a product just below 2^-1022 may round up to it) */
static inline int scaled_exactly(double x, double inv) {
    double y = x * inv;
    return isfinite(y) && (x == 0.0 || fabs(y) >= 0x1p-1022) && y / inv == x;
}

static int load_pair(pair *p, int d, const double *ra, const double *rb, const double *shift) {
    double big = 0.0;
    for (int a = 0; a < d; a++) big = fmax(big, fmax(ra[2 * d + a], rb[2 * d + a]));
    if (!(big > 0.0) || !isfinite(big)) return 0;
    int e;
    frexp(big, &e);
    double inv = ldexp(1.0, -e);   /* lengths scaled by 2^-e (exact): largest semi-axis in [1/2, 1) */
    p->d = d; p->n = d + 1; p->moves = 0;
    if (!load_body(&p->A, ra, d, inv) || !load_body(&p->B, rb, d, inv)) return 0;
    for (int a = 0; a < d; a++) {
        const double sh = shift ? shift[a] : 0.0;
        if (scaled_exactly(rb[a], inv) && scaled_exactly(rb[d + a], inv) && scaled_exactly(ra[a], inv) &&
            scaled_exactly(ra[d + a], inv) && scaled_exactly(sh, inv)) {
            /* the differences in the scaled units: their underflow terms (ETA) are relative to
             * order 1 there, not to the bodies' size (at size 1e-300, ETA is 2^-25 of it) */
            ball s = bx(sh * inv);
            p->d0[a] = bsub(badd(bx(rb[a] * inv), s), bx(ra[a] * inv));
            p->d1[a] = bsub(badd(bx(rb[d + a] * inv), s), bx(ra[d + a] * inv));
        } else {
            ball s = bx(sh);
            ball x0 = bsub(badd(bx(rb[a]), s), bx(ra[a]));
            ball x1 = bsub(badd(bx(rb[d + a]), s), bx(ra[d + a]));
            p->d0[a] = (ball){x0.v * inv, x0.r * inv + RESCALE_ETA};
            p->d1[a] = (ball){x1.v * inv, x1.r * inv + RESCALE_ETA};
        }
        if (!(fabs(p->d0[a].v) <= 0x1p+60 && fabs(p->d1[a].v) <= 0x1p+60)) return 0;
        if (rb[a] != rb[d + a] || ra[a] != ra[d + a]) p->moves = 1;
    }
    return 1;
}

/* T-polynomials of lane forms: out[k] is the coefficient of T^k (out of length nx + ny + 1) */
static void tl_mul(workspace *ws, lform *out, const lform *x, int nx, const lform *y, int ny) {
    for (int k = 0; k <= nx + ny; k++) out[k].n = -1;
    for (int i = 0; i <= nx; i++)
        for (int j = 0; j <= ny; j++) {
            if (out[i + j].n < 0) lf_mul(&out[i + j], &x[i], &y[j]);
            else { lf_mul(&ws->tmp, &x[i], &y[j]); lf_add(&out[i + j], &out[i + j], &ws->tmp); }
        }
}

/* a_i(t), i = 0..n, as Bernstein forms on [0, 1], for the pairs of the lanes (module
 * docstring); all lanes have the same degrees (the caller groups pairs by which bodies rotate
 * and whether they move). Returns a mask of the lanes whose forms are finite. */
static int pencil_forms(workspace *ws, pair *const P[LANES]) {
    pair *p0 = P[0];
    int d = p0->d, g = p0->moves;
    const body *A[LANES], *B[LANES];
    for (int l = 0; l < LANES; l++) { A[l] = &P[l]->A; B[l] = &P[l]->B; }
    body_forms(ws, A, ws->QA, &ws->NA2);
    body_forms(ws, B, ws->QB, &ws->NB2);
    for (int a = 0; a < d; a++) {
        lball x0, x1;
        for (int l = 0; l < LANES; l++) { x0.v[l] = P[l]->d0[a].v; x0.r[l] = P[l]->d0[a].r; x1.v[l] = P[l]->d1[a].v; x1.r[l] = P[l]->d1[a].r; }
        if (g) lf_line(&ws->dd[a], &x0, &x1);
        else lf_const(&ws->dd[a], &x0);
    }
    int E = ws->QA[0][0].n > ws->QB[0][0].n ? ws->QA[0][0].n : ws->QB[0][0].n;
    /* X = T Q~_A + Q~_B (T-linear), y = -Q~_B d, z = T (-N_A^2) + (d^T Q~_B d - N_B^2) */
    for (int i = 0; i < d; i++)
        for (int j = i; j < d; j++) {
            lf_elevate(&ws->X[i][j][0], &ws->QB[i][j], E);
            lf_elevate(&ws->X[i][j][1], &ws->QA[i][j], E);
        }
    for (int i = 0; i < d; i++) {
        lf_mul(&ws->acc, &ws->QB[i][0], &ws->dd[0]);
        for (int j = 1; j < d; j++) { lf_mul(&ws->tmp, &ws->QB[i][j], &ws->dd[j]); lf_add(&ws->acc, &ws->acc, &ws->tmp); }
        lf_times(&ws->y[i], &ws->acc, -1.0);
        if (i == 0) lf_mul(&ws->dQd, &ws->acc, &ws->dd[0]);
        else { lf_mul(&ws->tmp, &ws->acc, &ws->dd[i]); lf_add(&ws->dQd, &ws->dQd, &ws->tmp); }
        lf_elevate(&ws->y[i], &ws->y[i], E + g);
    }
    lf_sub(&ws->z[0], &ws->dQd, &ws->NB2);
    lf_elevate(&ws->z[0], &ws->z[0], E + 2 * g);
    lf_times(&ws->z[1], &ws->NA2, -1.0);
    lf_elevate(&ws->z[1], &ws->z[1], E + 2 * g);
    int nadj;
    if (d == 2) {
        nadj = 1;
        for (int k = 0; k < 2; k++) {
            ws->adj[0][0][k] = ws->X[1][1][k];
            ws->adj[1][1][k] = ws->X[0][0][k];
            lf_times(&ws->adj[0][1][k], &ws->X[0][1][k], -1.0);
        }
        tl_mul(ws, ws->m1, ws->X[0][0], 1, ws->X[1][1], 1);
        tl_mul(ws, ws->m2, ws->X[0][1], 1, ws->X[0][1], 1);
        for (int k = 0; k <= 2; k++) lf_sub(&ws->detX[k], &ws->m1[k], &ws->m2[k]);
    } else {
        nadj = 2;
        const int spec[6][10] = {
            {0, 0, 1, 1, 2, 2, 1, 2, 1, 2}, /* adj00 = X11 X22 - X12 X12 */
            {0, 1, 0, 2, 1, 2, 0, 1, 2, 2}, /* adj01 = X02 X12 - X01 X22 */
            {0, 2, 0, 1, 1, 2, 0, 2, 1, 1}, /* adj02 = X01 X12 - X02 X11 */
            {1, 1, 0, 0, 2, 2, 0, 2, 0, 2}, /* adj11 = X00 X22 - X02 X02 */
            {1, 2, 0, 1, 0, 2, 0, 0, 1, 2}, /* adj12 = X01 X02 - X00 X12 */
            {2, 2, 0, 0, 1, 1, 0, 1, 0, 1}, /* adj22 = X00 X11 - X01 X01 */
        };
        for (int sp = 0; sp < 6; sp++) {
            const int *c = spec[sp];
            tl_mul(ws, ws->m1, ws->X[c[2]][c[3]], 1, ws->X[c[4]][c[5]], 1);
            tl_mul(ws, ws->m2, ws->X[c[6]][c[7]], 1, ws->X[c[8]][c[9]], 1);
            for (int k = 0; k <= 2; k++) lf_sub(&ws->adj[c[0]][c[1]][k], &ws->m1[k], &ws->m2[k]);
        }
        /* det X = X00 adj00 + X01 adj01 + X02 adj02 (the adjugate's first column, by symmetry) */
        tl_mul(ws, ws->detX, ws->X[0][0], 1, ws->adj[0][0], 2);
        for (int j = 1; j < 3; j++) {
            tl_mul(ws, ws->part, ws->X[0][j], 1, ws->adj[0][j], 2);
            for (int k = 0; k <= 3; k++) lf_add(&ws->detX[k], &ws->detX[k], &ws->part[k]);
        }
    }
    /* w = y^T adj(X) y (T-polynomial of degree nadj); off-diagonal terms twice */
    for (int k = 0; k <= nadj; k++) ws->w[k].n = -1;
    for (int a = 0; a < d; a++)
        for (int c = a; c < d; c++) {
            lf_mul(&ws->yy, &ws->y[a], &ws->y[c]);
            if (c != a) lf_times(&ws->yy, &ws->yy, 2.0);
            for (int k = 0; k <= nadj; k++) {
                if (ws->w[k].n < 0) lf_mul(&ws->w[k], &ws->adj[a][c][k], &ws->yy);
                else { lf_mul(&ws->tmp, &ws->adj[a][c][k], &ws->yy); lf_add(&ws->w[k], &ws->w[k], &ws->tmp); }
            }
        }
    tl_mul(ws, ws->zd, ws->z, 1, ws->detX, d);
    int deg = ws->zd[0].n, ok = 0;
    for (int l = 0; l < LANES; l++) P[l]->deg = deg;
    for (int l = 0; l < LANES; l++) ok |= 1 << l;
    for (int k = 0; k <= p0->n; k++) {
        if (k <= nadj) lf_sub(&ws->ak, &ws->zd[k], &ws->w[k]);
        else ws->ak = ws->zd[k];
        lf_elevate(&ws->ak, &ws->ak, deg);
        for (int l = 0; l < LANES; l++) {
            if (!lf_finite(&ws->ak, l)) { ok &= ~(1 << l); continue; }
            lf_bernstein(&P[l]->b[k], &ws->ak, l);
            for (int j = 0; j <= deg; j++) P[l]->c[k][j] = ws->ak.v[j][l];
        }
    }
    return ok;
}

/* ------------------------------------------------------------------ float helpers (search) */

/* sum_k c_k (1-t)^(n-k) t^k at t in [0, 1] in floats (predictions only): Horner in t / (1 - t)
 * (or (1 - t) / t beyond 1/2), the stable O(n) evaluation of a Bernstein-type form */
static double form_value(const double *c, int n, double t) {
    if (t <= 0.5) {
        double s = t / (1.0 - t), acc = c[n], w = 1.0 - t, pw = 1.0;
        for (int k = n - 1; k >= 0; k--) acc = acc * s + c[k];
        for (int k = 0; k < n; k++) pw *= w;
        return acc * pw;
    }
    double s = (1.0 - t) / t, acc = c[0], pw = 1.0;
    for (int k = 1; k <= n; k++) acc = acc * s + c[k];
    for (int k = 0; k < n; k++) pw *= t;
    return acc * pw;
}

static double pencil_value(const double *a, int n, double T) {
    double s = a[n];
    for (int k = n - 1; k >= 0; k--) s = s * T + a[k];
    return s;
}

/* argmax over T > 0 of sum a_k T^k (a_0, a_n < 0), a float estimate; 0 when nothing is found */
static double best_T(const double *a, int n, double guess, int wide) {
    if (!(guess > 0.0) || !isfinite(guess)) {
        guess = pow(fabs(a[0] / a[n]), 1.0 / n);
        if (!(guess > 0.0) || !isfinite(guess)) guess = 1.0;
        wide = 1;
    }
    int K = wide ? 96 : 24;
    double best = -INFINITY, Tb = guess;
    double T0 = guess * exp2(-0.25 * K);
    for (int k = -K; k <= K; k++, T0 *= 1.189207115002721) {  /* steps of 2^(1/4) */
        double v = pencil_value(a, n, T0);
        if (v > best) { best = v; Tb = T0; }
    }
    /* Newton on P'(T) = 0 inside [Tb 2^-1/4, Tb 2^1/4] */
    double lo = Tb * 0.8408964152537145, hi = Tb * 1.189207115002721, T = Tb;
    for (int it = 0; it < 12; it++) {
        double d1 = 0.0, d2 = 0.0;
        for (int k = n; k >= 1; k--) d1 = d1 * T + k * a[k];
        for (int k = n; k >= 2; k--) d2 = d2 * T + k * (k - 1) * a[k];
        if (!(d2 < 0.0)) break;
        double Tn = T - d1 / d2;
        if (!(Tn > lo && Tn < hi)) break;
        if (fabs(Tn - T) <= 1e-15 * T) { T = Tn; break; }
        T = Tn;
    }
    if (pencil_value(a, n, T) < best) T = Tb;
    if (!(T >= 0x1p-200 && T <= 0x1p+200)) return 0.0;
    return T;
}

/* f = sum_k T^k b_k (Bernstein forms): P(t, T) for the float T, whose powers are balls */
static void combine(const pair *p, double T, form *f) {
    int n = p->n, deg = p->deg;
    ball Tk[5];
    Tk[0] = bx(1.0);
    Tk[1] = bx(T);
    for (int k = 2; k <= n; k++) Tk[k] = bmul(Tk[k - 1], Tk[1]);
    f->n = deg;
    for (int j = 0; j <= deg; j++) {
        double s = 0.0, S = 0.0, R = 0.0;
        for (int k = 0; k <= n; k++) {
            double y = p->b[k].v[j], x = Tk[k].v * y;
            s += x;
            S += fabs(x);
            R += Tk[k].v * p->b[k].r[j] + Tk[k].r * (fabs(y) + p->b[k].r[j]);
        }
        f->v[j] = s;
        f->r[j] = R + COMBINE_U(n + 1) * S + COMBINE_ETA(n + 1);
    }
}

/* first t in (ta, 1] where the float sum_k T^k a_k(t) <= 0 (prediction only); 2 if none */
static double predict_root(const pair *p, double T, double ta) {
    int n = p->n, deg = p->deg;
    double c[MAXF] = {0}, Tk[5] = {1.0, T, T * T, T * T * T, T * T * T * T};
    for (int j = 0; j <= deg; j++) {
        double s = 0.0;
        for (int k = 0; k <= n; k++) s += Tk[k] * p->c[k][j];
        c[j] = s;
    }
    double span = 1.0 - ta, prev = ta;
    if (!(form_value(c, deg, ta) > 0.0)) return ta;
    for (int s = 0; s < 54; s++) {
        /* samples: 2^-44 .. 2^-2 of the span (geometric), then 1/4 + k/32 (uniform) */
        double u = s < 22 ? ldexp(1.0, -44 + 2 * s) : 0.25 + (s - 21) * (0.75 / 32);
        double t = ta + span * u;
        if (u > 1.0 || t > 1.0) t = 1.0;
        if (!(form_value(c, deg, t) > 0.0)) {
            double lo = prev, hi = t;
            for (int it = 0; it < 80 && hi - lo > 1e-3 * (lo - ta) && hi - lo > 1e-300; it++) {
                double mid = 0.5 * (lo + hi);
                if (form_value(c, deg, mid) > 0.0) lo = mid; else hi = mid;
            }
            return lo;
        }
        prev = t;
        if (t >= 1.0) break;
    }
    return 2.0;
}

/* a point of both bodies at time t, certified: 1 yes, 0 not found */
static int common_point(const pair *p, double t) {
    int d = p->d;
    ball QA[3][3], QB[3][3], NA2, NB2, dd[3];
    body_at(&p->A, t, QA, &NA2);
    body_at(&p->B, t, QB, &NB2);
    for (int a = 0; a < d; a++) dd[a] = p->moves ? blerp(p->d0[a], p->d1[a], t) : p->d0[a];
    /* float search: Perram-Wertheim, lambda where f_A(x) = f_B(x) along the minimisers x(lambda) */
    double A[3][3], B[3][3], c[3], x[3] = {0, 0, 0};
    for (int i = 0; i < d; i++) {
        c[i] = dd[i].v;
        for (int j = 0; j < d; j++) { A[i][j] = QA[i][j].v / NA2.v; B[i][j] = QB[i][j].v / NB2.v; }
    }
    double Bc[3];
    for (int i = 0; i < d; i++) { Bc[i] = 0; for (int j = 0; j < d; j++) Bc[i] += B[i][j] * c[j]; }
    /* h(lambda) = f_A(x) - f_B(x) decreases from d^T A d > 0 (lambda = 0) to -d^T B d < 0
     * (lambda = 1): regula falsi with the Illinois rule, then x at the root */
    double lo = 0.0, hi = 1.0, hlo = 0.0, hhi = 0.0, lam = 0.5;
    int side = 0;
    for (int it = 0; it < 40; it++) {
        if (it == 0) lam = 0.0;
        else if (it == 1) lam = 1.0;
        else if (hlo > 0.0 && hhi < 0.0) {
            lam = (lo * hhi - hi * hlo) / (hhi - hlo);
            if (!(lam > lo && lam < hi)) lam = 0.5 * (lo + hi);
        } else lam = 0.5 * (lo + hi);
        double M[3][3], rhs[3];
        for (int i = 0; i < d; i++) {
            rhs[i] = (1 - lam) * Bc[i];
            for (int j = 0; j < d; j++) M[i][j] = lam * A[i][j] + (1 - lam) * B[i][j];
        }
        double det;
        if (d == 2) {
            det = M[0][0] * M[1][1] - M[0][1] * M[1][0];
            x[0] = (rhs[0] * M[1][1] - M[0][1] * rhs[1]) / det;
            x[1] = (M[0][0] * rhs[1] - rhs[0] * M[1][0]) / det;
        } else {
            double c00 = M[1][1] * M[2][2] - M[1][2] * M[2][1], c01 = M[1][2] * M[2][0] - M[1][0] * M[2][2];
            double c02 = M[1][0] * M[2][1] - M[1][1] * M[2][0];
            det = M[0][0] * c00 + M[0][1] * c01 + M[0][2] * c02;
            double c10 = M[0][2] * M[2][1] - M[0][1] * M[2][2], c11 = M[0][0] * M[2][2] - M[0][2] * M[2][0];
            double c12 = M[0][1] * M[2][0] - M[0][0] * M[2][1];
            double c20 = M[0][1] * M[1][2] - M[0][2] * M[1][1], c21 = M[0][2] * M[1][0] - M[0][0] * M[1][2];
            double c22 = M[0][0] * M[1][1] - M[0][1] * M[1][0];
            x[0] = (c00 * rhs[0] + c10 * rhs[1] + c20 * rhs[2]) / det;
            x[1] = (c01 * rhs[0] + c11 * rhs[1] + c21 * rhs[2]) / det;
            x[2] = (c02 * rhs[0] + c12 * rhs[1] + c22 * rhs[2]) / det;
        }
        double fa = -1.0, fb = -1.0;
        for (int i = 0; i < d; i++)
            for (int j = 0; j < d; j++) {
                fa += A[i][j] * x[i] * x[j];
                fb += B[i][j] * (x[i] - c[i]) * (x[j] - c[j]);
            }
        if (!isfinite(fa) || !isfinite(fb)) return 0;
        double h = fa - fb;
        if (it >= 2 && (fabs(h) <= 1e-13 * (fabs(fa) + fabs(fb)) || hi - lo <= 1e-15)) break;
        if (h > 0.0) {
            lo = lam; hlo = h;
            if (side == 1 && it >= 2) hhi *= 0.5;  /* Illinois: the stale end is halved */
            side = 1;
        } else {
            hi = lam; hhi = h;
            if (side == -1 && it >= 2) hlo *= 0.5;
            side = -1;
        }
    }
    /* certify f_A(x) = x^T Q~_A x - N_A^2 < 0 and f_B(x) = (x - d)^T Q~_B (x - d) - N_B^2 < 0 */
    ball fa = (ball){-NA2.v, NA2.r}, fb = (ball){-NB2.v, NB2.r}, u[3];
    for (int i = 0; i < d; i++) u[i] = bsub(bx(x[i]), dd[i]);
    for (int i = 0; i < d; i++)
        for (int j = 0; j < d; j++) {
            fa = badd(fa, bmul(bmul(QA[i][j], bx(x[i])), bx(x[j])));
            fb = badd(fb, bmul(bmul(QB[i][j], u[i]), u[j]));
        }
    return bneg(fa) && bneg(fb);
}

/* separate on [ta, tb] with this T (f = combine(T) on [0, 1]): largest certified end in
 * {tb, ta + (tb - ta) / 2, ...} (> ta), or ta */
static double certify_prefix(const form *f, double ta, double tb) {
    form g, h;
    if (ta > 0.0) f_split(f, ta, NULL, &g);
    else g = *f;
    double span = 1.0 - ta;
    for (int k = 0; k < 40 && tb > ta; k++) {
        if (tb >= 1.0) {
            if (f_positive(&g)) return 1.0;
        } else {
            /* u >= (tb - ta) / (1 - ta) exactly: the piece [ta, ta + u (1 - ta)] covers [ta, tb].
             * Two subtractions and a division leave the quotient >= (1 - u)^2 / (1 + u) times the
             * exact one; each step up multiplies it by more than 1 + u (an ulp is more than u
             * times the value): CERTIFY_STEPS_UP = 4 is the fewest that make up for it. */
            double u = (tb - ta) / span;
            for (int up = 0; up < CERTIFY_STEPS_UP; up++) u = nextafter(u, 2.0);
            if (u >= 1.0) { if (f_positive(&g)) return tb; }
            else {
                f_split(&g, u, &h, NULL);
                if (f_positive(&h)) return tb;
            }
        }
        double nt = ta + 0.5 * (tb - ta);
        if (!(nt > ta) || nt >= tb) break;
        tb = nt;
    }
    return ta;
}

/* One pair after its forms are built: status and bracket (module docstring). */
static int8_t search_pair(pair *p, double *tlo, double *thi, int32_t *iters) {
    int n = p->n;
    double a[5], T;
    for (int k = 0; k <= n; k++) a[k] = p->b[k].v[0];
    T = best_T(a, n, 0.0, 1);
    if (T == 0.0) return UNDECIDED;
    form f;
    combine(p, T, &f);
    if (!(f.v[0] > f.r[0] * RF)) return UNDECIDED;   /* not certified separate at 0 */
    double ta = 0.0;
    int misses = 0, stalls = 0;
    for (int it = 0; it < MAXIT; it++) {
        *iters = it + 1;
        double tr = predict_root(p, T, ta);
        double tb = tr > 1.0 ? 1.0 : ta + (tr - ta) * STEP_MARGIN;
        double c = tb > ta ? certify_prefix(&f, ta, tb) : ta;
        if (c >= 1.0) return NEVER;
        if (c > ta) { ta = c; stalls = 0; }
        else if (++stalls >= 3) return UNDECIDED;
        if (tr <= 1.0 && tr - ta <= NEAR) {
            double th = fmin(ta + BRACKET, 1.0);
            if (common_point(p, th)) { *tlo = ta; *thi = th; return CONTACT; }
            if (++misses >= 3) return UNDECIDED;
        }
        for (int k = 0; k <= n; k++) a[k] = form_value(p->c[k], p->deg, ta);
        double Tn = best_T(a, n, T, 0);
        if (Tn == 0.0) return UNDECIDED;
        if (Tn != T) { T = Tn; combine(p, T, &f); }
    }
    return UNDECIDED;
}

/* Pairs wait in a queue per shape of their forms (which bodies rotate, whether they move) until
 * LANES of them can be built at once. */
typedef struct {
    pair pairs[8][LANES];
    int64_t index[8][LANES];
    int count[8];
    workspace ws;
} batch;

static void run_group(batch *bt, int key, int8_t *status, double *tlo, double *thi, int32_t *iters) {
    int count = bt->count[key];
    pair *P[LANES];
    for (int l = 0; l < LANES; l++) P[l] = &bt->pairs[key][l < count ? l : 0];  /* spare lanes repeat lane 0 */
    int ok = pencil_forms(&bt->ws, P);
    for (int l = 0; l < count; l++) {
        int64_t k = bt->index[key][l];
        status[k] = (ok >> l) & 1 ? search_pair(P[l], tlo + k, thi + k, iters + k) : UNDECIDED;
    }
    bt->count[key] = 0;
}

/* Batch entry point (called by _sweep_module.c without the GIL): pairs (pi[k], pj[k]) of the n
 * bodies' rows (stride doubles each: c0, c1, r, q0, q1), j moved by shift[k] (d floats, or NULL);
 * writes status, t_lo, t_hi, iterations. An index outside [0, n) makes its pair UNDECIDED (the
 * caller refuses them; this guards against arrays changed by another thread meanwhile). Returns 0,
 * or -1 when out of memory (nothing written). */
int32_t sweep_batch(int32_t d, const double *bodies, int64_t n, int64_t stride, const int64_t *pi, const int64_t *pj,
                    const double *shift, int64_t m, int8_t *status, double *tlo, double *thi, int32_t *iters) {
    batch *bt = malloc(sizeof(batch));
    if (!bt) return -1;
    memset(bt->count, 0, sizeof(bt->count));
    for (int64_t k = 0; k < m; k++) {
        tlo[k] = thi[k] = NAN;
        iters[k] = 0;
        pair p;
        const int64_t a = pi[k], b = pj[k];  /* read once */
        if (a < 0 || a >= n || b < 0 || b >= n ||
            !load_pair(&p, d, bodies + a * stride, bodies + b * stride, shift ? shift + k * d : NULL)) {
            status[k] = UNDECIDED;
            continue;
        }
        if (common_point(&p, 0.0)) {
            tlo[k] = thi[k] = 0.0;
            status[k] = OVERLAP_AT_START;
            continue;
        }
        int key = p.A.rotates + 2 * p.B.rotates + 4 * p.moves;
        bt->pairs[key][bt->count[key]] = p;
        bt->index[key][bt->count[key]] = k;
        if (++bt->count[key] == LANES) run_group(bt, key, status, tlo, thi, iters);
    }
    for (int key = 0; key < 8; key++)
        if (bt->count[key]) run_group(bt, key, status, tlo, thi, iters);
    free(bt);
    return 0;
}
