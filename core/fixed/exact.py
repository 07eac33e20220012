"""Exact classification in rationals (python-flint): the certified fallback of the float filter.

Matrices are validated and normalised exactly, scaled by positive integers to ``fmpz`` (which
leaves the relation unchanged: det(T cA + dB) has the roots of P scaled by c/d > 0), and the
decision tree of :mod:`core.formulae.decision` runs on exact signs, computing s0, s1, s1,0 only when the
tree asks for them. Always decides; TANGENT exactly when the exact input is tangent.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from flint import fmpq, fmpz

from ..formulae.decision import Decision, decide
from ..formulae.pencil import determinant, pencil_coefficients
from ..formulae.subresultants import hat_s0, hat_s1, hat_s10
from ..shapes.numbers import sign
from ..shapes.quadrics import (
    SYMMETRY_TOLERANCE,
    check_determinant_sign,
    interior_sign,
    normalised_quadratic_part,
)

__all__ = ["ExactPair", "classify_exact", "exact_pair", "integer_matrix", "valid_float_matrix"]



def integer_matrix(M: list[list[fmpq]]) -> list[list[fmpz]]:
    """M times the positive lcm of its denominators (same quadric, integer entries)."""
    den = fmpz(1)
    for row in M:
        for v in row:
            q = v.q
            den = den * q // den.gcd(q)
    return [[v.p * (den // v.q) for v in row] for row in M]


@dataclass
class ExactPair:
    """A validated pair and its exact pencil; s-values are computed on first use and cached."""

    A: list[list[fmpq]] | None
    B: list[list[fmpq]] | None
    """Normalised exact matrices (None on the integer fast path for float input)."""
    coefficients: list[Any]
    """[a_0..a_n] of det(T A' + B') for the integer-scaled A', B' (positive multiples)."""
    _cache: dict[str, Any]

    @property
    def n(self) -> int:
        """Degree of P: 3 (ellipses) or 4 (ellipsoids)."""
        return len(self.coefficients) - 1

    def hat(self, which: str) -> Any:
        """hs0, hs1 or hs10 (sign-equivalent forms of s0, s1, s1,0), cached."""
        if which not in self._cache:
            f = {"s0": hat_s0, "s1": hat_s1, "s10": hat_s10}[which]
            self._cache[which] = f(self.coefficients)
        return self._cache[which]

    def decide(self) -> Decision:
        """The paper's tree on exact signs, computing only what it needs."""
        a = self.coefficients
        return decide(
            self.n,
            [sign(a[i]) for i in range(self.n, -1, -1)],
            lambda: sign(self.hat("s0")),
            lambda: sign(self.hat("s1")),
            lambda: sign(self.hat("s10")),
        )


def _float_int_matrix(M: Any) -> list[list[int]] | None:
    """2^k * (M + M^T) as Python ints for a float64 array symmetric up to rounding, or None.

    k is chosen so every entry is an integer; the matrix is sign-normalised so its quadratic
    block is positive definite. None if M is not such a finite (n, n) array or is invalid (the
    general path then produces the precise error message). A positive multiple of the symmetric
    part: the same shape. Each entry is read exactly as p / 2^j (``float.as_integer_ratio``, in C),
    with 2^k the largest such denominator: no numpy call on a 4 x 4 array (~2 us each).
    """
    if type(M) is not np.ndarray or M.dtype != np.float64 or M.ndim != 2 or M.shape[0] != M.shape[1]:
        return None
    n = M.shape[0]
    try:
        ratios = [v.as_integer_ratio() for v in M.ravel().tolist()]  # row-major
    except (OverflowError, ValueError):  # inf, NaN
        return None
    den = max([q for _, q in ratios])
    ints = [p * (den // q) for p, q in ratios]
    if not any(ints):
        return None
    trans = [v for j in range(n) for v in ints[j::n]]  # the transpose, row-major
    if ints != trans:
        tol = SYMMETRY_TOLERANCE
        m_row = [max(max(abs(ints[i * n + k]), abs(ints[k * n + i])) for k in range(n)) for i in range(n)]
        for i in range(n):
            for j in range(i + 1, n):
                d = ints[i * n + j] - ints[j * n + i]
                if d * d * tol.denominator**2 > tol.numerator**2 * m_row[i] * m_row[j]:
                    return None  # beyond rounding: the general path raises with the message
    S = [x + y for x, y in zip(ints, trans, strict=True)]
    rows = [S[i * n : (i + 1) * n] for i in range(n)]
    minors = [determinant([row[:k] for row in rows[:k]]) for k in range(1, n)]
    orient = interior_sign([sign(d) for d in minors])
    if orient is None:
        return None
    return rows if orient == 1 else [[-v for v in row] for row in rows]


def valid_float_matrix(M: Any) -> bool:
    """True when M, a float64 (n, n) array, is proven exactly an ellipse or ellipsoid.

    The integer form of :func:`_float_int_matrix` (symmetric within the tolerance, its quadratic
    block definite) and det < 0 after the sign normalisation: what ``validate_quadric`` decides,
    without rationals (~3x faster). False says nothing: ``validate_quadric`` then says what is wrong.
    """
    ints = _float_int_matrix(M)
    return ints is not None and determinant(ints) < 0


def exact_pair(A: Any, B: Any, *, scaled: bool = True) -> ExactPair:
    """Validate A and B exactly and build their pencil.

    Args:
        A: a matrix in any accepted input form (see :mod:`core.shapes.quadrics`).
        B: the same for B.
        scaled: use integer-scaled matrices (faster; coefficients are positive multiples of the
            true ones). ``False`` gives the true coefficients of det(T A + B), for display.

    Raises:
        ValueError: either matrix is invalid, or A and B differ in size.
    """
    if scaled:  # fast path for float arrays: straight to integers, no rationals
        IA, IB = _float_int_matrix(A), _float_int_matrix(B)
        if IA is not None and IB is not None and len(IA) == len(IB):
            n = len(IA)
            coeffs = pencil_coefficients(IA, IB)
            if coeffs[n] < 0 and coeffs[0] < 0:
                return ExactPair(None, None, coeffs, {})
    EA = normalised_quadratic_part(A, name="A")
    EB = normalised_quadratic_part(B, name="B")
    n = len(EA)
    if n != len(EB):
        raise ValueError(f"A is {n}x{n} but B is {len(EB)}x{len(EB)}: both must be ellipses or both ellipsoids")
    if scaled:
        coeffs = pencil_coefficients(integer_matrix(EA), integer_matrix(EB))
    else:
        coeffs = pencil_coefficients(EA, EB)
    # det A = a_n and det B = a_0 (up to positive factors): the last validity check, for free
    check_determinant_sign(sign(coeffs[n]), n, "A")
    check_determinant_sign(sign(coeffs[0]), n, "B")
    return ExactPair(EA, EB, coeffs, {})


def classify_exact(A: Any, B: Any) -> Decision:
    """Relation of one pair in exact arithmetic, with the deciding rule.

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> str(classify_exact(circle(0), circle(2)).relation)
        'tangent'
        >>> str(classify_exact(circle(0), circle(fmpq(2) + fmpq(1, 10**9))).relation)
        'separate'
    """
    return exact_pair(A, B).decide()
