"""Hypothesis strategies and constructions of ellipse/ellipsoid pairs (float and exact)."""

from __future__ import annotations

from fractions import Fraction as F
from typing import Any

import numpy as np
from cases import axis_ellipsoid, sphere
from hypothesis import strategies as st

from core import quadric_from_axes, rotation_from_quaternion


def float_shape(draw: Any, d: int, *, center: float = 4.0, lo: float = 0.2, hi: float = 3.0) -> np.ndarray:
    c = [draw(st.floats(-center, center)) for _ in range(d)]
    r = [draw(st.floats(lo, hi)) for _ in range(d)]
    if d == 2:
        o: Any = draw(st.floats(0, 3.2))
    else:
        o = [draw(st.floats(-1, 1)) for _ in range(4)]
        if sum(v * v for v in o) < 1e-3:
            o = [1.0, 0.0, 0.0, 0.0]
    return quadric_from_axes(c, r, o)


@st.composite
def float_pairs(draw: Any, d: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    d = d or draw(st.sampled_from([2, 3]))
    return float_shape(draw, d), float_shape(draw, d)


small_rationals = st.fractions(min_value=-5, max_value=5, max_denominator=12)
positive_rationals = st.fractions(min_value=F(1, 4), max_value=4, max_denominator=12)


@st.composite
def rational_quaternions(draw: Any) -> list[F]:
    q = [F(draw(st.integers(-4, 4))) for _ in range(4)]
    if not any(q):
        q[0] = F(1)
    return q


def rigid_motion(M: list[list[Any]], q: list[F], c: list[F]) -> list[list[F]]:
    """Exact matrix of the shape M moved by x -> R(q) x + c (R rational, from the quaternion)."""
    d = len(M) - 1
    R = rotation_from_quaternion(q, exact=True)
    if d == 2:
        R = [[R[0][0], R[0][1]], [R[1][0], R[1][1]]]
    Rf = [[F(int(v.p), int(v.q)) for v in row] for row in R]
    # G maps world to body: x_b = R^T (x - c)
    G = [[Rf[j][i] for j in range(d)] + [-sum(Rf[j][i] * c[j] for j in range(d))] for i in range(d)]
    G.append([F(0)] * d + [F(1)])
    Mf = [[F(v) for v in row] for row in M]
    MG = [[sum(Mf[i][k] * G[k][j] for k in range(d + 1)) for j in range(d + 1)] for i in range(d + 1)]
    return [[sum(G[k][i] * MG[k][j] for k in range(d + 1)) for j in range(d + 1)] for i in range(d + 1)]


@st.composite
def exact_shapes(draw: Any, d: int) -> list[list[F]]:
    center = [draw(small_rationals) for _ in range(d)]
    axes = [draw(positive_rationals) for _ in range(d)]
    q = draw(rational_quaternions())
    if d == 2:
        q = [q[0], F(0), F(0), q[3]] if (q[0] or q[3]) else [F(1), F(0), F(0), F(0)]
    return rigid_motion(axis_ellipsoid([0] * d, axes), q, center)


@st.composite
def tangent_pairs(draw: Any, d: int | None = None) -> tuple[list[list[F]], list[list[F]]]:
    """Exactly tangent: an axis-aligned ellipsoid and a ball touching it at the end of its
    first axis from outside (the ball lies in x >= a, the ellipsoid in x <= a), then the same
    exact rigid motion applied to both."""
    d = d or draw(st.sampled_from([2, 3]))
    axes = [draw(positive_rationals) for _ in range(d)]
    r = draw(positive_rationals)
    E = axis_ellipsoid([0] * d, axes)
    ball = axis_ellipsoid([axes[0] + r] + [0] * (d - 1), [r] * d)
    q = draw(rational_quaternions())
    if d == 2:
        q = [q[0], F(0), F(0), q[3]] if (q[0] or q[3]) else [F(1), F(0), F(0), F(0)]
    c = [draw(small_rationals) for _ in range(d)]
    return rigid_motion(E, q, c), rigid_motion(ball, q, c)


def dyadic_tangent_pair(d: int, a: float, r: float, shift: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """Float matrices (exactly representable) of an exactly tangent pair: ellipsoid with first
    semi-axis a (others 1) and a ball of radius r centred at (a + r, 0, ...), both shifted."""
    axes = [a] + [1.0] * (d - 1)
    E = axis_ellipsoid(shift, axes)
    ball = axis_ellipsoid([shift[0] + a + r, *shift[1:]], [r] * d)
    Ef = np.array([[float(v) for v in row] for row in E])
    Bf = np.array([[float(v) for v in row] for row in ball])
    assert all(F(x) == v for x, v in zip(Ef.flat, (v for row in E for v in row), strict=False))
    assert all(F(x) == v for x, v in zip(Bf.flat, (v for row in ball for v in row), strict=False))
    return Ef, Bf


__all__ = [
    "dyadic_tangent_pair",
    "exact_shapes",
    "float_pairs",
    "rational_quaternions",
    "rigid_motion",
    "sphere",
    "tangent_pairs",
]
