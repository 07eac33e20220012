"""The ring Q(sqrt d)[t]: polynomials ``p(t) + q(t) sqrt(d)`` kept exactly (paper 3.4, 4.4; Ex. 30).

Example 30 of the paper moves an ellipsoid by a rotation with sqrt(2) entries, so the pencil
coefficients a_i(t) and the subresultants s0, s1, s1,0 live in Q(sqrt d)[t]. They are kept
exactly as pairs ``p + q r`` of ``fmpq_poly`` with ``r = sqrt(d)`` (:class:`QSqrtPoly`); the class
supports ``+ - *`` and integer multiplication, so :func:`core.formulae.pencil.pencil_coefficients` and the
``hat_*`` functions of :mod:`core.formulae.subresultants` run on it unchanged. Signs at rational t are
exact (:func:`sign_qsqrt`); signs at real algebraic t are in :mod:`core.algebra.algebraic`.
"""

from __future__ import annotations

import math
from typing import Any

from flint import fmpq, fmpq_poly, fmpz, fmpz_poly

from ..shapes.numbers import sign
from .polysign import FloatPoly

__all__ = ["QSqrtPoly", "sign_qsqrt", "squarefree_decomposition"]


def squarefree_decomposition(n: int, trial_primes: int | None = None) -> tuple[int, int]:
    """Write a positive integer as ``k^2 * d`` with d not a perfect square; returns (k, d).

    Prime factors are found by trial division with ``trial_primes`` primes (default
    :data:`core.shapes.limits.LIBRARY`'s; never a full factorisation: a 100-digit semiprime would take
    forever) plus what FLINT finds cheaply; a cofactor left over is tested for being a perfect
    square. So d is squarefree except for square factors of primes beyond the trial bound, and
    never a perfect square: ``sqrt(d)`` is irrational (d > 1), all that the arithmetic of
    :class:`QSqrtPoly` needs.

    Examples:
        >>> squarefree_decomposition(8), squarefree_decomposition(4), squarefree_decomposition(2)
        ((2, 2), (2, 1), (1, 2))
        >>> p = 10**30 + 57                                     # a prime beyond trial division
        >>> squarefree_decomposition(3 * p**2) == (p, 3)
        True
    """
    if n <= 0:
        raise ValueError(f"need a positive integer, got {n}")
    if trial_primes is None:
        from ..shapes.limits import LIBRARY

        trial_primes = LIBRARY.sqrt_trial_primes
    k, d = fmpz(1), fmpz(1)
    for p, exp in fmpz(n).factor(trial_limit=trial_primes):
        e = int(exp)
        k *= p ** (e // 2)
        if e % 2:
            r = p.isqrt()
            if r * r == p:  # a composite cofactor that is a square
                k *= r
            else:
                d *= p
    r = d.isqrt()
    if r * r == d:  # two composite factors whose product is a square
        k, d = k * r, fmpz(1)
    return int(k), int(d)


def sign_qsqrt(a: fmpq, b: fmpq, d: int) -> int:
    """Exact sign of ``a + b sqrt(d)`` for rationals a, b and a positive integer d.

    Examples:
        >>> sign_qsqrt(fmpq(-7, 5), fmpq(1), 2), sign_qsqrt(fmpq(3, 2), fmpq(-1), 2)
        (1, 1)
    """
    sa, sb = sign(a), sign(b)
    if sb == 0 or d == 1:
        return sign(a + b) if d == 1 else sa
    if sa == 0 or sa == sb:
        return sb
    # opposite signs: compare a^2 with d b^2
    return sa * sign(a * a - b * b * d)


def _poly(x: Any) -> fmpq_poly:
    if isinstance(x, fmpq_poly):
        return x
    if isinstance(x, fmpz_poly):
        return fmpq_poly(x)
    return fmpq_poly([x])


class QSqrtPoly:
    """A polynomial ``p(t) + q(t) sqrt(d)`` with rational coefficients (d = 1: plain Q[t]).

    Elements with different d combine only if one of them is rational (q = 0); otherwise a
    ValueError is raised (one square root per motion pair).

    Examples:
        >>> r2 = QSqrtPoly(0, 1, 2)                       # sqrt(2)
        >>> t = QSqrtPoly(fmpq_poly([0, 1]))
        >>> x = (t - r2) * (t + r2)
        >>> x.p, x.q.is_zero()
        (x^2 + (-2), True)
        >>> (r2 * 3 + 1).q
        3
    """

    __slots__ = ("p", "q", "d", "_float")

    def __init__(self, p: Any = 0, q: Any = 0, d: int = 1) -> None:
        self.p = _poly(p)
        self.q = _poly(q)
        self.d = int(d)
        self._float: FloatPoly | None = None
        if self.d == 1 and not self.q.is_zero():
            self.p = self.p + self.q
            self.q = fmpq_poly()

    # --- ring structure -------------------------------------------------------------------
    def _coerce(self, other: Any) -> QSqrtPoly:
        if isinstance(other, QSqrtPoly):
            return other
        if isinstance(other, int | fmpz | fmpq | fmpq_poly | fmpz_poly):
            return QSqrtPoly(other, 0, self.d)
        return NotImplemented  # type: ignore[no-any-return]  # the operators pass it on

    def _join(self, other: QSqrtPoly) -> int:
        if self.d == other.d:
            return self.d
        if other.q.is_zero() and (self.d != 1 or other.d == 1):
            return self.d
        if self.q.is_zero():
            return other.d
        if other.q.is_zero():
            return self.d
        raise ValueError(
            f"two different square roots, sqrt({self.d}) and sqrt({other.d}): "
            "only one sqrt(d) is allowed per motion pair"
        )

    def __add__(self, other: Any) -> QSqrtPoly:
        o = self._coerce(other)
        if o is NotImplemented:
            return NotImplemented
        return QSqrtPoly(self.p + o.p, self.q + o.q, self._join(o))

    __radd__ = __add__

    def __sub__(self, other: Any) -> QSqrtPoly:
        o = self._coerce(other)
        if o is NotImplemented:
            return NotImplemented
        return QSqrtPoly(self.p - o.p, self.q - o.q, self._join(o))

    def __rsub__(self, other: Any) -> QSqrtPoly:
        o = self._coerce(other)
        if o is NotImplemented:
            return NotImplemented
        return o - self

    def __neg__(self) -> QSqrtPoly:
        return QSqrtPoly(-self.p, -self.q, self.d)

    def __mul__(self, other: Any) -> QSqrtPoly:
        if isinstance(other, int | fmpz | fmpq):
            return QSqrtPoly(self.p * other, self.q * other, self.d)
        o = self._coerce(other)
        if o is NotImplemented:
            return NotImplemented
        d = self._join(o)
        if self.q.is_zero():
            return QSqrtPoly(self.p * o.p, self.p * o.q, d)
        if o.q.is_zero():
            return QSqrtPoly(self.p * o.p, self.q * o.p, d)
        return QSqrtPoly(self.p * o.p + self.q * o.q * d, self.p * o.q + self.q * o.p, d)

    __rmul__ = __mul__

    def __pow__(self, e: int) -> QSqrtPoly:
        if not isinstance(e, int) or e < 0:
            raise ValueError(f"exponent must be a non-negative integer, got {e!r}")
        out = QSqrtPoly(1, 0, self.d)
        base = self
        while e:
            if e & 1:
                out = out * base
            base = base * base
            e >>= 1
        return out

    def __eq__(self, other: object) -> bool:
        o = self._coerce(other)
        if o is NotImplemented:
            return NotImplemented
        diff = self - o
        return diff.p.is_zero() and diff.q.is_zero()

    def __hash__(self) -> int:
        return hash((str(self.p), str(self.q), self.d))

    # --- structure ------------------------------------------------------------------------
    def is_zero(self) -> bool:
        """True iff identically zero."""
        return self.p.is_zero() and self.q.is_zero()

    def is_rational(self) -> bool:
        """True iff the sqrt(d) part is zero (an element of Q[t])."""
        return self.q.is_zero()

    def degree(self) -> int:
        """Degree in t (-1 for the zero polynomial)."""
        return max(self.p.degree(), self.q.degree())

    def conj(self) -> QSqrtPoly:
        """Conjugate ``p - q sqrt(d)``."""
        return QSqrtPoly(self.p, -self.q, self.d)

    def norm(self) -> fmpq_poly:
        """``p^2 - d q^2`` in Q[t]: its real roots contain those of self and of its conjugate."""
        if self.q.is_zero():
            return self.p * self.p
        return self.p * self.p - self.q * self.q * self.d

    def scale_positive(self, c: fmpq) -> QSqrtPoly:
        """Self times a positive rational (keeps every sign)."""
        return QSqrtPoly(self.p * c, self.q * c, self.d)

    # --- evaluation -----------------------------------------------------------------------
    def at(self, t: fmpq) -> tuple[fmpq, fmpq]:
        """Exact value at a rational t as (a, b) meaning a + b sqrt(d)."""
        return self.p(t), self.q(t)

    def sign_at_rational(self, t: fmpq) -> int:
        """Exact sign at a rational t."""
        a, b = self.at(t)
        return sign_qsqrt(a, b, self.d)

    def float_sign_at(self, t: float) -> int | None:
        """Certified sign at the float t, or None when the float bound cannot tell.

        A float Horner step with a proven error bound (:mod:`core.algebra.polysign`); on None use
        :meth:`sign_at_rational`. The float enclosure is built on first use.
        """
        if self._float is None:
            self._float = FloatPoly(self.p, self.q, self.d)
        return self._float.sign_at(t)

    def coefficients_float(self) -> list[float]:
        """Ascending float coefficients (display only; may overflow to inf for huge values)."""
        r = math.sqrt(self.d)
        n = self.degree() + 1
        pc = list(self.p.coeffs()) + [fmpq(0)] * (n - len(self.p.coeffs()))
        qc = list(self.q.coeffs()) + [fmpq(0)] * (n - len(self.q.coeffs()))
        return [_to_float(a) + _to_float(b) * r for a, b in zip(pc, qc, strict=False)]

    def __str__(self) -> str:
        if self.q.is_zero():
            return _poly_str(self.p)
        if self.q.degree() == 0:
            c = self.q.coeffs()[0]
            if c == 1 or c == -1:
                rpart = ("-" if c < 0 else "") + f"sqrt({self.d})"
            else:
                rpart = f"{c}*sqrt({self.d})"
        else:
            rpart = f"sqrt({self.d})*({_poly_str(self.q)})"
        if self.p.is_zero():
            return rpart
        if rpart.startswith("-"):
            return f"{_poly_str(self.p)} - {rpart[1:]}"
        return f"{_poly_str(self.p)} + {rpart}"

    def __repr__(self) -> str:
        return f"QSqrtPoly({self})"

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        """Pickle as integer (numerator, denominator) pairs.

        The analysis workers send these back to the GUI process.
        """
        return (_from_pairs, (_pairs(self.p), _pairs(self.q), self.d))


def _pairs(p: fmpq_poly) -> list[tuple[int, int]]:
    return [(int(c.p), int(c.q)) for c in p.coeffs()]


def _from_pairs(p: list[tuple[int, int]], q: list[tuple[int, int]], d: int) -> QSqrtPoly:
    return QSqrtPoly(fmpq_poly([fmpq(a, b) for a, b in p]), fmpq_poly([fmpq(a, b) for a, b in q]), d)


def _to_float(x: fmpq) -> float:
    try:
        return int(x.p) / int(x.q)
    except OverflowError:
        return math.inf if x > 0 else -math.inf


def _poly_str(p: fmpq_poly) -> str:
    """Ascending-free readable form in t, e.g. ``3*t^2 - 1/2*t + 1``."""
    coeffs = p.coeffs()
    if not coeffs:
        return "0"
    terms = []
    for k in range(len(coeffs) - 1, -1, -1):
        c = coeffs[k]
        if c == 0:
            continue
        sign = "-" if c < 0 else "+"
        a = -c if c < 0 else c
        mono = "" if k == 0 else ("t" if k == 1 else f"t^{k}")
        if k == 0:
            body = str(a)
        elif a == 1:
            body = mono
        else:
            body = f"{a}*{mono}"
        terms.append((sign, body))
    first_sign, first = terms[0]
    out = ("-" if first_sign == "-" else "") + first
    for sign, body in terms[1:]:
        out += f" {sign} {body}"
    return out
