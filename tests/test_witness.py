"""Witnesses (issue 15): contact scale, separating plane, contact point; checked independently.

Golden values come from closed forms (two spheres: mu = |c1 - c2| / (r1 + r2)), from the paper's
motions (the relation on each side of its tangency events), from the independent oracle of
tests/oracle.py (positive roots of det(T A + B) via flint's characteristic polynomial) applied
to the pairs scaled just below and above the reported bracket, and from exact checks written
here with ``fractions.Fraction`` and the Leibniz determinant (no code of core.witness):

* a plane misses a shape iff the quadric restricted to the plane has a positive minimum
  (Schur complement of the restricted matrix), and the shape lies on the side of its centre;
* a point is inside a shape iff X^T A X < 0, on its boundary iff X^T A X = 0.
"""

from __future__ import annotations

import math
from fractions import Fraction as F
from typing import Any

import numpy as np
import pytest
from cases import CASES, axis_ellipsoid, circle, sphere
from flint import fmpq
from hypothesis import given
from hypothesis import strategies as st
from oracle import oracle_relation
from strategies import dyadic_tangent_pair, exact_shapes, float_pairs, tangent_pairs
from witness_checks import check_bracket, check_distance, form, frac, plane_misses_on_side, q

from core import (
    Certifier,
    Relation,
    analyse,
    classify,
    contact_point,
    contact_scale,
    quadric_from_axes,
    rotation_from_quaternion,
    separating_plane,
)
from core.moving.motions import matrix_at_exact
from core.moving.presets import preset_arguments
from core.witness import ContactScale, NoWitness, SeparatingPlane, distance, margin_text, witness

# ------------------------------------------------------------------ contact scale


def test_spheres_exact_closed_form():
    # |c1 - c2| = 13 (5-12 in the plane z = 0 moved by 3-4-12 ... here 3, 4, 12), radii 2 and 3/2
    cs = contact_scale(sphere(0, 0, 0, 2), sphere(3, 4, 12, F(3, 2)))
    assert (cs.lo, cs.hi) == (fmpq(13) / fmpq(7, 2), fmpq(13) / fmpq(7, 2))
    assert cs.relation == Relation.SEPARATE and cs.algebraic().value == fmpq(26, 7)


@pytest.mark.parametrize(
    ("c2", "r1", "r2"),
    [((1, 1, 1), 1, 1), ((2, 0, 1), F(1, 3), F(5, 4)), ((0, 1, 1), 2, 3), ((7, 1, 0), F(1, 2), 2)],
)
def test_spheres_irrational_closed_form(c2, r1, r2):
    dist2 = sum(F(v) ** 2 for v in c2)
    mu2 = dist2 / (F(r1) + F(r2)) ** 2  # mu = sqrt(mu2), irrational here
    cs = contact_scale(sphere(0, 0, 0, r1), sphere(*c2, r2))
    assert q(cs.lo) ** 2 <= mu2 <= q(cs.hi) ** 2
    assert float(cs.hi - cs.lo) <= 1e-12 * float(cs.hi)
    assert cs.relation == (Relation.SEPARATE if mu2 > 1 else Relation.OVERLAP)
    a = cs.algebraic()
    # its defining polynomial is a multiple of the minimal polynomial x^2 - mu2
    p = [q(c) for c in a.poly.coeffs()]
    assert len(p) == 3 and p[1] == 0 and -p[0] / p[2] == mu2
    assert q(a.lo) ** 2 < mu2 < q(a.hi) ** 2
    assert a.decimal(40)[:30] == _sqrt_decimal(mu2, 40)[:30]


def _sqrt_decimal(x: F, digits: int) -> str:
    """sqrt(x) by integer square root (independent of core)."""
    scale = 10 ** (2 * digits)
    r = math.isqrt(x.numerator * scale // x.denominator)
    s = str(r)
    whole = len(str(math.isqrt(int(x)))) if x >= 1 else 0
    if x < 1:
        return "0." + s.rjust(digits, "0")
    return s[:whole] + "." + s[whole:]


def test_float_spheres_dyadic():
    # radii 1/2 and 2, dyadic centres: the float matrices are exactly the spheres, mu = 5 / 2.5
    A = quadric_from_axes([0.0, 0.0, 0.0], [0.5, 0.5, 0.5])
    B = quadric_from_axes([3.0, 4.0, 0.0], [2.0, 2.0, 2.0])
    cs = contact_scale(A, B)
    assert cs.lo == cs.hi == 2
    b = contact_scale(A[None], B[None])
    assert b[0].lo == b[0].hi == 2


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_catalogue(case):
    cs = contact_scale(case.A, case.B)
    assert str(cs.relation) == case.relation
    if case.relation == "tangent":
        assert cs.lo == cs.hi == 1
    else:
        assert (cs.lo > 1) if case.relation == "separate" else (cs.hi < 1)
    check_bracket(case.A, case.B, cs)


@given(exact_shapes(3), exact_shapes(3))
def test_random_exact_ellipsoids(A, B):
    cs = contact_scale(A, B)
    assert str(cs.relation) == oracle_relation(A, B)
    assert cs.relation == classify(A, B)
    check_bracket(A, B, cs)
    a = cs.algebraic()
    assert a.compare(cs.lo) >= 0 and a.compare(cs.hi) <= 0


@given(exact_shapes(2), exact_shapes(2))
def test_random_exact_ellipses(A, B):
    cs = contact_scale(A, B)
    assert str(cs.relation) == oracle_relation(A, B)
    check_bracket(A, B, cs)


@given(tangent_pairs())
def test_tangent_pairs_mu_is_one(pair):
    A, B = pair
    cs = contact_scale(A, B)
    assert cs.relation == Relation.TANGENT and cs.lo == cs.hi == 1


@given(tangent_pairs(), st.sampled_from([1, -1]), st.integers(5, 40))
def test_near_tangent_pairs(pair, sign, k):
    # B's constant term moved by +-10^-k: it shrinks (separate) or grows (overlap) a hair
    A, B = pair
    B = [row[:] for row in B]
    B[-1][-1] += sign * F(1, 10**k)
    cs = contact_scale(A, B)
    expected = oracle_relation(A, B)
    assert str(cs.relation) == expected == ("separate" if sign > 0 else "overlap")
    assert (cs.lo > 1) if sign > 0 else (cs.hi < 1)


@given(float_pairs())
def test_random_float_pairs(pair):
    A, B = pair
    cs = contact_scale(A, B)
    assert str(cs.relation) == oracle_relation(A, B)
    assert float(cs.hi - cs.lo) <= 1e-12 * float(cs.hi) + 1e-300
    # flipped signs and swapped order: the same scale
    cs2 = contact_scale(-B, A)
    assert cs2.relation == cs.relation
    assert cs2.lo <= cs.hi and cs.lo <= cs2.hi


def test_copies_of_one_shape():
    # translated copies: P(T) has the double root -1 for every translation (s0 = 0 identically)
    q = [0.9, 0.1, -0.3, 0.2]
    A = quadric_from_axes([0.0, 0.0, 0.0], [1.0, 2.0, 0.5], q)
    for shift, rel in (([0.1, 0.2, 0.0], "overlap"), ([3.0, 4.0, 5.0], "separate")):
        B = quadric_from_axes(shift, [1.0, 2.0, 0.5], q)
        cs = contact_scale(A, B)
        assert str(cs.relation) == oracle_relation(A, B) == rel
        check_bracket(A, B, cs)
    same = contact_scale(A, A.copy())
    assert same.lo == same.hi == 0 and same.relation == Relation.OVERLAP


def test_rtol_is_met():
    A = quadric_from_axes([0.0, 0.0, 0.0], [1.0, 2.0, 3.0], [1.0, 0.2, 0.3, 0.1])
    B = quadric_from_axes([3.0, 1.0, 0.5], [0.5, 1.0, 2.0], [0.3, 1.0, 0.2, 0.5])
    for rtol in (1e-3, 1e-12, 1e-40, 1e-200):
        cs = contact_scale(A, B, rtol=rtol)
        assert cs.hi - cs.lo <= cs.hi * fmpq(*rtol.as_integer_ratio())
    with pytest.raises(ValueError, match="rtol"):
        contact_scale(A, B, rtol=0.0)


def test_bad_input():
    with pytest.raises(ValueError, match="not an ellipse"):
        contact_scale([[1, 0, 0], [0, -1, 0], [0, 0, -1]], circle(0, 0, 1))
    with pytest.raises(ValueError, match="both must be ellipses or both ellipsoids"):
        contact_scale(circle(0, 0, 1), sphere(0, 0, 0, 1))


# ------------------------------------------------------------------ the paper's motions


def _at(name: str, t: F) -> tuple[Any, Any]:
    args = preset_arguments(name)
    return matrix_at_exact(args["A_t"], t), matrix_at_exact(args["B_t"], t)


@pytest.mark.parametrize("name", ["example-29", "example-31", "example-32", "circles-crossing", "circles-graze", "ellipse-spin"])
def test_paper_events(name):
    """mu = 1 exactly at rational events; on each side of every event mu is on the side of 1
    the motion analysis says (at the ends of the event's isolating interval, narrowed)."""
    r = analyse(**preset_arguments(name), digits=10)
    assert r.events
    for e in r.events:
        if e.time.value is not None:
            A, B = _at(name, q(e.time.value))
            cs = contact_scale(A, B)
            assert cs.relation == Relation.TANGENT and cs.lo == cs.hi == 1
            cp = contact_point(A, B)
            fa, fb = frac(A), frac(B)
            x = [q(c.value) for c in cp.point]
            assert form(fa, x) == 0 and form(fb, x) == 0
        e.time.refine_to(fmpq(1, 10**12))
        for t, rel in ((e.time.lo, e.before), (e.time.hi, e.after)):
            if rel is None or t == e.time.value:
                continue
            cs = contact_scale(*_at(name, q(t)))
            assert cs.relation == rel
            assert (cs.lo > 1) if rel == Relation.SEPARATE else (cs.hi < 1)


def test_example_31_margin_grows_away_from_event():
    # touch and leave at t = 4: mu - 1 is positive on both sides, larger further away
    m = [contact_scale(*_at("example-31", F(t))).approx for t in (3, F(39, 10), F(41, 10), 5)]
    assert m[0] > m[1] > 1 and 1 < m[2] < m[3]


# ------------------------------------------------------------------ separating plane


def _check_plane(A: Any, B: Any, plane: Any) -> None:
    n = [q(v) for v in plane.normal]
    d = q(plane.offset)
    assert plane_misses_on_side(frac(A), n, d, -1)
    assert plane_misses_on_side(frac(B), n, d, 1)


@given(exact_shapes(3), exact_shapes(3))
def test_separating_plane_exact_pairs(A, B):
    if classify(A, B) != Relation.SEPARATE:
        with pytest.raises(ValueError, match="no plane separates"):
            separating_plane(A, B)
        return
    _check_plane(A, B, separating_plane(A, B))


@given(float_pairs())
def test_separating_plane_float_pairs(pair):
    A, B = pair
    if classify(A, B) == Relation.SEPARATE:
        _check_plane(A, B, separating_plane(A, B))


@pytest.mark.parametrize("k", [3, 9, 20, 40])
def test_separating_plane_near_tangent(k):
    # an ellipse and a circle a hair apart (gap 10^-k)
    A = axis_ellipsoid([0, 0], [2, 1])
    B = circle(3 + F(1, 10**k), F(1, 10**k), 1)
    assert classify(A, B) == Relation.SEPARATE
    plane = separating_plane(A, B)
    _check_plane(A, B, plane)
    assert 0 < plane.gap < 2 * 10.0**-k


def test_separating_plane_simple_and_float_rotated():
    p = separating_plane(sphere(0, 0, 0, 1), sphere(0, 3, 0, 1))
    assert p.normal == (0, 1, 0) and p.offset == fmpq(3, 2)
    assert abs(p.gap - 1.0) < 1e-12
    A = quadric_from_axes([0.1, -0.2, 0.3], [1.0, 0.5, 0.25], [0.3, 0.5, -0.1, 0.8])
    B = quadric_from_axes([2.5, 1.0, -0.4], [0.7, 0.7, 1.1], [1.0, 0.0, 0.4, 0.1])
    _check_plane(A, B, separating_plane(A, B))
    _check_plane(-A, B, separating_plane(-A, B))  # flipped signs


def test_independent_plane_check_can_fail():
    A, B = circle(0, 0, 1), circle(3, 0, 1)
    assert plane_misses_on_side(frac(A), [F(1), F(0)], F(3, 2), -1)
    assert not plane_misses_on_side(frac(A), [F(1), F(0)], F(3, 2), 1)  # wrong side
    assert not plane_misses_on_side(frac(A), [F(1), F(0)], F(1), -1)  # touches A at (1, 0)
    assert not plane_misses_on_side(frac(B), [F(1), F(1)], F(3), 1)  # cuts B


def test_separating_plane_rejects():
    with pytest.raises(ValueError, match="tangent"):
        separating_plane(circle(0, 0, 1), circle(2, 0, 1))
    with pytest.raises(ValueError, match="overlap"):
        separating_plane(circle(0, 0, 1), circle(1, 0, 1))


# ------------------------------------------------------------------ contact point


@given(tangent_pairs())
def test_contact_point_tangent_exact(pair):
    A, B = pair
    cp = contact_point(A, B)
    assert cp.relation == Relation.TANGENT and cp.is_rational
    fa, fb = frac(A), frac(B)
    x = [q(c.value) for c in cp.point]
    assert form(fa, x) == 0 and form(fb, x) == 0
    n = [q(c.value) for c in cp.normal]
    d = len(x)
    ga = [sum(fa[i][j] * x[j] for j in range(d)) + fa[i][d] for i in range(d)]
    gb = [sum(fb[i][j] * x[j] for j in range(d)) + fb[i][d] for i in range(d)]
    assert n == ga  # out of A
    # B's gradient is antiparallel: gb = -t n with t > 0
    t = next(-gb[i] / n[i] for i in range(d) if n[i] != 0)
    assert t > 0 and all(gb[i] == -t * n[i] for i in range(d))


def test_contact_point_tangent_decimals_and_pencil_root():
    # circles 3-4-5: radii 2 and 3 at distance 5 touch at (6/5, 8/5)
    cp = contact_point(circle(0, 0, 2), circle(3, 4, 3))
    assert cp.rational_point == (fmpq(6, 5), fmpq(8, 5))
    d = cp.to_dict(digits=12)
    assert [c["exact"] for c in d["point"]] == ["6/5", "8/5"]
    assert d["pencil_root"]["exact"] is not None


@given(exact_shapes(3), exact_shapes(3))
def test_overlap_witness_inside_both(A, B):
    rel = classify(A, B)
    if rel == Relation.SEPARATE:
        with pytest.raises(ValueError, match="separate"):
            contact_point(A, B)
        return
    cp = contact_point(A, B)
    if rel == Relation.OVERLAP:
        x = [q(c.value) for c in cp.point]
        assert form(frac(A), x) < 0 and form(frac(B), x) < 0


@pytest.mark.parametrize("k", [3, 15, 40])
def test_overlap_witness_thin_lens(k):
    A = circle(0, 0, 1)
    B = circle(2 - F(1, 10**k), 0, 1)
    cp = contact_point(A, B)
    x = [q(c.value) for c in cp.point]
    assert form(frac(A), x) < 0 and form(frac(B), x) < 0


def test_overlap_witness_float_and_nested():
    A = quadric_from_axes([0.0, 0.0, 0.0], [3.0, 2.0, 1.0], [0.9, 0.1, 0.2, 0.3])
    for B in (quadric_from_axes([0.1, 0.1, 0.1], [0.2, 0.2, 0.2]), A.copy(), -quadric_from_axes([2.9, 0.0, 0.0], [1.0, 1.0, 1.0])):
        cp = contact_point(A, B)
        x = [q(c.value) for c in cp.point]
        assert form(frac(A), x) < 0 and form(frac(B), x) < 0


# ------------------------------------------------------------------ witness and margin


def test_witness_sentences():
    w = witness(circle(0, 0, 1), circle(3, 0, 1))
    assert w.sentence == "separate: this plane separates them" and w.plane is not None
    assert w.margin == "50 % apart"
    w = witness(circle(0, 0, 1), circle(2, 0, 1))
    assert w.sentence == "tangent: they touch here" and w.point.rational_point == (1, 0)
    assert w.margin == "touching"
    w = witness(circle(0, 0, 1), circle(F(194, 100), 0, 1))
    assert w.sentence == "overlap: this point is inside both"
    assert w.margin == "overlapping by 3 %"
    d = w.to_dict()
    assert d["contact_scale"]["lo"] == d["contact_scale"]["hi"] == "97/100"


def test_margin_text():
    assert margin_text(1.018, 1.018, Relation.SEPARATE) == "1.8 % apart"
    assert margin_text(0.5, 0.5, "overlap") == "overlapping by 50 %"


# ------------------------------------------------------------------ stacks and methods (issue 23)


def _random_stack(d: int, N: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(N):
        o = rng.uniform(0, 3) if d == 2 else rng.normal(size=4)
        out.append(quadric_from_axes(rng.uniform(-3, 3, d), rng.uniform(0.2, 3, d), o))
    return np.array(out)


def _json(r: Any) -> Any:
    """A result's whole JSON form (or a NoWitness's fields): what "the same answer" means."""
    if isinstance(r, NoWitness):
        return ("no witness", str(r.relation), r.kind, r.reason)
    return r.to_dict()


_FUNCTIONS = {
    "contact_scale": lambda a, b, **kw: contact_scale(a, b, rtol=1e-9, **kw),
    "separating_plane": separating_plane,
    "contact_point": contact_point,
    "distance": distance,
    "witness": witness,
}


@pytest.mark.parametrize("method", ["adaptive", "float", "exact"])
@pytest.mark.parametrize("name", list(_FUNCTIONS))
def test_stack_of_one_gives_what_one_pair_gives(name, method):
    """One meaning for one pair and stacks: the stack of one is the pair's answer in array form."""
    fn = _FUNCTIONS[name]
    c = lambda x: quadric_from_axes([x, 0.0], [1.0, 0.5], 0.3)  # noqa: E731
    cases = [(c(0.0), c(2.5)), (c(0.0), c(0.7)), (circle(0, 0, 1), circle(2, 0, 1)), (circle(0, 0, 1), circle(F(5, 2), 0, 1))]
    cases += list(zip(_random_stack(3, 3, 5), _random_stack(3, 3, 6), strict=True))
    for A, B in cases:
        one = fn(A, B, method=method, on_invalid="mark")
        stack = fn(np.asarray(A)[None] if isinstance(A, np.ndarray) else [A], np.asarray(B)[None] if isinstance(B, np.ndarray) else [B], method=method, on_invalid="mark")
        assert isinstance(stack, np.ndarray) and stack.dtype == object and stack.shape == (1,)
        assert type(stack[0]) is type(one) and _json(stack[0]) == _json(one)


@pytest.mark.parametrize("d", [2, 3])
def test_stack_answers_every_pair_and_agrees_with_one_pair(d):
    A, B = _random_stack(d, 60, d), _random_stack(d, 60, 10 + d)
    r = contact_scale(A, B)
    assert r.shape == (60,) and all(isinstance(c, ContactScale) for c in r)
    assert [int(c.relation) for c in r] == classify(A, B).tolist()
    for i in range(0, 60, 3):
        cs = contact_scale(A[i], B[i], method="exact")
        assert r[i].relation == cs.relation
        assert r[i].lo <= r[i].hi and r[i].hi - r[i].lo <= r[i].hi * fmpq(1, 10**12)
        assert r[i].lo <= cs.hi and cs.lo <= r[i].hi  # both certified: they intersect
    assert sum(c.certified_by == Certifier.FLOAT for c in r) >= 40  # the floats do most of the work


def test_stack_brackets_checked_by_oracle():
    A, B = _random_stack(3, 12, 5), _random_stack(3, 12, 6)
    r = contact_scale(A, B, rtol=1e-9)
    for i in range(12):
        check_bracket(A[i], B[i], r[i])


def test_stack_tangent_broadcast_and_exact_input():
    pairs = [dyadic_tangent_pair(3, a, rr, [0.5, -1.0, 2.0]) for a, rr in ((2.0, 1.0), (0.5, 4.0), (4.0, 0.25))]
    A = np.array([p[0] for p in pairs])
    B = np.array([p[1] for p in pairs])
    r = contact_scale(A, B)
    assert [(c.lo, c.hi) for c in r] == [(1, 1)] * 3
    # broadcasting one shape against a stack (2, 3)
    A0 = quadric_from_axes([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    Bs = np.array([[quadric_from_axes([x, 0.0, 0.0], [1.0, 1.0, 1.0]) for x in (1.0, 2.0, 3.0)]] * 2)
    r = contact_scale(A0, Bs)
    assert r.shape == (2, 3)
    assert [int(c.relation) for c in r[0]] == [2, 1, 0] and r[0, 2].lo == r[0, 2].hi == fmpq(3, 2)
    # exact input stacks: exact rationals
    r = contact_scale([circle(0, 0, 1), circle(0, 0, 1)], [circle(3, 0, 1), circle(1, 0, 1)])
    assert [(c.lo, c.hi, c.certified_by) for c in r] == [(fmpq(3, 2), fmpq(3, 2), Certifier.EXACT), (fmpq(1, 2), fmpq(1, 2), Certifier.EXACT)]


@pytest.mark.parametrize("d", [2, 3])
def test_stack_planes_certified_and_checked(d):
    A, B = _random_stack(d, 40, 20 + d), _random_stack(d, 40, 30 + d)
    p = separating_plane(A, B, on_invalid="mark")
    rel = classify(A, B)
    for i in range(40):
        if rel[i] == Relation.SEPARATE:
            assert isinstance(p[i], SeparatingPlane)
            _check_plane(A[i], B[i], p[i])
        else:
            assert isinstance(p[i], NoWitness) and p[i].kind == "none" and p[i].relation == rel[i]
    with pytest.raises(ValueError, match=r"pair \d+: A and B (are tangent|overlap)"):
        separating_plane(A, B)  # on_invalid="raise": a pair without a plane is an error


def test_one_float_pair_and_far_centres():
    # centres far out compared with the sizes make the plain float k lose digits, the compensated
    # enclosure does not; at 1e4 x the sizes the last entry loses s*: the exact stage takes over
    for shift in (0.0, 100.0, 1e4):
        A = quadric_from_axes([shift, shift, 0.0], [0.2, 0.3, 0.25], [0.9, 0.1, 0.2, 0.3])
        B = quadric_from_axes([shift + 0.5, shift + 0.3, 0.1], [0.1, 0.3, 0.2], [0.2, 0.8, 0.1, 0.3])
        r = contact_scale(A, B, rtol=1e-10)
        assert r.certified_by == (Certifier.EXACT if shift > 1000 else Certifier.FLOAT)
        fl = contact_scale(A, B, rtol=1e-10, method="float", on_invalid="mark")
        assert fl == r or isinstance(fl, NoWitness) and fl.kind == "undecided"  # scaled pairs may need exact classification
        cs = contact_scale(A, B, method="exact")
        assert r.relation == cs.relation and r.lo <= cs.hi and cs.lo <= r.hi
        assert r.hi - r.lo <= r.hi * fmpq(1, 10**10)
        if cs.relation == Relation.SEPARATE:
            _check_plane(A, B, separating_plane(A, B))


def test_methods_keep_their_meaning():
    """float: floats only (undecided where they cannot certify); exact: rationals throughout."""
    A, B = _random_stack(3, 20, 41), _random_stack(3, 20, 42)
    T1, T2 = dyadic_tangent_pair(3, 2.0, 1.0, [0.0, 0.0, 0.0])
    A, B = np.concatenate([A, T1[None]]), np.concatenate([B, T2[None]])
    for name, fn in _FUNCTIONS.items():
        fl = fn(A, B, method="float", on_invalid="mark")
        ex = fn(A, B, method="exact", on_invalid="mark")
        for f, e in zip(fl, ex, strict=True):
            assert isinstance(f, NoWitness) and f.kind in ("none", "undecided") or f.certified_by == Certifier.FLOAT, name
            assert isinstance(e, NoWitness) and e.kind == "none" or e.certified_by == Certifier.EXACT, name
        assert isinstance(fl[-1], NoWitness) and fl[-1].kind == "undecided"  # tangency needs exact arithmetic
    with pytest.raises(ValueError, match="valid options"):
        contact_scale(A, B, method="fast")
    with pytest.raises(ValueError, match="valid options"):
        witness(A, B, on_invalid="skip")


def _rotated(center: list[float], axes: list[float], q: list[float]) -> np.ndarray:
    """The way users build them: R diag(1/r^2) R^T from a float rotation (symmetric up to rounding)."""
    R = rotation_from_quaternion(q)
    Q = R @ np.diag([1 / r**2 for r in axes]) @ R.T
    c = np.array(center)
    M = np.zeros((4, 4))
    M[:3, :3] = Q
    M[:3, 3] = -Q @ c
    M[3, :3] = -(c @ Q)
    M[3, 3] = c @ Q @ c - 1
    return M


def test_near_symmetric_float_matrices():
    rng = np.random.default_rng(7)
    pairs = []
    while len(pairs) < 12:
        A = _rotated(list(rng.uniform(-2, 2, 3)), list(rng.uniform(0.3, 2, 3)), list(rng.normal(size=4)))
        B = _rotated(list(rng.uniform(-2, 2, 3)), list(rng.uniform(0.3, 2, 3)), list(rng.normal(size=4)))
        if not (np.array_equal(A, A.T) and np.array_equal(B, B.T)):
            pairs.append((A, B))
    A = np.array([p[0] for p in pairs])
    B = np.array([p[1] for p in pairs])
    r = contact_scale(A, B, rtol=1e-9)
    p = separating_plane(A, B, on_invalid="mark")
    for i, (a, b) in enumerate(pairs):
        cs = contact_scale(a, b)
        assert str(cs.relation) == oracle_relation(frac(a), frac(b)) == str(r[i].relation)
        assert r[i].lo <= cs.hi and cs.lo <= r[i].hi
        if cs.relation == Relation.SEPARATE:
            _check_plane(a, b, separating_plane(a, b))
            _check_plane(a, b, p[i])
            assert p[i].certified_by == Certifier.FLOAT  # the exact symmetric part, certified in floats
        else:
            cp = contact_point(a, b)
            if cs.relation == Relation.OVERLAP:
                x = [q(c.value) for c in cp.point]
                assert form(frac(a), x) < 0 and form(frac(b), x) < 0


# ------------------------------------------------------------------ distance (stretch)


def _check_distance(A: Any, B: Any, r: Any) -> None:
    """Exactly: the two points lie in the shapes, |p - q| <= hi, 0 < lo <= hi, the slab is lo wide."""
    check_distance(A, B, r.lo, r.hi, r.point_a, r.point_b, r.normal)
    assert r.lo > 0


@pytest.mark.parametrize(("c2", "r1", "r2"), [((3, 4, 12), 2, F(3, 2)), ((1, 1, 1), F(1, 3), F(1, 4)), ((5, 0, 0), 1, 2)])
def test_distance_spheres(c2, r1, r2):
    A, B = sphere(0, 0, 0, r1), sphere(*c2, r2)
    dist = math.sqrt(sum(F(v) ** 2 for v in c2)) - r1 - r2  # closed form (float only for irrational |c2|)
    r = distance(A, B)
    _check_distance(A, B, r)
    assert float(r.lo) <= dist + 1e-15 and dist - 1e-15 <= float(r.hi)
    assert r.hi - r.lo <= r.hi * fmpq(1, 10**12)


@pytest.mark.parametrize("k", [2, 9, 20, 40])
def test_distance_ellipse_and_circle(k):
    # ellipse x^2/4 + y^2 <= 1 and a unit circle centred at (3 + g, 0): distance exactly g
    g = F(1, 10**k)
    A, B = axis_ellipsoid([0, 0], [2, 1]), circle(3 + g, 0, 1)
    r = distance(A, B)
    _check_distance(A, B, r)
    assert q(r.lo) <= g <= q(r.hi) and r.hi - r.lo <= r.hi * fmpq(1, 10**12)


@pytest.mark.parametrize("method", ["adaptive", "float", "exact"])
@given(pair=float_pairs())
def test_distance_random(method, pair):
    A, B = pair
    r = distance(A, B, method=method, on_invalid="mark")
    if isinstance(r, NoWitness):  # method="float": the floats could not certify it
        assert method == "float" and r.kind == "undecided"
        return
    if method != "adaptive":
        assert r.certified_by == (Certifier.EXACT if method == "exact" else Certifier.FLOAT)
    if classify(A, B) != Relation.SEPARATE:
        assert r.lo == r.hi == 0
        return
    _check_distance(A, B, r)
    assert r.hi - r.lo <= r.hi * fmpq(1, 10**12)
    # the plane with normal n through the middle of the slab separates them (independent check)
    n = [q(v) for v in r.normal]
    p, qq = [q(v) for v in r.point_a], [q(v) for v in r.point_b]
    mid = (sum(a * b for a, b in zip(n, p, strict=True)) + sum(a * b for a, b in zip(n, qq, strict=True))) / 2
    assert plane_misses_on_side(frac(A), n, mid, -1) and plane_misses_on_side(frac(B), n, mid, 1)


# ------------------------------------------------------------------ generated kernels


def test_determinant_kernels_are_generated_and_current(tmp_path, monkeypatch):
    """core/witness/_det_kernels.py is what core.witness.detgen writes today (no drift), and the check notices drift."""
    from core.witness import detgen

    assert detgen.main(["--check"]) == 0
    stale = tmp_path / "_det_kernels.py"
    stale.write_text(detgen.GENERATED_PATH.read_text().replace("DET2_CONSTANT = ", "DET2_CONSTANT = 0.5 * "))
    monkeypatch.setattr(detgen, "GENERATED_PATH", stale)
    assert detgen.main(["--check"]) == 1
