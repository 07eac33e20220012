"""Exact numbers for witnesses: square-root bounds, values of rational functions at algebraic roots.

* :func:`sqrt_bounds`: rationals lo <= sqrt(q) <= hi, equal when q is a rational square.
* :func:`value_at_root`: the real algebraic number num(alpha) / den(alpha) (or its square root)
  for alpha a real root of an irreducible polynomial h. Its defining polynomial is the
  resultant Res_lambda(h, num - y den) (degree <= deg h in y; interpolated from deg h + 1
  exact resultants in Q[lambda]), and it is told apart from the other roots by an arb enclosure
  of num/den over alpha's isolating interval, narrowed until exactly one root is left inside.
* :func:`algebraic_dict`: the JSON form of a real algebraic number (decimal, exact, interval,
  polynomial).
"""

from __future__ import annotations

from typing import Any

from flint import arb, arb_poly, fmpq, fmpq_poly

from ..algebra.algebraic import RealAlgebraic, arb_to_fmpq, simplest_between, working_precision
from ..algebra.qsqrt import QSqrtPoly
from ..algebra.realroots import real_roots
from ..shapes.numbers import to_float

__all__ = ["sqrt_bounds", "simplest_between", "value_at_root", "algebraic_dict", "rational_near", "to_float"]


def rational_near(x: float, rel: float) -> fmpq:
    """The simplest rational within ``rel * |x|`` of a finite float (x itself when rel = 0)."""
    q = fmpq(*float(x).as_integer_ratio())
    if rel <= 0 or q == 0:
        return q
    w = abs(q) * fmpq(*float(rel).as_integer_ratio())
    return simplest_between(q - w, q + w)


def _floor_sqrt_scaled(q: fmpq, b: int) -> int:
    """floor(sqrt(q) * 2^b) for q >= 0 (b may be negative)."""
    x = q * fmpq(4) ** b if b >= 0 else q / fmpq(4) ** (-b)
    return int((x.p // x.q).isqrt())


def sqrt_bounds(q: fmpq, bits: int = 64) -> tuple[fmpq, fmpq]:
    """Rationals lo <= sqrt(q) <= hi with hi - lo <= 2^-bits sqrt(q); lo = hi if sqrt(q) is rational.

    Examples:
        >>> sqrt_bounds(fmpq(9, 4))
        (3/2, 3/2)
        >>> lo, hi = sqrt_bounds(fmpq(2), 20); lo * lo < 2 < hi * hi, float(hi - lo) < 2**-19
        (True, True)
    """
    if q < 0:
        raise ValueError(f"square root of a negative number {q}")
    if q == 0:
        return fmpq(0), fmpq(0)
    rp, rq = q.p.isqrt(), q.q.isqrt()
    if rp * rp == q.p and rq * rq == q.q:
        r = fmpq(rp, rq)
        return r, r
    # sqrt(q) ~ 2^e: scale by 2^b so that the integer part has about bits + 2 bits
    e = (int(q.p.bit_length()) - int(q.q.bit_length())) // 2
    b = bits + 2 - e
    s = _floor_sqrt_scaled(q, b)
    den = fmpq(2) ** b if b >= 0 else 1 / fmpq(2) ** (-b)
    return fmpq(s) / den, fmpq(s + 1) / den


def _interpolate(xs: list[fmpq], ys: list[fmpq]) -> fmpq_poly:
    """The polynomial of degree < len(xs) through the points (Lagrange, exact)."""
    out = fmpq_poly(0)
    for i, (xi, yi) in enumerate(zip(xs, ys, strict=True)):
        if yi == 0:
            continue
        term = fmpq_poly([yi])
        for j, xj in enumerate(xs):
            if j != i:
                term *= fmpq_poly([-xj, 1]) / (xi - xj)
        out += term
    return out


def _defining_polynomial(h: fmpq_poly, num: fmpq_poly, den: fmpq_poly) -> fmpq_poly:
    """R(y) = Res_lambda(h, num - y den) up to a constant factor, in Q[y]."""
    e = max(num.degree(), den.degree())
    xs: list[fmpq] = []
    ys: list[fmpq] = []
    y = 0
    while len(xs) < h.degree() + 1:
        y += 1
        p = num - den * y
        if p.degree() != e:  # the leading coefficient vanishes here: not the generic degree
            continue
        xs.append(fmpq(y))
        ys.append(h.resultant(p))
    R = _interpolate(xs, ys)
    if R.is_zero():
        raise RuntimeError("num/den is not determined by the root (zero resultant)")
    return R


def value_at_root(alpha: RealAlgebraic, num: fmpq_poly, den: fmpq_poly, *, square_root: bool = False) -> RealAlgebraic:
    """The real algebraic number v = num(alpha) / den(alpha), or sqrt(v) with ``square_root``.

    Args:
        alpha: a real root of an irreducible polynomial (``alpha.poly``), or a rational.
        num: numerator polynomial.
        den: denominator polynomial, den(alpha) != 0.
        square_root: return sqrt(v) instead (v must be positive).

    Examples:
        >>> r2 = RealAlgebraic.isolating(fmpq_poly([-2, 0, 1]), fmpq(1), fmpq(2))   # sqrt(2)
        >>> value_at_root(r2, fmpq_poly([1, 1]), fmpq_poly([0, 1])).decimal(15)       # (1 + r)/r
        '1.70710678118655'
        >>> value_at_root(r2, fmpq_poly([0, 0, 8]), fmpq_poly([1]), square_root=True)   # sqrt(16)
        RealAlgebraic(4)
    """
    if alpha.value is not None:
        v = num(alpha.value) / den(alpha.value)
        if not square_root:
            return RealAlgebraic.rational(v)
        lo, hi = sqrt_bounds(v)
        if lo == hi:
            return RealAlgebraic.rational(lo)
        return RealAlgebraic.isolating(fmpq_poly([-v, 0, 1]), lo, hi)
    R = _defining_polynomial(alpha.poly, num, den)
    if square_root:
        R = R(fmpq_poly([0, 0, 1]))
    prec = 64
    for _ in range(64):
        with working_precision(prec):
            x = alpha.enclosure(prec)
            ball = arb_poly(num)(x) / arb_poly(den)(x)
            if square_root:
                ball = ball.sqrt()
            if ball.is_finite():
                mid, rad = arb_to_fmpq(ball)
                roots = real_roots(QSqrtPoly(R), mid - rad, mid + rad)
                if len(roots) == 1:
                    return roots[0]
                if not roots:
                    raise RuntimeError("the enclosure of num/den at the root holds no root of its polynomial")
        alpha.refine_to(alpha.width / 2**32)
        if alpha.value is not None:
            return value_at_root(alpha, num, den, square_root=square_root)
        prec *= 2
    raise RuntimeError("value_at_root did not separate the roots (precision limit)")


def algebraic_dict(a: RealAlgebraic, digits: int = 20) -> dict[str, Any]:
    """JSON form of a real algebraic number: :meth:`core.algebra.algebraic.RealAlgebraic.to_dict`.

    Decimal ``value``, ``approx`` float, ``exact`` "p/q" when rational, else the isolating
    interval and the integer ``polynomial`` (ascending coefficients) it is a root of.
    """
    return a.to_dict(digits)


def arb_bounds(x: arb) -> tuple[fmpq, fmpq]:
    """Rational ends of an arb ball."""
    mid, rad = arb_to_fmpq(x)
    return mid - rad, mid + rad
