"""Every valid pair answered at any scale (issue 21.1): classify, explain and every witness.

Valid pairs (generic, near tangent with gaps 1e-7..1e-14, exactly tangent, needles) are scaled
by 2^k and 10^k: each matrix by its own factor (the shapes do not change) or space itself
(x -> L x: the shapes grow or shrink together), k up to +-300 for floats (as far as the float
range allows) and +-1000 for exact rationals. The expected label always comes from the exact
oracle of tests/oracle.py on the scaled pair itself, every witness is checked exactly and
independently (tests/witness_checks.py), explain's numbers must be short text that reads as the
exact value, and stacks must answer every pair. Sizes follow the hypothesis profile
(tests/conftest.py: "ci" small, "dev" for long runs).
"""

from __future__ import annotations

import json
import math
from fractions import Fraction as F
from typing import Any

import numpy as np
import pytest
from cases import axis_ellipsoid
from flint import fmpq, fmpz
from hypothesis import assume, example, given
from hypothesis import strategies as st
from oracle import oracle_relation
from strategies import dyadic_tangent_pair, exact_shapes, float_pairs, tangent_pairs
from witness_checks import (
    check_bracket,
    check_distance,
    check_inside_both,
    check_mu_bracket,
    check_on_both,
    check_plane,
    is_valid,
)

from core import (
    Certifier,
    Relation,
    classify,
    contact_point,
    contact_scale,
    explain,
    separating_plane,
)
from core.witness import NoWitness, distance, witness

# ------------------------------------------------------------------ pairs and their scalings


def space_exact(M: list[list[Any]], L: F) -> list[list[F]]:
    """The shape seen through x -> L x: entry (i, j) divided by L per spatial index."""
    n = len(M)
    d = n - 1
    return [[F(M[i][j]) / L ** ((i < d) + (j < d)) for j in range(n)] for i in range(n)]


def space_float(M: np.ndarray, L: float) -> np.ndarray:
    """The same for a float matrix (rounded: the oracle decides what the floats are)."""
    d = M.shape[0] - 1
    out = np.array(M, dtype=float)
    out[:d, :d] = out[:d, :d] / L / L
    out[:d, d] = out[:d, d] / L
    out[d, :d] = out[d, :d] / L
    return out


GAPS = [F(1, 10**7), F(1, 10**8), F(1, 10**9), F(1, 10**14)]


@st.composite
def exact_base(draw: Any) -> tuple[list[list[F]], list[list[F]]]:
    """Generic, tangent, near-tangent (gap or overlap 1e-7..1e-14) and needle pairs, exact."""
    d = draw(st.sampled_from([2, 3]))
    kind = draw(st.sampled_from(["generic", "tangent", "near", "needle"]))
    if kind == "generic":
        return draw(exact_shapes(d)), draw(exact_shapes(d))
    if kind == "needle":  # a needle (axes 1000 and 1/1000) and a ball at its tip or side, gap 1e-14
        long, thin = F(1000), F(1, 1000)
        g = draw(st.sampled_from(GAPS)) * draw(st.sampled_from([1, -1]))
        A = axis_ellipsoid([0] * d, [long] + [thin] * (d - 1))
        tip = draw(st.booleans())
        c = [long + 1 + g] + [0] * (d - 1) if tip else [0, thin + 1 + g] + [0] * (d - 2)
        return A, axis_ellipsoid(c, [1] * d)
    A, B = draw(tangent_pairs(d))
    if kind == "near":  # B's constant term moved: it shrinks (separate) or grows (overlap) a hair
        B = [row[:] for row in B]
        B[-1][-1] += draw(st.sampled_from(GAPS)) * draw(st.sampled_from([1, -1]))
    return A, B


@st.composite
def float_base(draw: Any) -> tuple[np.ndarray, np.ndarray]:
    """Generic float pairs, and exactly tangent dyadic pairs moved by 2^-24 .. 2^-46."""
    if draw(st.booleans()):
        return draw(float_pairs())
    d = draw(st.sampled_from([2, 3]))
    a = draw(st.sampled_from([0.5, 1.0, 2.0, 4.0]))
    r = draw(st.sampled_from([0.25, 1.0, 2.0]))
    A, B = dyadic_tangent_pair(d, a, r, [draw(st.sampled_from([0.0, 0.5, -1.25])) for _ in range(d)])
    B = B.copy()
    B[-1, -1] += draw(st.sampled_from([0.0, 2.0**-24, -(2.0**-30), 2.0**-46]))
    return A, B


@st.composite
def scaled_exact(draw: Any) -> tuple[Any, Any, str]:
    A, B = draw(exact_base())
    base = draw(st.sampled_from([2, 10]))
    k = draw(st.integers(-1000, 1000))
    if draw(st.booleans()):
        kb = draw(st.integers(-1000, 1000))
        A = [[v * F(base) ** k for v in row] for row in A]
        B = [[v * F(base) ** kb for v in row] for row in B]
        return A, B, f"matrices by {base}^{k}, {base}^{kb}"
    L = F(base) ** k
    return space_exact(A, L), space_exact(B, L), f"space by {base}^{k}"


@st.composite
def scaled_float(draw: Any) -> tuple[np.ndarray, np.ndarray, str]:
    A, B = draw(float_base())
    base = draw(st.sampled_from([2, 10]))
    space = draw(st.booleans())
    kmax = (300 if base == 10 else 1000) // (2 if space else 1)  # space scales entries by L^2
    k = draw(st.integers(-kmax, kmax))
    factor = math.ldexp(1.0, k) if base == 2 else float(F(10) ** k)
    if space:
        A, B, how = space_float(A, factor), space_float(B, factor), f"space by {base}^{k}"
    else:
        kb = draw(st.integers(-kmax, kmax))
        fb = math.ldexp(1.0, kb) if base == 2 else float(F(10) ** kb)
        A, B, how = A * factor, B * fb, f"matrices by {base}^{k}, {base}^{kb}"
    assume(np.isfinite(A).all() and np.isfinite(B).all() and is_valid(A) and is_valid(B))
    return A, B, how


# ------------------------------------------------------------------ checks


def check_explain(A: Any, B: Any, rel: str) -> None:
    """Same label as the oracle; every number short, reading as its exact value (5 digits)."""
    e = explain(A, B)
    assert str(e.relation) == rel
    json.dumps(e.to_dict())
    for qty in [*e.coefficients, e.s0, e.s1, e.s10]:
        if qty is None:
            continue
        assert 0 < len(qty.text) <= 16, qty.text
        if qty.exact is not None:
            num, _, den = qty.exact.partition("/")
            exact = fmpq(fmpz(num), fmpz(den or "1"))
            shown = F(qty.text)
            if exact == 0:
                assert shown == 0
            else:
                assert abs(fmpq(shown.numerator, shown.denominator) - exact) <= abs(exact) * fmpq(1, 10**5)


def check_single(A: Any, B: Any) -> None:
    """classify, explain and every one-pair witness against the oracle, checked independently."""
    rel = oracle_relation(A, B)
    assert str(classify(A, B)) == rel
    check_explain(A, B, rel)
    cs = contact_scale(A, B)
    assert str(cs.relation) == rel
    assert (cs.lo > 1) if rel == "separate" else (cs.hi < 1) if rel == "overlap" else (cs.lo == cs.hi == 1)
    check_bracket(A, B, cs)
    w = witness(A, B)
    assert str(w.relation) == rel
    dist = distance(A, B)
    if rel == "separate":
        plane = separating_plane(A, B)
        check_plane(A, B, plane.normal, plane.offset)
        assert w.plane is not None
        check_plane(A, B, w.plane.normal, w.plane.offset)
        check_distance(A, B, dist.lo, dist.hi, dist.point_a, dist.point_b, dist.normal)
        assert dist.normal is not None and dist.lo > 0
    else:
        cp = contact_point(A, B)
        assert dist.lo == dist.hi == 0
        assert w.point is not None
        for p in (cp, w.point):
            if rel == "tangent" and p.rational_point is not None:
                check_on_both(A, B, p.rational_point)
            elif rel == "overlap":
                check_inside_both(A, B, p.rational_point)


def check_stack(A: Any, B: Any, rel: str) -> None:
    """The pair and its swap as a stack of two: both answered, each checked, by every method."""
    if isinstance(A, np.ndarray):
        SA, SB = np.stack([A, B]), np.stack([B, A])
    else:
        SA, SB = [A, B], [B, A]
    swap = ((A, B), (B, A))
    r = contact_scale(SA, SB, rtol=1e-9)
    assert [str(c.relation) for c in r] == [rel, rel]
    for c, (a, b) in zip(r, swap, strict=True):
        check_mu_bracket(a, b, c.lo, c.hi)
    p = separating_plane(SA, SB, on_invalid="mark")
    pt = contact_point(SA, SB, on_invalid="mark")
    for i, (a, b) in enumerate(swap):
        if rel == "separate":
            check_plane(a, b, p[i].normal, p[i].offset)
            assert isinstance(pt[i], NoWitness) and pt[i].kind == "none"
        else:
            assert isinstance(p[i], NoWitness) and p[i].kind == "none"
            if rel == "overlap":
                check_inside_both(a, b, pt[i].rational_point)
    for w, (a, b) in zip(witness(SA, SB, method="float", on_invalid="mark"), swap, strict=True):
        if isinstance(w, NoWitness):  # floats could not certify it (tangency always needs exact)
            assert w.kind == "undecided"
            continue
        assert str(w.relation) == rel and w.certified_by == Certifier.FLOAT
        check_mu_bracket(a, b, w.scale.lo, w.scale.hi)
        if w.plane is not None:
            check_plane(a, b, w.plane.normal, w.plane.offset)
        if w.point is not None:
            check_inside_both(a, b, w.point.rational_point)


# ------------------------------------------------------------------ the properties


@given(scaled_exact())
@example(([[F(2**-1000), 0, 0], [0, F(2**-1000), 0], [0, 0, -F(2**-1000)]], [[F(1), 0, F(-3)], [0, F(1), 0], [F(-3), 0, F(8)]], "README"))
def test_exact_pairs_at_any_scale(case):
    A, B, _ = case
    check_single(A, B)


@given(scaled_float())
@example(
    (
        np.diag([2.0**-1000, 2.0**-1000, -(2.0**-1000)]),
        np.array([[1.0, 0.0, -3.0], [0.0, 1.0, 0.0], [-3.0, 0.0, 8.0]]) * 1e-300,
        "issue 21: a unit circle against one at distance 3 scaled by 1e-300",
    )
)
def test_float_pairs_at_any_scale(case):
    A, B, _ = case
    check_single(A, B)


@given(st.one_of(scaled_exact(), scaled_float()))
def test_stacks_at_any_scale(case):
    A, B, _ = case
    check_stack(A, B, oracle_relation(A, B))


@pytest.mark.parametrize("k", [100, -100, 1000, -1000])
@pytest.mark.parametrize("gap", [F(1, 10**7), F(1, 10**9)])
def test_issue_reproducers_exact_space(k, gap):
    """Exact pairs scaled by 10^+-100 at gaps 1e-7..1e-9 raised 'bracket did not converge'."""
    A = space_exact(axis_ellipsoid([0, 0, 0], [2, 1, 1]), F(10) ** k)
    B = space_exact(axis_ellipsoid([3 + gap, F(1, 1000), 0], [1, 1, 1]), F(10) ** k)
    check_single(A, B)


def test_tight_rtol_is_met_quickly_and_exactly():
    """rtol far below float precision: the bracket is within it (precision follows the accuracy)."""
    A = space_exact(axis_ellipsoid([0, 0, 0], [2, 1, F(1, 2)]), F(10) ** 300)
    B = space_exact(axis_ellipsoid([F(31, 10), F(1, 3), 0], [1, 1, 1]), F(10) ** 300)
    for rtol in (1e-40, 1e-200):
        cs = contact_scale(A, B, rtol=rtol)
        assert cs.hi - cs.lo <= cs.hi * fmpq(*rtol.as_integer_ratio())
        check_bracket(A, B, cs)


def test_one_hard_pair_never_costs_the_others(monkeypatch):
    """A pair whose exact computation fails (simulated) is marked; the other pairs keep their answers."""
    import core.witness.api as api

    circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]  # noqa: E731
    A = [circle(0), circle(0), circle(0)]
    B = [circle(3), circle(F(1, 2)), circle(F(5, 2))]
    real = api.scale_exact

    def flaky(pairs, i, rtol):
        if str(pairs.b[i][0][2]) == "-1/2":  # the pair with circle(1/2)
            raise RuntimeError("simulated failure")
        return real(pairs, i, rtol)

    monkeypatch.setattr(api, "scale_exact", flaky)
    r = contact_scale(A, B)  # even with on_invalid="raise": a failure is that pair's alone
    assert isinstance(r[1], NoWitness) and r[1].kind == "failed" and "simulated failure" in r[1].reason
    assert r[1].relation == Relation.OVERLAP
    assert (r[0].lo, r[0].hi) == (fmpq(3, 2), fmpq(3, 2)) and (r[2].lo, r[2].hi) == (fmpq(5, 4), fmpq(5, 4))
    with pytest.raises(RuntimeError, match="simulated failure"):  # one pair: the failure is the answer
        contact_scale(A[1], B[1])


def test_invalid_pairs_marked_in_stacks():
    circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]  # noqa: E731
    hyperbola = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
    A = np.array([circle(0), hyperbola, circle(0)], float)
    B = np.array([circle(3), circle(1), circle(1)], float)
    with pytest.raises(ValueError, match="pair 1: A is not an ellipse"):
        contact_scale(A, B)
    r = contact_scale(A, B, on_invalid="mark")
    assert [c.relation for c in r] == [Relation.SEPARATE, Relation.INVALID, Relation.OVERLAP]
    assert isinstance(r[1], NoWitness) and r[1].kind == "invalid" and "not an ellipse" in r[1].reason
    assert r[0].lo <= fmpq(3, 2) <= r[0].hi and r[2].hi <= 1
    p = separating_plane(A, B, on_invalid="mark")
    assert [type(x).__name__ for x in p] == ["SeparatingPlane", "NoWitness", "NoWitness"]
    assert [x.kind for x in p[1:]] == ["invalid", "none"]
