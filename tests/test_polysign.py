"""The float sign filter for exact polynomials (core.algebra.polysign): it may abstain, never be wrong.

Ground truth: exact evaluation in Q(sqrt d) (flint fmpq_poly at the exact binary value of the
float t, sign of a + b sqrt(d) by squaring), not the code under test.
"""

from __future__ import annotations

import math

from flint import fmpq, fmpq_poly
from hypothesis import given, settings
from hypothesis import strategies as st

from core.algebra.polysign import FloatPoly
from core.algebra.qsqrt import QSqrtPoly, sign_qsqrt
from core.shapes.numbers import to_fmpq

rationals = st.builds(fmpq, st.integers(-10**12, 10**12), st.integers(1, 10**6))


def exact_sign(P: QSqrtPoly, t: float) -> int:
    a, b = P.at(to_fmpq(t))
    return sign_qsqrt(a, b, P.d)


@st.composite
def poly_and_points(draw):
    """A polynomial in Q(sqrt d)[t] with known real roots (some of them sqrt(d)-rational), a scale
    from 1e-300 to 1e300, and float points on and next to the roots."""
    d = draw(st.sampled_from([1, 2, 3, 5, 7]))
    roots = draw(st.lists(rationals, max_size=4))
    rest = draw(st.lists(rationals, min_size=1, max_size=12))
    P = QSqrtPoly(fmpq_poly(rest), fmpq_poly(draw(st.lists(rationals, max_size=6))), d)
    for r in roots:
        P = P * QSqrtPoly(fmpq_poly([-r, 1]))
    if d != 1 and draw(st.booleans()):  # a root at sqrt(d) + r: massive cancellation in Q(sqrt d)
        r = draw(rationals)
        P = P * QSqrtPoly(fmpq_poly([-r, 1]), fmpq_poly([-1]), d)
        roots = roots + [fmpq(int(float(r) * 2**40), 2**40) + fmpq(int(math.sqrt(d) * 2**40), 2**40)]
    k = draw(st.integers(-300, 300))
    P = P * QSqrtPoly(fmpq(10) ** k if k >= 0 else fmpq(1, 10 ** -k))
    points = []
    for r in roots:
        x = float(r)
        points += [x, math.nextafter(x, math.inf), math.nextafter(x, -math.inf), x * (1 + 1e-9)]
    points += draw(st.lists(st.floats(-1e6, 1e6, allow_nan=False), max_size=4))
    points += draw(st.lists(st.floats(-1e-300, 1e-300, allow_nan=False), max_size=2))
    return P, points


@settings(deadline=None, max_examples=300)
@given(poly_and_points())
def test_float_sign_never_contradicts_exact(case):
    P, points = case
    fp = FloatPoly(P.p, P.q, P.d)
    for t in points:
        s = fp.sign_at(t)
        if s is not None:
            assert s == exact_sign(P, t), (P, t)


def test_filter_decides_well_conditioned_cases():
    """The filter must also be useful: away from roots it decides (this is what it is for)."""
    P = QSqrtPoly(fmpq_poly([-2, 0, 1]))  # t^2 - 2
    fp = FloatPoly(P.p)
    assert [fp.sign_at(t) for t in (-3.0, 0.0, 1.0, 1.5, 1e100, 1e200)] == [1, -1, -1, 1, 1, None]  # 1e400 overflows
    Q = QSqrtPoly(fmpq_poly([0, 1]), fmpq_poly([-1]), 2)  # t - sqrt(2)
    fq = FloatPoly(Q.p, Q.q, Q.d)
    s2 = math.sqrt(2)
    assert fq.sign_at(1.0) == -1 and fq.sign_at(2.0) == 1
    assert fq.sign_at(1.41421356) == -1 and fq.sign_at(1.41421357) == 1
    assert fq.sign_at(s2) is None  # within rounding of sqrt(2): abstains, the caller goes exact
    assert FloatPoly(fmpq_poly()).sign_at(5.0) == 0


def test_qsqrt_method_falls_back_to_exact_when_the_filter_abstains():
    """QSqrtPoly.float_sign_at abstains (None) only; decide_at then evaluates exactly."""
    from core import analyse
    from core.moving.presets import preset_arguments
    from core.moving.signs import decide_at

    r = analyse(**preset_arguments("example-30"))
    polys = r.polynomials()
    lo, hi = r._window(None, None)
    abstained = 0
    for i in range(60):
        t = lo + (hi - lo) * (i + 0.5) / 60
        for name, p in polys.items():
            s = p.float_sign_at(t)
            abstained += s is None
            if s is not None:
                assert s == p.sign_at_rational(to_fmpq(t)), (name, t)
        dec, signs = decide_at(r.n, polys, t)
        assert dec.relation == r.relation_at(t)
        assert signs == decide_at(r.n, polys, to_fmpq(t))[1]  # float t vs its exact rational
    assert abstained > 0  # Example 30's s0 is ill-conditioned: the exact path is exercised


@st.composite
def clustered_roots(draw):
    """Wilkinson-like products prod (t - r_i) with up to 16 nearby rational roots: Horner's
    rounding error is then many ulps of |value| (a bound short by a factor n is caught here)."""
    base = draw(st.integers(-20, 20))
    roots = [fmpq(base * 8 + draw(st.integers(-8, 8)), draw(st.sampled_from([1, 2, 4, 3, 7])))
             for _ in range(draw(st.integers(4, 16)))]
    p = fmpq_poly([1])
    for r in roots:
        p = p * fmpq_poly([-r, 1])
    spread = [float(r) for r in roots]
    points = []
    for x in spread:
        for k in (-64, -16, -4, -1, 1, 4, 16, 64):
            points.append(x + k * 2.0**-40 * max(1.0, abs(x)))
    mid = (min(spread) + max(spread)) / 2
    points += [mid + k * 0.013 for k in range(-40, 41)]
    return QSqrtPoly(p), points


@settings(deadline=None, max_examples=150)
@given(clustered_roots())
def test_float_sign_near_clustered_roots(case):
    P, points = case
    fp = FloatPoly(P.p)
    for t in points:
        s = fp.sign_at(t)
        if s is not None:
            assert s == exact_sign(P, t), (P, t)
