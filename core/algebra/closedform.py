"""Exact forms of a real algebraic number for people: closed form up to degree 2, else its polynomial.

An event of a motion is a real algebraic time (:class:`core.algebra.algebraic.RealAlgebraic`):
the root of an integer polynomial F in an isolating interval. When the factor of F that vanishes
there has degree <= 2 the number has a closed form ``(p + q*sqrt(d))/r`` (Example 29 of the paper:
(12 - 2 sqrt 2)/17), written so that :func:`core.moving.expressions.parse_expression` reads it
back; otherwise it is given by its minimal polynomial and isolating interval. The square root is
reduced by :func:`core.algebra.qsqrt.squarefree_decomposition` (trial division: never a full
factorisation), and which of the two roots is meant is decided exactly (the sign of the root's
offset from -b/(2a), not a float).
"""

from __future__ import annotations

from dataclasses import dataclass
from math import gcd

from flint import fmpq, fmpq_poly, fmpz

from .algebraic import RealAlgebraic
from .qsqrt import squarefree_decomposition

__all__ = ["QuadraticForm", "quadratic_form", "closed_form", "polynomial_text", "algebraic_from_quadratic"]

MAX_FACTOR_DEGREE = 200
"""Largest degree of F that is factored to look for a linear or quadratic factor (ms)."""


def _digits(n: int) -> str:
    """Decimal text of an integer of any size (flint's conversion: str(int) stops at 4300 digits)."""
    return str(fmpz(n))


@dataclass(frozen=True)
class QuadraticForm:
    """A number ``(p + q*sqrt(d)) / r`` in lowest terms.

    Integers p, q, r > 0 with gcd(p, q, r) = 1, d > 1 not a square (or q = 0 and d = 1 for a
    rational).
    """

    p: int
    q: int
    d: int
    r: int

    def text(self, *, unicode: bool = False) -> str:
        """``"(12 - 2*sqrt(2))/17"`` (parseable), or ``"(12 − 2√2)/17"`` with ``unicode``.

        Examples:
            >>> QuadraticForm(12, -2, 2, 17).text(), QuadraticForm(12, -2, 2, 17).text(unicode=True)
            ('(12 - 2*sqrt(2))/17', '(12 − 2√2)/17')
            >>> QuadraticForm(0, 1, 5, 2).text(), QuadraticForm(-1, 0, 1, 3).text()
            ('sqrt(5)/2', '-1/3')
        """
        minus = "−" if unicode else "-"
        p, r, d = _digits(abs(self.p)), _digits(self.r), _digits(self.d)
        if self.q == 0:
            num = f"{minus if self.p < 0 else ''}{p}"
            return num if self.r == 1 else f"{num}/{r}"
        root = f"√{d}" if unicode else f"sqrt({d})"
        k = abs(self.q)
        surd = root if k == 1 else (f"{_digits(k)}{root}" if unicode else f"{_digits(k)}*{root}")
        if self.p == 0:
            num = f"{minus if self.q < 0 else ''}{surd}"
            paren = False
        else:
            sign = minus if self.q < 0 else "+"
            num = f"{minus if self.p < 0 else ''}{p} {sign} {surd}"
            paren = True
        if self.r == 1:
            return num
        return f"({num})/{r}" if paren else f"{num}/{r}"

    def value(self) -> tuple[fmpq, fmpq, int]:
        """(a, b, d) with the number = a + b sqrt(d), a and b rational."""
        return fmpq(self.p, self.r), fmpq(self.q, self.r), self.d


def _vanishing_factor(alpha: RealAlgebraic) -> fmpq_poly | None:
    """The factor of alpha's polynomial of degree <= 2 that has alpha as a root, or None."""
    F = alpha.poly
    if F.degree() <= 2:
        return F
    if F.degree() > MAX_FACTOR_DEGREE:
        return None
    for g, _ in F.factor()[1]:
        if g.degree() <= 2 and g(alpha.lo) * g(alpha.hi) < 0:
            return fmpq_poly(g)
    return None


def quadratic_form(alpha: RealAlgebraic) -> QuadraticForm | None:
    """Closed form of alpha when it is rational or a root of a quadratic factor, else None.

    Examples:
        >>> from flint import fmpz_poly
        >>> a = RealAlgebraic.isolating(fmpz_poly([136, -408, 289]), fmpq(1, 2), fmpq(3, 5))
        >>> quadratic_form(a).text()                       # Example 29, alpha_1
        '(12 - 2*sqrt(2))/17'
        >>> quadratic_form(RealAlgebraic.rational(fmpq(1, 3))).text()
        '1/3'
        >>> cubic = RealAlgebraic.isolating(fmpz_poly([-2, 0, 0, 1]), fmpq(1), fmpq(2))   # 2^(1/3)
        >>> quadratic_form(cubic) is None
        True
    """
    if alpha.value is not None:
        v = alpha.value
        return QuadraticForm(int(v.p), 0, 1, int(v.q))
    g = _vanishing_factor(alpha)
    if g is None:
        return None
    if g.degree() == 1:
        b, a = g.coeffs()
        v = -b / a
        return QuadraticForm(int(v.p), 0, 1, int(v.q))
    c, b, a = (fmpq(x) for x in g.coeffs())
    # integer coefficients: roots (-B ± sqrt(B^2 - 4AC)) / (2A) with A > 0
    den = fmpz(1)
    for x in (a, b, c):
        den = den * x.q // gcd(int(den), int(x.q))
    A, B, C = (int(x * den) for x in (a, b, c))
    if A < 0:
        A, B, C = -A, -B, -C
    disc = B * B - 4 * A * C
    if disc <= 0:  # a double or complex root cannot isolate a simple real root
        return None
    k, d = squarefree_decomposition(disc)
    # which root: the larger one iff alpha > -B/(2A) (exact comparison, alpha is not that point)
    sign = 1 if alpha.compare(fmpq(-B, 2 * A)) > 0 else -1
    if d == 1:
        v = fmpq(-B + sign * k, 2 * A)
        return QuadraticForm(int(v.p), 0, 1, int(v.q))
    p, q, r = -B, sign * k, 2 * A
    g_ = gcd(gcd(abs(p), abs(q)), r)
    return QuadraticForm(p // g_, q // g_, d, r // g_)


def closed_form(alpha: RealAlgebraic, *, unicode: bool = False) -> str | None:
    """Text of :func:`quadratic_form` (None when the vanishing factor has degree > 2)."""
    f = quadratic_form(alpha)
    return None if f is None else f.text(unicode=unicode)


def polynomial_text(alpha: RealAlgebraic) -> str:
    """The number as "root of F(t) in (lo, hi)": F its primitive integer polynomial, exact ends.

    Examples:
        >>> from flint import fmpz_poly
        >>> polynomial_text(RealAlgebraic.isolating(fmpz_poly([-2, 0, 0, 1]), fmpq(1), fmpq(2)))
        'root of t^3 - 2 in (1, 2)'
    """
    if alpha.value is not None:
        return str(alpha.value)
    F = alpha.poly
    den = fmpz(1)
    for x in F.coeffs():
        den = den * fmpq(x).q // gcd(int(den), int(fmpq(x).q))
    coeffs = [int(fmpq(x) * den) for x in F.coeffs()]
    g = 0
    for c in coeffs:
        g = gcd(g, abs(c))
    if coeffs[-1] < 0:
        g = -g
    coeffs = [c // g for c in coeffs]
    terms = []
    for i in range(len(coeffs) - 1, -1, -1):
        c = coeffs[i]
        if c == 0:
            continue
        mono = "" if i == 0 else ("t" if i == 1 else f"t^{i}")
        mag = abs(c)
        body = str(mag) if not mono else (mono if mag == 1 else f"{mag}*{mono}")
        terms.append(("- " if c < 0 else "+ ") + body)
    text = " ".join(terms)
    text = text[2:] if text.startswith("+ ") else "-" + text[2:]
    return f"root of {text} in ({alpha.lo}, {alpha.hi})"


def algebraic_from_quadratic(a: fmpq, b: fmpq, d: int) -> RealAlgebraic:
    """The real number a + b sqrt(d) as a :class:`RealAlgebraic` (exact; d > 1 not a square, b != 0).

    Its polynomial is (t - a)^2 - b^2 d; the isolating interval is a rational bracket of sqrt(d)
    (integer square roots, refined until it excludes the conjugate root a - b sqrt(d)).

    Examples:
        >>> x = algebraic_from_quadratic(fmpq(12, 17), fmpq(-2, 17), 2)
        >>> x.decimal(12)
        '0.539504286780'
    """
    if b == 0:
        return RealAlgebraic.rational(a)
    F = fmpq_poly([a * a - b * b * d, -2 * a, 1])
    scale = 1
    while True:
        s = fmpz(d * scale * scale).isqrt()  # s/scale <= sqrt(d) < (s + 1)/scale
        lo_r, hi_r = fmpq(int(s), scale), fmpq(int(s) + 1, scale)
        lo, hi = (a + b * lo_r, a + b * hi_r) if b > 0 else (a + b * hi_r, a + b * lo_r)
        if hi - lo < abs(b) * lo_r:  # narrower than the gap 2|b|sqrt(d) to the conjugate root
            return RealAlgebraic.isolating(F, lo, hi)
        scale *= 16
