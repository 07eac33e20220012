"""classify(): golden cases, properties against exact arithmetic and an independent oracle."""

from __future__ import annotations

import math
from fractions import Fraction as F

import numpy as np
import pytest
from cases import CASES, circle, sphere
from hypothesis import given
from hypothesis import strategies as st
from oracle import oracle_relation
from strategies import (
    dyadic_tangent_pair,
    exact_shapes,
    float_pairs,
    positive_rationals,
    rational_quaternions,
    rigid_motion,
    small_rationals,
    tangent_pairs,
)

from core import Relation, Stats, classify, explain, quadric_from_axes

U = Relation.UNDECIDED


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_golden_cases(case):
    assert oracle_relation(case.A, case.B) == case.relation  # the catalogue itself is right
    for method in ("adaptive", "exact"):
        assert str(classify(case.A, case.B, method=method)) == case.relation
        assert str(classify(case.B, case.A, method=method)) == case.relation
    if case.rule:
        assert explain(case.A, case.B).rule == case.rule


def test_exact_decimal_strings_differ_from_floats():
    # "0.1" is 1/10 exactly; 0.1 is the nearest double, slightly larger than 1/10.
    A = circle(0, 0, 1)
    B = [[1, 0, "-2.1"], [0, 1, 0], ["-2.1", 0, str(F("2.1") ** 2 - F("1.1") ** 2)]]
    assert classify(A, B) == Relation.TANGENT  # radius 1.1 at distance 2.1, exactly
    Bf = [[1.0, 0.0, -2.1], [0.0, 1.0, 0.0], [-2.1, 0.0, float(F("2.1") ** 2 - F("1.1") ** 2)]]
    assert classify(A, Bf) == Relation[oracle_relation(A, Bf).upper()]


def test_flipped_sign_is_normalised():
    A = [[-v for v in row] for row in sphere(0, 0, 0, 1)]
    assert classify(A, sphere(2, 0, 0, 1)) == Relation.TANGENT
    # spheres always have s0 = 0 (a double root -1): use generic ellipsoids for the float path
    E = quadric_from_axes([0, 0, 0], [1.0, 2.0, 1.5])
    far = quadric_from_axes([5.0, 0, 0], [1.0, 0.5, 2.0])
    assert classify(-E, far, method="float") == Relation.SEPARATE
    assert classify(E, -far, method="float") == Relation.SEPARATE
    assert classify(-E, -E) == Relation.OVERLAP


@pytest.mark.parametrize(
    "A, message",
    [
        ([[1, 0], [0, 1]], "3x3"),
        ([[1, 2, 0], [0, 1, 0], [0, 0, -1]], "not symmetric"),
        ([[1, 0, 0], [0, float("nan"), 0], [0, 0, -1]], "finite"),
        ([[1, 0, 0], [0, float("inf"), 0], [0, 0, -1]], "finite"),
        ([[1, 0, 0], [0, -1, 0], [0, 0, -1]], "indefinite or semidefinite"),
        ([[1, 0, 0], [0, 0, 0], [0, 0, -1]], "indefinite or semidefinite"),
        ([[1, 0, 0], [0, 1, 0], [0, 0, 0]], "degenerate"),
        ([[1, 0, 0], [0, 1, 0], [0, 0, 1]], "empty interior"),
        ([[1, 0, 0], [0, 1, 0], [0, 0, "x"]], "not a number"),
    ],
)
def test_bad_input_messages(A, message):
    # every method checks its input, also "float" (which validates the pairs it cannot certify),
    # for a nested list, a float array (the single-pair fast path) and inside a batch
    forms = [A]
    try:
        forms.append(np.array(A, dtype=float))
    except ValueError:
        pass
    for method in ("adaptive", "float", "exact"):
        for form in forms:
            with pytest.raises(ValueError, match=message):
                classify(form, np.array(circle(5, 0, 1), dtype=float) if len(np.shape(form)) == 2 and np.shape(form)[0] == 3 else circle(5, 0, 1), method=method)
        if len(A) == 3 and all(len(r) == 3 for r in A):
            with pytest.raises(ValueError, match="pair 1: .*" + message):
                classify([circle(0, 0, 1), A], circle(5, 0, 1), method=method)
            marked = classify([circle(0, 0, 1), A], circle(5, 0, 1), method=method, on_invalid="mark")
            assert marked.tolist()[1] == Relation.INVALID
            assert marked.tolist()[0] in ((Relation.SEPARATE, U) if method == "float" else (Relation.SEPARATE,))


def test_bad_method_and_shapes():
    with pytest.raises(ValueError, match="valid options"):
        classify(circle(0, 0, 1), circle(3, 0, 1), method="fast")
    with pytest.raises(ValueError, match="both must be ellipses or both ellipsoids"):
        classify(circle(0, 0, 1), sphere(3, 0, 0, 1))
    with pytest.raises(ValueError, match="do not broadcast"):
        classify(np.stack([np.eye(3)] * 2), np.stack([np.eye(3)] * 3))


def test_batch_errors_name_the_pair():
    good = np.array(quadric_from_axes([0, 0], [1, 1]))
    bad = good.copy()
    bad[0, 1] = 0.5
    with pytest.raises(ValueError, match="pair 1: A is not symmetric"):
        classify(np.stack([good, bad]), good + 0.0)


@given(float_pairs())
def test_float_never_contradicts_exact_and_oracle(pair):
    A, B = pair
    exact = classify(A, B, method="exact")
    assert str(exact) == oracle_relation(A, B)
    f = classify(A, B, method="float")
    assert f in (U, exact)
    assert classify(A, B) == exact


@given(float_pairs())
def test_symmetry(pair):
    A, B = pair
    assert classify(A, B) == classify(B, A)


@given(st.sampled_from([2, 3]).flatmap(lambda d: st.tuples(exact_shapes(d), exact_shapes(d))),
       rational_quaternions(), st.lists(small_rationals, min_size=3, max_size=3),
       positive_rationals, positive_rationals)
def test_invariance_under_rigid_motion_and_scaling(pair, q, c, sa, sb):
    A, B = pair
    d = len(A) - 1
    if d == 2:
        q = [q[0], F(0), F(0), q[3]] if (q[0] or q[3]) else [F(1), F(0), F(0), F(0)]
    base = classify(A, B)
    A2, B2 = rigid_motion(A, q, c[:d]), rigid_motion(B, q, c[:d])
    assert classify(A2, B2) == base
    scaled_a = [[sa * v for v in row] for row in A2]
    scaled_b = [[sb * v for v in row] for row in B2]
    assert classify(scaled_a, scaled_b) == base
    assert str(base) == oracle_relation(A, B)


@given(tangent_pairs())
def test_exactly_tangent_pairs(pair):
    A, B = pair
    assert classify(A, B) == Relation.TANGENT
    assert classify(A, B, method="float") in (U, Relation.TANGENT)
    assert classify(A, B, method="exact") == Relation.TANGENT
    assert oracle_relation(A, B) == "tangent"


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("a, r", [(2.0, 1.0), (0.5, 0.25), (4.0, 0.125)])
def test_dyadic_tangent_float_abstains(d, a, r):
    A, B = dyadic_tangent_pair(d, a, r, [0.5] * d)
    assert classify(A, B, method="float") == U
    assert classify(A, B) == Relation.TANGENT
    e = explain(A, B)
    assert e.certified_by == "exact" and e.relation == Relation.TANGENT


@pytest.mark.parametrize("batch_shape", [(1,), (3,), (3, 1, 2)])
@pytest.mark.parametrize("d", [2, 3])
def test_batch_equals_per_pair(batch_shape, d):
    rng = np.random.default_rng(sum(batch_shape) + d)
    size = int(np.prod(batch_shape))

    def shapes(k):
        out = []
        for _ in range(k):
            o = rng.uniform(0, 3) if d == 2 else rng.normal(size=4)
            out.append(quadric_from_axes(rng.uniform(-2, 2, d), rng.uniform(0.3, 2, d), o))
        return np.array(out)

    A = shapes(size).reshape(*batch_shape, d + 1, d + 1)
    B = shapes(batch_shape[-1]).reshape(batch_shape[-1], d + 1, d + 1)  # broadcasts
    codes = classify(A, B)
    assert codes.shape == batch_shape and codes.dtype == np.int8
    Bb = np.broadcast_to(B, A.shape)
    for idx in np.ndindex(*batch_shape):
        assert codes[idx] == classify(A[idx], Bb[idx])
        assert codes[idx] == classify(A[idx].tolist(), Bb[idx].tolist(), method="exact")


def test_stats_counts_escalations():
    A, B = dyadic_tangent_pair(3, 2.0, 1.0, [0.0, 0.0, 0.0])
    far = quadric_from_axes([10.0, 1.0, 2.0], [1.0, 2.0, 3.0], [0.9, 0.1, 0.2, 0.3])
    stats = Stats()
    classify(np.stack([A, A]), np.stack([B, far]), stats=stats)
    assert (stats.pairs, stats.escalated) == (2, 1)


def _near_tangent(d: int, gap: float, sign: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A generic (rotated, off-centre) ellipsoid and ball whose touching distance is scaled by
    1 + sign * gap; both are rounded to floats (labels come from the oracle on those floats)."""
    rng = np.random.default_rng(seed)
    axes = rng.uniform(0.5, 2.0, d)
    r = rng.uniform(0.3, 1.5)
    if d == 2:
        th = rng.uniform(0, 3)
        R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        o = th
    else:
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        o = q
        from core import rotation_from_quaternion

        R = rotation_from_quaternion(q)
    c = rng.uniform(-3, 3, d)
    dist = (axes[0] + r) * (1 + sign * gap)
    return quadric_from_axes(c, axes, o), quadric_from_axes(c + dist * R[:, 0], [r] * d)


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("exponent", range(3, 16))
@pytest.mark.parametrize("sign", [1, -1])
def test_near_tangent_against_oracle(d, exponent, sign):
    for seed in range(3):
        A, B = _near_tangent(d, 10.0**-exponent, sign, seed + 10 * exponent)
        truth = oracle_relation(A, B)
        assert str(classify(A, B)) == truth
        f = classify(A, B, method="float")
        assert f in (U, Relation[truth.upper()])
        if exponent <= 6:  # a useful filter decides clear cases itself
            assert f != U


EXTREMES = [
    ("tiny and huge axes", [0, 0, 0], [1e-6, 1.0, 1e6], [0.5, 0, 0], [1.0, 1.0, 1.0]),
    ("tiny and huge, rotated", [0, 0, 0], [1e-6, 1.0, 1e6], [0.5, 0, 0], [1.0, 1.0, 1.0]),
    ("aspect 1e6", [0, 0, 0], [1e6, 1.0, 1.0], [0, 3.0, 0], [1.0, 2.0, 1.0]),
    ("centres at 1e6", [1e6, 1e6, 1e6], [1.0, 2.0, 3.0], [1e6 + 3.5, 1e6, 1e6], [1.0, 1.0, 1.0]),
    ("touching at 1e6", [1e6, 0, 0], [2.0, 1.0, 1.0], [1e6 + 3.0, 0, 0], [1.0, 1.0, 1.0]),
    ("micro shapes", [0, 0, 0], [1e-6, 2e-6, 3e-6], [4e-6, 0, 0], [3e-6, 1e-6, 1e-6]),
]


@pytest.mark.parametrize("name, ca, ra, cb, rb", EXTREMES, ids=[e[0] for e in EXTREMES])
@pytest.mark.parametrize("scale", [1.0, 1e-150, 1e150])
def test_extreme_inputs(name, ca, ra, cb, rb, scale):
    # axis-aligned where the float rotation of axes 1e-6 .. 1e6 would round to a non-ellipsoid
    rot = None if name == "tiny and huge axes" else [0.9, 0.1, 0.3, 0.2]
    A = quadric_from_axes(ca, ra, rot) * scale
    B = quadric_from_axes(cb, rb, [0.3, 0.7, 0.1, 0.2])
    # every case reaches classify (was a skip "scaled matrix overflowed" that no case took, with no
    # floor on what would remain if one did): entries up to ~1e12 scaled by 1e150 are still finite
    assert np.isfinite(A).all() and np.isfinite(B).all()
    try:
        truth = oracle_relation(A, B)
    except (AssertionError, ZeroDivisionError):
        truth = None
    try:
        got = classify(A, B)
    except ValueError as e:  # rounding made a matrix stop being an ellipsoid: must be reported
        assert "not an ellipsoid" in str(e) or "degenerate" in str(e) or "empty" in str(e)
        return
    assert truth is not None and str(got) == truth
    assert classify(A, B, method="float") in (U, got)
    assert classify(B, A) == got
