"""The float filter: generated kernels are current, error bounds hold, implementations agree."""

from __future__ import annotations

from fractions import Fraction as F

import numpy as np
import pytest
from flint import fmpq
from strategies import dyadic_tangent_pair

from core import Relation, classify, explain, quadric_from_axes
from core.fixed import _kernels as K
from core.fixed import compiled
from core.fixed.errorbound import UNIT_ROUNDOFF, gamma_constant
from core.fixed.exact import exact_pair
from core.fixed.filters import (
    _HAT,
    _PENCIL,
    _Prepared,
    _relations,
    _run_hat,
    _run_pencil,
    rules_numpy,
)
from core.fixed.kernelgen import main as kernelgen_main
from core.formulae.decision import RULE_RELATION
from core.formulae.pencil import pencil_coefficients
from core.formulae.subresultants import hat_s0, hat_s1, hat_s10


def test_generated_kernels_are_current():
    assert kernelgen_main(["--check"]) == 0


@pytest.mark.parametrize("K_, Kb", [(1, 1), (10, 18), (14, 18), (99, 120)])
def test_gamma_constant_matches_formula(K_, Kb):
    u = UNIT_ROUNDOFF
    exact = K_ * u / (1 - K_ * u) / (1 - u) ** (Kb + 2)
    c = gamma_constant(K_, Kb)
    assert F(c) >= exact and F(c) < exact * (1 + F(1, 2**50))


def _random_matrices(rng, n, count):
    """Valid ellipses/ellipsoids, some near-degenerate, entries rounded to floats."""
    out = []
    for _ in range(count):
        d = n - 1
        c = rng.uniform(-5, 5, d) * (10.0 ** rng.integers(-3, 4))
        r = rng.uniform(0.1, 3, d) * (10.0 ** rng.integers(-2, 3))
        o = rng.uniform(0, 3) if d == 2 else rng.normal(size=4)
        out.append(quadric_from_axes(c, r, o))
    return np.array(out)


def _exact(M):
    return [[fmpq(*float(v).as_integer_ratio()) for v in row] for row in M]


@pytest.mark.parametrize("n", [3, 4])
def test_pencil_error_bounds_hold(n):
    rng = np.random.default_rng(n)
    A = _random_matrices(rng, n, 60)
    B = _random_matrices(rng, n, 60)
    B[::7] = A[::7]  # identical shapes: coefficients with huge cancellation
    prep = _Prepared(A, B)
    out = _run_pencil(prep.a, prep.b)
    for i in range(len(A)):
        EA, EB = _exact(prep.a[i]), _exact(prep.b[i])
        coeffs = pencil_coefficients(EA, EB)
        for k, c in enumerate(coeffs):
            v, bd = out[f"c{k}"]
            assert abs(fmpq(*float(v[i]).as_integer_ratio()) - c) <= fmpq(*float(bd[i]).as_integer_ratio())


def _fq(x):
    return fmpq(*float(x).as_integer_ratio())


def _numpy_built(rng, n, count):
    """R diag R^T computed in floats: symmetric only up to rounding (the leaf_K = 1 case)."""
    d = n - 1
    out = []
    for _ in range(count):
        q = rng.normal(size=4)
        R = quadric_from_axes([0] * d, [1] * d, q if d == 3 else float(rng.uniform(0, 3)))[:d, :d]  # a rotation-ish block
        w, v = np.linalg.eigh(R)
        rot = v if d == 3 else np.array([[np.cos(q[0]), -np.sin(q[0])], [np.sin(q[0]), np.cos(q[0])]])
        S = rot @ np.diag(rng.uniform(0.2, 3, d) ** -2) @ rot.T
        c = rng.uniform(-5, 5, d)
        M = np.empty((n, n))
        M[:d, :d], M[:d, d], M[d, :d], M[d, d] = S, -S @ c, -c @ S, c @ S @ c - 1
        out.append(M)
    return np.array(out)


@pytest.mark.parametrize("n", [3, 4])
def test_pencil_error_bounds_hold_for_rounded_symmetrisation(n):
    # the prepared entries are rounded half sums; the bound (leaf_K = 1 constants) must cover
    # the pencil of the EXACT symmetric part of the input
    rng = np.random.default_rng(30 + n)
    A, B = _numpy_built(rng, n, 50), _numpy_built(rng, n, 50)
    prep = _Prepared(A, B)
    assert prep.rounded.mean() > 0.5 and prep.ok.all()
    out = _run_pencil(prep.a, prep.b, prep.rounded)
    for i in range(len(A)):
        ea, eb = int(prep.ea[i]), int(prep.eb[i])
        fa = fmpq(2) ** ea if ea >= 0 else fmpq(1, 2 ** (-ea))
        fb = fmpq(2) ** eb if eb >= 0 else fmpq(1, 2 ** (-eb))
        sa = 1 if A[i, 0, 0] > 0 else -1
        sb = 1 if B[i, 0, 0] > 0 else -1
        EA = [[(_fq(A[i, r, c]) + _fq(A[i, c, r])) / 2 * fa * sa for c in range(n)] for r in range(n)]
        EB = [[(_fq(B[i, r, c]) + _fq(B[i, c, r])) / 2 * fb * sb for c in range(n)] for r in range(n)]
        for k, c in enumerate(pencil_coefficients(EA, EB)):
            v, bd = out[f"c{k}"]
            assert abs(_fq(v[i]) - c) <= _fq(bd[i])


@pytest.mark.parametrize("n", [3, 4])
def test_certificate_kernels_bounds_hold(n):
    """pencil_at (P(T) from a_i with radii) and form (X^T M X with entry radii) against exact
    values for inputs anywhere inside their radii."""
    from core.fixed import _kernels as KK

    rng = np.random.default_rng(40 + n)
    for _ in range(40):
        c = rng.normal(size=n + 1) * 10.0 ** rng.integers(-3, 4, n + 1)
        cr = np.abs(c) * 10.0 ** rng.uniform(-16, -8, n + 1)
        T = float(2.0 ** rng.uniform(-10, 10))
        v, r = getattr(KK, f"pencil_at{n}")(list(c), list(cr), T)
        bound = r * (1 + 2.0**-40) + getattr(KK, f"PENCIL_AT{n}_FLOOR")
        for sign in (-1, 1):  # exact coefficients at either end of their intervals
            ct = [_fq(ci) + sign * (1 if k % 2 else -1) * _fq(ri) for k, (ci, ri) in enumerate(zip(c, cr, strict=False))]
            exact = sum(ct[k] * _fq(T) ** k for k in range(n + 1))
            assert abs(_fq(v) - exact) <= _fq(bound)
        M = rng.normal(size=(n, n))
        M = (M + M.T) * 4
        Mr = np.abs(M) * 2.0**-52 * rng.integers(0, 2)
        x = rng.normal(size=n - 1) * 10.0 ** rng.integers(0, 6)
        v, r = getattr(KK, f"form{n}")(M, Mr, x)
        bound = r * (1 + 2.0**-40) + getattr(KK, f"FORM{n}_FLOOR")
        X = [_fq(xi) for xi in x] + [fmpq(1)]
        for sign in (-1, 1):
            Mt = [[_fq(M[i, j]) + sign * _fq(Mr[min(i, j), max(i, j)]) for j in range(n)] for i in range(n)]
            exact = sum(X[i] * Mt[i][j] * X[j] for i in range(n) for j in range(n))
            assert abs(_fq(v) - exact) <= _fq(bound)


@pytest.mark.parametrize("n", [3, 4])
@pytest.mark.parametrize("which", ["s0", "s1", "s10"])
def test_subresultant_error_bounds_hold(n, which):
    rng = np.random.default_rng(10 * n + len(which))
    A = _random_matrices(rng, n, 40)
    B = _random_matrices(rng, n, 40)
    prep = _Prepared(A, B)
    out = _run_pencil(prep.a, prep.b)
    f = {"s0": hat_s0, "s1": hat_s1, "s10": hat_s10}[which]
    for i in range(len(A)):
        exact = f(pencil_coefficients(_exact(prep.a[i]), _exact(prep.b[i])))
        vals = [float(out[f"c{k}"][0][i]) for k in range(n + 1)]
        radii = [float(out[f"c{k}"][1][i]) for k in range(n + 1)]
        v, bd = _run_hat(n, which, vals, radii)
        assert abs(fmpq(*float(v).as_integer_ratio()) - exact) <= fmpq(*float(bd).as_integer_ratio())


def test_kernel_tables_are_consistent():
    for n in (3, 4):
        fn, outputs, consts, floor = _PENCIL[n]
        assert len(outputs) == len(consts) and 0 < floor < 2.0**-850
        for which in ("s0", "s1", "s10"):
            assert 0 < _HAT[(n, which)][1] < 2.0**-850
    assert K.PENCIL4_OUTPUTS[:2] == ("c0", "c0_M")


def _structured(rng, n, count):
    """Spheres, translated copies and homothetic copies: s0 vanishes identically for all of them."""
    d = n - 1
    A, B = [], []
    for k in range(count):
        kind = k % 3
        r = rng.uniform(0.2, 3, d)
        if kind == 0:
            r[:] = r[0]  # spheres / circles
        o = rng.uniform(0, 3) if d == 2 else rng.normal(size=4)
        ca = rng.uniform(-4, 4, d)
        cb = ca + rng.normal(size=d) * rng.uniform(0.2, 8)
        factor = rng.uniform(0.3, 3) if kind == 2 else 1.0
        A.append(quadric_from_axes(ca, r, o if kind else None))
        B.append(quadric_from_axes(cb, r * factor, o if kind else None))
    return np.array(A), np.array(B)


@pytest.mark.parametrize("n", [3, 4])
def test_compiled_numpy_and_single_pair_paths_agree(n):
    assert compiled.warm_up(), compiled.status()
    rng = np.random.default_rng(42 + n)
    A = _random_matrices(rng, n, 300)
    B = _random_matrices(rng, n, 300)
    T1, T2 = dyadic_tangent_pair(n - 1, 2.0, 1.0, [0.0] * (n - 1))
    A[:5], B[:5] = T1, T2  # exactly tangent: must abstain
    A[5] = -A[5]  # flipped sign
    B[6, 0, 1] += 1e-3  # not symmetric
    A[7, 1, 1] = np.nan
    B[8] = A[8]  # identical
    A[9:60:3] *= 10.0 ** rng.integers(-150, 150, (17, 1, 1))  # scaled: the fast path rescales too
    B[10:60:7] *= 2.0**-1040  # subnormal entries: the one-pair path rescales
    SA, SB = _structured(rng, n, 120)
    NA, NB = _numpy_built(rng, n, 64), _numpy_built(rng, n, 64)  # symmetric only up to rounding
    NA[::5] *= 1e-7  # ... and rescaled by the fast path
    A, B = np.concatenate([A, SA, NA]), np.concatenate([B, SB, NB])
    a = compiled.rules(A, B, threads=1)
    b = rules_numpy(A, B)
    c = np.array([compiled.rule_one(np.ascontiguousarray(A[i]), np.ascontiguousarray(B[i])) for i in range(len(A))])
    d = compiled.rules(A, B, threads=4)
    assert (a == b).all() and (a == c).all() and (a == d).all()
    assert (a[:5] == -1).all() and (a[6:8] == -1).all()
    assert RULE_RELATION[a[8]] == Relation.OVERLAP or a[8] == -1
    # the structured pairs: decided by the certificates, never wrong
    from oracle import oracle_relation

    tail = a[300:420]
    assert (tail >= 0).mean() > 0.95
    assert (a[420:] >= 0).mean() > 0.95  # numpy-built pairs stay in the filter
    for i in range(300, len(A), 7):
        if a[i] >= 0:
            assert str(Relation(int(RULE_RELATION[a[i]]))) == oracle_relation(A[i], B[i])


@pytest.mark.parametrize("n", [3, 4])
def test_filter_decides_ordinary_pairs(n):
    """At scene scales (centres within 5, axes 0.2 .. 3) the filter should almost never abstain."""
    rng = np.random.default_rng(5 + n)

    def shapes(k):
        d = n - 1
        return np.array([
            quadric_from_axes(rng.uniform(-5, 5, d), rng.uniform(0.2, 3, d),
                              rng.uniform(0, 3) if d == 2 else rng.normal(size=4))
            for _ in range(k)
        ])

    codes = compiled.rules(shapes(5000), shapes(5000))
    assert (codes == -1).mean() < 0.001


@pytest.mark.parametrize("n", [3, 4])
def test_explain_float_values_within_bounds(n):
    rng = np.random.default_rng(7 + n)
    for _ in range(20):
        A = _random_matrices(rng, n, 1)[0]
        B = _random_matrices(rng, n, 1)[0]
        e = explain(A, B)
        if e.certified_by != "float":
            continue
        pair = exact_pair(A, B, scaled=False)
        for q, c in zip(e.coefficients, pair.coefficients, strict=False):
            assert q.bound is not None and abs(F(q.approx) - F(int(c.p), int(c.q))) <= F(q.bound) * (1 + F(1, 10**6))
            assert q.sign == (c > 0) - (c < 0)


def _far_pairs(rng, n, count, centre, axes=(0.3, 3.0), gap=None):
    d = n - 1
    from core import validate_quadric

    A, B = [], []
    while len(A) < count:
        o = (lambda: rng.uniform(0, 3)) if d == 2 else (lambda: rng.normal(size=4))
        a = quadric_from_axes(centre + rng.uniform(-3, 3, d), rng.uniform(*axes, d), o())
        b = quadric_from_axes(centre + rng.uniform(-3, 3, d), rng.uniform(*axes, d), o())
        try:  # far from the origin, rounding to floats can leave a matrix that is no ellipsoid
            validate_quadric(a), validate_quadric(b)
        except ValueError:
            continue
        A.append(a)
        B.append(b)
    return np.array(A), np.array(B)


@pytest.mark.parametrize("n", [3, 4])
@pytest.mark.parametrize("centre", [1e3, 1e6, -3e7])
def test_translated_stage_is_sound_and_useful(n, centre):
    rng = np.random.default_rng(int(abs(centre)) % 1000 + n)
    A, B = _far_pairs(rng, n, 150, centre)
    from core.fixed.filters import classify_translated

    codes = _relations(classify_translated(A, B))
    exact = classify(A, B, method="exact")
    decided = codes != Relation.UNDECIDED
    assert (codes[decided] == exact[decided]).all()
    if abs(centre) <= 1e6:
        assert decided.mean() > 0.5  # the first stage decides none of these at 1e6
    # batches run it on what the first stage leaves undecided; never a wrong label
    f = classify(A, B, method="float")
    assert ((f == Relation.UNDECIDED) | (f == exact)).all()


@pytest.mark.parametrize("n", [3, 4])
def test_translated_stage_abstains_on_exact_tangency_far_away(n):
    from core.fixed.filters import classify_translated

    A, B = dyadic_tangent_pair(n - 1, 2.0, 1.0, [2.0**20] * (n - 1))
    assert classify_translated(A[None], B[None])[0] == -1
    assert classify(np.stack([A, A]), np.stack([B, B])).tolist() == [Relation.TANGENT] * 2


@pytest.mark.parametrize("n", [3, 4])
def test_translated_stage_near_tangent_far_away(n):
    """Near-tangent pairs around 1e5 at gaps 1e-4..1e-12: labels from the independent oracle."""
    from oracle import oracle_relation

    from core.fixed.filters import classify_translated

    rng = np.random.default_rng(99 + n)
    d = n - 1
    for exponent in range(4, 13, 2):
        for sign in (1, -1):
            axes = rng.uniform(0.5, 2.0, d)
            r = rng.uniform(0.3, 1.5)
            c = 1e5 + rng.uniform(-3, 3, d)
            dist = (axes[0] + r) * (1 + sign * 10.0**-exponent)
            A = quadric_from_axes(c, axes, None)
            off = np.zeros(d)
            off[0] = dist
            B = quadric_from_axes(c + off, [r] * d)
            code = _relations(classify_translated(A[None], B[None]))[0]
            truth = oracle_relation(A, B)
            assert code == Relation.UNDECIDED or str(Relation(code)) == truth
