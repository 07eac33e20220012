"""The float filter: generated files are current, error bounds hold, numpy and every SIMD variant of the C agree."""

from __future__ import annotations

from fractions import Fraction as F

import numpy as np
import pytest
from flint import fmpq
from strategies import dyadic_tangent_pair

import bench.datasets as D
from core import Relation, bodies_from_axes, classify, classify_detailed, explain, quadric_from_axes
from core.fixed import _kernels as K
from core.fixed import compiled
from core.fixed.errorbound import RADIUS_FACTOR, UNIT_ROUNDOFF, gamma_constant
from core.fixed.exact import exact_pair
from core.fixed.filters import first_stage, relations, rules_numpy
from core.fixed.kernelgen import main as kernelgen_main
from core.formulae.decision import RULE_RELATION
from core.formulae.pencil import pencil_coefficients
from core.formulae.subresultants import hat_s0, hat_s1, hat_s10


def test_generated_files_are_current():
    # _kernels.py (numpy) and _kernels.h (C) are what the description generates today
    assert kernelgen_main(["--check"]) == 0


def test_extension_is_built_from_the_committed_header():
    assert compiled.available(), compiled.status()
    assert compiled._EXT.kernels_sha256() == compiled.header_sha256()


class _Run:
    """The first stage on stacks: prepared matrices (upper triangles), a_i with bounds."""

    def __init__(self, A, B):
        run = first_stage(A, B)
        n = A.shape[-1]
        self.n = n
        self.a = _full(run.a.W, n)
        self.b = _full(run.b.W, n)
        self.ea, self.eb = run.a.k, run.b.k
        self.ok = run.a.ok & run.b.ok
        self.rounded = run.a.rounded | run.b.rounded
        self.c, self.cr = run.c, run.cr


def _full(W, n):
    N = np.shape(W[0, 0])[0]
    S = np.empty((N, n, n))
    for (i, j), v in W.items():
        S[:, i, j] = S[:, j, i] = v
    return S


def _hat(n, which, vals, radii):
    v, r = getattr(K, f"hat_{which}_{n}")(vals, radii)
    return v, r * RADIUS_FACTOR + getattr(K, f"HAT_{which.upper()}_{n}_FLOOR")


@pytest.mark.parametrize("K_, Kb", [(1, 1), (10, 18), (14, 18), (99, 120)])
def test_gamma_constant_bounds_the_worst_rounding_and_is_tight(K_, Kb):
    """What the constant is for, not its formula (was: the test computed K u / (1 - K u) / (1 - u)^(Kb + 2),
    the very expression of gamma_constant). K roundings move a value by at most (1 + u)^K - 1 relative
    (every rounding at its worst, in the same direction); the bound M is computed with Kb roundings
    (M >= its exact value times (1 - u)^Kb) and C * M with two more. So C (1 - u)^(Kb + 2) must cover
    (1 + u)^K - 1, and a useful C is within a hair of it (gamma_K exceeds it by a factor 1 + O(K u))."""
    u = UNIT_ROUNDOFF
    worst = (1 + u) ** K_ - 1  # the product of K worst roundings, exactly (a Fraction)
    covered = F(gamma_constant(K_, Kb)) * (1 - u) ** (Kb + 2)
    assert worst <= covered < worst * (1 + F(1, 2**40))


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
    run = _Run(A, B)
    assert not run.rounded.any()
    for i in range(len(A)):
        coeffs = pencil_coefficients(_exact(run.a[i]), _exact(run.b[i]))
        for k, c in enumerate(coeffs):
            assert abs(fmpq(*float(run.c[k][i]).as_integer_ratio()) - c) <= fmpq(*float(run.cr[k][i]).as_integer_ratio())


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
    run = _Run(A, B)
    assert run.rounded.mean() > 0.5 and run.ok.all()
    for i in range(len(A)):
        ea, eb = int(run.ea[i]), int(run.eb[i])
        fa = fmpq(2) ** ea if ea >= 0 else fmpq(1, 2 ** (-ea))
        fb = fmpq(2) ** eb if eb >= 0 else fmpq(1, 2 ** (-eb))
        sa = 1 if A[i, 0, 0] > 0 else -1
        sb = 1 if B[i, 0, 0] > 0 else -1
        EA = [[(_fq(A[i, r, c]) + _fq(A[i, c, r])) / 2 * fa * sa for c in range(n)] for r in range(n)]
        EB = [[(_fq(B[i, r, c]) + _fq(B[i, c, r])) / 2 * fb * sb for c in range(n)] for r in range(n)]
        for k, c in enumerate(pencil_coefficients(EA, EB)):
            assert abs(_fq(run.c[k][i]) - c) <= _fq(run.cr[k][i])


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
        g, f = getattr(KK, f"FORM{n}_CONSTANTS")
        v, vm = getattr(KK, f"form{n}")(M, Mr, x, g)
        bound = vm * f + getattr(KK, f"FORM{n}_FLOOR")
        X = [_fq(xi) for xi in x] + [fmpq(1)]
        for sign in (-1, 1):
            Mt = [[_fq(M[i, j]) + sign * _fq(Mr[min(i, j), max(i, j)]) for j in range(n)] for i in range(n)]
            exact = sum(X[i] * Mt[i][j] * X[j] for i in range(n) for j in range(n))
            assert abs(_fq(v) - exact) <= _fq(bound)
        # the form's bound is not loose: within a few units of its own rounding and the radii
        perm = sum(abs(X[i]) * (abs(_fq(M[i, j])) * _fq(g) + _fq(Mr[min(i, j), max(i, j)])) * abs(X[j])
                   for i in range(n) for j in range(n))
        assert _fq(bound) <= perm * (1 + fmpq(1, 2**40)) + _fq(getattr(KK, f"FORM{n}_FLOOR"))


@pytest.mark.parametrize("n", [3, 4])
@pytest.mark.parametrize("which", ["s0", "s1", "s10"])
def test_subresultant_error_bounds_hold(n, which):
    rng = np.random.default_rng(10 * n + len(which))
    A = _random_matrices(rng, n, 40)
    B = _random_matrices(rng, n, 40)
    run = _Run(A, B)
    f = {"s0": hat_s0, "s1": hat_s1, "s10": hat_s10}[which]
    for i in range(len(A)):
        exact = f(pencil_coefficients(_exact(run.a[i]), _exact(run.b[i])))
        vals = [float(run.c[k][i]) for k in range(n + 1)]
        radii = [float(run.cr[k][i]) for k in range(n + 1)]
        v, bd = _hat(n, which, vals, radii)
        assert abs(fmpq(*float(v).as_integer_ratio()) - exact) <= fmpq(*float(bd).as_integer_ratio())


@pytest.mark.parametrize("n", [3, 4])
def test_semi_static_s0_bound_holds_for_inputs_within_relative_accuracy(n):
    """Stage 2's s0 test: for a_i known to relative accuracy rho (S0_RHO), |fl(hs0) - hs0(exact)|
    <= C s0_M + floor (core.fixed.errorbound.relative_input_constant), checked exactly at the
    corners of the box of exact inputs and inside it; the perturbation term is what the bound is
    made of (without it the corners break the bound)."""
    from core.fixed import _kernels as KK
    from core.fixed.errorbound import S0_RHO

    rng = np.random.default_rng(50 + n)
    (C,) = getattr(KK, f"HAT_S0_REL_{n}_CONSTANTS")
    floor = getattr(KK, f"HAT_S0_REL_{n}_FLOOR")
    rho = fmpq(S0_RHO.numerator, S0_RHO.denominator)
    A, B = _random_matrices(rng, n, 40), _random_matrices(rng, n, 40)
    run = _Run(A, B)
    worst = fmpq(0)
    for i in range(len(A)):
        c = [float(run.c[k][i]) for k in range(n + 1)]
        v, m = getattr(KK, f"hat_s0_rel_{n}")(c)
        bound = _fq(C * m + floor)
        for _ in range(12):
            signs = rng.choice([-1, 0, 1], n + 1) if _ % 3 else rng.choice([-1, 1], n + 1)
            exact = hat_s0([_fq(ck) * (1 + int(sg) * rho) for ck, sg in zip(c, signs, strict=True)])
            err = abs(_fq(v) - exact)
            assert err <= bound
            worst = max(worst, err / bound) if bound > 0 else worst
    assert worst > fmpq(1, 20)  # the inputs' relative error, not the rounding, fills the bound


@pytest.mark.parametrize("n", [3, 4])
def test_random_pairs_take_the_semi_static_s0_test(n):
    """Where the tree asks for s0 on random pairs, the cheap test (stage 2) tells its sign: the
    running-error test (stage 4) is left for near tangency."""
    from core.fixed.driver import NEEDS_S0_RADIUS, decide, decide_s0, pencil_bounds
    from core.fixed.lanes import NumpyLanes

    rng = np.random.default_rng(60 + n)

    def shapes(k):  # the benchmark's random pairs: centres in [-4, 4], axes 0.2 .. 3
        d = n - 1
        return np.array([
            quadric_from_axes(rng.uniform(-4, 4, d), rng.uniform(0.2, 3, d), rng.uniform(0, 3) if d == 2 else rng.normal(size=4))
            for _ in range(k)
        ])

    run = first_stage(shapes(400), shapes(400))
    asked = np.flatnonzero(run.asked_s0)
    assert asked.size > 100
    X = NumpyLanes()
    c, cr, minors = pencil_bounds(X, n, run.a, run.b)
    _, _, idx = decide(X, n, c, cr, minors, run.a.ok & run.b.ok)
    code = decide_s0(X, n, [v[asked] for v in c], [v[asked] for v in cr], idx[asked])
    assert (code != NEEDS_S0_RADIUS).mean() > 0.95


def test_kernel_tables_are_consistent():
    # the underflow floors stay far under any value the filter certifies: an unscaled matrix has
    # its largest entry >= NO_SCALE_MIN = 2^-8, so a kernel of degree <= 24 in the entries meets
    # values around 2^-192 or larger; the floors (2^-536 at most with LEAF_MAX = 2^24) lie 2^300 below
    from core.fixed.errorbound import LEAF_MAX, NO_SCALE_MIN

    assert NO_SCALE_MIN == F(1, 2**8) and LEAF_MAX <= 2**24
    for n in (3, 4):
        outputs, consts = getattr(K, f"PENCIL{n}_OUTPUTS"), getattr(K, f"PENCIL{n}_CONSTANTS")
        assert len(outputs) == len(consts) and 0 < getattr(K, f"PENCIL{n}_FLOOR") < 2.0**-900
        for which in ("s0", "s1", "s10"):
            assert 0 < getattr(K, f"HAT_{which.upper()}_{n}_FLOOR") < 2.0**-192 * 2.0**-300
    assert K.PENCIL4_OUTPUTS[:2] == ("c0", "c0_M")


def test_copies_skip_the_semi_static_s0_test_and_stay_right():
    """Ellipsoids whose quadratic blocks are proportional (spheres, translated and homothetic
    copies: s0 vanishes) skip stage 2 (driver.skips_s0), whatever the sign or power-of-two scale
    of their matrices, random pairs keep it, and a pair whose diagonals alone are proportional (s0
    not zero) skips it too and still gets the exact answer, in numpy and in C alike."""
    from oracle import oracle_relation

    from core.fixed.driver import skips_s0
    from core.fixed.lanes import NumpyLanes

    X = NumpyLanes()

    def skip(A, B):
        return np.asarray(skips_s0(X, 4, lambda i, j: A[:, i, j], lambda i, j: B[:, i, j]))

    rng = np.random.default_rng(5)
    SA, SB = _structured(rng, 4, 90)
    assert skip(SA, SB).all()
    assert skip(-SA, SB * 2.0**-30).all() and skip(SA * 2.0**40, -SB).all()
    RA, RB = _random_matrices(rng, 4, 200), _random_matrices(rng, 4, 200)
    assert not skip(RA, RB).any()
    assert skips_s0(X, 3, None, None) is False  # 2D: s0 of copies does not vanish
    # same diagonals, different off-diagonal entries: not copies, s0 generic
    def quadric(Q, c):  # [[Q, -Q c], [-c^T Q, c^T Q c - 1]]
        M = np.empty((4, 4))
        M[:3, :3], M[:3, 3] = Q, -Q @ c
        M[3, :3], M[3, 3] = M[:3, 3], c @ Q @ c - 1.0
        return M

    Q = np.diag([1.0, 0.5, 0.25])
    Qb = Q + 0.125 * (np.eye(3)[0][:, None] * np.eye(3)[1] + np.eye(3)[1][:, None] * np.eye(3)[0])
    A = np.array([quadric(Q, rng.uniform(-3, 3, 3)) for _ in range(80)])
    B = np.array([quadric(Qb, rng.uniform(-3, 3, 3)) for _ in range(80)])
    assert skip(A, B).all()
    want = rules_numpy(A, B)
    assert (compiled.rules(A, B, threads=1) == want).all()
    got = [str(Relation(int(g))) for g in classify(A, B)]
    assert got == [oracle_relation(A[i], B[i]) for i in range(len(A))]
    assert {"overlap", "separate"} <= set(got)
    assert (want >= 0).mean() > 0.9  # still decided by the float filter


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


def _mixed(n, seed=42):
    """Random pairs with every case of the prepare step, and structured and numpy-built pairs."""
    rng = np.random.default_rng(seed + n)
    A = _random_matrices(rng, n, 300)
    B = _random_matrices(rng, n, 300)
    T1, T2 = dyadic_tangent_pair(n - 1, 2.0, 1.0, [0.0] * (n - 1))
    A[:5], B[:5] = T1, T2  # exactly tangent: must abstain
    A[5] = -A[5]  # flipped sign
    A[60:120:2] *= -1.0  # more flipped signs, of A, of B and of both: the unscaled first pass of
    B[61:120:3] *= -1.0  # the C applies them to the pencil's results, not to the entries
    B[6, 0, 1] += 1e-3  # not symmetric
    A[7, 1, 1] = np.nan
    B[8] = A[8]  # identical
    A[9:60:3] *= 10.0 ** rng.integers(-150, 150, (17, 1, 1))  # scaled by a power of two in prepare
    B[10:60:7] *= 2.0**-1040  # subnormal entries
    A[11] *= 2.0**1000  # near the top of the float range
    B[12, 2, 1] = np.inf
    SA, SB = _structured(rng, n, 120)
    NA, NB = _numpy_built(rng, n, 64), _numpy_built(rng, n, 64)  # symmetric up to rounding: the full prepare
    NA[::5] *= 1e-7  # ... and rescaled
    NB[1::5, 0, n - 1] = NB[1::5, n - 1, 0] * (1 + 2.0**-30)  # within the tolerance, far from exact
    return np.concatenate([A, SA, NA]), np.concatenate([B, SB, NB])


def _every_variant(A, B):
    """Rule ids of the C on every SIMD variant this CPU runs (restoring the chosen one)."""
    assert compiled.available(), compiled.status()
    chosen = compiled.variant()
    out = {}
    try:
        for v in compiled.variants():
            compiled.select(v)
            out[v] = compiled.rules(A, B, threads=1)
    finally:
        compiled.select(chosen)
    return out


@pytest.mark.parametrize("n", [3, 4])
def test_numpy_and_every_simd_variant_agree_bit_for_bit(n):
    A, B = _mixed(n)
    expected = rules_numpy(A, B)  # the description run by numpy
    runs = _every_variant(A, B)
    assert "baseline" in runs
    for v, got in runs.items():
        assert (got == expected).all(), (v, np.flatnonzero(got != expected)[:10])
    assert (compiled.rules(A, B, threads=4) == expected).all()  # split over threads
    one = [compiled.rule_one(A[i], B[i]) for i in range(0, len(A), 5)]
    assert one == expected[::5].tolist()
    assert (expected[:5] == -1).all() and (expected[6:8] == -1).all() and expected[12] == -1
    assert RULE_RELATION[expected[8]] == Relation.OVERLAP or expected[8] == -1
    # the structured pairs: decided by the certificates, never wrong
    from oracle import oracle_relation

    assert (expected[300:420] >= 0).mean() > 0.95
    assert (expected[420:] >= 0).mean() > 0.95  # numpy-built pairs stay in the filter
    for i in range(300, len(A), 7):
        if expected[i] >= 0:
            assert str(Relation(int(RULE_RELATION[expected[i]]))) == oracle_relation(A[i], B[i])


@pytest.mark.parametrize("n", [3, 4])
def test_a_pair_answers_alike_whatever_its_neighbours_in_the_block(n):
    """The C runs each later stage in place or on packed subsets, by how many pairs of a block of
    8 or 16 need it: shuffled, repeated and cut at several lengths, each pair still gets the rule
    of the numpy description, and the undecided count is that of its rules."""
    A, B = _mixed(n)
    expected = rules_numpy(A, B)
    rng = np.random.default_rng(n)
    order = np.concatenate([rng.permutation(len(A)) for _ in range(3)])
    A2, B2, want = np.ascontiguousarray(A[order]), np.ascontiguousarray(B[order]), expected[order]
    for v, got in _every_variant(A2, B2).items():
        assert (got == want).all(), (v, np.flatnonzero(got != want)[:10])
    table = np.arange(256, dtype=np.int64).astype(np.int8)  # rule ids through the table: the same bytes
    for count in (1, 7, 9, 17, 100, len(A2)):
        got, undecided = compiled.mapped(A2[:count], B2[:count], table, threads=1)
        assert (got == want[:count]).all() and undecided == int(np.count_nonzero(want[:count] < 0))


def _tangent_spheres(n, count):
    """Externally tangent spheres (circles) with dyadic radii along the axes: exactly tangent, so
    every float test abstains and the pair reaches the last stage of the filter, undecided."""
    d = n - 1
    A, B = [], []
    for k in range(count):
        r = 2.0 ** (k % 5 - 2)
        axis = np.zeros(d)
        axis[k % d] = (-1) ** k * 2 * r
        A.append(quadric_from_axes(np.zeros(d), [r] * d))
        B.append(quadric_from_axes(axis, [r] * d))
    return np.array(A), np.array(B)


@pytest.mark.parametrize("n", [3, 4])
def test_pairs_left_to_the_full_certificates_answer_from_the_queue(n):
    """The pairs stage 3a leaves open wait in a queue that runs the full certificates and the
    running-error s0 test a block at a time, and once more at the end of a batch: in runs
    longer than a block, one per block among pairs decided earlier, cut at every length around
    the queue's size, through the table, each gets the rule of the numpy description and the
    undecided among them are counted."""
    from core.fixed.driver import RULE_POINT

    rng = np.random.default_rng(7 + n)
    SA, SB = _structured(rng, n, 900)
    TA, TB = _tangent_spheres(n, 40)
    A, B = np.concatenate([SA, TA]), np.concatenate([SB, TB])
    expected = rules_numpy(A, B)
    late = np.flatnonzero(expected == RULE_POINT)  # common-point: only the full certificates give it
    tangent = np.arange(len(SA), len(A))
    assert (expected[tangent] == -1).all()  # the running-error s0 test too could not tell
    early = np.flatnonzero((expected >= 0) & (expected != RULE_POINT))
    assert (late.size >= 20 or n == 3) and early.size >= 200, (late.size, early.size)  # 2D: s0 decides copies
    run = np.concatenate([late, tangent])  # more than two blocks (8 or 16 pairs) of queued pairs in a row
    scattered = np.concatenate([np.concatenate([[q], early[7 * i:7 * i + 7]]) for i, q in enumerate(run[:25])])
    order = np.concatenate([run, scattered, rng.permutation(run), early[:5]])
    A2, B2, want = np.ascontiguousarray(A[order]), np.ascontiguousarray(B[order]), expected[order]
    for v, got in _every_variant(A2, B2).items():
        assert (got == want).all(), (v, np.flatnonzero(got != want)[:10])
    table = np.arange(256, dtype=np.int64).astype(np.int8)
    for count in (1, 7, 8, 9, 15, 16, 17, 33, len(run), len(run) + 1, len(run) + 9, len(A2)):
        got, undecided = compiled.mapped(A2[:count], B2[:count], table, threads=1)
        assert (got == want[:count]).all() and undecided == int(np.count_nonzero(want[:count] < 0)), count


@pytest.mark.parametrize("n", [3, 4])
def test_kernel_writes_relation_codes_and_counts_the_undecided(n):
    # classify_float's path: the C maps each rule id through a 256-byte table as it finishes a
    # block and returns how many pairs it left undecided; the same as relations() of the rule ids
    from core.fixed.filters import _RELATION_OF

    A, B = _mixed(n, seed=5)
    expected = rules_numpy(A, B)
    assert (expected == -1).sum() >= 5  # the exactly tangent and invalid pairs: the count is tested
    chosen = compiled.variant()
    try:
        for v in compiled.variants():
            compiled.select(v)
            for threads in (1, 3):
                codes, undecided = compiled.mapped(A, B, _RELATION_OF, threads=threads)
                assert codes.dtype == np.int8 and (codes == relations(expected)).all(), (v, threads)
                assert undecided == int((expected == -1).sum()), (v, threads)
            marks = np.arange(256, dtype=np.uint8).view(np.int8)  # the identity: rule ids as bytes
            assert (compiled.mapped(A, B, marks, threads=1)[0] == expected).all(), v
    finally:
        compiled.select(chosen)
    from core.fixed import _filter

    with pytest.raises(ValueError, match="256 bytes"):
        _filter.classify(n, A[:2].copy(), B[:2].copy(), np.empty(2, np.int8), b"\x00" * 10)


@pytest.mark.parametrize("n", [3, 4])
def test_float32_input_is_certified_for_its_own_values(n):
    # float32 entries widen exactly: the C reads them as they are (half the bytes) and agrees
    # with the numpy description on the widened values; labels against the exact path
    A, B = _mixed(n, seed=7)
    with np.errstate(over="ignore"):  # the pairs scaled beyond the float32 range become inf: abstain
        A32, B32 = A.astype(np.float32), B.astype(np.float32)
    expected = rules_numpy(A32.astype(np.float64), B32.astype(np.float64))
    for v, got in _every_variant(A32, B32).items():
        assert (got == expected).all(), v
    codes = classify(A32, B32, method="float", on_invalid="mark")
    decided = np.flatnonzero(codes >= 0)
    assert decided.size > 0.8 * len(A)
    exact = classify(A32[decided[::9]], B32[decided[::9]], method="exact", on_invalid="mark")
    assert (codes[decided[::9]] == exact).all()


def _benchmark_sets(dim):
    from bench import datasets as D

    sets = [D.random_pairs(dim, 60, seed=3), D.tangent_pairs(dim, 12, seed=3)]
    sets += [D.structured_pairs(dim, 30, kind=k, seed=3) for k in D.STRUCTURED_KINDS]
    sets += [D.extreme_pairs(dim, 12, kind=k, seed=3) for k in D.EXTREME_KINDS]
    sets += [D.big_small_pairs(dim, 16, gap=g, sign=s, seed=3) for g in (1e-3, 1e-1) for s in (1, -1)]
    return sets


def _near_tangent_sets(dim):
    """Adversarial: near-tangent pairs at relative gaps 1e-3 .. 1e-16 on both sides."""
    from bench import datasets as D

    return [D.near_tangent_pairs(dim, 6, gap=10.0**-e, sign=s, seed=e) for e in (3, 6, 9, 12, 14, 16) for s in (1, -1)]


@pytest.mark.parametrize("dim", [2, 3])
def test_vector_kernel_agrees_with_the_exact_path_on_benchmark_and_near_tangent_sets(dim):
    """Every SIMD variant on every data set of the benchmark and on near-tangent pairs: where it
    decides, the label is the exact one (the oracle's: exact characteristic polynomial and
    certified root isolation), and it decides exactly what the numpy description decides."""
    for ds in _benchmark_sets(dim) + _near_tangent_sets(dim):
        expected = rules_numpy(ds.A, ds.B)
        for v, got in _every_variant(ds.A, ds.B).items():
            assert (got == expected).all(), (ds.name, v)
        codes = relations(expected)
        decided = codes != Relation.UNDECIDED
        assert (codes[decided] == ds.truth[decided]).all(), ds.name
        if ds.family == "tangent":
            assert not decided.any()  # a float filter never certifies tangency


@pytest.mark.parametrize("dim", [2, 3])
def test_pairs_with_large_entries_are_certified_without_the_scaling(dim):
    """Matrices whose largest entry lies in (2^8, 2^24] (bodies far from the origin, as in a
    simulation box) now take the unscaled first pass (LEAF_MAX = 2^24, was 2^8): the benchmark's
    sets and near-tangent pairs with every matrix multiplied by an exact 2^j (the relation does
    not change) are decided alike by every SIMD variant and the numpy description, every decided
    label is the oracle's, and random pairs are decided as at size 1."""
    from core.fixed.errorbound import LEAF_MAX

    rng = np.random.default_rng(70 + dim)
    for ds in _benchmark_sets(dim) + _near_tangent_sets(dim):
        N = len(ds.A)
        # largest entry of each matrix moved into [2^9, 2^24) by an exact power of two
        A, B = (np.ldexp(M, (rng.integers(10, 25, N) - np.frexp(np.abs(M).max(axis=(1, 2)))[1])[:, None, None]) for M in (ds.A, ds.B))
        top = np.abs(np.concatenate([A, B])).max(axis=(1, 2))
        assert ((top >= 2.0**9) & (top < LEAF_MAX)).all(), ds.name
        expected = rules_numpy(A, B)
        for v, got in _every_variant(A, B).items():
            assert (got == expected).all(), (ds.name, v)
        codes = relations(expected)
        decided = codes != Relation.UNDECIDED
        assert (codes[decided] == ds.truth[decided]).all(), ds.name
        if ds.family == "random":
            assert decided.mean() >= 0.95, ds.name
        if ds.family == "tangent":
            assert not decided.any()


def test_numpy_fallback_warns_once_naming_cause_and_fix(monkeypatch):
    A, B = _mixed(3, seed=5)
    expected = classify(A, B, method="float", on_invalid="mark")
    monkeypatch.setattr(compiled, "_EXT", None)
    monkeypatch.setattr(compiled, "_STATUS", "the compiled float filter core.fixed._filter is not built (test)")
    monkeypatch.setitem(compiled._state, "warned", False)
    with pytest.warns(RuntimeWarning, match=r"not built \(test\).*numpy filter.*pip install -e \."):
        got = classify(A, B, method="float", on_invalid="mark")
    assert (got == expected).all()
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # once only
        classify(A, B, method="float", on_invalid="mark")


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
    checked = 0
    for _ in range(20):
        A = _random_matrices(rng, n, 1)[0]
        B = _random_matrices(rng, n, 1)[0]
        e = explain(A, B)
        if e.certified_by != "float":
            continue
        checked += 1
        pair = exact_pair(A, B, scaled=False)
        for q, c in zip(e.coefficients, pair.coefficients, strict=True):
            assert q.bound is not None and abs(F(q.approx) - F(int(c.p), int(c.q))) <= F(q.bound) * (1 + F(1, 10**6))
            assert q.sign == (c > 0) - (c < 0)
    assert checked >= 10  # most pairs are the float stage's (19 and 16 of 20 today): the loop checks something


def _plain_matrix(c, r, o):
    """The float builder's formula without its checks: past 2^26 radii from the origin the builders
    refuse the shape (FAR_FROM_ORIGIN), but the filter must be sound on whatever matrix it is given."""
    from core.shapes.quadrics import _assemble_plain, rotations_from_orientations

    return _assemble_plain(np.array([c]), np.array([r]), rotations_from_orientations(np.array([o]), 1, len(c)))[0]


def _far_pairs(rng, n, count, centre, axes=(0.3, 3.0), gap=None):
    d = n - 1
    from core import validate_quadric

    A, B = [], []
    while len(A) < count:
        o = (lambda: rng.uniform(0, 3)) if d == 2 else (lambda: rng.normal(size=4))
        a = _plain_matrix(centre + rng.uniform(-3, 3, d), rng.uniform(*axes, d), o())
        b = _plain_matrix(centre + rng.uniform(-3, 3, d), rng.uniform(*axes, d), o())
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

    codes = relations(classify_translated(A, B))
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
            code = relations(classify_translated(A[None], B[None]))[0]
            truth = oracle_relation(A, B)
            assert code == Relation.UNDECIDED or str(Relation(code)) == truth


def _space_scaled(M, e, j):
    """The same bodies in space scaled by 2^-e, each matrix times 2^j: the congruence by
    diag(1, .., 1, 2^e) and a positive factor, exact in floats (checked): the same relation."""
    n = M.shape[-1]
    g = np.zeros((n, n), dtype=np.int64)
    g[:, n - 1] += e
    g[n - 1, :] += e
    g = g[None] + np.asarray(j)[:, None, None]
    out = np.ldexp(M, g)
    assert (np.ldexp(out, -g) == M).all() and ((out == 0) | (np.abs(out) >= np.finfo(float).tiny)).all()
    return out


@pytest.mark.parametrize("dim", [3, 2])
def test_the_float_filter_certifies_bodies_at_any_float_scale(dim):
    """Was: bodies far from size 1 (1e9, 1e-150, 1e300: |Q| ~ 1/s^2, the corner ~ |c|^2/s^2) spread
    their entries over decades the bounds cannot follow, so every such pair went to exact
    arithmetic (1e9: 999 of 1000 random pairs). The second stage now scales space by a power of
    two to the bodies' size first. Pairs of the benchmark's sets (random, tangent, near-tangent
    down to 1e-13, spheres and copies) moved to 2^-900 .. 2^900 exactly: the oracle's labels of
    the unscaled pairs hold (a common scaling keeps the relation), the filter is never wrong, and
    it certifies nearly every random pair at every scale."""
    rng = np.random.default_rng(dim)
    sets = [D.random_pairs(dim, 120, seed=3), D.tangent_pairs(dim, 60, seed=4)]
    sets += [D.near_tangent_pairs(dim, 40, gap=g, sign=s, seed=5) for g in (1e-3, 1e-8, 1e-13) for s in (1, -1)]
    sets += [D.structured_pairs(dim, 40, kind=k, seed=6) for k in D.STRUCTURED_KINDS]
    for e in (-900, -300, -30, 30, 300, 900):
        for ds in sets:
            N = len(ds.A)
            A, B = (_space_scaled(M, e, -e + rng.integers(-8, 8, N)) for M in (ds.A, ds.B))  # entries 2^-e Q, m, 2^e k
            res = classify_detailed(A, B)
            assert (res.relation == ds.truth).all(), (ds.name, e)
            f = classify(A, B, method="float")
            assert ((f == Relation.UNDECIDED) | (f == ds.truth)).all(), (ds.name, e)
            if ds.family == "random":
                assert (f != Relation.UNDECIDED).mean() >= 0.95, (ds.name, e, (f == Relation.UNDECIDED).sum())



def test_the_numpy_fallback_agrees_at_any_float_scale(monkeypatch):
    """The balanced first stage runs compiled, or as its numpy twin without the extension: the
    same rule ids for pairs far from size 1 (and the translated stage after either)."""
    from core.fixed.filters import rules_float

    sets = [D.random_pairs(3, 80, seed=7), D.near_tangent_pairs(3, 40, gap=1e-8, sign=1, seed=8), D.random_pairs(2, 80, seed=9)]
    cases = [(_space_scaled(ds.A, e, np.full(len(ds.A), -e)), _space_scaled(ds.B, e, np.full(len(ds.B), -e + 3)))
             for ds in sets for e in (-700, 400)]
    with np.errstate(over="ignore"):  # _mixed makes an inf on purpose
        cases += [_mixed(3, seed=5), _mixed(4, seed=6)]  # every case of the prepare step, scaled entries among them
    compiled_rules = [rules_float(A, B) for A, B in cases]
    assert all((r >= 0).mean() > 0.5 for r in compiled_rules)
    monkeypatch.setattr(compiled, "_EXT", None)
    monkeypatch.setattr(compiled, "_STATUS", "the compiled float filter core.fixed._filter is not built (test)")
    monkeypatch.setitem(compiled._state, "warned", True)
    assert all((rules_float(A, B) == r).all() for (A, B), r in zip(cases, compiled_rules, strict=True))


def _exact_validity_error(A, B):
    """The exact verdict on a pair's input (independent of the filter): None, or the error."""
    from core.shapes.quadrics import validate_quadric

    try:
        validate_quadric(A, name="A")
        validate_quadric(B, name="B")
    except ValueError as e:
        return str(e)
    return None


def _near_symmetric(n):
    """Off-diagonal asymmetry at 0.5, 0.99, 1.01 and 2 times the exact tolerance (both signs)."""
    from core.shapes.quadrics import SYMMETRY_TOLERANCE

    base = quadric_from_axes([0.5] * (n - 1), [1.0, 2.0, 3.0][: n - 1], None)
    A, B = [], []
    for f in (0.5, 0.99, 1.01, 2.0, -0.5, -0.99, -1.01, -2.0):
        M = np.array(base, dtype=float)
        M[0, 1] = M[1, 0] + f * float(SYMMETRY_TOLERANCE) * max(abs(M[0]).max(), abs(M[1]).max())
        A.append(M)
        B.append(quadric_from_axes([3.0] * (n - 1), [1.0] * (n - 1), None))
    return np.array(A), np.array(B)


@pytest.mark.parametrize("n", [3, 4])
def test_certified_validity_implies_exact_validity(n):
    """Where the filter proves a pair valid, exact validation agrees: every benchmark, near-tangent,
    hostile (NaN, inf, flipped, asymmetric, subnormal) and near-tolerance pair, float64 and float32."""
    from core.fixed.filters import certified_valid

    sets = [_mixed(n, seed=7), _near_symmetric(n)]
    sets += [(ds.A, ds.B) for ds in _benchmark_sets(n - 1) + _near_tangent_sets(n - 1)]
    proven_total = 0
    for A, B in sets:
        with np.errstate(over="ignore"):  # entries near 2^1000 become inf in float32: hostile input too
            narrow = (A.astype(np.float32), B.astype(np.float32))
        for a, b in ((A, B), narrow):
            proven = certified_valid(a, b)
            proven_total += int(proven.sum())
            for i in np.flatnonzero(proven):
                assert _exact_validity_error(a[i], b[i]) is None, (i, a[i], b[i])
    assert proven_total > 1000  # the proof holds on most valid pairs, not vacuously


@pytest.mark.parametrize("n", [3, 4])
def test_float_method_validates_exactly_only_what_the_filter_could_not_prove(n, monkeypatch):
    """method="float" on pairs it leaves undecided: no exact validation where the filter proved
    the input valid (near tangency: 0.15 ms per pair, 3000x the filter), and invalid input still
    marked or refused with the exact message."""
    import core.fixed.classify as classify_module
    from bench import datasets as D

    near = [D.near_tangent_pairs(n - 1, 20, gap=g, sign=s, seed=4) for g in (1e-13, 1e-16) for s in (1, -1)]
    A = np.concatenate([ds.A for ds in near])
    B = np.concatenate([ds.B for ds in near])
    calls = []
    real = classify_module._validate_pair
    monkeypatch.setattr(classify_module, "_validate_pair", lambda a, b: (calls.append(1), real(a, b))[1])
    got = classify(A, B, method="float")
    assert (got == Relation.UNDECIDED).sum() >= len(A) // 2, (got == Relation.UNDECIDED).sum()  # what this is about
    assert calls == []
    decided = got != Relation.UNDECIDED
    truth = np.concatenate([ds.truth for ds in near])
    assert (got[decided] == truth[decided]).all()

    MA, MB = _mixed(n, seed=11)
    marked = classify(MA, MB, method="float", on_invalid="mark")
    for i in range(len(MA)):
        error = _exact_validity_error(MA[i], MB[i])
        assert (marked[i] == Relation.INVALID) == (error is not None), (i, error)
        if error is not None:
            with pytest.raises(ValueError) as e:
                classify(MA[i], MB[i], method="float")
            assert str(e.value) == error


@pytest.mark.parametrize("n", [3, 4])
def test_integer_matrices_of_the_exact_path_are_positive_multiples_of_the_exact_symmetric_part(n):
    """The exact path's shortcut for float64 input (integers, no rationals) against the general
    reader (``normalised_quadratic_part``, fmpq): where the shortcut applies it gives c * E with
    one c > 0 (so every sign downstream is E's); where it declines, the input is non-finite,
    asymmetric beyond rounding, or not definite (the general path then raises)."""
    from core.fixed.exact import _float_int_matrix
    from core.shapes.quadrics import normalised_quadratic_part

    A, B = _mixed(n, seed=13)
    NA, NB = _near_symmetric(n)
    zeros = np.zeros((2, n, n))
    zeros[1, 0, 0] = -0.0
    taken = 0
    with np.errstate(over="ignore"):  # some entries overflow to inf: hostile input too
        scaled = [*(A[:40] * 2.0**-1060), *(B[:40] * 2.0**1000)]
    for M in [*A, *B, *NA, *NB, *zeros, *scaled]:
        ints = _float_int_matrix(np.ascontiguousarray(M))
        try:
            E = normalised_quadratic_part(M)
        except ValueError:
            E = None
        if ints is None:
            assert E is None or not np.isfinite(M).all() or not np.array_equal(M, M.T) or not M.any(), M
            continue
        assert E is not None, M
        k, l = next((i, j) for i in range(n) for j in range(n) if E[i][j] != 0)
        c = fmpq(ints[k][l]) / E[k][l]
        assert c > 0 and all(fmpq(ints[i][j]) == c * E[i][j] for i in range(n) for j in range(n)), M
        taken += 1
    assert taken > 500


@pytest.mark.parametrize("n", [3, 4])
def test_validity_in_integers_agrees_with_the_rational_reader(n):
    """valid_float_matrix (the integer shortcut of the exact validation) against validate_quadric
    (fmpq): True only for valid matrices, and for every valid one among hostile, scaled,
    near-tolerance, flipped, empty (det > 0) and point (det = 0) ellipses/ellipsoids."""
    from core.fixed.exact import valid_float_matrix
    from core.shapes.quadrics import validate_quadric

    A, B = _mixed(n, seed=17)
    NA, NB = _near_symmetric(n)
    empty = np.array([np.diag([1.0] * (n - 1) + [1.0]), np.diag([-1.0] * (n - 1) + [-1.0])])  # no real points
    point = np.diag([1.0] * (n - 1) + [0.0])[None]  # det = 0
    with np.errstate(over="ignore"):
        scaled = [*(A[:40] * 2.0**-1060), *(B[:40] * 2.0**1000)]
    seen = {True: 0, False: 0}
    for M in [*A, *B, *NA, *NB, *empty, *point, *scaled]:
        try:
            validate_quadric(M)
            valid = True
        except ValueError:
            valid = False
        got = valid_float_matrix(np.ascontiguousarray(M))
        assert got == valid, M  # on these inputs the shortcut never has to decline a valid matrix
        seen[valid] += 1
    assert seen[True] > 500 and seen[False] >= 8, seen


def test_scaled_pairs_refuse_what_the_exact_path_refuses():
    """The scaling for bodies far from size 1 never turns a refused matrix into an accepted one:
    asymmetries around the tolerance (relative to rows the scaling changes unequally), at scales
    1 .. 1e150, give the exact path's error or its label, stacked and one pair at a time."""
    def outcome(f):
        try:
            return ("label", np.asarray(f()).tolist())
        except ValueError as e:
            return ("error", str(e).split(":")[0])

    for s in (1.0, 1e6, 1e9, 1e30, 1e150):
        Q = bodies_from_axes([[1.0 * s, 2 * s, 3 * s], [4 * s, 2 * s, 3 * s]], [[1.0 * s] * 3, [1.5 * s] * 3])
        for factor in (1 + 1e-9, 1 + 1e-6, 1 + 1e-3, 1.5, 3.0, 100.0):
            A, B = Q[0].copy(), Q[1].copy()
            A[0, 3] *= factor  # A symmetric only up to this factor
            for a, b in ((A[None], B[None]), (A, B)):
                got = outcome(lambda a=a, b=b: classify(a, b))
                want = outcome(lambda a=a, b=b: classify(a, b, method="exact"))
                assert got == want, (s, factor, got, want)


def test_the_compiled_change_of_units_is_its_numpy_twin_bit_for_bit(monkeypatch):
    """The second stage's scaling of space to the bodies' size runs as one compiled loop
    (``balance`` in core/fixed/_filter.c; the numpy array passes cost ~0.9 us a pair: 100,000
    pairs at 1e9 took 99 ms against 7 ms at scale 1). Both must give the same e, the same
    matrices and shifts bit for bit: pairs at 2^-1000 .. 2^1000, with periodic shifts, and every
    edge of the rule (non-finite, zero, asymmetric, subnormal entries, centred bodies with m = 0,
    a zero corner, exponents at the clip of +-1000, changed entries that overflow or underflow, or
    that round up to the smallest normal number)."""
    from core.fixed import filters
    from core.shapes.quadrics import quadrics_from_axes

    if not compiled.balance_available():
        pytest.skip("the compiled extension (with balance) is not built")
    rng = np.random.default_rng(11)
    cases = []
    for dim in (2, 3):
        N = 300
        c, r = rng.uniform(-5, 5, (2 * N, dim)), rng.uniform(0.3, 2, (2 * N, dim))
        q = rng.normal(size=(2 * N, 4)) if dim == 3 else rng.uniform(0, 6, 2 * N)
        for s in (2.0**-1000, 1e-300, 1e-9, 1.0, 3e7, 1e150, 2.0**1000):
            Q = quadrics_from_axes(c * s, r * s, q)
            shift = rng.uniform(-10, 10, (N, dim)) * s
            cases.append((Q[:N], Q[N:], shift))
        A, B = quadrics_from_axes(c, r, q)[:N].copy(), quadrics_from_axes(c * 1e120, r * 1e120, q)[N:].copy()
        d = dim
        A[0, 0, 0] = np.nan
        A[1, d, d] = np.inf
        A[2] = 0.0
        A[3, 0, 1] += 1e-3  # not symmetric
        A[4, :d, d] = A[4, d, :d] = 0.0  # centred: m = 0
        A[5, d, d] = 0.0  # zero corner
        A[6, d, d] = 1e-310  # a subnormal corner
        A[7, :d, :d] *= 2.0**-1040  # Q subnormal: a huge body
        A[8, :d, :d] *= 2.0**1000  # changed entries underflow
        A[9, d, :d] = A[9, :d, d] = 1e300  # changed entries overflow
        A[10, :d, :d] = 2.0**-1074  # e beyond the clip
        for M in (A, B):  # e = -1000 (clipped), and m's second entry times 2^-1000 rounds up to 2^-1022
            M[11] = 0.0
            M[11, :d, :d] = np.eye(d) * 2.0**-1000
            M[11, 0, d] = M[11, d, 0] = 2.0**1000
            M[11, 1, d] = M[11, d, 1] = (2 - 2.0**-52) * 2.0**-23
        cases.append((A, B, rng.uniform(-1e120, 1e120, (N, d))))
    for A, B, shift in cases:
        for s in (None, shift):
            got = filters._balanced(A, B, s)
            with monkeypatch.context() as m:
                m.setattr(compiled, "balance_available", lambda: False)
                want = filters._balanced(A, B, s)
            assert (got[3] == want[3]).all()
            for x, y in zip(got[:3], want[:3], strict=True):
                assert (x is None) == (y is None)
                if x is not None:
                    assert np.array_equal(x.view(np.int64), np.asarray(y, dtype=np.float64).view(np.int64))
    moved = [filters._balanced(A, B, None)[3].mean() for A, B, _ in cases]
    assert min(moved[:7]) > 0.5  # not vacuous: most pairs move at every scale (bodies of size ~5 at scale 1)


def test_a_power_of_two_that_rounds_up_to_the_smallest_normal_is_not_exact():
    """x 2^k exactly halfway below 2^-1022 rounds (to even) up to 2^-1022, a normal number: the
    check "finite and normal" called it exact, so a scaled matrix could differ from the true one
    by 2^-1075. The way back (y 2^-k == x) tells; an exact product still passes."""
    from core.fixed.filters import times_power_of_two

    x = np.array([(2 - 2.0**-52) * 2.0**-23, 1.5 * 2.0**-21, 0.0])
    y, ok = times_power_of_two(x, np.array([-1000, -1000, -1000]))
    assert y[0] == 2.0**-1022  # rounded up to the smallest normal
    assert ok.tolist() == [False, True, True]
