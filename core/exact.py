"""Exact classification in rationals (python-flint): the certified fallback of the float filter.

Matrices are validated and normalised exactly, scaled by positive integers to ``fmpz`` (which
leaves the relation unchanged: det(T cA + dB) has the roots of P scaled by c/d > 0), and the
decision tree of :mod:`core.decision` runs on exact signs, computing s0, s1, s1,0 only when the
tree asks for them. Always decides; TANGENT exactly when the exact input is tangent.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from flint import fmpq, fmpz

from .decision import Decision, decide
from .pencil import pencil_coefficients
from .quadrics import validate_quadric
from .subresultants import hat_s0, hat_s1, hat_s10

__all__ = ["ExactPair", "classify_exact", "exact_pair", "integer_matrix"]


def _sign(x: Any) -> int:
    return (x > 0) - (x < 0)


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

    A: list[list[fmpq]]
    B: list[list[fmpq]]
    coefficients: list[Any]
    """[a_0..a_n] of det(T A' + B') for the integer-scaled A', B' (positive multiples)."""
    _cache: dict[str, Any]

    @property
    def n(self) -> int:
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
        middle = [_sign(a[i]) for i in range(self.n - 1, 0, -1)]
        return decide(
            self.n,
            middle,
            lambda: _sign(self.hat("s0")),
            lambda: _sign(self.hat("s1")),
            lambda: _sign(self.hat("s10")),
        )


def exact_pair(A: Any, B: Any, *, scaled: bool = True) -> ExactPair:
    """Validate A and B exactly and build their pencil.

    Args:
        A, B: matrices in any accepted input form (see :mod:`core.quadrics`).
        scaled: use integer-scaled matrices (faster; coefficients are positive multiples of the
            true ones). ``False`` gives the true coefficients of det(T A + B), for display.

    Raises:
        ValueError: either matrix is invalid, or A and B differ in size.
    """
    EA = validate_quadric(A, name="A")
    EB = validate_quadric(B, name="B")
    if len(EA) != len(EB):
        raise ValueError(f"A is {len(EA)}x{len(EA)} but B is {len(EB)}x{len(EB)}: both must be ellipses or both ellipsoids")
    if scaled:
        coeffs = pencil_coefficients(integer_matrix(EA), integer_matrix(EB))
    else:
        coeffs = pencil_coefficients(EA, EB)
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
