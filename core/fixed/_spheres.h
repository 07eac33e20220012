/* Certified bounding spheres of exactly symmetric bodies in floats: the proof of core/bodies/bounds.py.
 *
 * The C twin of core.bodies.bounds._exact_spheres, operation for operation (its numpy code is the
 * reference and the fallback; tests/test_index.py checks both against exact arithmetic): for a
 * body [[Q, m], [m^T, g0]] whose entries are exact (an exactly symmetric float matrix), any
 * float centre c and any 0 < lambda <= lambda_min(Q), the body lies in the ball of radius
 * rho = (|g| + sqrt(|g|^2 - lambda f0)) / lambda about c, g = Q c + m, f0 = f(c). lambda is a
 * float estimate shrunk by 1 - 2^-10 (then 1 - 2^-4, 0.5) and proven by Sylvester's minors of
 * Q - lambda I; g and f0 are carried in midpoint-radius arithmetic (every operation's rounding,
 * 2^-52 |result| + 2^-1074 for a product), and rho is rounded up by 1 + 2^-40 at each of its
 * few operations. The same certificate proves the body valid (Q > 0, f0 < 0).
 *
 * Scalar code, one body at a time: the index asks about one body per call (a Monte Carlo move),
 * where the numpy version costs ~100 array operations; batches are split over threads by the
 * caller (the GIL is released).
 */

#define SPH_U 0x1p-52                 /* _U: u / (1 - u) */
#define SPH_TINY 0x1p-1074            /* _TINY: a product's error in the subnormal range */
#define SPH_RF (1.0 + 0x1p-40)        /* _RADIUS_FACTOR */
#define SPH_UP (1.0 + 0x1p-40)        /* _UP */
#define SPH_PI 3.141592653589793      /* numpy.pi (M_PI is not in strict C99) */

/* Status of one body (spheres(): the status buffer). */
#define SPHERE_TIGHT 0 /* certified */
#define SPHERE_LOOSE 1 /* certified, more than 1 % above the radius of an exact centre and lambda_min */
#define SPHERE_NONE 2  /* no sphere here: the careful paths of bounds.py (or exact arithmetic) decide */
#define SPHERE_OTHER 3 /* not exactly symmetric, or M_00 == 0: bounds.py's general path */

typedef struct {
    double v, r; /* |exact - v| <= r; r < 0 marks an exact value (bounds.py: the radius 0.0 as a Python float) */
} ball;

static inline ball b_exact(double v) { return (ball){v, -1.0}; }

/* _radius_sum: one rounding plus the operands' radii (in that order) */
static inline ball b_add(ball a, ball b, double z) {
    double r = SPH_U * fabs(z);
    if (a.r >= 0.0) r += a.r;
    if (b.r >= 0.0) r += b.r;
    return (ball){z, r};
}
static inline ball b_plus(ball a, ball b) { return b_add(a, b, a.v + b.v); }
static inline ball b_minus(ball a, ball b) { return b_add(a, b, a.v - b.v); }

/* _Ball.__mul__ */
static inline ball b_mul(ball a, ball o) {
    const double z = a.v * o.v;
    if (a.r < 0.0 && o.r < 0.0) return (ball){z, SPH_U * fabs(z) + SPH_TINY};
    if (a.r < 0.0) { /* o * self */
        const ball t = a;
        a = o;
        o = t;
    }
    if (o.r < 0.0) return (ball){z, a.r * fabs(o.v) + (SPH_U * fabs(z) + SPH_TINY)};
    return (ball){z, fabs(a.v) * o.r + a.r * (fabs(o.v) + o.r) + (SPH_U * fabs(z) + SPH_TINY)};
}

/* _definite_minors: Q - lam I proven positive definite (w: the d x d block, row-major n x n) */
static int sph_definite(const double *w, int n, double lam) {
    const int d = n - 1;
    if (!(isfinite(lam) && lam > 0.0)) return 0;
    const ball L = b_exact(lam);
    ball P[3][3];
    for (int i = 0; i < d; i++)
        for (int j = 0; j < d; j++) {
            const ball q = b_exact(w[(i < j ? i : j) * n + (i < j ? j : i)]);
            P[i][j] = i == j ? b_minus(q, L) : q;
        }
    ball m[3];
    m[0] = P[0][0];
    m[1] = b_minus(b_mul(P[0][0], P[1][1]), b_mul(P[0][1], P[0][1]));
    if (d == 3)
        m[2] = b_plus(b_minus(b_mul(P[0][0], b_minus(b_mul(P[1][1], P[2][2]), b_mul(P[1][2], P[1][2]))),
                              b_mul(P[0][1], b_minus(b_mul(P[0][1], P[2][2]), b_mul(P[1][2], P[0][2])))),
                      b_mul(P[0][2], b_minus(b_mul(P[0][1], P[1][2]), b_mul(P[1][1], P[0][2]))));
    for (int k = 0; k < d; k++)
        if (!(m[k].v > (m[k].r < 0.0 ? 0.0 : m[k].r) * SPH_RF)) return 0;
    return 1;
}

/* One body: centre c[0..d), radius *rho and its status (the numpy of _exact_spheres, per column). */
static int sphere_one(const double *M, int n, double *c, double *rho) {
    const int d = n - 1;
    double w[16];
    int sym = 1, finite = 1;
    double mx = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            const double v = M[i * n + j];
            if (j > i) sym &= v == M[j * n + i];
            finite &= isfinite(v);
            mx = fabs(v) > mx || isnan(v) ? fabs(v) : mx; /* numpy's max propagates NaN */
        }
    for (int i = 0; i < d; i++) c[i] = NAN;
    *rho = NAN;
    if (!sym || M[0] == 0.0) return SPHERE_OTHER;
    if (!finite) return SPHERE_NONE;
    /* small bodies scaled up by a power of two (largest entry into [1, 2): exact), positive Q */
    int k = 0;
    if (mx > 0.0 && mx < 0x1p-8) {
        int e;
        frexp(mx, &e);
        k = 1 - e < 1000 ? 1 - e : 1000;
    }
    const double g1 = (M[0] < 0.0 ? -1.0 : 1.0) * ldexp(1.0, k);
    for (int i = 0; i < n * n; i++) w[i] = M[i] * g1;
#define W(i, j) w[((i) < (j) ? (i) : (j)) * n + ((i) < (j) ? (j) : (i))]
    /* the centre estimate (_centre_columns) and lambda_min's (_lambda_columns) */
    double lam_est;
    if (d == 2) {
        const double det = W(0, 0) * W(1, 1) - W(0, 1) * W(0, 1);
        const double m0 = W(0, 2), m1 = W(1, 2);
        c[0] = -(W(1, 1) * m0 - W(0, 1) * m1) / det;
        c[1] = -(-W(0, 1) * m0 + W(0, 0) * m1) / det;
        lam_est = (W(0, 0) + W(1, 1)) / 2 - hypot((W(0, 0) - W(1, 1)) / 2, W(0, 1));
    } else {
        const double a00 = W(1, 1) * W(2, 2) - W(1, 2) * W(1, 2);
        const double a01 = W(0, 2) * W(1, 2) - W(0, 1) * W(2, 2);
        const double a02 = W(0, 1) * W(1, 2) - W(0, 2) * W(1, 1);
        const double a11 = W(0, 0) * W(2, 2) - W(0, 2) * W(0, 2);
        const double a12 = W(0, 1) * W(0, 2) - W(0, 0) * W(1, 2);
        const double a22 = W(0, 0) * W(1, 1) - W(0, 1) * W(0, 1);
        const double det = W(0, 0) * a00 + W(0, 1) * a01 + W(0, 2) * a02;
        const double m0 = W(0, 3), m1 = W(1, 3), m2 = W(2, 3);
        c[0] = -(a00 * m0 + a01 * m1 + a02 * m2) / det;
        c[1] = -(a01 * m0 + a11 * m1 + a12 * m2) / det;
        c[2] = -(a02 * m0 + a12 * m1 + a22 * m2) / det;
        const double q = (W(0, 0) + W(1, 1) + W(2, 2)) / 3;
        const double b00 = W(0, 0) - q, b11 = W(1, 1) - q, b22 = W(2, 2) - q;
        const double b01 = W(0, 1), b02 = W(0, 2), b12 = W(1, 2);
        const double p = sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2 * (b01 * b01 + b02 * b02 + b12 * b12)) / 6);
        const double safe = p > 0 ? p : 1.0;
        const double bdet = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02);
        double half = bdet / (safe * safe * safe) / 2;
        half = half < -1.0 ? -1.0 : (half > 1.0 ? 1.0 : half);
        lam_est = p > 0 ? q + 2 * p * cos(acos(half) / 3 + 2 * SPH_PI / 3) : q;
    }
    int ok = isfinite(lam_est) && lam_est > 0;
    for (int i = 0; i < d; i++) ok &= isfinite(c[i]);
    if (!ok) {
        for (int i = 0; i < d; i++) c[i] = 0.0;
        return SPHERE_NONE;
    }
    /* _proven_lambda */
    static const double shrink[3] = {1.0 - 0x1p-10, 1.0 - 0x1p-4, 0.5};
    double lam = NAN;
    for (int f = 0; f < 3 && !(lam == lam); f++) {
        const double trial = lam_est * shrink[f];
        if (sph_definite(w, n, trial)) lam = trial;
    }
    if (!(isfinite(lam) && lam > 0.0)) return SPHERE_NONE;
    /* g = Q c + m and f0 = m_dd + sum c_i (g_i + m_i), certified */
    ball g[3];
    for (int i = 0; i < d; i++) {
        ball acc = b_exact(W(i, d));
        for (int j = 0; j < d; j++) acc = b_plus(acc, b_mul(b_exact(W(i, j)), b_exact(c[j])));
        g[i] = acc;
    }
    ball f0 = b_exact(W(d, d));
    for (int i = 0; i < d; i++) f0 = b_plus(f0, b_mul(b_exact(c[i]), b_plus(g[i], b_exact(W(i, d)))));
#undef W
    /* _radius */
    const double f0r = (f0.r < 0.0 ? 0.0 : f0.r) * SPH_RF;
    if (!(f0.v + f0r < 0)) return SPHERE_NONE;
    double G2 = 0.0;
    for (int i = 0; i < d; i++) {
        const double t = fabs(g[i].v) + (g[i].r < 0.0 ? 0.0 : g[i].r) * SPH_RF;
        G2 = i ? G2 + t * t : t * t;
    }
    G2 = G2 * SPH_UP;
    const double F = (-f0.v + f0r) * SPH_UP;
    const double r = (sqrt(G2) * SPH_UP + sqrt((G2 + lam * F) * SPH_UP) * SPH_UP) / lam * SPH_UP;
    if (!isfinite(r)) return SPHERE_NONE;
    *rho = r;
    return r > 1.01 * sqrt(F / lam_est) ? SPHERE_LOOSE : SPHERE_TIGHT;
}
