"""Inputs as users build them: numpy matrices symmetric up to rounding, number types, extreme values,
flipped and negatively scaled motions, invalid pairs in a batch (issue 10).

Expected values come from the independent oracle (tests/oracle.py: exact symmetric part, flint
characteristic polynomial and certified root isolation) or from exact constructions.
"""

from __future__ import annotations

import json
from fractions import Fraction as F

import numpy as np
import pytest
from cases import circle, sphere
from flint import fmpq
from hypothesis import given
from hypothesis import strategies as st
from oracle import oracle_relation

from core import Relation, analyse, classify, explain, preset, preset_names
from core.fixed.classify import Certifier, classify_detailed
from core.moving.motions import as_motion

U, INVALID = Relation.UNDECIDED, Relation.INVALID


# -------------------------------------------------------------------------------------------
# matrices built with numpy, the way users build them


def _rotation(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def numpy_shape(c: np.ndarray, axes: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """S = R diag(1/ax^2) R^T and M = [[S, -S c], [-c^T S, c^T S c - 1]] in plain float64 numpy:
    symmetric only up to rounding, as user code produces it."""
    d = len(c)
    S = rot @ np.diag(1 / axes**2) @ rot.T
    M = np.empty((d + 1, d + 1))
    M[:d, :d] = S
    M[:d, d] = -S @ c
    M[d, :d] = -c @ S
    M[d, d] = c @ S @ c - 1
    return M


@st.composite
def numpy_pairs(draw, d=None, spread=4.0):
    d = d or draw(st.sampled_from([2, 3]))
    out = []
    for _ in range(2):
        c = np.array([draw(st.floats(-spread, spread)) for _ in range(d)])
        axes = np.array([draw(st.floats(0.2, 3.0)) for _ in range(d)])
        if d == 3:
            q = np.array([draw(st.floats(-1, 1)) for _ in range(4)])
            if np.linalg.norm(q) < 1e-2:
                q = np.array([1.0, 0, 0, 0])
            rot = _rotation(q)
        else:
            th = draw(st.floats(0, 3.2))
            rot = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
        out.append(numpy_shape(c, axes, rot))
    return out


@given(numpy_pairs())
def test_numpy_built_pairs_are_classified_as_their_quadratic_form(pair):
    A, B = pair
    truth = Relation[oracle_relation(A, B).upper()]  # oracle: exact (A + A^T)/2
    for method in ("adaptive", "exact"):
        assert classify(A, B, method=method) == truth
    assert classify(A, B, method="float") in (U, truth)
    assert classify(B, A) == truth
    assert explain(A, B).relation == truth


def test_numpy_built_batches_stay_in_the_float_filter():
    rng = np.random.default_rng(7)
    for d in (2, 3):
        mats = []
        for _ in range(400):
            q = rng.normal(size=4)
            rot = _rotation(q) if d == 3 else _rotation(np.array([q[0], 0, 0, q[3]]))[:2, :2]
            mats.append(numpy_shape(rng.uniform(-4, 4, d), rng.uniform(0.3, 2.5, d), rot))
        M = np.array(mats)
        A, B = M[:200], M[200:]
        asym = np.count_nonzero((A != np.swapaxes(A, 1, 2)).any(axis=(1, 2)))
        assert asym > 50  # the data really is symmetric only up to rounding
        res = classify_detailed(A, B)
        # generic pairs: the filter certifies nearly all of them (none is near tangency)
        assert np.count_nonzero(res.certified_by == Certifier.FLOAT) >= 190
        for i in range(0, 200, 23):
            assert res.relation[i] == Relation[oracle_relation(A[i], B[i]).upper()]
        # the numpy filter (no compiler, or while the C kernels build) takes the same decisions
        from core.fixed.filters import classify_float_numpy

        codes = classify_float_numpy(A, B)
        decided = codes != U
        assert (codes[decided] == res.relation[decided]).all()


def test_asymmetry_is_an_input_uncertainty_near_tangency():
    # exactly tangent circles, with the off-diagonal pair perturbed by one ulp: the quadratic
    # form is the average, so the label is that of the average (oracle), never guessed
    A = np.array(circle(0, 0, 1), dtype=float)
    for dx in (0.0, 2**-50, -(2**-50)):
        B = np.array(circle(2 + dx, 0, 1), dtype=float)
        B[0, 2] = np.nextafter(B[0, 2], 0)  # B[2, 0] keeps the other value
        truth = Relation[oracle_relation(A, B).upper()]
        assert classify(A, B) == truth
        assert classify(A, B, method="float") in (U, truth)


def test_clearly_asymmetric_matrix_is_refused_with_advice():
    A = np.array(sphere(0, 0, 0, 1), dtype=float)
    A[0, 1] = 1e-3  # far beyond rounding
    with pytest.raises(ValueError, match=r"not symmetric: entry \(0,1\).*relative.*\(A \+ A\.T\) / 2"):
        classify(A, np.array(sphere(3, 0, 0, 1), dtype=float))
    with pytest.raises(ValueError, match="not symmetric"):
        classify(A, np.array(sphere(3, 0, 0, 1), dtype=float), method="float")
    # within the tolerance (2^-20 of the row scale): accepted and classified as the average
    A[0, 1] = 2.0**-22
    assert classify(A, np.array(sphere(3, 0, 0, 1), dtype=float)) == Relation.SEPARATE


def test_tolerance_is_applied_the_same_way_by_every_path():
    # an asymmetry just below and just above the threshold, with exact and float input
    from core.shapes.quadrics import SYMMETRY_TOLERANCE

    tol = float(SYMMETRY_TOLERANCE)
    for factor, ok in ((0.999, True), (1.001, False)):
        A = np.array(sphere(0, 0, 0, 1), dtype=float)
        A[1, 2] = tol * factor  # rows 1, 2 have scale 1: the limit is tol exactly
        B = np.array(sphere(5, 0, 0, 1), dtype=float)
        for method in ("adaptive", "float", "exact"):
            for form in (A, A.tolist(), [[F(v) for v in row] for row in A.tolist()]):
                if ok:
                    assert classify(form, B, method=method) in (Relation.SEPARATE, U)
                else:
                    with pytest.raises(ValueError, match="not symmetric"):
                        classify(form, B, method=method)


# -------------------------------------------------------------------------------------------
# batches with invalid pairs


def test_one_invalid_pair_does_not_cost_the_batch():
    rng = np.random.default_rng(3)
    mats = np.array(
        [numpy_shape(rng.uniform(-3, 3, 3), rng.uniform(0.5, 2, 3), _rotation(rng.normal(size=4))) for _ in range(600)]
    )
    A, B = mats[:300].copy(), mats[300:].copy()
    A[17, 1, 1] = np.nan
    A[42, 0, 1] += 0.5  # clearly asymmetric
    B[99] = np.diag([1.0, -1.0, 1.0, -1.0])  # a hyperboloid
    with pytest.raises(ValueError, match="pair 17: "):
        classify(A, B)
    marked = classify(A, B, on_invalid="mark")
    assert set(np.flatnonzero(marked == INVALID)) == {17, 42, 99}
    res = classify_detailed(A, B, on_invalid="mark")
    assert set(res.errors) == {17, 42, 99}
    assert "finite" in res.errors[17] and "not symmetric" in res.errors[42] and "not an ellipsoid" in res.errors[99]
    good = np.setdiff1d(np.arange(300), [17, 42, 99])
    assert (marked[good] == classify(A[good], B[good])).all()
    assert (classify(A, B, method="float", on_invalid="mark")[[17, 42, 99]] == INVALID).all()
    assert classify(A[17], B[17], on_invalid="mark") == INVALID


# -------------------------------------------------------------------------------------------
# number types: exact or refused, never rounded


@pytest.mark.skipif(np.finfo(np.longdouble).nmant <= 52, reason="long double is float64 on this platform")
def test_long_double_is_read_exactly():
    eps = np.longdouble(2) ** -60
    A = np.array(circle(0, 0, 1), dtype=np.longdouble)
    B = np.array(circle(0, 0, 1), dtype=np.longdouble)
    c = np.longdouble(2) + eps  # unit circles 2 + 2^-60 apart: exactly separate
    B[0, 2] = B[2, 0] = -c
    B[2, 2] = c * c - 1  # rounded in long double: check the truth with the oracle
    truth = oracle_relation(A.tolist(), B.tolist())
    assert truth == "separate"
    for method in ("adaptive", "exact"):
        assert str(classify(A, B, method=method)) == truth
    assert str(classify(A.astype(np.float64), B.astype(np.float64))) == "tangent"  # what rounding would say


@pytest.mark.parametrize("dtype", [np.float16, np.float32, np.int8, np.int16, np.int32, np.int64, np.uint8])
def test_narrow_numpy_types_are_their_exact_values(dtype):
    A = np.array([[1, 0, 0], [0, 1, 0], [0, 0, -1]], dtype=np.int64)
    B = np.array([[1, 0, -2], [0, 1, 0], [-2, 0, 3]], dtype=np.int64)  # tangent unit circles
    if np.issubdtype(dtype, np.unsignedinteger):
        A, B = 2 * np.eye(3, dtype=np.int64), 2 * np.eye(3, dtype=np.int64)  # not ellipses
        with pytest.raises(ValueError, match="empty interior"):
            classify(A.astype(dtype), B.astype(dtype))
        return
    assert classify(A.astype(dtype), B.astype(dtype)) == Relation.TANGENT
    if np.issubdtype(dtype, np.floating):  # float32 0.1 is an exact binary rational, not 1/10
        tenth = dtype(0.1)
        Bt = B.astype(dtype)
        Bt[0, 2] = Bt[2, 0] = -(2 + tenth)
        assert classify(A.astype(dtype), Bt) == Relation[oracle_relation(A.astype(dtype).tolist(), [[fmpq(*v.as_integer_ratio()) for v in row] for row in Bt]).upper()]


def test_big_integers_and_object_arrays_are_exact():
    k = 2**80 + 1  # not a float64 value
    A = np.array(circle(0, 0, 1), dtype=object) * k
    B = np.array(circle(2, 0, 1), dtype=object)
    assert classify(A, B) == Relation.TANGENT
    assert classify(np.array([[k, 0, 0], [0, k, 0], [0, 0, -k]], dtype=object), B) == Relation.TANGENT
    fr = np.array([[F(1), F(0), F(-2)], [F(0), F(1), F(0)], [F(-2), F(0), F(3)]], dtype=object)
    assert classify(A, fr) == Relation.TANGENT
    fq = np.array([[fmpq(v.numerator, v.denominator) for v in row] for row in fr], dtype=object)
    assert classify(A, fq) == Relation.TANGENT
    with pytest.raises(ValueError, match="booleans"):
        classify(np.eye(3, dtype=bool), B)
    with pytest.raises(ValueError, match="complex"):
        classify(np.eye(3, dtype=complex), B)


@pytest.mark.parametrize("bad", [np.float64(1.0), np.array(1.0), 3, "x", [1, 2, 3], np.zeros((2, 2)), np.zeros((3, 4))])
def test_wrong_shapes_name_the_expected_shape(bad):
    with pytest.raises(ValueError, match=r"3x3 \(ellipse\) or 4x4 \(ellipsoid\)"):
        classify(bad, circle(0, 0, 1))


# -------------------------------------------------------------------------------------------
# explain answers every pair classify answers, at any scale


def _extreme_pairs():
    a = np.array(circle(0, 0, 1), dtype=float)
    b = np.array(circle(3, 0, 1), dtype=float)
    yield a * 1e300, b
    yield a * 2.0**-600, b * 2.0**-600
    yield a * 2.0**-1060, b  # subnormal entries
    yield a * 1e150, b * 1e-150
    yield circle(0, 0, 1), circle(2 + F(1, 10**40), 0, 1)
    yield [["1e-400", 0, 0], [0, "1e-400", 0], [0, 0, "-1e-400"]], circle(3, 0, 1)
    yield [["1e400", 0, 0, 0], [0, "1e400", 0, 0], [0, 0, "1e400", 0], [0, 0, 0, "-1e400"]], sphere(F(1, 2), 0, 0, 1)
    e = np.array(sphere(0, 0, 0, 1), dtype=float)
    yield e * 1e300, np.array(sphere(1e-5, 0, 0, 1), dtype=float) * 1e-300


@pytest.mark.parametrize("pair", list(_extreme_pairs()), ids=lambda p: "pair")
def test_explain_answers_every_pair_classify_answers(pair):
    A, B = pair
    rel = classify(A, B)
    assert str(rel) == oracle_relation(A, B)
    e = explain(A, B)
    assert e.relation == rel
    d = e.to_dict()
    json.dumps(d, allow_nan=False)  # JSON-ready: no inf or nan anywhere
    for q in e.coefficients:
        assert q.text and (q.approx is None or np.isfinite(q.approx))
        if q.exact is not None:  # the text is the exact value's scientific form
            v = fmpq(*map(int, q.exact.split("/"))) if "/" in q.exact else fmpq(int(q.exact))
            assert (q.text.startswith("-")) == (v < 0)


# -------------------------------------------------------------------------------------------
# flipped and negatively scaled motions (the sign of a matrix is normalised on I)


def test_flipped_matrix_motion_example_from_the_issue():
    A_neg = [["-1", "0", "0"], ["0", "-1", "0"], ["0", "0", "1"]]
    B = [["1", "0", "-t"], ["0", "1", "0"], ["-t", "0", "t^2-1"]]
    r = analyse(A_neg, B, interval=("-3", "3"))
    assert [(e.value, str(e.relation), e.kind) for e in r.events] == [("-2", "tangent", "change"), ("2", "tangent", "change")]
    assert r.relation_at(0) == Relation.OVERLAP  # identical circles
    B5 = [[f"({e})/(t-5)" for e in row] for row in B]  # a denominator negative on [0, 3]
    r = analyse([["1", "0", "0"], ["0", "1", "0"], ["0", "0", "-1"]], B5, interval=("0", "3"))
    assert r.relation_at(0) == Relation.OVERLAP
    assert [(e.value, str(e.relation)) for e in r.events] == [("2", "tangent")]


def _matrix_strings(motion, factor):
    return [[f"({factor})*({e})" for e in row] for row in as_motion(motion).matrix()]


def _summary(r):
    return (
        [(e.decimal(15), str(e.relation), e.kind) for e in r.events],
        [str(iv.relation) for iv in r.intervals],
        [e.decimal(15) for e in r.roots],
    )


@pytest.mark.parametrize("name", preset_names())
def test_every_preset_is_unchanged_by_flips_and_negative_scalings(name):
    p = preset(name)
    interval = tuple(p["interval"])
    base = _summary(analyse(p["A"], p["B"], interval))
    heavy = name == "example-30"  # degree 84: keep CI fast with the constant flips only
    factors = ["-1", "-7/3"] if heavy else ["-1", "-(t^2 + 1)", "(t^2 + 2)"]
    for fa, fb in [(factors[0], "1"), ("1", factors[1]), (factors[-1], factors[0])]:
        r = analyse(_matrix_strings(p["A"], fa), _matrix_strings(p["B"], fb), interval)
        assert _summary(r) == base, (fa, fb)


# -- one test of "this number is a binary64 value", shared by every reader (issue 23.4) --------
_WIDE = np.longdouble(1) / 3  # not a float64 value where long double is wider (x86: 80 bits)
_IS_BINARY64 = [  # (number, its exact value)
    (0.5, F(1, 2)), (-3, F(-3)), (2**60, F(2**60)), (F(1, 4), F(1, 4)), (fmpq(-3, 8), F(-3, 8)), ("0.125", F(1, 8)),
    (np.float32(0.1), F(13421773, 134217728)), (np.longdouble(0.5), F(1, 2)), (np.int64(7), F(7)),
]
_NOT_BINARY64 = [F(1, 3), "0.1", 2**53 + 1, F(10**400), fmpq(1, 3), True, "x"]


@pytest.mark.parametrize(("v", "value"), _IS_BINARY64, ids=lambda x: repr(x)[:20])
def test_binary64_values_are_read_as_floats_everywhere(v, value):
    from core.bodies.search import read_bodies
    from core.moving.linear import read_linear_motions
    from core.shapes.numbers import binary64, binary64_array

    f = binary64(v)
    assert f is not None and F(f) == value
    arr = np.array([[v, 0.0], [1.0, 2.0]], dtype=object)
    assert binary64_array(arr).dtype == np.float64 and binary64_array(arr)[0, 0] == f
    # the readers: classify's filter input, the sweep's parameters, the bodies' matrices
    Q = np.array([[[1, 0, 0], [0, 1, 0], [0, 0, -1]]] * 2, dtype=object)
    Q[1, 2, 2] = v if f < 0 else -abs(f)
    assert read_bodies(Q).dtype == np.float64
    c0 = np.array([[v, 0.0]], dtype=object)
    assert read_linear_motions(c0, c0, [[1.0, 1.0]])[0].centers0[0, 0] == f


@pytest.mark.parametrize("v", _NOT_BINARY64, ids=lambda v: repr(v)[:20])
def test_other_numbers_are_never_rounded(v):
    from core.bodies.search import read_bodies
    from core.moving.linear import read_linear_motions
    from core.shapes.numbers import binary64, binary64_array

    assert binary64(v) is None
    assert binary64_array(np.array([[v, 0.0], [1.0, 2.0]], dtype=object)) is None
    with pytest.raises(ValueError, match="float64"):
        read_bodies(np.array([[[v, 0, 0], [0, 1, 0], [0, 0, -1]]], dtype=object))
    with pytest.raises(ValueError, match="float64 value|booleans"):
        read_linear_motions(np.array([[v, 0.0]], dtype=object), [[0.0, 0.0]], [[1.0, 1.0]])


def test_wide_and_big_integer_arrays_are_exact():
    from core.shapes.numbers import binary64_array

    assert binary64_array(np.array([2**60, 1])) is not None  # a float64 value beyond 2^53
    assert binary64_array(np.array([2**53 + 1])) is None
    assert binary64_array(np.array([2**64 - 1], dtype=np.uint64)) is None
    assert binary64_array([[2**60 + 1, 0.5]]) is None  # numpy's own conversion would round it
    if np.finfo(np.longdouble).nmant > 52:
        assert binary64_array(np.array([_WIDE])) is None
