"""Constructors both ways, exact validation, number input."""

from __future__ import annotations

import math
from fractions import Fraction as F

import numpy as np
import pytest
from flint import fmpq
from hypothesis import given
from hypothesis import strategies as st

from core import axes_from_quadric, quadric_from_axes, rotation_from_quaternion, validate_quadric
from core.shapes.numbers import to_fmpq


def test_unit_sphere_exact():
    M = quadric_from_axes([0, 0, 0], [1, 1, 1], exact=True)
    assert M == [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, -1]]


def test_exact_construction_is_on_the_boundary():
    # point c + R (a, 0, 0) lies on the ellipsoid: X^T M X = 0 exactly
    q = [1, 2, 3, 4]
    c = [fmpq(1, 2), fmpq(-3), fmpq(2, 7)]
    M = quadric_from_axes(c, ["3/2", 2, "1/3"], q, exact=True)
    R = rotation_from_quaternion(q, exact=True)
    X = [c[i] + R[i][0] * fmpq(3, 2) for i in range(3)] + [1]
    val = sum(X[i] * M[i][j] * X[j] for i in range(4) for j in range(4))
    assert val == 0
    inside = c + [1]
    assert sum(inside[i] * M[i][j] * inside[j] for i in range(4) for j in range(4)) == -1


def test_rotation_is_orthogonal_exactly():
    R = rotation_from_quaternion([3, -1, 2, 5], exact=True)
    for i in range(3):
        for j in range(3):
            assert sum(R[k][i] * R[k][j] for k in range(3)) == (1 if i == j else 0)


@given(
    st.lists(st.floats(-10, 10), min_size=3, max_size=3),
    st.lists(st.floats(0.1, 10), min_size=3, max_size=3),
    st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: sum(v * v for v in q) > 0.01),
)
def test_round_trip_3d(c, r, q):
    M = quadric_from_axes(c, r, q)
    p = axes_from_quadric(M)
    M2 = quadric_from_axes(p.center, p.semi_axes, p.orientation)
    assert np.allclose(M, M2, rtol=1e-7, atol=1e-7 * np.abs(M).max())
    assert sorted(p.semi_axes) == pytest.approx(sorted(r), rel=1e-6)


@given(st.floats(-5, 5), st.floats(-5, 5), st.floats(0.1, 5), st.floats(0.1, 5), st.floats(-3, 3))
def test_round_trip_2d(x, y, a, b, th):
    M = quadric_from_axes([x, y], [a, b], th)
    p = axes_from_quadric(M)
    assert p.center == pytest.approx((x, y), abs=1e-7)
    assert sorted(p.semi_axes) == pytest.approx(sorted([a, b]), rel=1e-7)
    assert -math.pi / 2 < p.orientation[0] <= math.pi / 2


def test_validation_normalises_and_rejects():
    flipped = [[-1, 0, 0], [0, -1, 0], [0, 0, 1]]
    assert validate_quadric(flipped) == [[1, 0, 0], [0, 1, 0], [0, 0, -1]]
    with pytest.raises(ValueError, match="A is not symmetric"):
        validate_quadric([[1, 1, 0], [0, 1, 0], [0, 0, -1]], name="A")
    with pytest.raises(ValueError, match="3x3 .* or 4x4"):
        validate_quadric([[1, 0], [0, 1]])
    with pytest.raises(ValueError, match="indefinite"):
        validate_quadric([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 0], [0, 0, 0, -1]])
    with pytest.raises(ValueError, match="empty interior"):
        validate_quadric([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    with pytest.raises(ValueError, match="degenerate"):
        validate_quadric([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"entry \(1,1\): not a finite number"):
        validate_quadric([[1, 0, 0], [0, float("nan"), 0], [0, 0, -1]])
    with pytest.raises(ValueError, match="semi-axes must be positive"):
        quadric_from_axes([0, 0], [1, -1])


@pytest.mark.parametrize(
    "text, value",
    [("0.1", F(1, 10)), ("3/7", F(3, 7)), ("-2.5e-3", F(-1, 400)), ("1e3", F(1000)), (".5", F(1, 2))],
)
def test_exact_number_strings(text, value):
    q = to_fmpq(text)
    assert F(int(q.p), int(q.q)) == value


@pytest.mark.parametrize("bad", ["nan", "inf", "1/0", "0x10", "1e99999", "", "2**3", True])
def test_bad_numbers(bad):
    with pytest.raises(ValueError):
        to_fmpq(bad)


def test_float_is_exact_binary_value():
    assert to_fmpq(0.1) == fmpq(3602879701896397, 2**55)
