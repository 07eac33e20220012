/* The paper's decision tree in plain, UNCERTIFIED float64 C: the speed baseline of the benchmark.
 *
 * Built at benchmark time by bench/baseline.py with `gcc -O3 -march=native` (one thread). Same
 * input as the certified filter (contiguous (N, 4, 4) or (N, 3, 3) float64 stacks); P(T) =
 * det(T A + B) by Laplace expansion along two rows (ellipsoids) / the first row (ellipses), signs
 * of a_n..a_0 as they come out of the floats, Var, then the sign of the discriminant-type s0
 * (Section 4.3's 18-multiplication form for quartics; -Disc for cubics). No error bound, no
 * validation, no scaling: this is what the certification is measured against, not a method
 * anyone should trust near tangency. Writes Relation codes (0 separate, 1 tangent, 2 overlap).
 */
#include <stdint.h>

static inline void minor2(const double *A, const double *B, int n, int r0, int r1, int j, int k, double *p) {
    p[2] = A[r0 * n + j] * A[r1 * n + k] - A[r0 * n + k] * A[r1 * n + j];
    p[1] = (A[r0 * n + j] * B[r1 * n + k] + B[r0 * n + j] * A[r1 * n + k]) -
           (A[r0 * n + k] * B[r1 * n + j] + B[r0 * n + k] * A[r1 * n + j]);
    p[0] = B[r0 * n + j] * B[r1 * n + k] - B[r0 * n + k] * B[r1 * n + j];
}

static inline int var_sign(double x) { return x > 0 ? 1 : (x < 0 ? -1 : 0); }

static inline int variations(const int *s, int m) {
    int last = 0, count = 0;
    for (int i = 0; i < m; i++) {
        if (s[i] == 0) continue;
        if (last != 0 && s[i] != last) count++;
        last = s[i];
    }
    return count;
}

static inline int tree4(const double *A0, const double *B0) {
    double A[16], B[16];
    const double fa = A0[0] < 0 ? -1.0 : 1.0, fb = B0[0] < 0 ? -1.0 : 1.0;
    for (int i = 0; i < 16; i++) {
        A[i] = fa * A0[i];
        B[i] = fb * B0[i];
    }
    double a[5] = {0, 0, 0, 0, 0};
    static const int J[6] = {0, 0, 0, 1, 1, 2}, Kk[6] = {1, 2, 3, 2, 3, 3};
    static const int CJ[6] = {2, 1, 1, 0, 0, 0}, CK[6] = {3, 3, 2, 3, 2, 1};
    for (int t = 0; t < 6; t++) {
        double top[3], bot[3];
        minor2(A, B, 4, 0, 1, J[t], Kk[t], top);
        minor2(A, B, 4, 2, 3, CJ[t], CK[t], bot);
        const double sgn = ((J[t] + Kk[t] + 1) % 2 == 1) ? -1.0 : 1.0;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) a[i + j] += sgn * top[i] * bot[j];
    }
    int s[5] = {var_sign(a[4]), var_sign(a[3]), var_sign(a[2]), var_sign(a[1]), var_sign(a[0])};
    if (variations(s, 5) != 2) return 2;
    const double t4 = 12 * a[4], t3 = -3 * a[3], t2 = 2 * a[2], t1 = -3 * a[1], t0 = 12 * a[0];
    const double d2 = t3 * t3 - t2 * t4, d3 = t2 * t2 - t3 * t1, w1 = t1 * t4 - t3 * t2, w3 = t0 * t4 - t3 * t1;
    const double aa = w3 + 3 * d3, bb = t1 * w1 + t0 * d2 + t2 * d3;
    const double hs0 = 27 * bb * bb - aa * aa * aa;
    if (hs0 < 0) return 0;
    if (hs0 > 0) return 2;
    const double hs1 = w3 * d2 + 3 * w1 * w1 - 9 * d2 * d3;
    if (hs1 > 0) return 2;
    if (hs1 == 0) return 1;
    const double hs10 = -(3 * bb * t3 + aa * w1);
    return hs10 > 0 ? 1 : 0;
}

static inline int tree3(const double *A0, const double *B0) {
    double A[9], B[9];
    const double fa = A0[0] < 0 ? -1.0 : 1.0, fb = B0[0] < 0 ? -1.0 : 1.0;
    for (int i = 0; i < 9; i++) {
        A[i] = fa * A0[i];
        B[i] = fb * B0[i];
    }
    double a[4] = {0, 0, 0, 0};
    for (int j = 0; j < 3; j++) {
        const int k0 = j == 0 ? 1 : 0, k1 = j == 2 ? 1 : 2;
        double m[3];
        minor2(A, B, 3, 1, 2, k0, k1, m);
        const double sgn = (j % 2) ? -1.0 : 1.0;
        for (int i = 0; i < 3; i++) {
            a[i] += sgn * B[j] * m[i];
            a[i + 1] += sgn * A[j] * m[i];
        }
    }
    int s[4] = {var_sign(a[3]), var_sign(a[2]), var_sign(a[1]), var_sign(a[0])};
    if (variations(s, 4) != 2) return 2;
    const double hs0 = -(27 * a[0] * a[0] * a[3] * a[3] - 18 * a[0] * a[1] * a[2] * a[3] + 4 * a[0] * a[2] * a[2] * a[2] +
                         4 * a[1] * a[1] * a[1] * a[3] - a[1] * a[1] * a[2] * a[2]);
    return hs0 > 0 ? 0 : (hs0 == 0 ? 1 : 2);
}

void baseline4(const double *A, const double *B, signed char *out, int64_t count) {
    for (int64_t i = 0; i < count; i++) out[i] = (signed char)tree4(A + 16 * i, B + 16 * i);
}

void baseline3(const double *A, const double *B, signed char *out, int64_t count) {
    for (int64_t i = 0; i < count; i++) out[i] = (signed char)tree3(A + 9 * i, B + 9 * i);
}

/* The memory-read limit: sum every input double once (what any method must at least do). */
double read_all(const double *A, const double *B, int64_t count) {
    double s = 0.0;
    for (int64_t i = 0; i < count; i++) s += A[i] + B[i];
    return s;
}
