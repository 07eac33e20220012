"""The characteristic pencil P(T) = det(T A + B) of two quadrics, written once for any ring.

The same straight-line formula serves float64 arrays (vectorised over pairs), exact rationals
(``fmpq``/``fmpz``), polynomials in time t (``fmpq_poly``) and Q(sqrt d)[t] elements: it uses only
``+``, ``-`` and ``*`` on matrix entries, no division and no inversion (paper, Definitions 6 and 18).
Coefficients are returned in ascending order ``[a_0, ..., a_n]``; a_n = det A, a_0 = det B.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, TypeAlias, TypeVar

if TYPE_CHECKING:
    import numpy as np

__all__ = ["determinant", "pencil_coefficients", "poly_mul"]

R = TypeVar("R")
Matrix: TypeAlias = "Sequence[Sequence[Any]] | np.ndarray"
"""Square matrix indexable as ``M[i][j]``: nested sequences or a numpy array."""


def poly_mul(p: Sequence[Any], q: Sequence[Any]) -> list[Any]:
    """Product of two ascending coefficient lists (schoolbook, ring-generic).

    Examples:
        >>> poly_mul([1, 2], [3, 1])    # (1 + 2T)(3 + T)
        [3, 7, 2]
    """
    out: list[Any] = [None] * (len(p) + len(q) - 1)
    for i, pi in enumerate(p):
        for j, qj in enumerate(q):
            term = pi * qj
            out[i + j] = term if out[i + j] is None else out[i + j] + term
    return out


def determinant(M: Matrix) -> Any:
    """Determinant of a 1x1 .. 4x4 matrix over any ring (+, -, * only; no division).

    Explicit formulas up to 3x3, Laplace expansion along the first row above. Used exactly
    (fmpq, fmpz, polynomials in t) and traced for the float kernels (leading minors).

    Examples:
        >>> determinant([[2, 1, 0], [1, 2, 1], [0, 1, 2]])
        4
    """
    n = len(M)
    if n == 1:
        return M[0][0]
    if n == 2:
        return M[0][0] * M[1][1] - M[0][1] * M[1][0]
    if n == 3:
        return (
            M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1])
            - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0])
            + M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0])
        )
    out: Any = None
    for j in range(n):
        term = M[0][j] * determinant([list(row[:j]) + list(row[j + 1 :]) for row in M[1:]])
        out = term if out is None else (out + term if j % 2 == 0 else out - term)
    return out


def _minor2(A: Matrix, B: Matrix, r0: int, r1: int, j: int, k: int) -> list[Any]:
    """Det of rows (r0, r1), columns (j, k) of T A + B, as [c0, c1, c2] in T."""
    c2 = A[r0][j] * A[r1][k] - A[r0][k] * A[r1][j]
    c1 = (A[r0][j] * B[r1][k] + B[r0][j] * A[r1][k]) - (A[r0][k] * B[r1][j] + B[r0][k] * A[r1][j])
    c0 = B[r0][j] * B[r1][k] - B[r0][k] * B[r1][j]
    return [c0, c1, c2]


def _add_into(acc: list[Any] | None, p: list[Any], negate: bool) -> list[Any]:
    if acc is None:
        return [-c for c in p] if negate else list(p)
    return [a - c for a, c in zip(acc, p, strict=False)] if negate else [a + c for a, c in zip(acc, p, strict=False)]


def pencil_coefficients(A: Matrix, B: Matrix) -> list[Any]:
    """Coefficients ``[a_0, ..., a_n]`` of P(T) = det(T A + B) for n = 3 or 4.

    Args:
        A: n x n entries, indexable as ``A[i][j]``; each entry a ring element (float, fmpq,
            numpy array of shape (N,) for N pairs at once, fmpq_poly in t, ...).
        B: same shape and ring as ``A``.

    Returns:
        ``[a_0, ..., a_n]`` in ascending order of T.

    Examples:
        >>> A = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]          # unit circle
        >>> pencil_coefficients(A, A)                       # det((T+1) A) = -(T+1)^3
        [-1, -3, -3, -1]
    """
    n = len(A)
    if n == 3:
        acc: list[Any] | None = None
        for j in range(3):
            k0, k1 = [c for c in range(3) if c != j]
            minor = _minor2(A, B, 1, 2, k0, k1)
            term = poly_mul([B[0][j], A[0][j]], minor)
            acc = _add_into(acc, term, negate=(j % 2 == 1))
        assert acc is not None
        return acc
    if n == 4:
        # Laplace expansion along rows (0, 1) against the complementary rows (2, 3):
        # det M = sum_{j<k} (-1)^(j+k+1) M[01; jk] M[23; complement(jk)].
        acc = None
        for j in range(4):
            for k in range(j + 1, 4):
                cj, ck = [c for c in range(4) if c not in (j, k)]
                top = _minor2(A, B, 0, 1, j, k)
                bottom = _minor2(A, B, 2, 3, cj, ck)
                acc = _add_into(acc, poly_mul(top, bottom), negate=((j + k + 1) % 2 == 1))
        assert acc is not None
        return acc
    raise ValueError(f"pencil needs 3x3 (ellipse) or 4x4 (ellipsoid) matrices, got {n}x{n}")
