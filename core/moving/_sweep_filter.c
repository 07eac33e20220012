/* Certified float filter for the first contact of two ellipsoids (ellipses) in linear motion.
 *
 * Hand-written C, read by core/moving/sweep_filter.py (the proofs are there and here), compiled
 * once per machine by core/fixed/compiled.py with the project's flags: no -ffast-math, no
 * contraction into FMA: every operation rounds once, to nearest, as the bounds assume.
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
 * Radii: each operation's rounding (<= U |result|, U = 2^-52 >= u / (1 - u)) and underflow
 * (<= 2^-1075 per product; ETA = 2^-1022 per product is added, generously: a normal number,
 * so no operation ever runs on subnormals, which are slow) is added; the radius formulas are
 * themselves evaluated in floats on non-negative terms, so each computed radius is at least
 * (1 - u)^k times its formula's value after k dependent operations (a product's underflow
 * loss is covered by the ETAs added): comparisons use radius * RF, RF = 1 + 2^-30, which
 * covers k < 2^22, far more than any chain here.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#define U 2.220446049250313e-16          /* 2^-52 */
#define ETA 0x1p-1022                    /* 2^-1022 >= any underflow loss (2^-1075); normal, so never slow */
#define RF (1.0 + 9.313225746154785e-10) /* 1 + 2^-30 */
#define MAXF 20                          /* coefficients per form: degree <= 19 (3D: 18) */
#define MAXIT 100                        /* advancement steps before the filter abstains */
#define STEP_MARGIN 0.99609375           /* target 1 - 2^-8 of the way to the predicted root */
#define NEAR 5e-10                       /* predicted root this close: test a point of both */
#define BRACKET 9.5e-10                  /* t_h - t_a (< 1e-9 with the rounding of t_a + 9.5e-10) */
#define IN_RANGE(x) (fabs(x) <= 1.0 && (fabs(x) >= 0x1p-100 || (x) == 0.0))

enum { NEVER = 0, CONTACT = 1, OVERLAP_AT_START = 2, UNDECIDED = -1 };

typedef struct { double v, r; } ball;
typedef struct { int n; double v[MAXF]; double r[MAXF]; } form;

/* ---------------------------------------------------------------- balls (midpoint, radius) */

static inline ball bx(double x) { ball o = {x, 0.0}; return o; }
static inline ball badd(ball x, ball y) { double z = x.v + y.v; ball o = {z, x.r + y.r + U * fabs(z) + ETA}; return o; }
static inline ball bsub(ball x, ball y) { double z = x.v - y.v; ball o = {z, x.r + y.r + U * fabs(z) + ETA}; return o; }
static inline ball bmul(ball x, ball y) {
    double z = x.v * y.v;
    ball o = {z, fabs(x.v) * y.r + x.r * (fabs(y.v) + y.r) + U * fabs(z) + 5 * ETA};
    return o;
}
/* (1 - t) x0 + t x1 for a float t in [0, 1]: 1 - t is exact for t >= 1/2, else within u (1 - t) */
static inline ball blerp(ball x0, ball x1, double t) {
    double al = 1.0 - t;
    double z = al * x0.v + t * x1.v;
    double mag = al * (fabs(x0.v) + x0.r) + t * fabs(x1.v);
    ball o = {z, al * x0.r + t * x1.r + 4 * U * mag + 4 * U * fabs(z) + 6 * ETA};
    return o;
}
static inline int bneg(ball x) { return isfinite(x.v) && isfinite(x.r) && x.v < -x.r * RF; }

/* ------------------------------------------------------------ forms in (1 - t, t), with radii */

static void f_const(form *f, ball b) { f->n = 0; f->v[0] = b.v; f->r[0] = b.r; }
static void f_line(form *f, ball b0, ball b1) { f->n = 1; f->v[0] = b0.v; f->r[0] = b0.r; f->v[1] = b1.v; f->r[1] = b1.r; }

/* z = a * (1 - t + t)^(n - a.n): the same polynomial as a form of degree n (z may be a) */
static void f_elevate(form *z, const form *a, int n) {
    int m = a->n;
    double v[MAXF], r[MAXF];
    for (int k = 0; k <= m; k++) { v[k] = a->v[k]; r[k] = a->r[k]; }
    for (; m < n; m++) {  /* degree m -> m + 1, in place from the top */
        v[m + 1] = v[m];
        r[m + 1] = r[m];
        for (int k = m; k >= 1; k--) {
            double x = v[k] + v[k - 1];
            v[k] = x;
            r[k] = r[k] + r[k - 1] + U * fabs(x) + ETA;
        }
    }
    z->n = n > a->n ? n : a->n;
    for (int k = 0; k <= z->n; k++) { z->v[k] = v[k]; z->r[k] = r[k]; }
}

/* z = a + sa * b with sa = +1 or -1 (degrees raised to the larger; z may be a or b) */
static void f_addsub(form *z, const form *a, const form *b, double sa) {
    form x;
    if (a->n < b->n) { f_elevate(&x, a, b->n); a = &x; }
    else if (b->n < a->n) { f_elevate(&x, b, a->n); b = &x; }
    int n = a->n;
    for (int k = 0; k <= n; k++) {
        double s = a->v[k] + sa * b->v[k];
        double rr = a->r[k] + b->r[k] + U * fabs(s) + ETA;
        z->v[k] = s;
        z->r[k] = rr;
    }
    z->n = n;
}
static void f_add(form *z, const form *a, const form *b) { f_addsub(z, a, b, 1.0); }
static void f_sub(form *z, const form *a, const form *b) { f_addsub(z, a, b, -1.0); }

/* z = c * a for an exact c in {-2, -1, 2} (no rounding beyond overflow) */
static void f_times(form *z, const form *a, double c) {
    z->n = a->n;
    for (int k = 0; k <= a->n; k++) { z->v[k] = c * a->v[k]; z->r[k] = fabs(c) * a->r[k] + ETA; }
}

/* z = a * b (ball b): each coefficient times a ball */
static void f_scale(form *z, const form *a, ball b) {
    z->n = a->n;
    for (int k = 0; k <= a->n; k++) {
        ball o = bmul((ball){a->v[k], a->r[k]}, b);
        z->v[k] = o.v; z->r[k] = o.r;
    }
}

/* z = a * b: convolution. Coefficient k is a sum of m products, accumulated in order of i: it
 * rounds by <= m U sum|a_i b_j| (plus underflow, <= ETA per product); the inputs' radii add
 * sum |a_i| rb_j + ra_i (|b_j| + rb_j). */
static void f_mul(form *z, const form *a, const form *b) {
    int na = a->n, nb = b->n, n = na + nb;
    double av[MAXF], aa[MAXF], ar[MAXF], bv[MAXF], ab[MAXF], br[MAXF], bb[MAXF], v[MAXF], r[MAXF];
    for (int i = 0; i <= na; i++) { av[i] = a->v[i]; aa[i] = fabs(av[i]); ar[i] = a->r[i]; }
    for (int j = 0; j <= nb; j++) { bv[j] = b->v[j]; ab[j] = fabs(bv[j]); br[j] = b->r[j]; bb[j] = ab[j] + br[j]; }
    for (int k = 0; k <= n; k++) {
        int lo = k > nb ? k - nb : 0, hi = k < na ? k : na;
        double s = 0.0, S = 0.0, R = 0.0;
        for (int i = lo; i <= hi; i++) {
            int j = k - i;
            s += av[i] * bv[j];
            S += aa[i] * ab[j];
            R += aa[i] * br[j] + ar[i] * bb[j];
        }
        int m = hi - lo + 1;
        v[k] = s;
        r[k] = R + m * U * S + (8 * m + 2) * ETA;
    }
    z->n = n;
    for (int k = 0; k <= n; k++) { z->v[k] = v[k]; z->r[k] = r[k]; }
}

/* Bernstein coefficients on [0, 1]: b_k = c_k / C(n, k) (C exact: n <= 19) */
static void f_bernstein(form *z, const form *a) {
    double C = 1.0;
    z->n = a->n;
    for (int k = 0; k <= a->n; k++) {
        double x = a->v[k] / C;
        z->v[k] = x;
        z->r[k] = a->r[k] / C + U * fabs(x) + ETA;
        C = C * (a->n - k) / (k + 1);
    }
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
            r[i] = al * r[i] + tau * r[i + 1] + 4 * U * mag + 6 * ETA;
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

static int f_finite(const form *b) {
    for (int k = 0; k <= b->n; k++)
        if (!(isfinite(b->v[k]) && isfinite(b->r[k]) && fabs(b->v[k]) < 0x1p+900 && b->r[k] < 0x1p+900)) return 0;
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
        double s2 = s * s, D = 1.0 / s2;    /* two roundings: |D - 1/s^2| <= 3 U D */
        b->D[a].v = D;
        b->D[a].r = 3 * U * D;
    }
    return 1;
}

/* rotation numerator R~(q) (d x d forms) and N = |q|^2, for a quaternion/half-angle form q */
static void rotation_forms(const form *q, int d, form R[3][3], form *N) {
    if (d == 2) {
        form ww, ss, ws;
        f_mul(&ww, &q[0], &q[0]); f_mul(&ss, &q[1], &q[1]); f_mul(&ws, &q[0], &q[1]);
        f_sub(&R[0][0], &ww, &ss); R[1][1] = R[0][0];
        f_times(&R[1][0], &ws, 2.0); f_times(&R[0][1], &ws, -2.0);
        f_add(N, &ww, &ss);
        return;
    }
    form ww, xx, yy, zz, xy, wz, xz, wy, yz, wx, t1, t2;
    f_mul(&ww, &q[0], &q[0]); f_mul(&xx, &q[1], &q[1]); f_mul(&yy, &q[2], &q[2]); f_mul(&zz, &q[3], &q[3]);
    f_mul(&xy, &q[1], &q[2]); f_mul(&wz, &q[0], &q[3]); f_mul(&xz, &q[1], &q[3]);
    f_mul(&wy, &q[0], &q[2]); f_mul(&yz, &q[2], &q[3]); f_mul(&wx, &q[0], &q[1]);
    /* R00 = w2 + x2 - y2 - z2, R11 = w2 - x2 + y2 - z2, R22 = w2 - x2 - y2 + z2 */
    f_add(&t1, &ww, &xx); f_add(&t2, &yy, &zz); f_sub(&R[0][0], &t1, &t2);
    f_sub(&t1, &ww, &xx); f_sub(&t2, &yy, &zz); f_add(&R[1][1], &t1, &t2);
    f_sub(&t1, &ww, &xx); f_sub(&t2, &zz, &yy); f_add(&R[2][2], &t1, &t2);
    f_sub(&t1, &xy, &wz); f_times(&R[0][1], &t1, 2.0);
    f_add(&t1, &xz, &wy); f_times(&R[0][2], &t1, 2.0);
    f_add(&t1, &xy, &wz); f_times(&R[1][0], &t1, 2.0);
    f_sub(&t1, &yz, &wx); f_times(&R[1][2], &t1, 2.0);
    f_sub(&t1, &xz, &wy); f_times(&R[2][0], &t1, 2.0);
    f_add(&t1, &yz, &wx); f_times(&R[2][1], &t1, 2.0);
    f_add(&t1, &ww, &xx); f_add(&t2, &yy, &zz); f_add(N, &t1, &t2);
}

/* Q~ = R~ D R~^T (upper triangle, forms) and N^2, for one body over [0, 1] */
static void body_forms(const body *b, form Q[3][3], form *N2) {
    int d = b->d;
    form q[4], R[3][3], N, RD[3][3];
    for (int c = 0; c < b->nq; c++) {
        if (b->rotates) f_line(&q[c], bx(b->q0[c]), bx(b->q1[c]));
        else f_const(&q[c], bx(b->q0[c]));
    }
    rotation_forms(q, d, R, &N);
    for (int i = 0; i < d; i++)
        for (int k = 0; k < d; k++) f_scale(&RD[i][k], &R[i][k], b->D[k]);
    for (int i = 0; i < d; i++)
        for (int j = i; j < d; j++) {
            form acc, p;
            f_mul(&acc, &RD[i][0], &R[j][0]);
            for (int k = 1; k < d; k++) { f_mul(&p, &RD[i][k], &R[j][k]); f_add(&acc, &acc, &p); }
            Q[i][j] = acc;
            Q[j][i] = acc;
        }
    f_mul(N2, &N, &N);
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
        ball s = bx(shift ? shift[a] : 0.0);
        ball x0 = bsub(badd(bx(rb[a]), s), bx(ra[a]));
        ball x1 = bsub(badd(bx(rb[d + a]), s), bx(ra[d + a]));
        p->d0[a] = (ball){x0.v * inv, x0.r * inv + ETA};
        p->d1[a] = (ball){x1.v * inv, x1.r * inv + ETA};
        if (!(fabs(p->d0[a].v) <= 0x1p+60 && fabs(p->d1[a].v) <= 0x1p+60)) return 0;
        if (rb[a] != rb[d + a] || ra[a] != ra[d + a]) p->moves = 1;
    }
    return 1;
}

/* T-polynomials of forms: P[k] is the coefficient of T^k */
static void tl_mul(form *out, const form *x, int nx, const form *y, int ny) {
    form tmp;
    for (int k = 0; k <= nx + ny; k++) out[k].n = -1;
    for (int i = 0; i <= nx; i++)
        for (int j = 0; j <= ny; j++) {
            f_mul(&tmp, &x[i], &y[j]);
            if (out[i + j].n < 0) out[i + j] = tmp;
            else f_add(&out[i + j], &out[i + j], &tmp);
        }
}

/* a_i(t), i = 0..n, as Bernstein forms on [0, 1] (module docstring) */
static int pencil_forms(pair *p) {
    int d = p->d;
    form QA[3][3], QB[3][3], NA2, NB2, dd[3];
    body_forms(&p->A, QA, &NA2);
    body_forms(&p->B, QB, &NB2);
    for (int a = 0; a < d; a++) {
        if (p->moves) f_line(&dd[a], p->d0[a], p->d1[a]);
        else f_const(&dd[a], p->d0[a]);
    }
    int E = QA[0][0].n > QB[0][0].n ? QA[0][0].n : QB[0][0].n, g = p->moves;
    /* X = T Q~_A + Q~_B (T-linear), y = -Q~_B d, z = T (-N_A^2) + (d^T Q~_B d - N_B^2) */
    form X[3][3][2], y[3], z[2], tmp;
    for (int i = 0; i < d; i++)
        for (int j = 0; j < d; j++) {
            f_elevate(&X[i][j][0], &QB[i][j], E);
            f_elevate(&X[i][j][1], &QA[i][j], E);
        }
    form dQd;
    for (int i = 0; i < d; i++) {
        form acc;
        f_mul(&acc, &QB[i][0], &dd[0]);
        for (int j = 1; j < d; j++) { f_mul(&tmp, &QB[i][j], &dd[j]); f_add(&acc, &acc, &tmp); }
        f_times(&y[i], &acc, -1.0);
        if (i == 0) f_mul(&dQd, &acc, &dd[0]);
        else { f_mul(&tmp, &acc, &dd[i]); f_add(&dQd, &dQd, &tmp); }
        f_elevate(&y[i], &y[i], E + g);
    }
    f_sub(&z[0], &dQd, &NB2);
    f_elevate(&z[0], &z[0], E + 2 * g);
    f_times(&z[1], &NA2, -1.0);
    f_elevate(&z[1], &z[1], E + 2 * g);
    form adj[3][3][3], detX[4], w[3], zd[5];
    int nadj;
    if (d == 2) {
        nadj = 1;
        for (int k = 0; k < 2; k++) {
            adj[0][0][k] = X[1][1][k];
            adj[1][1][k] = X[0][0][k];
            f_times(&adj[0][1][k], &X[0][1][k], -1.0);
        }
        form m1[3], m2[3];
        tl_mul(m1, X[0][0], 1, X[1][1], 1);
        tl_mul(m2, X[0][1], 1, X[0][1], 1);
        for (int k = 0; k <= 2; k++) f_sub(&detX[k], &m1[k], &m2[k]);
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
        for (int s = 0; s < 6; s++) {
            const int *c = spec[s];
            form m1[3], m2[3];
            tl_mul(m1, X[c[2]][c[3]], 1, X[c[4]][c[5]], 1);
            tl_mul(m2, X[c[6]][c[7]], 1, X[c[8]][c[9]], 1);
            for (int k = 0; k <= 2; k++) {
                f_sub(&adj[c[0]][c[1]][k], &m1[k], &m2[k]);
                adj[c[1]][c[0]][k] = adj[c[0]][c[1]][k];
            }
        }
        form part[4];
        tl_mul(detX, X[0][0], 1, adj[0][0], 2);
        for (int j = 1; j < 3; j++) {
            tl_mul(part, X[0][j], 1, adj[j][0], 2);
            for (int k = 0; k <= 3; k++) f_add(&detX[k], &detX[k], &part[k]);
        }
    }
    /* w = y^T adj(X) y (T-polynomial of degree nadj) */
    for (int k = 0; k <= nadj; k++) w[k].n = -1;
    for (int a = 0; a < d; a++)
        for (int c = a; c < d; c++) {
            form yy;
            f_mul(&yy, &y[a], &y[c]);
            if (c != a) f_times(&yy, &yy, 2.0);
            for (int k = 0; k <= nadj; k++) {
                f_mul(&tmp, &adj[a][c][k], &yy);
                if (w[k].n < 0) w[k] = tmp;
                else f_add(&w[k], &w[k], &tmp);
            }
        }
    tl_mul(zd, z, 1, detX, d);
    p->deg = zd[0].n;
    for (int k = 0; k <= p->n; k++) {
        form ak;
        if (k <= nadj) f_sub(&ak, &zd[k], &w[k]);
        else ak = zd[k];
        f_elevate(&ak, &ak, p->deg);
        if (!f_finite(&ak)) return 0;
        f_bernstein(&p->b[k], &ak);
        for (int j = 0; j <= ak.n; j++) p->c[k][j] = ak.v[j];
    }
    return 1;
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
        f->r[j] = R + (n + 1) * U * S + (4 * n + 8) * ETA;
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
             * Two subtractions and a division leave the quotient >= (1 - 3u) times the exact one;
             * four steps up add at least 4u of it (an ulp is at least u times the value). */
            double u = (tb - ta) / span;
            for (int up = 0; up < 4; up++) u = nextafter(u, 2.0);
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

/* One pair: status and bracket (module docstring). */
static int8_t first_contact_pair(int d, const double *ra, const double *rb, const double *shift, double *tlo, double *thi, int32_t *iters) {
    pair p;
    *tlo = *thi = NAN;
    *iters = 0;
    if (!load_pair(&p, d, ra, rb, shift)) return UNDECIDED;
    if (common_point(&p, 0.0)) { *tlo = *thi = 0.0; return OVERLAP_AT_START; }
    if (!pencil_forms(&p)) return UNDECIDED;
    int n = p.n;
    double a[5], T;
    for (int k = 0; k <= n; k++) a[k] = p.b[k].v[0];
    T = best_T(a, n, 0.0, 1);
    if (T == 0.0) return UNDECIDED;
    form f;
    combine(&p, T, &f);
    if (!(f.v[0] > f.r[0] * RF)) return UNDECIDED;   /* not certified separate at 0 */
    double ta = 0.0;
    int misses = 0, stalls = 0;
    for (int it = 0; it < MAXIT; it++) {
        *iters = it + 1;
        double tr = predict_root(&p, T, ta);
        double tb = tr > 1.0 ? 1.0 : ta + (tr - ta) * STEP_MARGIN;
        double c = tb > ta ? certify_prefix(&f, ta, tb) : ta;
        if (c >= 1.0) return NEVER;
        if (c > ta) { ta = c; stalls = 0; }
        else if (++stalls >= 3) return UNDECIDED;
        if (tr <= 1.0 && tr - ta <= NEAR) {
            double th = fmin(ta + BRACKET, 1.0);
            if (common_point(&p, th)) { *tlo = ta; *thi = th; return CONTACT; }
            if (++misses >= 3) return UNDECIDED;
        }
        for (int k = 0; k <= n; k++) a[k] = form_value(p.c[k], p.deg, ta);
        double Tn = best_T(a, n, T, 0);
        if (Tn == 0.0) return UNDECIDED;
        if (Tn != T) { T = Tn; combine(&p, T, &f); }
    }
    return UNDECIDED;
}

/* Batch entry point: pairs (pi[k], pj[k]) of the bodies' rows (stride doubles each: c0, c1, r,
 * q0, q1), j moved by shift[k] (d floats, or NULL); writes status, t_lo, t_hi, iterations. */
void sweep_pairs(int32_t d, const double *bodies, int64_t stride, const int64_t *pi, const int64_t *pj,
                 const double *shift, int64_t m, int8_t *status, double *tlo, double *thi, int32_t *iters) {
    for (int64_t k = 0; k < m; k++) {
        status[k] = first_contact_pair(d, bodies + pi[k] * stride, bodies + pj[k] * stride,
                                       shift ? shift + k * d : NULL, tlo + k, thi + k, iters + k);
    }
}
