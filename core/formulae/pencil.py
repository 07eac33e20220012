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


_COLUMNS3 = tuple((j, *[c for c in range(3) if c != j], j % 2 == 1) for j in range(3))
"""3x3: (column j of row 0, the two columns of its minor in rows 1-2, whether the term is subtracted)."""
_COLUMNS4 = tuple(
    (j, k, *[c for c in range(4) if c not in (j, k)], (j + k + 1) % 2 == 1) for j in range(4) for k in range(j + 1, 4)
)
"""4x4: (columns j < k of rows 0-1, the complementary columns of rows 2-3, whether subtracted)."""


def _accumulate(acc: list[Any], term: list[Any], negate: bool) -> list[Any]:
    """Coefficient-wise acc + term, or acc - term (the first term starts acc, negated if subtracted)."""
    if not acc:
        return [-c for c in term] if negate else term
    return [a - c for a, c in zip(acc, term, strict=True)] if negate else [a + c for a, c in zip(acc, term, strict=True)]


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
    # written out (no helper call or list per 2x2 minor): the exact path calls this once per pair.
    # The operations and their order must stay as they are: the float kernels are traced from
    # them (core.fixed.kernelgen; test_generated_files_are_current fails on any change)
    n = len(A)
    if n == 3:
        A1, A2, B1, B2 = A[1], A[2], B[1], B[2]
        out: list[Any] = []
        for j, k0, k1, negate in _COLUMNS3:
            c2 = A1[k0] * A2[k1] - A1[k1] * A2[k0]
            c1 = (A1[k0] * B2[k1] + B1[k0] * A2[k1]) - (A1[k1] * B2[k0] + B1[k1] * A2[k0])
            c0 = B1[k0] * B2[k1] - B1[k1] * B2[k0]
            b, a = B[0][j], A[0][j]
            # poly_mul's order: every product of b, then a's, each added as it comes
            p0, p1, p2 = b * c0, b * c1, b * c2
            s1 = p1 + a * c0
            s2 = p2 + a * c1
            term = [p0, s1, s2, a * c2]
            out = _accumulate(out, term, bool(negate))
        return out
    if n == 4:
        # Laplace expansion along rows (0, 1) against the complementary rows (2, 3):
        # det M = sum_{j<k} (-1)^(j+k+1) M[01; jk] M[23; complement(jk)].
        A0, A1, A2, A3, B0, B1, B2, B3 = A[0], A[1], A[2], A[3], B[0], B[1], B[2], B[3]
        out = []
        for j, k, cj, ck, negate in _COLUMNS4:
            t2 = A0[j] * A1[k] - A0[k] * A1[j]
            t1 = (A0[j] * B1[k] + B0[j] * A1[k]) - (A0[k] * B1[j] + B0[k] * A1[j])
            t0 = B0[j] * B1[k] - B0[k] * B1[j]
            u2 = A2[cj] * A3[ck] - A2[ck] * A3[cj]
            u1 = (A2[cj] * B3[ck] + B2[cj] * A3[ck]) - (A2[ck] * B3[cj] + B2[ck] * A3[cj])
            u0 = B2[cj] * B3[ck] - B2[ck] * B3[cj]
            o0, o1, o2 = t0 * u0, t0 * u1, t0 * u2  # poly_mul's order, as above
            o1 = o1 + t1 * u0
            o2 = o2 + t1 * u1
            o3 = t1 * u2
            o2 = o2 + t2 * u0
            o3 = o3 + t2 * u1
            term = [o0, o1, o2, o3, t2 * u2]
            out = _accumulate(out, term, bool(negate))
        return out
    raise ValueError(f"pencil needs 3x3 (ellipse) or 4x4 (ellipsoid) matrices, got {n}x{n}")
