"""First contact of two moving shapes (core.moving.first_contact) and its lazy root isolation.

Goldens are independent of the code under test: hand-solved motions (circles whose centres
move on lines: the contact time solves a quadratic), the paper's Example 29 closed form
(12 - 2 sqrt 2) / 17 (NOTES.md), and the full exact analysis :func:`core.analyse` (every event
and interval; first_contact must give its first non-separate time) on the presets and on random
rational motions. The root isolation is checked against :func:`core.algebra.realroots.real_roots`
(factorisation + Descartes on each factor).
"""

from __future__ import annotations

import random

import pytest
from flint import fmpq, fmpq_poly
from hypothesis import given
from hypothesis import strategies as st

from core import Relation, analyse, first_contact, preset, preset_names
from core.algebra.qsqrt import QSqrtPoly
from core.algebra.realroots import real_roots, roots_in_order
from core.moving.result import Event


def circle(x: str, y: str = "0", r: str = "1") -> list[list[str]]:
    """Circle of radius r centred at (x, y): expressions in t."""
    return [
        ["1", "0", f"-({x})"],
        ["0", "1", f"-({y})"],
        [f"-({x})", f"-({y})", f"({x})^2 + ({y})^2 - ({r})^2"],
    ]


def truth(A, B, lo, hi):
    """(t*, relation) from the full exact analysis: t* = lo if not separate there, else the first event."""
    r = analyse(A, B, (lo, hi))
    rel = r.relation_at(lo)
    if rel != Relation.SEPARATE:
        return fmpq(lo), rel
    for e in r.events:
        if e.time.compare(fmpq(lo)) > 0:
            return e.time, e.relation
    return None, None


def same_time(a, b) -> bool:
    """Two exact times (RealAlgebraic or fmpq) are equal."""
    from core.algebra.algebraic import RealAlgebraic

    a = a if isinstance(a, RealAlgebraic) else RealAlgebraic.rational(a)
    b = b if isinstance(b, RealAlgebraic) else RealAlgebraic.rational(b)
    if a.value is not None:
        return b.compare(a.value) == 0
    if b.value is not None:
        return a.compare(b.value) == 0
    a.refine_to(fmpq(1, 10**40))
    b.refine_to(fmpq(1, 10**40))
    return not (a.hi < b.lo or b.hi < a.lo) and a.poly.gcd(b.poly).degree() > 0


# ------------------------------------------------------------------------ hand-solved cases


def test_circles_approaching_touch_at_a_quarter():
    # |c_A - c_B| = 3 - 4t = 2 (sum of radii) at t = 1/4; overlap after
    e = first_contact(circle("3 - 4*t"), circle("0"), (0, 1))
    assert isinstance(e, Event)
    assert e.time.compare(fmpq(1, 4)) == 0 and e.value == "0.25"
    assert (e.relation, e.kind, e.before, e.after) == (Relation.TANGENT, "change", Relation.SEPARATE, Relation.OVERLAP)


def test_circles_moving_apart_never_meet():
    assert first_contact(circle("3 + t"), circle("0"), (0, 1)) is None
    assert first_contact(circle("3 + t"), circle("0"), (0, None)) is None  # no end


def test_overlap_and_tangency_at_the_start():
    e = first_contact(circle("1"), circle("0"), (0, 1))
    assert (e.value, e.relation, e.kind, e.before, e.after) == ("0", Relation.OVERLAP, "endpoint", None, Relation.OVERLAP)
    e = first_contact(circle("2 + t"), circle("0"), (0, 1))  # tangent at 0, then apart
    assert (e.value, e.relation, e.kind, e.after) == ("0", Relation.TANGENT, "endpoint", Relation.SEPARATE)


def test_graze_is_a_touch_and_the_end_is_an_endpoint():
    # centre (t - 1/2, 2): distance to the origin >= 2, equal only at t = 1/2
    e = first_contact(circle("t - 1/2", "2"), circle("0"), (0, 1))
    assert (e.value, e.relation, e.kind, e.after) == ("0.5", Relation.TANGENT, "touch", Relation.SEPARATE)
    e = first_contact(circle("4 - 2*t"), circle("0"), (0, 1))  # touch exactly at hi = 1
    assert (e.value, e.kind, e.after) == ("1", "endpoint", None)
    assert first_contact(circle("4 - 2*t"), circle("0"), (0, "1/2")) is None


def test_irrational_contact_time():
    # centres (3 - 4t, 1): (3 - 4t)^2 + 1 = 4 at t = (3 - sqrt 3) / 4
    e = first_contact(circle("3 - 4*t", "1"), circle("0"), (0, 1))
    quad = fmpq_poly([3, -12, 8])  # 8 t^2 - 12 t + 3: roots (3 -+ sqrt 3) / 4
    assert e.time.value is None and quad(e.time.lo) * quad(e.time.hi) < 0  # the isolating interval holds its root
    assert e.time.hi < 1 and e.decimal(15) == "0.316987298107781"


def test_example_29_closed_form():
    p = preset("example-29")  # NOTES.md: tangent at (12 - 2 sqrt 2) / 17 first
    e = first_contact(p["A"], p["B"], (0, 1))
    assert e.relation == Relation.TANGENT and e.kind == "change"
    # (17 t - 12)^2 = 8 at t = (12 - 2 sqrt 2) / 17 = 0.5395042867796...
    assert e.decimal(13) == "0.5395042867796"
    assert e.time.poly(e.time.lo) * e.time.poly(e.time.hi) < 0


@pytest.mark.parametrize("name", preset_names())
def test_presets_against_the_full_analysis(name):
    p = preset(name)
    lo, hi = p["interval"]
    lo = "-3" if lo is None else lo
    hi = "5" if hi is None else hi
    for start in (lo, str((fmpq(lo) * 2 + fmpq(hi)) / 3)):
        t, rel = truth(p["A"], p["B"], start, hi)
        e = first_contact(p["A"], p["B"], (start, hi))
        if t is None:
            assert e is None
        else:
            assert e is not None and e.relation == rel and same_time(e.time, t), (name, start)


@given(
    st.integers(-6, 6), st.integers(-6, 6), st.integers(-6, 6), st.integers(-6, 6),
    st.integers(1, 3), st.integers(1, 3), st.integers(0, 3),
)
def test_random_moving_ellipses_against_the_full_analysis(x0, vx, y0, vy, a, b, turn):
    # ellipse A turning (rational rotation), ellipse B translating; interval [0, 2]
    A = {"shape": {"center": [0, 0], "semi_axes": [a, 1]}, "rotation": {"quaternion": ["1", f"{turn}*t/2"]}}
    B = {"shape": {"center": [0, 0], "semi_axes": [1, b]}, "translation": [f"{x0} + {vx}*t", f"{y0}/2 + {vy}*t/2"]}
    t, rel = truth(A, B, "0", "2")
    e = first_contact(A, B, ("0", "2"))
    if t is None:
        assert e is None
    else:
        assert e is not None and e.relation == rel and same_time(e.time, t)


def test_bad_input():
    with pytest.raises(ValueError, match="finite start"):
        first_contact(circle("t"), circle("0"), (None, 1))
    with pytest.raises(ValueError, match="digits"):
        first_contact(circle("t"), circle("0"), (0, 1), digits=0)
    with pytest.raises(ValueError, match="empty interval"):
        first_contact(circle("t"), circle("0"), (1, 1))
    with pytest.raises(ValueError, match="stops being an ellipse"):  # as analyse: invalid in I
        first_contact([["1 - t", "0", "0"], ["0", "1", "0"], ["0", "0", "-1"]], circle("3"), (0, 2))


# ------------------------------------------------------------------------ lazy root isolation


def test_roots_in_order_matches_real_roots():
    rng = random.Random(1)
    for trial in range(300):
        p = fmpq_poly([rng.randint(-20, 20) for _ in range(rng.randint(2, 9))])
        for _ in range(rng.randint(0, 3)):  # rational roots, sometimes at the ends of boxes
            p = p * fmpq_poly([-fmpq(rng.randint(-10, 10), rng.randint(1, 4)), 1])
        if p.degree() < 1:
            continue
        s = QSqrtPoly(p) if trial % 3 else QSqrtPoly(p, fmpq_poly([rng.randint(-3, 3), 1]), 2)
        lo = fmpq(rng.randint(-5, 5), rng.randint(1, 3))
        for hi in (lo + fmpq(rng.randint(1, 10), rng.randint(1, 3)), None):
            want = [r for r in real_roots(s, lo, hi) if r.compare(lo) > 0]
            got = list(roots_in_order(s, lo, hi))
            assert len(got) == len(want), (trial, s, lo, hi)
            for w, g in zip(want, got, strict=True):
                g.refine_to(fmpq(1, 10**20))
                assert w.compare(g.lo) >= 0 and w.compare(g.hi) <= 0, (trial, s, lo, hi)


def test_roots_in_order_is_lazy_and_ascending():
    s = QSqrtPoly(fmpq_poly([-6, 11, -6, 1]))  # (t - 1)(t - 2)(t - 3)
    it = roots_in_order(s, fmpq(0), fmpq(3))
    assert next(it).compare(fmpq(3, 2)) < 0
    assert next(it).compare(fmpq(5, 2)) < 0
    assert next(it).compare(fmpq(3)) == 0  # the root at hi comes last
    assert next(it, None) is None
    assert list(roots_in_order(s, fmpq(1), fmpq(2))) != [] and len(list(roots_in_order(s, fmpq(1), fmpq(2)))) == 1  # (1, 2]: only 2
    with pytest.raises(ValueError):
        list(roots_in_order(QSqrtPoly(fmpq_poly([0])), fmpq(0)))
