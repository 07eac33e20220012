"""Closed forms of real algebraic numbers (core.algebra.closedform): hand-checkable values,
exact round trips through the expression parser, and the choice between conjugate roots."""

from __future__ import annotations

import pytest
from flint import fmpq, fmpz_poly
from hypothesis import assume, given
from hypothesis import strategies as st

from core.algebra.algebraic import RealAlgebraic
from core.algebra.closedform import (
    algebraic_from_quadratic,
    closed_form,
    polynomial_text,
    quadratic_form,
)
from core.moving.expressions import parse_expression


def roots_of(coeffs: list[int]) -> list[RealAlgebraic]:
    """Both real roots of a quadratic with integer coefficients (ascending), isolated by hand."""
    F = fmpz_poly(coeffs)
    c, b, a = coeffs
    mid = fmpq(-b, 2 * a)
    big = fmpq(abs(a) + abs(b) + abs(c), abs(a)) + 1
    out = [RealAlgebraic.isolating(F, -big, mid), RealAlgebraic.isolating(F, mid, big)]
    for r in out:
        r.try_rational()  # as the analysis does: a rational root becomes exact
    return out


def test_example_29_events():
    # paper, Example 29: 17 t^2 - 24 t + 8 = 0 at the two tangencies, t = (12 -+ 2 sqrt 2)/17
    lo, hi = roots_of([8, -24, 17])
    assert closed_form(lo) == "(12 - 2*sqrt(2))/17"
    assert closed_form(hi) == "(12 + 2*sqrt(2))/17"
    assert closed_form(lo, unicode=True) == "(12 − 2√2)/17"


@pytest.mark.parametrize(
    "coeffs, texts",
    [
        ([-5, 0, 4], ["-sqrt(5)/2", "sqrt(5)/2"]),  # Example 32: t = -+ sqrt(5)/2
        ([-2, 0, 1], ["-sqrt(2)", "sqrt(2)"]),
        ([-8, 0, 1], ["-2*sqrt(2)", "2*sqrt(2)"]),  # sqrt(32)/2 reduced
        ([2, -3, 1], ["1", "2"]),  # rational roots of a quadratic: no square root
        ([-1, 1, 1], ["(-1 - sqrt(5))/2", "(-1 + sqrt(5))/2"]),
    ],
)
def test_quadratics(coeffs, texts):
    assert [closed_form(r) for r in roots_of(coeffs)] == texts


def test_rationals_and_higher_degree():
    assert closed_form(RealAlgebraic.rational(fmpq(1, 3))) == "1/3"
    assert closed_form(RealAlgebraic.rational(fmpq(-4))) == "-4"
    cube_root = RealAlgebraic.isolating(fmpz_poly([-2, 0, 0, 1]), fmpq(1), fmpq(2))
    assert closed_form(cube_root) is None
    assert polynomial_text(cube_root) == "root of t^3 - 2 in (1, 2)"
    # a quadratic factor of a quartic is found: (t^2 - 2)(t^2 - 3) around sqrt(3)
    quartic = RealAlgebraic.isolating(fmpz_poly([6, 0, -5, 0, 1]), fmpq(3, 2), fmpq(2))
    assert closed_form(quartic) == "sqrt(3)"


@given(
    a=st.integers(1, 50), b=st.integers(-200, 200), c=st.integers(-200, 200)
)
def test_closed_form_reads_back_exactly(a, b, c):
    assume(b * b - 4 * a * c > 0)  # two real roots (was a silent return: hypothesis now fails if few examples remain)
    for r in roots_of([c, b, a]):
        text = closed_form(r)
        rf = parse_expression(text)
        x, y, d = rf.num.p[0] if rf.num.p.degree() == 0 else fmpq(0), rf.num.q[0] if rf.num.q.degree() == 0 else fmpq(0), int(rf.num.d)
        back = algebraic_from_quadratic(fmpq(x), fmpq(y), d)
        # the same number: exactly equal when rational, else a root of r's polynomial whose
        # isolating interval meets r's (each contains exactly one root of its polynomial)
        if r.is_rational:
            assert back.is_rational and back.value == r.value
        elif back.is_rational:  # r isolated on a polynomial with a rational root (x^2 + 2x: -2): that root
            assert r.compare(back.value) == 0, (r, back)
        else:
            assert back.poly.gcd(r.poly).degree() > 0
            assert max(back.lo, r.lo) < min(back.hi, r.hi)
        f = quadratic_form(r)
        assert f is not None and f.r > 0
