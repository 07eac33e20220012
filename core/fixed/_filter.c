/* core.fixed._filter: the compiled float filter as a Python extension (built by setup.py).
 *
 * The kernels (_kernels.h, generated from core/fixed/driver.py) are compiled three times in one
 * build, for baseline x86-64 (SSE2), AVX2 and AVX-512 (_filter_<variant>.c, chosen by target
 * pragmas), and the best variant this CPU supports is chosen when the module is imported; on
 * other architectures the portable baseline alone is built. ELLIPSOID_SIMD=baseline|avx2|avx512
 * asks for a lower variant (tests compare them). No compiler, cache or thread is needed at run
 * time.
 *
 * classify(n, a, b, out[, table]): a, b C-contiguous float64 or float32 buffers of count * n * n
 * values, out a writable int8 buffer of count rule ids (-1 undecided), or of table[rule id read
 * as a byte] when a 256-byte table is given (the relation codes, written as the block is
 * finished); returns how many pairs are undecided. The GIL is released while the kernels run,
 * so core/fixed/compiled.py splits large batches over threads.
 *
 * balance(n, a, b, a_out, b_out, e_out[, shift, shift_out]): the second stage's change of units
 * (core/fixed/filters.py: _balanced, whose numpy code is the twin of this loop, bit for bit): each
 * pair of float64 matrices with space scaled by 2^e, e from the bodies' sizes, where that is
 * exact; returns how many pairs moved (e != 0 in e_out).
 *
 * spheres(n, m, centres_out, radii_out, status_out): certified bounding spheres of count bodies
 * (m: count n x n float64 matrices; _spheres.h, the float proof of core/bodies/bounds.py), the
 * status of each (0 tight, 1 loose, 2 none, 3 not exactly symmetric); returns how many have a
 * sphere.
 *
 * query_one(geometry_i, geometry_d, table, cr, frac, Q, B, rel, out, kout, codes, exclude): one new
 * body B asked of a BodyIndex (_near.h): its certified sphere (_spheres.h), its cell, the indexed bodies whose spheres meet its own, sorted (ids to out, their
 * lattice images to kout in a box), and with Q (the indexed matrices; empty: none) the relations
 * of the pairs without an image through the filter (codes[i] = rel[rule]; NEAR_MOVED for a pair
 * with an image, left to the caller), keeping only the pairs that are not separate (and those
 * left to the caller), their certifiers to by (1: the filter, 0: left). geometry_i: int64 (d, cap, periodic, tilted, n[3],
 * stride[3]); geometry_d: float64 (L[3], H[9], origin[3], cell[3], big, span, limit, pad,
 * cell_error, far, eps_max, gamma, tiny), packed by the index. Returns (candidates, kept, left):
 * the pairs whose spheres meet, the pairs written, and of those the ones left to the caller (all
 * of them without Q); or (a negative code, 0, 0): QUERY_GENERAL, NEAR_TOO_FAR, NEAR_FAR_BOX,
 * QUERY_SPACE - needed.
 *
 * query_many(geometry_i, geometry_d, table, cr, frac, Q, B, rel, spheres, exclude, qout, out, kout,
 * codes, by, start): query_one for each new body k >= start of B (M of them) with its certified
 * sphere given (spheres: (M, d + 1) centre and radius, NaN radius: none, skipped) and its own
 * excluded body, the pairs appended in order (qout: the new body of each); stops where the
 * outputs are full. Returns (bodies done, candidates, kept, left, status), status 0 or the code
 * that stopped it at body `bodies done` (QUERY_SPACE - needed: room for that body).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef int64_t (*kernel64)(const double *, const double *, signed char *, int64_t, const signed char *);
typedef int64_t (*kernel32)(const float *, const float *, signed char *, int64_t, const signed char *);

#define DECLARE(v)                                                              \
    int64_t classify3_f64_##v(const double *, const double *, signed char *, int64_t, const signed char *); \
    int64_t classify3_f32_##v(const float *, const float *, signed char *, int64_t, const signed char *);   \
    int64_t classify4_f64_##v(const double *, const double *, signed char *, int64_t, const signed char *); \
    int64_t classify4_f32_##v(const float *, const float *, signed char *, int64_t, const signed char *);
DECLARE(baseline)
/* BASELINE_ONLY: a developer build of the baseline alone (setup.py, ELLIPSOID_BUILD_VARIANTS=baseline) */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(BASELINE_ONLY)
#define HAVE_X86_VARIANTS 1
DECLARE(avx2)
DECLARE(avx512)
#endif

typedef struct {
    const char *name;
    kernel64 f64[2]; /* n = 3, 4 */
    kernel32 f32[2];
} variant;

#define VARIANT_ENTRY(v) {#v, {classify3_f64_##v, classify4_f64_##v}, {classify3_f32_##v, classify4_f32_##v}}
static const variant VARIANTS[] = {
    VARIANT_ENTRY(baseline),
#ifdef HAVE_X86_VARIANTS
    VARIANT_ENTRY(avx2),
    VARIANT_ENTRY(avx512),
#endif
};
static const variant *current = &VARIANTS[0];

/* Whether this CPU (and its OS: the compiler's checks include the saved register state) runs a variant. */
static int supported(const char *name) {
    if (strcmp(name, "baseline") == 0) return 1;
#ifdef HAVE_X86_VARIANTS
    __builtin_cpu_init();
    if (strcmp(name, "avx2") == 0) return __builtin_cpu_supports("avx2");
    if (strcmp(name, "avx512") == 0)
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl") &&
               __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512cd");
#endif
    return 0;
}

static PyObject *select_variant(PyObject *self, PyObject *args) {
    const char *name;
    if (!PyArg_ParseTuple(args, "s", &name)) return NULL;
    for (size_t i = 0; i < sizeof(VARIANTS) / sizeof(VARIANTS[0]); i++)
        if (strcmp(VARIANTS[i].name, name) == 0) {
            if (!supported(name)) return PyErr_Format(PyExc_ValueError, "this CPU cannot run the %s variant", name);
            current = &VARIANTS[i];
            Py_RETURN_NONE;
        }
    return PyErr_Format(PyExc_ValueError, "unknown SIMD variant %s (this build has: %s)", name, VARIANTS[sizeof(VARIANTS) / sizeof(VARIANTS[0]) - 1].name);
}

static PyObject *get_variant(PyObject *self, PyObject *noargs) { return PyUnicode_FromString(current->name); }

static PyObject *get_variants(PyObject *self, PyObject *noargs) {
    PyObject *out = PyList_New(0);
    if (!out) return NULL;
    for (size_t i = 0; i < sizeof(VARIANTS) / sizeof(VARIANTS[0]); i++)
        if (supported(VARIANTS[i].name)) {
            PyObject *s = PyUnicode_FromString(VARIANTS[i].name);
            if (!s || PyList_Append(out, s) < 0) {
                Py_XDECREF(s);
                Py_DECREF(out);
                return NULL;
            }
            Py_DECREF(s);
        }
    return out;
}

static PyObject *classify(PyObject *self, PyObject *args) {
    int n;
    Py_buffer a, b, out, table = {0};
    if (!PyArg_ParseTuple(args, "iy*y*w*|y*", &n, &a, &b, &out, &table)) return NULL;
    PyObject *result = NULL;
    const Py_ssize_t count = out.len;
    const char *fa = a.format ? a.format : "B", *fb = b.format ? b.format : "B";
    if (n != 3 && n != 4) {
        PyErr_Format(PyExc_ValueError, "n must be 3 or 4, got %d", n);
    } else if (a.itemsize != b.itemsize || (a.itemsize != 8 && a.itemsize != 4)) {
        PyErr_SetString(PyExc_TypeError, "a and b must both be float64 or both float32");
    } else if (a.len != count * n * n * a.itemsize || b.len != a.len) {
        PyErr_Format(PyExc_ValueError, "a and b must hold %zd pairs of %dx%d matrices", count, n, n);
    } else if (table.obj && table.len != 256) {
        PyErr_Format(PyExc_ValueError, "table must hold 256 bytes, got %zd", table.len);
    } else if (!PyBuffer_IsContiguous(&a, 'C') || !PyBuffer_IsContiguous(&b, 'C') || !PyBuffer_IsContiguous(&out, 'C')) {
        PyErr_SetString(PyExc_ValueError, "buffers must be C-contiguous");
    } else {
        (void)fa;
        (void)fb;
        const variant *v = current;
        const signed char *tab = table.obj ? (const signed char *)table.buf : NULL;
        int64_t undecided;
        Py_BEGIN_ALLOW_THREADS
        if (a.itemsize == 8)
            undecided = v->f64[n - 3]((const double *)a.buf, (const double *)b.buf, (signed char *)out.buf, (int64_t)count, tab);
        else
            undecided = v->f32[n - 3]((const float *)a.buf, (const float *)b.buf, (signed char *)out.buf, (int64_t)count, tab);
        Py_END_ALLOW_THREADS
        result = PyLong_FromLongLong((long long)undecided);
    }
    PyBuffer_Release(&a);
    PyBuffer_Release(&b);
    PyBuffer_Release(&out);
    if (table.obj) PyBuffer_Release(&table);
    return result;
}

/* frexp's exponent of a finite x != 0 (x in [2^(E-1), 2^E)): from the bits where x is normal */
static inline int exponent_of(double x) {
    uint64_t bits;
    memcpy(&bits, &x, 8);
    const int biased = (int)((bits >> 52) & 0x7ff);
    if (biased) return biased - 1022;
    int e;
    frexp(x, &e); /* subnormal */
    return e;
}

/* Twice log2 of a body's size from its n x n matrix [[Q, m], [m^T, g]] (row-major), by the frexp
 * exponents E of its largest entries: max(E(g) - E(Q), 2 (E(m) - E(Q))), a term skipped where m or
 * g is zero; 0 where undefined (a non-finite entry, Q zero, m and g zero). The numpy twin is
 * core.fixed.filters.twice_log2_size. */
static inline __attribute__((always_inline)) int64_t twice_log2_size(const double *M, int n) {
    const int d = n - 1;
    double q = 0.0, m = 0.0;
    for (int k = 0; k < n * n; k++)
        if (!isfinite(M[k])) return 0;
    for (int i = 0; i < d; i++) {
        for (int j = 0; j < d; j++) q = fabs(M[i * n + j]) > q ? fabs(M[i * n + j]) : q;
        m = fabs(M[i * n + d]) > m ? fabs(M[i * n + d]) : m;
    }
    const double g = fabs(M[d * n + d]);
    if (q == 0.0 || (m == 0.0 && g == 0.0)) return 0;
    const int eq = exponent_of(q);
    int64_t s = INT64_MIN;
    if (g != 0.0) s = (int64_t)exponent_of(g) - eq;
    if (m != 0.0) {
        const int64_t t = 2 * ((int64_t)exponent_of(m) - eq);
        s = t > s ? t : s;
    }
    return s;
}

/* 2^k for -1022 <= k <= 1023 (a normal number, exact) */
static inline double pow2(int64_t k) {
    const uint64_t bits = (uint64_t)(k + 1023) << 52;
    double x;
    memcpy(&x, &bits, 8);
    return x;
}

/* x 2^k, and whether that is exact (filters.times_power_of_two): finite, normal unless x is 0, and
 * scaled back it is x again (a product just below 2^-1022 may round up to it). One multiplication
 * by 2^k rounds once, as ldexp does: the same bits. */
static inline int times_pow2(double x, int64_t k, double *y) {
    if (k >= -1022 && k <= 1022) {
        *y = x * pow2(k);
        return isfinite(*y) && (x == 0.0 || fabs(*y) >= DBL_MIN) && *y * pow2(-k) == x;
    }
    *y = ldexp(x, (int)k);
    return isfinite(*y) && (x == 0.0 || fabs(*y) >= DBL_MIN) && ldexp(*y, (int)-k) == x;
}

/* tmp = M with space scaled by 2^e (last column and row times 2^e, the corner times 2^2e); whether
 * M is exactly symmetric and every changed entry exact (filters.space_scaled) */
static inline __attribute__((always_inline)) int space_scaled(const double *M, double *tmp, int n, int64_t e) {
    const int d = n - 1;
    int exact = 1;
    memcpy(tmp, M, sizeof(double) * n * n);
    for (int i = 0; i < n; i++) /* the diagonal too: NaN == NaN is false, as in numpy's M == M^T */
        for (int j = i; j < n; j++) exact &= M[i * n + j] == M[j * n + i];
    for (int i = 0; i < d; i++) {
        exact &= times_pow2(M[i * n + d], e, &tmp[i * n + d]);
        exact &= times_pow2(M[d * n + i], e, &tmp[d * n + i]);
    }
    exact &= times_pow2(M[d * n + d], 2 * e, &tmp[d * n + d]);
    return exact;
}

/* the pairs of A, B (and shifts S) with space scaled per pair into A2, B2 (S2), e into E; the
 * outputs may be the inputs (scaled in place) */
static inline __attribute__((always_inline)) int64_t balance_pairs(int n, const double *A, const double *B, double *A2, double *B2,
                                                                   int64_t *E, const double *S, double *S2, int64_t count) {
    int64_t moved = 0;
    const int d = n - 1, nn = n * n;
    for (int64_t p = 0; p < count; p++) {
        const double *a = A + p * nn, *b = B + p * nn;
        double ta[16], tb[16], ts[3];
        const int64_t s = twice_log2_size(a, n) + twice_log2_size(b, n);
        double r = -nearbyint((double)s * 0.25); /* round half to even, as numpy's rint */
        r = r < -1000.0 ? -1000.0 : (r > 1000.0 ? 1000.0 : r);
        int64_t e = (int64_t)r;
        int exact = e != 0;
        if (exact) exact = space_scaled(a, ta, n, e) & space_scaled(b, tb, n, e);
        if (exact && S)
            for (int i = 0; i < d; i++) exact &= times_pow2(S[p * d + i], e, &ts[i]);
        if (exact) {
            memcpy(A2 + p * nn, ta, sizeof(double) * nn);
            memcpy(B2 + p * nn, tb, sizeof(double) * nn);
            if (S) memcpy(S2 + p * d, ts, sizeof(double) * d);
        } else {
            e = 0;
            if (A2 != A) memcpy(A2 + p * nn, a, sizeof(double) * nn);
            if (B2 != B) memcpy(B2 + p * nn, b, sizeof(double) * nn);
            if (S && S2 != S) memcpy(S2 + p * d, S + p * d, sizeof(double) * d);
        }
        E[p] = e;
        moved += e != 0;
    }
    return moved;
}

/* balance_pairs with n a constant (its loops unrolled) */
static int64_t balance3(const double *A, const double *B, double *A2, double *B2, int64_t *E, const double *S, double *S2, int64_t count) {
    return balance_pairs(3, A, B, A2, B2, E, S, S2, count);
}
static int64_t balance4(const double *A, const double *B, double *A2, double *B2, int64_t *E, const double *S, double *S2, int64_t count) {
    return balance_pairs(4, A, B, A2, B2, E, S, S2, count);
}

static PyObject *balance(PyObject *self, PyObject *args) {
    int n;
    Py_buffer a, b, a2, b2, e, s = {0}, s2 = {0};
    if (!PyArg_ParseTuple(args, "iy*y*w*w*w*|y*w*", &n, &a, &b, &a2, &b2, &e, &s, &s2)) return NULL;
    PyObject *result = NULL;
    const Py_ssize_t count = e.len / 8;
    if (n != 3 && n != 4) {
        PyErr_Format(PyExc_ValueError, "n must be 3 or 4, got %d", n);
    } else if (e.len != count * 8 || a.len != count * n * n * 8 || b.len != a.len || a2.len != a.len || b2.len != a.len) {
        PyErr_Format(PyExc_ValueError, "a, b, a_out and b_out must hold %zd pairs of %dx%d float64 matrices", count, n, n);
    } else if ((s.obj != NULL) != (s2.obj != NULL) || (s.obj && (s.len != count * (n - 1) * 8 || s2.len != s.len))) {
        PyErr_Format(PyExc_ValueError, "shift and shift_out must both hold %zd float64 vectors of %d", count, n - 1);
    } else if (!PyBuffer_IsContiguous(&a, 'C') || !PyBuffer_IsContiguous(&b, 'C') || !PyBuffer_IsContiguous(&a2, 'C') ||
               !PyBuffer_IsContiguous(&b2, 'C') || !PyBuffer_IsContiguous(&e, 'C') ||
               (s.obj && (!PyBuffer_IsContiguous(&s, 'C') || !PyBuffer_IsContiguous(&s2, 'C')))) {
        PyErr_SetString(PyExc_ValueError, "buffers must be C-contiguous");
    } else {
        int64_t moved;
        Py_BEGIN_ALLOW_THREADS
        moved = (n == 3 ? balance3 : balance4)((const double *)a.buf, (const double *)b.buf, (double *)a2.buf, (double *)b2.buf, (int64_t *)e.buf,
                              s.obj ? (const double *)s.buf : NULL, s.obj ? (double *)s2.buf : NULL, (int64_t)count);
        Py_END_ALLOW_THREADS
        result = PyLong_FromLongLong((long long)moved);
    }
    PyBuffer_Release(&a);
    PyBuffer_Release(&b);
    PyBuffer_Release(&a2);
    PyBuffer_Release(&b2);
    PyBuffer_Release(&e);
    if (s.obj) PyBuffer_Release(&s);
    if (s2.obj) PyBuffer_Release(&s2);
    return result;
}

#include "_spheres.h"

static PyObject *spheres(PyObject *self, PyObject *args) {
    int n;
    Py_buffer m, c, r, st;
    if (!PyArg_ParseTuple(args, "iy*w*w*w*", &n, &m, &c, &r, &st)) return NULL;
    PyObject *result = NULL;
    const Py_ssize_t count = st.len;
    if (n != 3 && n != 4) {
        PyErr_Format(PyExc_ValueError, "n must be 3 or 4, got %d", n);
    } else if (m.len != count * n * n * 8 || c.len != count * (n - 1) * 8 || r.len != count * 8) {
        PyErr_Format(PyExc_ValueError, "m, centres_out and radii_out must hold %zd float64 bodies of %dx%d, centres and radii", count, n, n);
    } else if (!PyBuffer_IsContiguous(&m, 'C') || !PyBuffer_IsContiguous(&c, 'C') || !PyBuffer_IsContiguous(&r, 'C') ||
               !PyBuffer_IsContiguous(&st, 'C')) {
        PyErr_SetString(PyExc_ValueError, "buffers must be C-contiguous");
    } else {
        int64_t found = 0;
        const double *M = (const double *)m.buf;
        double *C = (double *)c.buf, *R = (double *)r.buf;
        signed char *S = (signed char *)st.buf;
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t k = 0; k < count; k++) {
            S[k] = (signed char)sphere_one(M + k * n * n, n, C + k * (n - 1), R + k);
            found += S[k] <= SPHERE_LOOSE;
        }
        Py_END_ALLOW_THREADS
        result = PyLong_FromLongLong((long long)found);
    }
    PyBuffer_Release(&m);
    PyBuffer_Release(&c);
    PyBuffer_Release(&r);
    PyBuffer_Release(&st);
    return result;
}

#include "_near.h"

#define QUERY_GEOMETRY_D 27 /* doubles of the float geometry (core.bodies.index: _pack_geometry) */
/* Outcomes besides a count (>= 0) and NEAR_TOO_FAR, NEAR_FAR_BOX */
#define QUERY_GENERAL (-2) /* no float sphere here, or a body too large for the box: the general path */
#define QUERY_SPACE (-10)  /* QUERY_SPACE - needed: the outputs must hold `needed` more bodies */

/* The index as query_one / query_many read it (geometry packed by core.bodies.index._pack_geometry). */
typedef struct {
    int d, nn, periodic, tilted;
    int64_t cap, nbody;
    const int64_t *n, *stride;
    const double *L, *H, *o, *h;
    double big, span, limit, pad, cell_error, far, eps_max, gamma, tiny;
    const int32_t *table;
    const double *cr, *frac, *Q; /* Q NULL: classify nothing */
    const signed char *rel;
} grid;

/* (id, image) pairs: sorted by id before they are classified */
typedef struct {
    int64_t id;
    signed char k[3];
} near_hit;

static int near_hit_order(const void *x, const void *y) {
    const int64_t a = ((const near_hit *)x)->id, b = ((const near_hit *)y)->id;
    return (a > b) - (a < b);
}

/* Reads the buffers of a call into g; 0, or -1 with a Python error set. */
static int read_grid(grid *g, Py_buffer *gi, Py_buffer *gd, Py_buffer *table, Py_buffer *cr, Py_buffer *frac, Py_buffer *Q, Py_buffer *rel) {
    const int64_t *G = (const int64_t *)gi->buf;
    const double *D = (const double *)gd->buf;
    if (gi->len != 10 * 8 || gd->len != QUERY_GEOMETRY_D * 8 || (G[0] != 2 && G[0] != 3) || G[1] < 1) {
        PyErr_SetString(PyExc_ValueError, "BodyIndex query: bad geometry");
        return -1;
    }
    g->d = (int)G[0];
    g->nn = (g->d + 1) * (g->d + 1);
    g->cap = G[1];
    g->periodic = (int)G[2];
    g->tilted = (int)G[3];
    g->n = G + 4;
    g->stride = G + 7;
    g->nbody = cr->len / (8 * (g->d + 1));
    int64_t cells = 1;
    for (int a = 0; a < g->d; a++) cells *= g->n[a];
    if (table->len != cells * g->cap * 4 || (g->tilted && frac->len != g->nbody * g->d * 8) ||
        (Q->len && (Q->len != g->nbody * g->nn * 8 || rel->len != 256))) {
        PyErr_SetString(PyExc_ValueError, "BodyIndex query: buffers of the wrong size");
        return -1;
    }
    g->L = D;
    g->H = D + 3;
    g->o = D + 12;
    g->h = D + 15;
    g->big = D[18];
    g->span = D[19];
    g->limit = D[20];
    g->pad = D[21];
    g->cell_error = D[22];
    g->far = D[23];
    g->eps_max = D[24];
    g->gamma = D[25];
    g->tiny = D[26];
    g->table = (const int32_t *)table->buf;
    g->cr = (const double *)cr->buf;
    g->frac = (const double *)frac->buf;
    g->Q = Q->len ? (const double *)Q->buf : NULL;
    g->rel = (const signed char *)rel->buf;
    return 0;
}

/* One new body with its certified sphere (c, rho) asked of the grid (BodyIndex._place_one and
 * _near_one): writes the indexed bodies whose spheres meet its own at ids (their lattice images
 * at K), sorted by body, room for `room`. Returns how many, or a negative code: NEAR_TOO_FAR,
 * NEAR_FAR_BOX, QUERY_GENERAL (too large for the box, or out of memory), QUERY_SPACE - needed
 * (room too small: nothing written). */
static int64_t lookup_body(const grid *g, const double *c, double rho, int64_t exclude, int64_t room, int64_t *ids, signed char *K) {
    const int d = g->d;
    if (g->periodic && !(rho + g->big < g->limit)) return QUERY_GENERAL;
    /* its cell, the cells within its reach, the padding of the sphere test */
    const double reach = rho + g->big;
    int64_t u[3] = {0, 0, 0}, m[3] = {0, 0, 0}, visit = 1;
    double f[3] = {0.0, 0.0, 0.0}, top = 0.0;
    for (int a = 0; a < d; a++) {
        m[a] = (int64_t)ceil(reach / g->h[a] * (1 + 0x1p-40) + g->cell_error);
        visit *= (g->periodic && 2 * m[a] + 1 >= g->n[a]) ? g->n[a] : 2 * m[a] + 1;
        top = fabs(c[a]) > top ? fabs(c[a]) : top;
    }
    if (room < visit * g->cap) return QUERY_SPACE - visit * g->cap;
    const double rpad = rho + g->pad * (top + g->span + reach);
    if (place_one(d, g->periodic, g->H, g->n, g->o, g->h, g->gamma, g->tiny, g->eps_max, g->far, c, u, f) < 0) return NEAR_FAR_BOX;
    const int64_t found = near_one(d, g->table, g->cap, g->nbody, g->n, g->stride, g->periodic, g->tilted, g->L, g->H, g->cr, g->frac, u, m, c,
                                   f, rpad, exclude, ids, K);
    if (found > 1) { /* sorted by indexed body, the images along */
        near_hit small[64], *hits = found <= 64 ? small : (near_hit *)malloc(sizeof(near_hit) * (size_t)found);
        if (!hits) return QUERY_GENERAL;
        for (int64_t i = 0; i < found; i++) {
            hits[i].id = ids[i];
            for (int a = 0; a < d; a++) hits[i].k[a] = g->periodic ? K[i * d + a] : 0;
        }
        qsort(hits, (size_t)found, sizeof(near_hit), near_hit_order);
        for (int64_t i = 0; i < found; i++) {
            ids[i] = hits[i].id;
            if (g->periodic)
                for (int a = 0; a < d; a++) K[i * d + a] = hits[i].k[a];
        }
        if (hits != small) free(hits);
    }
    return found;
}

#define QUERY_GATHER 2048 /* pairs gathered for one call of the filter (2 x 512 kB of ellipsoids) */

/* The `count` pairs (indexed body ids[i], new body B + qi[i] * nn; qi NULL: B itself) through the
 * filter where they have no lattice image (codes rel[rule]; NEAR_MOVED for the others), the
 * separate ones dropped: the arrays (qi, ids, K, code, cert) compacted in place, cert 1 where the
 * filter decided. Without Q every pair is kept and left. Adds the kept pairs to *kept and those left
 * to the caller (images, undecided) to *left; -1 when out of memory, else 0. */
static int classify_found(const grid *g, const double *B, int64_t *qi, int64_t *ids, signed char *K, signed char *code, signed char *cert,
                          int64_t count, int64_t *kept, int64_t *left) {
    const int d = g->d, nn = g->nn;
    if (!g->Q) {
        for (int64_t i = 0; i < count; i++) code[i] = NEAR_MOVED, cert[i] = 0;
        *kept += count;
        *left += count;
        return 0;
    }
    const int64_t chunk = count < QUERY_GATHER ? count : QUERY_GATHER;
    double small_a[2 * 16 * 16];
    double *pa = chunk <= 16 ? small_a : (double *)malloc(sizeof(double) * (size_t)(2 * chunk * nn));
    if (!pa) return -1;
    double *pb = pa + chunk * nn;
    signed char res[QUERY_GATHER];
    int64_t slot[QUERY_GATHER];
    for (int64_t s0 = 0; s0 < count; s0 += chunk) { /* the filter writes each pair's code in place */
        const int64_t s1 = s0 + chunk < count ? s0 + chunk : count;
        int64_t q = 0;
        for (int64_t i = s0; i < s1; i++) {
            int moved = 0;
            if (g->periodic)
                for (int a = 0; a < d; a++) moved |= K[i * d + a] != 0;
            code[i] = (signed char)NEAR_MOVED;
            if (moved) continue;
            memcpy(pa + q * nn, g->Q + ids[i] * nn, sizeof(double) * nn);
            memcpy(pb + q * nn, B + (qi ? qi[i] : 0) * nn, sizeof(double) * nn);
            slot[q++] = i;
        }
        if (q) current->f64[d - 2](pa, pb, res, q, g->rel);
        for (int64_t j = 0; j < q; j++) code[slot[j]] = res[j];
    }
    if (pa != small_a) free(pa);
    /* keep the pairs that are not separate (and those left to the caller), in order */
    int64_t w = 0;
    for (int64_t i = 0; i < count; i++) {
        const signed char r = code[i];
        if (r == 0) continue; /* separate */
        if (qi) qi[w] = qi[i];
        ids[w] = ids[i];
        if (g->periodic)
            for (int a = 0; a < d; a++) K[w * d + a] = K[i * d + a];
        code[w] = r;
        cert[w] = r >= 0; /* Certifier.FLOAT where the filter decided */
        *left += r < 0;
        w++;
    }
    *kept += w;
    return 0;
}

static PyObject *query_one(PyObject *self, PyObject *args) {
    Py_buffer gi, gd, table, cr, frac, Q, B, rel, out, kout, codes, by;
    long long exclude;
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*y*y*y*w*w*w*w*L", &gi, &gd, &table, &cr, &frac, &Q, &B, &rel, &out, &kout, &codes, &by, &exclude))
        return NULL;
    PyObject *result = NULL;
    grid g;
    if (read_grid(&g, &gi, &gd, &table, &cr, &frac, &Q, &rel) == 0) {
        const int64_t room = out.len / 8;
        if (B.len != g.nn * 8 || out.len % 8 || (g.periodic && kout.len < room * g.d) || codes.len < room || by.len < room) {
            PyErr_SetString(PyExc_ValueError, "query_one: buffers of the wrong size");
        } else {
            double c[3] = {0.0, 0.0, 0.0}, rho;
            int64_t kept = 0, left = 0, found = QUERY_GENERAL;
            if (sphere_one((const double *)B.buf, g.d + 1, c, &rho) <= SPHERE_LOOSE) /* its certified sphere (_spheres.h) */
                found = lookup_body(&g, c, rho, (int64_t)exclude, room, (int64_t *)out.buf, (signed char *)kout.buf);
            if (found > 0 && classify_found(&g, (const double *)B.buf, NULL, (int64_t *)out.buf, (signed char *)kout.buf, (signed char *)codes.buf,
                                            (signed char *)by.buf, found, &kept, &left) < 0)
                found = QUERY_GENERAL;
            result = Py_BuildValue("LLL", (long long)found, (long long)kept, (long long)left);
        }
    }
    PyBuffer_Release(&gi);
    PyBuffer_Release(&gd);
    PyBuffer_Release(&table);
    PyBuffer_Release(&cr);
    PyBuffer_Release(&frac);
    PyBuffer_Release(&Q);
    PyBuffer_Release(&B);
    PyBuffer_Release(&rel);
    PyBuffer_Release(&out);
    PyBuffer_Release(&kout);
    PyBuffer_Release(&codes);
    PyBuffer_Release(&by);
    return result;
}

static PyObject *query_many(PyObject *self, PyObject *args) {
    Py_buffer gi, gd, table, cr, frac, Q, B, rel, spheres, exclude, qout, out, kout, codes, by;
    long long start;
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*y*y*y*y*y*w*w*w*w*w*L", &gi, &gd, &table, &cr, &frac, &Q, &B, &rel, &spheres, &exclude, &qout, &out,
                          &kout, &codes, &by, &start))
        return NULL;
    PyObject *result = NULL;
    grid g;
    if (read_grid(&g, &gi, &gd, &table, &cr, &frac, &Q, &rel) == 0) {
        const int64_t room = out.len / 8, M = exclude.len / 8;
        if (B.len != M * g.nn * 8 || spheres.len != M * (g.d + 1) * 8 || exclude.len % 8 || out.len % 8 || qout.len != out.len ||
            (g.periodic && kout.len < room * g.d) || codes.len < room || by.len < room || start < 0 || start > M) {
            PyErr_SetString(PyExc_ValueError, "query_many: buffers of the wrong size");
        } else {
            const double *S = (const double *)spheres.buf, *Bm = (const double *)B.buf;
            const int64_t *ex = (const int64_t *)exclude.buf;
            int64_t *qi = (int64_t *)qout.buf, *ids = (int64_t *)out.buf;
            signed char *K = (signed char *)kout.buf, *code = (signed char *)codes.buf, *cert = (signed char *)by.buf;
            int64_t k = start, kept = 0, left = 0, candidates = 0, status = 0;
            Py_BEGIN_ALLOW_THREADS
            for (; k < M; k++) { /* every body's candidates, then one pass of the filter over them all */
                const double *s = S + k * (g.d + 1);
                if (!(s[g.d] >= 0.0)) continue; /* no sphere (an invalid body): nothing to find */
                const int64_t found = lookup_body(&g, s, s[g.d], ex[k], room - candidates, ids + candidates, K + candidates * g.d);
                if (found < 0) {
                    status = found;
                    break;
                }
                for (int64_t i = candidates; i < candidates + found; i++) qi[i] = k;
                candidates += found;
            }
            if (classify_found(&g, Bm, qi, ids, K, code, cert, candidates, &kept, &left) < 0) status = QUERY_GENERAL;
            Py_END_ALLOW_THREADS
            /* (bodies done, candidates, kept, left, status): status QUERY_SPACE - needed stops at body k */
            result = Py_BuildValue("LLLLL", (long long)k, (long long)candidates, (long long)kept, (long long)left, (long long)status);
        }
    }
    PyBuffer_Release(&gi);
    PyBuffer_Release(&gd);
    PyBuffer_Release(&table);
    PyBuffer_Release(&cr);
    PyBuffer_Release(&frac);
    PyBuffer_Release(&Q);
    PyBuffer_Release(&B);
    PyBuffer_Release(&rel);
    PyBuffer_Release(&spheres);
    PyBuffer_Release(&exclude);
    PyBuffer_Release(&qout);
    PyBuffer_Release(&out);
    PyBuffer_Release(&kout);
    PyBuffer_Release(&codes);
    PyBuffer_Release(&by);
    return result;
}

#ifndef KERNELS_SHA256
#define KERNELS_SHA256 "unknown"
#endif
static PyObject *kernels_sha256(PyObject *self, PyObject *noargs) { return PyUnicode_FromString(KERNELS_SHA256); }

static PyMethodDef METHODS[] = {
    {"kernels_sha256", kernels_sha256, METH_NOARGS, "First 16 hex digits of the SHA-256 of the _kernels.h this module was built from."},
    {"classify", classify, METH_VARARGS, "classify(n, a, b, out[, table]): rule ids (or table[rule id] with a 256-byte table) of count pairs into the int8 buffer out, GIL released; returns how many are undecided."},
    {"balance", balance, METH_VARARGS, "balance(n, a, b, a_out, b_out, e_out[, shift, shift_out]): pairs with space scaled by 2^e to the bodies' size where exact (e_out 0 elsewhere), GIL released; returns how many moved."},
    {"spheres", spheres, METH_VARARGS, "spheres(n, m, centres_out, radii_out, status_out): certified bounding spheres of float64 bodies (status 0 tight, 1 loose, 2 none, 3 not exactly symmetric), GIL released; returns how many have one."},
    {"query_many", query_many, METH_VARARGS, "query_many(geometry_i, geometry_d, table, cr, frac, Q, B, rel, spheres, exclude, qout, out, kout, codes, by, start): query_one for new bodies B with their spheres, from body start on, GIL released; returns (bodies done, candidates, kept, left, status)."},
    {"query_one", query_one, METH_VARARGS, "query_one(geometry_i, geometry_d, table, cr, frac, Q, B, rel, out, kout, codes, by, exclude): one new body asked of a BodyIndex (its sphere, the bodies near it, sorted, their images, the relations of the pairs without one, the separate ones dropped); returns (candidates, kept, left), or (a negative code, 0, 0)."},
    {"variant", get_variant, METH_NOARGS, "The SIMD variant in use."},
    {"variants", get_variants, METH_NOARGS, "The variants of this build that this CPU can run (slowest first)."},
    {"select", select_variant, METH_VARARGS, "select(name): use this variant (ValueError if unknown or unsupported here)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef MODULE = {PyModuleDef_HEAD_INIT, "_filter", "The compiled certified float filter.", -1, METHODS, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__filter(void) {
    PyObject *m = PyModule_Create(&MODULE);
    if (!m) return NULL;
    /* the best supported variant, unless ELLIPSOID_SIMD asks for another one this CPU runs */
    const char *want = getenv("ELLIPSOID_SIMD");
    for (size_t i = 0; i < sizeof(VARIANTS) / sizeof(VARIANTS[0]); i++)
        if (supported(VARIANTS[i].name)) {
            current = &VARIANTS[i];
            if (want && strcmp(want, VARIANTS[i].name) == 0) break;
        }
    return m;
}
