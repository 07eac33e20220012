"""analyse(): the paper's Examples 29-33, 2D cases checked by hand, bad input, and a property test.

Golden values come from the paper's printed numbers (NOTES.md lists the misprinted ones) or from
closed forms computed here with Python's decimal module, never from the code under test.
"""

from decimal import Decimal, getcontext
from fractions import Fraction

import pytest
from flint import arb, arb_poly, ctx, fmpq, fmpq_poly
from hypothesis import given, settings
from hypothesis import strategies as st

from core import Relation, analyse, classify
from core.formulae.pencil import pencil_coefficients
from core.moving.motions import matrix_at_exact
from core.moving.presets import preset_arguments, preset_names

getcontext().prec = 60
S, T_, O = Relation.SEPARATE, Relation.TANGENT, Relation.OVERLAP


def dec(x: str) -> Decimal:
    return Decimal(x)


def close(value: str, expected: Decimal, digits: int) -> bool:
    """value agrees with expected to ``digits`` significant digits (one unit of slack)."""
    v = Decimal(value)
    scale = Decimal(10) ** (expected.adjusted() - digits + 1)
    return abs(v - expected) <= scale


def rounds_to(value: str, printed: str) -> bool:
    """Our decimal agrees with the paper's printed decimal to its last digit, within one unit
    there (the paper truncates some values, e.g. -0.24393036786... printed -0.2439303678)."""
    p = Decimal(printed)
    return abs(Decimal(value) - p) <= Decimal(1).scaleb(p.as_tuple().exponent)


def contains(event, x: Decimal) -> bool:
    return Decimal(int(event.lo.p)) / Decimal(int(event.lo.q)) <= x <= Decimal(int(event.hi.p)) / Decimal(int(event.hi.q))


def has_positive_double_root(P: arb_poly, rel: float) -> bool:
    """P (ball coefficients, high precision) has a positive root T* of P' with |P(T*)| tiny.

    Starting points from numpy's float roots of P', polished by Newton's method on P' in ball
    arithmetic at the current precision.
    """
    import numpy as np

    dP = P.derivative()
    ddP = dP.derivative()
    scale = max(abs(c).upper() for c in P.coeffs())
    for z0 in np.polynomial.polynomial.polyroots([float(c.mid()) for c in dP.coeffs()]):
        if abs(z0.imag) > 1e-6 * max(1.0, abs(z0)) or z0.real <= 0:
            continue
        z = arb(float(z0.real))
        for _ in range(60):
            z = (z - dP(z) / ddP(z)).mid()
        if z > 0 and abs(P(z)).upper() < scale * rel:
            return True
    return False


def T(coeffs):  # polynomial in t from ascending rational coefficients
    return fmpq_poly([fmpq(c.numerator, c.denominator) if isinstance(c, Fraction) else c for c in coeffs])


# -------------------------------------------------------------------------------------------
# Example 29 (paper 4.5; NOTES.md erratum 12 confirms P, s1 = s1,0 and the events)


@pytest.fixture(scope="module")
def ex29():
    return analyse(**preset_arguments("example-29"))


def test_example29_pencil_and_subresultants(ex29):
    b = T([-34, 96, -68])  # -68 t^2 + 96 t - 34
    q = fmpq(-1, 4)
    expected = [T([q]), (b + 2) * q, (b * 2 + 2) * q, (b + 2) * q, T([q])]  # -1/4 (T+1)^2 (T^2 + bT + 1)
    assert [p.p for p in ex29.a] == expected and all(p.q.is_zero() for p in ex29.a)
    assert ex29.case == "s1" and ex29.s0.is_zero()
    assert ex29.a[3] == ex29.a[1]
    # true s1 = -a4 * s1hat; paper: s1 = s1,0 = -1/2 (17t^2 - 24t + 8)(17t^2 - 24t + 9)^3
    target = T([8, -24, 17]) * T([9, -24, 17]) ** 3 * fmpq(-1, 2)
    assert (ex29.s1 * (-ex29.a[4].p)).p == target
    assert (ex29.s10 * (-ex29.a[4].p)).p == target
    full = ex29.subresultants()
    assert full["s1"].p == target and full["s10"].p == target and full["s0"].is_zero()


def test_example29_events_and_intervals(ex29):
    r2 = Decimal(2).sqrt()
    a1, a2 = (12 - 2 * r2) / 17, (12 + 2 * r2) / 17
    assert [str(e.relation) for e in ex29.events] == ["tangent", "tangent"]
    assert close(ex29.events[0].value, a1, 20) and close(ex29.events[1].value, a2, 20)
    assert rounds_to(ex29.events[0].value, "0.5395042868") and rounds_to(ex29.events[1].value, "0.8722604191")
    assert contains(ex29.events[0], a1) and contains(ex29.events[1], a2)
    assert [iv.relation for iv in ex29.intervals] == [S, O, S]
    assert [e.kind for e in ex29.events] == ["change", "change"]
    # Var(-, 0, 1/2, 0, -) = 2 at both events (sign table rows at the points)
    rows = [r for r in ex29.sign_table if r.where == "point"]
    assert [r.a for r in rows] == [(-1, 0, 1, 0, -1)] * 2 and all(r.var == 2 for r in rows)
    # the paper's samples: s1 < 0 at 0 and 1, > 0 at 3/4; relations free / overlap / free
    assert [ex29.relation_at(x) for x in (0, "3/4", 1)] == [S, O, S]
    assert ex29.s1.sign_at_rational(fmpq(0)) < 0 < ex29.s1.sign_at_rational(fmpq(3, 4))


# -------------------------------------------------------------------------------------------
# Example 30 (NOTES.md erratum 11: alpha_4..alpha_6 printed values are wrong; certify our own)


@pytest.fixture(scope="module")
def ex30():
    return analyse(**preset_arguments("example-30"))


def test_example30_degrees_and_roots(ex30):
    assert max(p.degree() for p in ex30.a) == 14
    assert (ex30.s0.degree(), ex30.s1.degree(), ex30.s10.degree()) == (84, 56, 56)
    assert ex30.sqrt_d == 2 and ex30.case == "s0"
    alphas = sorted([*ex30.events, *ex30.roots], key=float)
    assert len(alphas) == 6 and sum(float(a) < 0 for a in alphas) == 2
    assert rounds_to(alphas[0].value, "-0.2439303678")
    assert rounds_to(alphas[1].value, "-0.1859966702")
    assert alphas[2].time.value == fmpq(1, 2) and alphas[2].value == "0.5"


def test_example30_relations(ex30):
    assert [e.value[:6] for e in ex30.events][:3] == ["-0.243", "-0.185", "0.5"]
    assert len(ex30.events) == 4 and all(e.relation == T_ for e in ex30.events)
    assert [iv.relation for iv in ex30.intervals] == [S, O, S, O, S]
    # alpha_4, alpha_5: roots of s0 inside (alpha_3, alpha_6) where the shapes overlap,
    # with s1 < 0, s1,0 < 0 and Var = 0 (the paper's qualitative statement)
    assert [r.relation for r in ex30.roots] == [O, O]
    assert 0.5 < float(ex30.roots[0]) < float(ex30.roots[1]) < float(ex30.events[3])
    rows = [r for r in ex30.sign_table if r.where == "point" and r.relation == O]
    assert len(rows) == 2 and all(r.s1 < 0 and r.s10 < 0 and r.var == 0 for r in rows)
    # tangent points: s1 < 0, s1,0 > 0 (Theorem 24(2))
    for r in (r for r in ex30.sign_table if r.where == "point" and r.relation == T_):
        assert r.s1 < 0 < r.s10
    # the paper's delta points
    assert [ex30.relation_at(x) for x in ("-0.3", "-0.2", 0, 1)] == [S, O, S, S]
    assert ex30.relation_at("1/2") == T_


def test_example30_half_is_exactly_tangent_independently():
    """At t = 1/2, P(T) has a positive double root: computed from the paper's printed data with
    mpmath-free ball arithmetic (flint arb), without the parser, motions or analysis code."""
    ctx.prec = 300
    try:
        r2 = arb(2).sqrt()
        t = arb(1) / 2
        # rotation and translation of A and B at t = 1/2 from the paper's formulas
        D = 8 * t**2 - 8 * t + 3
        RA = [[(-8 * t**2 + 8 * t - 1) / D, (-4 * t + 2) / D, (4 * t - 2) / D],
              [(4 * t - 2) / D, 1 / D, 2 * (2 * t - 1) ** 2 / D],
              [(-4 * t + 2) / D, 2 * (2 * t - 1) ** 2 / D, 1 / D]]
        E = -6 * t**2 + 6 * t - 2
        RB = [[r2 * (t - 1) * (3 * t - 1) / E, 2 * t * (2 * t - 1) / E, r2 * (t - 1) ** 2 / E],
              [r2 * (2 * t - 1) / E, -2 * t * (t - 1) / E, r2 * (2 * t - 1) ** 2 / E],
              [-r2 * t * (3 * t - 2) / E, 2 * (2 * t - 1) * (t - 1) / E, r2 * t**2 / E]]
        cA = [-8 * t**3 + 24 * t**2 - 6 * t - 2, -24 * t**3 + 24 * t**2 + 6 * t - 6, -32 * t**3 + 48 * t**2 - 12 * t - 2]
        cB = [(72 - 24 * r2) * t**3 + (-156 + 72 * r2) * t**2 + (114 - 72 * r2) * t - 27 + 24 * r2, 12 * t - 6,
              (88 - 24 * r2) * t**3 + (-168 + 72 * r2) * t**2 + (114 - 72 * r2) * t - 26 + 24 * r2]

        def world(R, c, axes):
            Q = [[sum(R[i][k] * R[j][k] / axes[k] ** 2 for k in range(3)) for j in range(3)] for i in range(3)]
            Qc = [sum(Q[i][j] * c[j] for j in range(3)) for i in range(3)]
            return [[*Q[i], -Qc[i]] for i in range(3)] + [[*(-v for v in Qc), sum(c[i] * Qc[i] for i in range(3)) - 1]]

        A = world(RA, cA, [2, 4, 2])
        B = world(RB, cB, [1, 3, 4])
        assert has_positive_double_root(arb_poly(pencil_coefficients(A, B)), 1e-40)
    finally:
        ctx.prec = 53


# -------------------------------------------------------------------------------------------
# Examples 31-33


def test_example31_touch_and_leave():
    r = analyse(**preset_arguments("example-31"))
    assert [(e.value, e.relation, e.kind) for e in r.events] == [("4", T_, "touch")]
    assert [iv.relation for iv in r.intervals] == [S, S]
    assert r.s0.degree() == 12 and r.a[4].degree() == 0 and r.a[0].degree() == 0
    assert [r.a[i].degree() for i in (1, 2, 3)] == [2, 2, 2] and len({str(r.a[i]) for i in (1, 2, 3)}) == 3
    root = Decimal(336).sqrt()  # alpha_1,3 = 4 -+ sqrt(336) = -14.3303027798, 22.3303027798
    assert close(r.roots[0].value, 4 - root, 20) and close(r.roots[1].value, 4 + root, 20)
    assert rounds_to(r.roots[0].value, "-14.3303027798") and rounds_to(r.roots[1].value, "22.3303027798")
    rows = [row for row in r.sign_table if row.where == "point"]
    assert [(row.s1, row.s10) for row in rows] == [(-1, -1), (-1, 1), (-1, -1)]
    assert [r.relation_at(x) for x in (0, 5, 4, "4.000000001")] == [S, S, T_, S]


def test_example32():
    r = analyse(**preset_arguments("example-32"))
    half5 = Decimal(5).sqrt() / 2
    assert close(r.events[0].value, -half5, 20) and close(r.events[1].value, half5, 20)
    assert rounds_to(r.events[0].value, "-1.118033989") and rounds_to(r.events[1].value, "1.118033989")
    assert [iv.relation for iv in r.intervals] == [O, S, O]
    assert all(p.degree() == 4 for p in r.a)
    # the paper's degrees are of s_j = -a4 * shat_j
    assert r.s0.degree() + r.a[4].degree() == 26 and r.s1.degree() + 4 == 20 and r.s10.degree() + 4 == 20
    full = r.subresultants()
    assert (full["s0"].degree(), full["s1"].degree(), full["s10"].degree()) == (26, 20, 20)
    rows = [row for row in r.sign_table if row.where == "point"]
    assert all(row.s1 < 0 < row.s10 for row in rows)
    assert [r.relation_at(x) for x in (-2, 0, 2)] == [O, S, O]


def test_example33_identically_tangent():
    r = analyse(**preset_arguments("example-33"))
    assert r.case == "s1" and r.events == [] and [iv.relation for iv in r.intervals] == [T_]
    # P = -(T+1)(T+4)(T-1)^2 / 576 up to a positive factor: ascending [-4, 3, 5, -3, -1]
    target = [-4, 3, 5, -3, -1]
    k = r.a[4].p.coeffs()[0] / target[4]
    assert k > 0 and all(r.a[i].p == fmpq_poly([k * c]) for i, c in enumerate(target))
    assert r.relation_at("123/7") == T_


# -------------------------------------------------------------------------------------------
# 2D cases verified by hand


def circle(x: str, y: str = "0") -> list[list[str]]:
    """Unit circle centred at (x(t), y(t)) as a matrix of expressions."""
    return [["1", "0", f"-({x})"], ["0", "1", f"-({y})"], [f"-({x})", f"-({y})", f"({x})^2 + ({y})^2 - 1"]]


def test_circles_crossing_on_a_line():
    r = analyse(circle("t"), circle("-t"), (-2, 2))  # centres 2|t| apart: tangent iff |t| = 1
    assert [(e.time.value, e.kind) for e in r.events] == [(-1, "change"), (1, "change")]
    assert [iv.relation for iv in r.intervals] == [S, O, S]
    assert [(float(iv.lo), float(iv.hi)) for iv in r.intervals] == [(-2, -1), (-1, 1), (1, 2)]
    assert [str(x.relation) for x in r.roots] == ["overlap"]  # t = 0: identical circles


def test_touch_and_leave_2d():
    r = analyse(circle("t", "2"), circle("0"), ("-3", "3"))  # distance sqrt(t^2 + 4) >= 2
    assert [(e.time.value, e.kind, e.before, e.after) for e in r.events] == [(0, "touch", S, S)]


def test_sqrt2_in_the_input():
    r = analyse(circle("sqrt(2)*t"), circle("0"), (None, None))  # tangent at |t| = sqrt 2
    r2 = Decimal(2).sqrt()
    assert close(r.events[0].value, -r2, 20) and close(r.events[1].value, r2, 20)
    assert r.sqrt_d == 2 and [iv.relation for iv in r.intervals] == [S, O, S]
    assert r.relation_at("1.4142135623") == O and r.relation_at("1.4142135624") == S


def test_events_at_interval_ends():
    r = analyse(circle("t"), circle("-t"), ("1", "2"))
    assert [(e.time.value, e.kind, e.before, e.after) for e in r.events] == [(1, "endpoint", None, S)]
    assert [iv.relation for iv in r.intervals] == [S]
    assert r.relation_at(1) == T_ and r.relation_at(2) == S
    r = analyse(circle("t"), circle("-t"), ("0", "1"))
    assert [(e.time.value, e.kind, e.before, e.after) for e in r.events] == [(1, "endpoint", O, None)]
    with pytest.raises(ValueError, match="outside"):
        r.relation_at(3)


def test_no_events_and_identical_shapes():
    r = analyse(circle("t", "5"), circle("0"), (-1, 1))
    assert r.events == [] and [iv.relation for iv in r.intervals] == [S]
    same = analyse(circle("t"), circle("t"), (None, None))
    assert same.case == "none" and same.events == [] and [iv.relation for iv in same.intervals] == [O]


def test_refine_to_50_digits():
    r = analyse(**preset_arguments("example-29"))
    r2 = Decimal(2).sqrt()
    assert close(r.events[0].decimal(50), (12 - 2 * r2) / 17, 50)


def test_to_dict_is_json_ready():
    import json

    r = analyse(circle("t"), circle("-t"), ("-2", "2"), digits=12)
    d = json.loads(json.dumps(r.to_dict()))
    assert d["events"][0]["exact"] == "-1" and d["events"][0]["relation"] == "tangent"
    assert [iv["relation"] for iv in d["intervals"]] == ["separate", "overlap", "separate"]
    assert d["intervals"][0]["lo"]["exact"] == "-2" and d["polynomials"]["degrees"]["s0"] == 8
    assert {"where", "a", "s0", "s1", "s10", "var", "relation"} <= set(d["sign_table"][0])
    s = r.samples(num=11)
    assert len(s["t"]) == 11 and len(s["a"]) == 4 and s["t"][0] == -2.0


# -------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize(
    "A, B, interval, fragment",
    [
        (circle("1/(t - 1)"), circle("0"), (0, 2), "denominator vanishes at t ≈ 1"),
        ([["t", "0", "0"], ["0", "1", "0"], ["0", "0", "-1"]], circle("3"), (-1, 3), "stops being an ellipse at t ≈ 0"),
        ([["1", "0", "0"], ["0", "-1", "0"], ["0", "0", "-1"]], circle("3"), (-1, 1), "not an ellipse anywhere in [-1, 1]"),
        ({"shape": {"center": [0, 0], "semi_axes": ["t", "1"]}}, circle("3"), ("1/2", 2), None),
        ({"shape": {"center": [0, 0], "semi_axes": ["t - 1", "1"]}}, circle("3"), (0, 2), "vanishes at t ≈ 1"),
        (circle("t^20"), circle("0"), (0, 1), "degree in t too high"),
        (circle("3*t + x"), circle("0"), (0, 1), "unexpected 'x'"),
        (circle("t" + " + t" * 1000), circle("0"), (0, 1), None),  # long but cheap: the library takes it
        (circle("sqrt(2)*t"), circle("sqrt(3)"), (0, 1), "only one square root"),
        (circle("t"), circle("0"), (1, 1), "empty interval"),
        (circle("t"), [["1", "0", "0", "0"], ["0", "1", "0", "0"], ["0", "0", "1", "0"], ["0", "0", "0", "-1"]], (0, 1), "both ellipses or both ellipsoids"),
        (circle("t"), circle("0"), (0, 1, 2), "pair"),
    ],
)
def test_bad_input(A, B, interval, fragment):
    if fragment is None:  # valid on [1/2, 2]: no error
        analyse(A, B, interval)
        return
    with pytest.raises(ValueError) as e:
        analyse(A, B, interval)
    assert fragment in str(e.value)


def test_digits_argument():
    with pytest.raises(ValueError, match="digits"):
        analyse(circle("t"), circle("-t"), (-2, 2), digits=0)
    r = analyse(circle("t"), circle("sqrt(2)"), (-1, 4), digits=5)  # |t - sqrt 2| = 2
    assert [e.value for e in r.events] == ["-0.58579", "3.4142"]


# -------------------------------------------------------------------------------------------
# property: intervals agree with classify at rational points; events are tangent


def _poly_str(coeffs):
    return " + ".join(f"({c})*t^{k}" for k, c in enumerate(coeffs)) or "0"


def _pv(coeffs, t):
    return sum(Fraction(c) * t**k for k, c in enumerate(coeffs))


small = st.integers(-3, 3)


@st.composite
def moving_pair(draw):
    dim = draw(st.sampled_from([2, 3]))
    shapes = []
    for _ in range(2):
        axes = [draw(st.integers(1, 3)) for _ in range(dim)]
        trans = [[draw(small) for _ in range(draw(st.integers(1, 3)))] for _ in range(dim)]
        shapes.append((axes, trans))
    return dim, shapes


def _matrix_strings(axes, trans):
    d = len(axes)
    c = [_poly_str(p) for p in trans]
    q = [f"1/{a * a}" for a in axes]
    M = [[q[i] if i == j else "0" for j in range(d)] + [f"-({q[i]})*({c[i]})"] for i in range(d)]
    M.append([f"-({q[i]})*({c[i]})" for i in range(d)] + [" + ".join(f"({q[i]})*({c[i]})^2" for i in range(d)) + " - 1"])
    return M


def _matrix_at(axes, trans, t):
    d = len(axes)
    c = [_pv(p, t) for p in trans]
    q = [Fraction(1, a * a) for a in axes]
    M = [[q[i] if i == j else Fraction(0) for j in range(d)] + [-q[i] * c[i]] for i in range(d)]
    M.append([-q[i] * c[i] for i in range(d)] + [sum(q[i] * c[i] ** 2 for i in range(d)) - 1])
    return [[fmpq(v.numerator, v.denominator) for v in row] for row in M]


def _tangent_at(axes_trans, ev) -> bool:
    """Independent check at an algebraic time: P(T) has a positive double root (ball arithmetic)."""
    ctx.prec = 400
    try:
        ev.time.refine_to(fmpq(1, 2**300))
        x = arb((ev.time.lo + ev.time.hi) / 2)
        mats = []
        for axes, trans in axes_trans:
            d = len(axes)
            c = [sum(arb(v) * x**k for k, v in enumerate(p)) for p in trans]
            q = [arb(1) / (a * a) for a in axes]
            M = [[q[i] if i == j else arb(0) for j in range(d)] + [-q[i] * c[i]] for i in range(d)]
            M.append([-q[i] * c[i] for i in range(d)] + [sum(q[i] * c[i] ** 2 for i in range(d)) - 1])
            mats.append(M)
        return has_positive_double_root(arb_poly(pencil_coefficients(*mats)), 1e-60)
    finally:
        ctx.prec = 53


@settings(deadline=None, max_examples=40)
@given(moving_pair(), st.data())
def test_property_intervals_match_classify(pair, data):
    dim, shapes = pair
    A, B = (_matrix_strings(*s) for s in shapes)
    r = analyse(A, B, ("-2", "2"), digits=10)
    for iv in r.intervals:
        lo = iv.lo.hi if iv.lo is not None else fmpq(-2)
        hi = iv.hi.lo if iv.hi is not None else fmpq(2)
        points = [iv.sample, lo + (hi - lo) / 3, lo + (hi - lo) * 2 / 3]
        for t in points:
            if not lo < t < hi:
                continue
            tf = Fraction(int(t.p), int(t.q))
            rel = classify(_matrix_at(*shapes[0], tf), _matrix_at(*shapes[1], tf), method="exact")
            assert rel == iv.relation, (t, rel, iv.relation)
            assert r.relation_at(t) == iv.relation
    for ev in r.events:
        assert ev.relation == T_
        if ev.time.value is not None:
            tf = Fraction(int(ev.time.value.p), int(ev.time.value.q))
            assert classify(_matrix_at(*shapes[0], tf), _matrix_at(*shapes[1], tf), method="exact") == T_
        else:
            assert _tangent_at(shapes, ev)
    # and the exact evaluation of the motions agrees with this test's own matrices
    t0 = fmpq(1, 3)
    assert matrix_at_exact(A, t0) == _matrix_at(*shapes[0], Fraction(1, 3))


@st.composite
def rotating_pair(draw):
    def motion():
        q = ["1"] + [f"{draw(small)}*t + {draw(small)}" for _ in range(3)]
        return {
            "shape": {"center": [0, 0, 0], "semi_axes": [draw(st.integers(1, 3)) for _ in range(3)]},
            "translation": [f"{draw(small)}*t + {draw(small)}" for _ in range(3)],
            "rotation": {"quaternion": q},
        }

    return motion(), motion()


def _rf_at(e, x):
    num = arb_poly(e.num.p)(x)
    if not e.num.q.is_zero():
        num += arb_poly(e.num.q)(x) * arb(e.num.d).sqrt()
    return num / arb_poly(e.den)(x)


@settings(deadline=None, max_examples=12)
@given(rotating_pair())
def test_property_rotating_ellipsoids(pair):
    A, B = pair
    try:
        r = analyse(A, B, ("-2", "2"), digits=10)
    except ValueError as e:  # a random quaternion may vanish in I: then the error says so
        assert "vanishes" in str(e) or "stops being" in str(e)
        return
    for iv in r.intervals:
        t = iv.sample
        rel = classify(matrix_at_exact(A, t), matrix_at_exact(B, t), method="exact")
        assert rel == iv.relation
    for ev in r.events:
        ctx.prec = 400
        try:
            ev.time.refine_to(fmpq(1, 2**300))
            x = arb((ev.time.lo + ev.time.hi) / 2)
            mats = [[[_rf_at(e, x) for e in row] for row in r.A.matrix()], [[_rf_at(e, x) for e in row] for row in r.B.matrix()]]
            assert has_positive_double_root(arb_poly(pencil_coefficients(*mats)), 1e-60)
        finally:
            ctx.prec = 53


# -------------------------------------------------------------------------------------------
# the exact layer underneath: Q(sqrt d)[t], real roots, signs at algebraic numbers


def test_real_roots_of_qsqrt_polynomials():
    from core.algebra.qsqrt import QSqrtPoly
    from core.algebra.realroots import real_roots

    t = QSqrtPoly(fmpq_poly([0, 1]))
    r2 = QSqrtPoly(0, 1, 2)
    roots = real_roots((t - r2) * (t + 1))  # the conjugate root -sqrt 2 of the norm is not a root
    assert [x.value for x in roots[:1]] == [-1] and len(roots) == 2
    assert close(roots[1].decimal(30), Decimal(2).sqrt(), 30)
    # two roots 1e-30 apart, plus complex ones
    eps = fmpq(1, 10**30)
    f = QSqrtPoly(fmpq_poly([-fmpq(1, 3), 1]) * fmpq_poly([-fmpq(1, 3) - eps, 1]) * fmpq_poly([1, 0, 1]))
    got = real_roots(f)
    assert [x.value for x in got] == [fmpq(1, 3), fmpq(1, 3) + eps]
    # irrational roots 3.5e-31 apart: sqrt 2 and sqrt(2 + 1e-30) (and their negatives)
    g = QSqrtPoly(fmpq_poly([-2, 0, 1]) * fmpq_poly([-2 - eps, 0, 1]))
    got = real_roots(g, fmpq(0), None)
    assert len(got) == 2 and got[0].hi < got[1].lo
    assert close(got[0].decimal(40), Decimal(2).sqrt(), 40)
    assert close(got[1].decimal(40), (2 + Decimal(1) / Decimal(10**30)).sqrt(), 40)
    # Wilkinson's polynomial of degree 20: all 20 integer roots, exactly
    w = fmpq_poly([1])
    for k in range(1, 21):
        w *= fmpq_poly([-k, 1])
    assert [x.value for x in real_roots(QSqrtPoly(w))] == list(range(1, 21))
    assert [x.value for x in real_roots(QSqrtPoly(w), fmpq(5), fmpq(7))] == [5, 6, 7]  # closed interval


def test_signs_at_algebraic_numbers_are_exact():
    from flint import fmpz_poly

    from core.algebra.algebraic import RealAlgebraic, sign_at
    from core.algebra.qsqrt import QSqrtPoly

    alpha = RealAlgebraic.isolating(fmpz_poly([-2, 0, 1]), fmpq(1), fmpq(2))  # sqrt 2
    t = fmpq_poly([0, 1])
    assert sign_at(QSqrtPoly(-2, t, 2), alpha) == 0  # sqrt2 * sqrt2 - 2, with p, q both nonzero
    assert sign_at(QSqrtPoly(2, t, 2), alpha) == 1
    assert sign_at(QSqrtPoly(t * t - 2), alpha) == 0
    # a rational 1e-40 below sqrt 2: the sign of t - r at sqrt 2 is +1 (needs refinement)
    getcontext().prec = 80
    r = Decimal(2).sqrt().quantize(Decimal(10) ** -40, rounding="ROUND_FLOOR")
    rq = fmpq(int(r.scaleb(40)), 10**40)
    assert sign_at(QSqrtPoly(t - rq), alpha) == 1
    assert sign_at(QSqrtPoly(t - rq - fmpq(1, 10**40)), alpha) == -1
    getcontext().prec = 60


def test_relation_at_lookup_agrees_with_static_classifier():
    """relation_at's interval lookup against core.classify on the exact A(t), B(t)."""
    from core.moving.presets import preset_arguments

    for name in ("example-29", "example-31", "example-32", "example-33", "circles-crossing"):
        r = analyse(**preset_arguments(name))
        lo = r.interval[0] if r.interval[0] is not None else fmpq(-3)
        hi = r.interval[1] if r.interval[1] is not None else fmpq(6)
        for k in range(0, 41):
            t = lo + (hi - lo) * fmpq(k, 40)
            assert r.relation_at(t) == r.relation_at(t, via="classify"), (name, t)
    with pytest.raises(ValueError, match="valid options"):
        r.relation_at(0, via="guess")
    with pytest.warns(DeprecationWarning, match="via="):  # the old keyword still answers
        assert r.relation_at(lo, method="classify") == r.relation_at(lo)


def test_sign_row_at_agrees_with_the_static_explanation():
    """Signs at a rational t from the analysis polynomials == signs of core.explain on the exact
    A(t), B(t) (an independent path: static pencil of the evaluated matrices), and the row's
    relation == classify there. The analysis' a_i are a positive multiple of the true ones."""
    from core import explain

    for name in ("example-29", "example-31", "example-32", "example-33", "circles-crossing", "circles-graze"):
        r = analyse(**preset_arguments(name))
        lo = r.interval[0] if r.interval[0] is not None else fmpq(-3)
        hi = r.interval[1] if r.interval[1] is not None else fmpq(6)
        for k in range(0, 31):
            t = lo + (hi - lo) * fmpq(k, 30)
            row = r.sign_row_at(t)
            e = explain(matrix_at_exact(r.A, t), matrix_at_exact(r.B, t))
            assert row.a == tuple(q.sign for q in reversed(e.coefficients)), (name, t)
            assert row.relation == e.relation == classify(matrix_at_exact(r.A, t), matrix_at_exact(r.B, t)), (name, t)
            assert row.relation == r.relation_at(t), (name, t)
            for key in ("s0", "s1", "s10"):  # the tree's needed s_j: same sign as the paper's s_j
                q = getattr(e, key)
                if q is not None:
                    assert getattr(row, key) == q.sign, (name, t, key)
    with pytest.raises(ValueError, match="outside"):
        r.sign_row_at(hi + 1)


def test_sign_row_at_sqrt2_motion_matches_interval_rows():
    """Example 30 (sqrt 2 entries): at each interval's sample the row is the sign table's row."""
    r = analyse(**preset_arguments("example-30"))
    rows = [row for row in r.sign_table if row.where == "interval"]
    assert rows
    for row in rows:
        got = r.sign_row_at(row.t)
        assert (got.a, got.s0, got.s1, got.s10, got.var, got.relation, got.rule) == (
            row.a, row.s0, row.s1, row.s10, row.var, row.relation, row.rule)
    # alpha_3 = 1/2 is a rational event: the row there is tangent with s0 = 0
    half = r.sign_row_at(fmpq(1, 2))
    assert half.relation == Relation.TANGENT and half.s0 == 0


def test_qsqrt_polynomials_pickle_exactly():
    """The scene's workers send the analysis polynomials back through pickle."""
    import pickle

    r = analyse(**preset_arguments("example-30"))
    polys = r.polynomials()
    back = pickle.loads(pickle.dumps(polys))
    assert back == polys and all(back[k].d == polys[k].d for k in polys)


@pytest.mark.parametrize("name", preset_names())
def test_analysis_pickles_exactly(name):
    """The result travels between processes unchanged (flint polynomials included)."""
    import pickle

    r = analyse(**preset_arguments(name))
    r2 = pickle.loads(pickle.dumps(r))
    assert [(e.decimal(40), e.relation, e.kind) for e in r2.events] == [(e.decimal(40), e.relation, e.kind) for e in r.events]
    assert [str(p) for p in r2.a] == [str(p) for p in r.a] and str(r2.s0) == str(r.s0)
    lo, hi = r.interval
    for t in [x for x in (lo, hi, "1/3", "-7/5", "2") if x is not None]:
        try:
            want = r.relation_at(t)
        except ValueError:  # outside I
            continue
        assert r2.relation_at(t) == want and r2.sign_row_at(t) == r.sign_row_at(t)
