"""An ellipse/ellipsoid in centred form: centre c, size k and inverse shape matrix S, exactly.

A valid matrix, normalised so that its quadratic block M is positive definite
(:func:`core.shapes.quadrics.validate_quadric`), is A = [[M, m], [m^T, a]] = k [[Q, -Q c], [-c^T Q,
c^T Q c - 1]] with

* centre c = -M^-1 m,
* k = c^T M c - a = -det(A) / det(M) > 0 (any positive multiple of A is the same shape),
* Q = M / k, so the shape is {x : q(x) <= 1} with q(x) = (x - c)^T Q (x - c) = 1 + X^T A X / k,
* S = Q^-1 = k M^-1, the inverse shape matrix (its support function is n.c + sqrt(n^T S n)).

Scaling the shape about its centre by mu replaces 1 by mu^2 in q: the matrix becomes
A + k (1 - mu^2) e e^T (e = last unit vector), linear in s = mu^2. Everything here is exact
(python-flint ``fmpq``/``fmpq_mat``); the float counterpart for stacks is in
:mod:`core.witness.floats`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from flint import fmpq, fmpq_mat

from ..shapes.numbers import to_float
from ..shapes.quadrics import validate_quadric

__all__ = ["CentredShape", "centred_pair", "column", "dot"]


def column(values: list[fmpq]) -> fmpq_mat:
    """A column vector (d x 1 ``fmpq_mat``)."""
    return fmpq_mat([[v] for v in values])


def dot(u: fmpq_mat, v: fmpq_mat) -> fmpq:
    """U . v for two column vectors."""
    return (u.transpose() * v)[0, 0]


@dataclass(frozen=True)
class CentredShape:
    """Exact centred form of one validated ellipse/ellipsoid (see the module docstring)."""

    matrix: fmpq_mat
    """The normalised homogeneous matrix A (quadratic block positive definite, det < 0)."""
    centre: fmpq_mat
    """c, a d x 1 column."""
    k: fmpq
    """-det(A) / det(M) > 0."""
    S: fmpq_mat
    """Inverse shape matrix k M^-1 (symmetric positive definite)."""

    @property
    def d(self) -> int:
        """Dimension of the space: 2 (ellipse) or 3 (ellipsoid)."""
        return self.centre.nrows()

    @classmethod
    def of(cls, A: Any, name: str = "A") -> CentredShape:
        """Validate ``A`` exactly (any input form core accepts) and compute its centred form.

        Raises:
            ValueError: ``A`` is not an ellipse/ellipsoid (the message names it ``name``).
        """
        E = validate_quadric(A, name=name)
        n = len(E)
        d = n - 1
        M = fmpq_mat([row[:d] for row in E[:d]])
        m = column([E[i][d] for i in range(d)])
        Minv = M.inv()
        c = -(Minv * m)
        k = -dot(m, c) - E[d][d]
        return cls(fmpq_mat(E), c, k, Minv * k)

    def form(self, x: fmpq_mat) -> fmpq:
        """X^T A X at X = (x, 1): negative inside, zero on the boundary, positive outside."""
        d = self.d
        X = fmpq_mat([[x[i, 0]] for i in range(d)] + [[fmpq(1)]])
        return (X.transpose() * self.matrix * X)[0, 0]

    def q(self, x: fmpq_mat) -> fmpq:
        """(x - c)^T S^-1 (x - c): below 1 inside, 1 on the boundary (= 1 + X^T A X / k)."""
        return 1 + self.form(x) / self.k

    def floats(self) -> tuple[list[float], list[list[float]]]:
        """(centre, S) as Python floats (for float estimates only)."""
        d = self.d
        return [to_float(self.centre[i, 0]) for i in range(d)], [
            [to_float(self.S[i, j]) for j in range(d)] for i in range(d)
        ]


def centred_pair(A: Any, B: Any) -> tuple[CentredShape, CentredShape]:
    """Both shapes in centred form; ValueError if either is invalid or their sizes differ."""
    a = CentredShape.of(A, "A")
    b = CentredShape.of(B, "B")
    if a.d != b.d:
        n, m = a.d + 1, b.d + 1
        raise ValueError(f"A is {n}x{n} but B is {m}x{m}: both must be ellipses or both ellipsoids")
    return a, b
