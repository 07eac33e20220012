"""Real algebraic numbers and exact signs of Q(sqrt d)[t] elements at them (paper 3.4, 4.4).

A :class:`RealAlgebraic` is a rational, or the unique root of a squarefree (in practice
irreducible) polynomial F in an interval ``(lo, hi)`` with rational ends and ``F(lo) F(hi) < 0``.
It is refined by Newton steps certified by sign changes (or bisection) and printed to any number
of digits. The sign of ``v = p + q sqrt(d)`` at such a number is decided by :func:`sign_at`: ball
arithmetic (arb) at increasing precision when it is nonzero, and an exact zero test otherwise:
v(alpha) = 0 iff alpha is a root of gcd(F, N(v)) with N(v) = p^2 - d q^2 and p(alpha) =
-sqrt(d) q(alpha), i.e. p and q both vanish at alpha (gcd test) or have opposite signs there.
No floating approximation of sqrt(d) ever decides a sign. Root isolation is in
:mod:`core.algebra.realroots`.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from flint import (
    arb,
    arb_poly,
    ctx,
    fmpq,
    fmpq_poly,
    fmpz,
    fmpz_poly,  # noqa: F401  (the doctests use it)
)

from ..shapes.numbers import decimal_exponent, floor_log10
from ..shapes.numbers import sign as _sgn
from ..shapes.numbers import to_float as _to_float
from .qsqrt import QSqrtPoly, _poly

__all__ = ["RealAlgebraic", "sign_at", "simplest_between", "working_precision", "arb_to_fmpq"]


# --------------------------------------------------------------------------------------------
# real algebraic numbers


@contextmanager
def working_precision(bits: int) -> Iterator[None]:
    """Run the body with arb's working precision set to ``bits``.

    ctx.prec is process-global in python-flint; arb balls stay rigorous whatever the
    precision, so a concurrent change can only cost an extra refinement round, never a sign.
    """
    # ctx.prec is process-global in python-flint; arb balls stay rigorous whatever the
    # precision, so a concurrent change can only cost an extra refinement round, never a sign.
    old = ctx.prec
    ctx.prec = bits
    try:
        yield
    finally:
        ctx.prec = old


def arb_to_fmpq(x: arb) -> tuple[fmpq, fmpq]:
    """Exact (midpoint, radius) of an arb ball as rationals."""
    m, e = x.mid().man_exp()
    r, f = x.rad().man_exp()
    mid = fmpq(m) * (fmpq(2) ** e if e >= 0 else fmpq(1, 2 ** (-e)))
    rad = fmpq(r) * (fmpq(2) ** f if f >= 0 else fmpq(1, 2 ** (-f)))
    return mid, rad


def simplest_between(lo: fmpq, hi: fmpq) -> fmpq:
    """The rational with the smallest denominator in the closed interval [lo, hi] (lo <= hi).

    Stern-Brocot descent on the continued fractions of the ends, without recursion: intervals
    a few thousand bits wide (exact refinements) need thousands of terms.

    Examples:
        >>> simplest_between(fmpq(31, 100), fmpq(34, 100))
        1/3
        >>> x = fmpq(2**3000 + 1, 2**3000); simplest_between(x, x) == x
        True
    """
    if lo <= 0 <= hi:
        return fmpq(0)
    if hi < 0:
        return -simplest_between(-hi, -lo)
    terms = []
    a, b = lo, hi
    while True:
        fl = a.p // a.q
        if fmpq(fl) == a:
            terms.append(fl)
            break
        if fl + 1 <= b:
            terms.append(fl + 1)
            break
        terms.append(fl)
        a, b = 1 / (b - fl), 1 / (a - fl)
    # fold the continued fraction [t0; t1, ..., tk] with integer convergents
    h0, h1, k0, k1 = fmpz(1), terms[0], fmpz(0), fmpz(1)
    for t in terms[1:]:
        h0, h1 = h1, t * h1 + h0
        k0, k1 = k1, t * k1 + k0
    return fmpq(h1, k1)


_ARB_POLY_CACHE: dict[tuple[int, int], tuple[fmpq_poly, arb_poly]] = {}


def _arb_poly(F: fmpq_poly, prec: int) -> arb_poly:
    """arb_poly of F at ``prec`` bits, cached (keyed by identity; the entry keeps F alive)."""
    key = (id(F), prec)
    hit = _ARB_POLY_CACHE.get(key)
    if hit is not None and hit[0] is F:
        return hit[1]
    if len(_ARB_POLY_CACHE) > 4096:
        _ARB_POLY_CACHE.clear()
    with working_precision(prec):
        ap = arb_poly(F)
    _ARB_POLY_CACHE[key] = (F, ap)
    return ap


def _poly_sign_at(F: fmpq_poly, x: fmpq) -> int:
    """Exact sign of F(x) at a rational x: ball arithmetic first, exact evaluation if unsure."""
    for prec in (64, 256, 1024):
        with working_precision(prec):
            v = _arb_poly(F, prec)(arb(x))
            if v > 0:
                return 1
            if v < 0:
                return -1
    # exact: sign of sum a_i p^i q^(n-i) (q > 0), integers only
    num = F.numer()
    p, q = x.p, x.q
    cs = num.coeffs()
    n = len(cs) - 1
    acc = cs[n]
    qpow = fmpz(1)
    for i in range(n - 1, -1, -1):
        qpow = qpow * q
        acc = acc * p + cs[i] * qpow
    return _sgn(acc)


class RealAlgebraic:
    """A real algebraic number: a rational, or the unique root of F in an open interval.

    ``poly`` is a squarefree integer polynomial with exactly one root in ``(lo, hi)`` and
    ``F(lo) F(hi) < 0``. Refinement (bisection on exact rationals) keeps that invariant; if a
    bisection point is a root the number becomes exactly rational.

    Examples:
        >>> a = RealAlgebraic.isolating(fmpz_poly([-2, 0, 1]), fmpq(1), fmpq(2))   # sqrt(2)
        >>> a.decimal(20)
        '1.4142135623730950488'
        >>> a.compare(fmpq(141421356, 10**8)), a.compare(fmpq(3, 2))
        (1, -1)
    """

    __slots__ = ("poly", "lo", "hi", "value", "_slo")

    def __init__(self) -> None:
        self.poly: fmpq_poly = fmpq_poly([0, 1])
        self.lo: fmpq = fmpq(0)
        self.hi: fmpq = fmpq(0)
        self.value: fmpq | None = None
        self._slo = 0

    @classmethod
    def rational(cls, value: fmpq) -> RealAlgebraic:
        """The rational number ``value``."""
        a = cls()
        a.value = fmpq(value)
        a.lo = a.hi = a.value
        a.poly = fmpq_poly([-a.value, 1])
        return a

    @classmethod
    def isolating(cls, F: Any, lo: fmpq, hi: fmpq) -> RealAlgebraic:
        """Root of squarefree F in (lo, hi); requires F(lo) F(hi) < 0 (else ValueError)."""
        F = _poly(F)
        flo, fhi = F(lo), F(hi)
        if flo == 0:
            return cls.rational(lo)
        if fhi == 0:
            return cls.rational(hi)
        if _sgn(flo) == _sgn(fhi):
            raise ValueError("not an isolating interval: no sign change of F")
        a = cls()
        a.poly, a.lo, a.hi, a._slo = F, fmpq(lo), fmpq(hi), _sgn(flo)
        return a

    @property
    def is_rational(self) -> bool:
        """True when the exact rational value is known."""
        return self.value is not None

    @property
    def width(self) -> fmpq:
        """Width hi - lo of the isolating interval (0 for a known rational)."""
        return self.hi - self.lo

    def _become(self, v: fmpq) -> None:
        self.value = v
        self.lo = self.hi = v

    def bisect(self) -> None:
        """Halve the isolating interval (exact)."""
        if self.value is not None:
            return
        mid = (self.lo + self.hi) / 2
        s = _poly_sign_at(self.poly, mid)
        if s == 0:
            self._become(mid)
        elif s == self._slo:
            self.lo = mid
        else:
            self.hi = mid

    def try_rational(self) -> bool:
        """Test the simplest rational of the interval exactly; adopt it if it is the root."""
        if self.value is not None:
            return True
        c = simplest_between(self.lo, self.hi)
        if self.lo < c < self.hi and self.poly(c) == 0:
            self._become(c)
            return True
        return False

    def refine_to(self, width: fmpq) -> None:
        """Narrow the interval below ``width``: Newton steps certified by sign changes, else bisection."""
        while self.value is None and self.hi - self.lo >= width:
            if not self._newton(width):
                for _ in range(4):
                    self.bisect()

    def _newton(self, width: fmpq) -> bool:
        """Try Newton's method from the midpoint; adopt [x - w/4, x + w/4] if F changes sign there."""
        lo, hi = self.lo, self.hi
        # enough bits to represent x to within width/16, plus a margin for cancellation
        mag = max(abs(lo), abs(hi), fmpq(1))
        ratio = mag / width if width > 0 else fmpq(2) ** 64
        bits = min(int(ratio.p // ratio.q).bit_length() + 72, 40000) + 2 * self.poly.degree()
        with working_precision(bits):
            F = arb_poly(self.poly)
            dF = F.derivative()
            x = arb((lo + hi) / 2)
            for _ in range(40):
                fx, dx = F(x), dF(x)
                if dx.contains(0):
                    return False
                step = (fx / dx).mid()
                x = (x - step).mid()
                if not (arb(lo) < x < arb(hi)):
                    return False
                if abs(step) < arb(width) / 16:
                    break
            xm, _ = arb_to_fmpq(x)
        w = width / 4
        a, b = max(xm - w, lo), min(xm + w, hi)
        if not a < b:
            return False
        sa, sb = _poly_sign_at(self.poly, a), _poly_sign_at(self.poly, b)
        if sa == 0:
            self._become(a)
            return True
        if sb == 0:
            self._become(b)
            return True
        if sa == self._slo and sb != self._slo:
            self.lo, self.hi = a, b
            return True
        return False

    def enclosure(self, prec: int) -> arb:
        """An arb ball containing the number (computed at ``prec`` bits)."""
        with working_precision(prec):
            if self.value is not None:
                return arb(self.value)
            return arb.union(arb(self.lo), arb(self.hi))

    def compare(self, x: Any) -> int:
        """Exact sign of (self - x) for a rational x."""
        x = fmpq(x) if not isinstance(x, fmpq) else x
        if self.value is not None:
            return _sgn(self.value - x)
        if x <= self.lo:
            return 1
        if x >= self.hi:
            return -1
        sx = _poly_sign_at(self.poly, x)
        if sx == 0:
            self._become(x)
            return 0
        # same sign as F(lo): x is left of the root
        return 1 if sx == self._slo else -1

    def __float__(self) -> float:
        if self.value is not None:
            return _to_float(self.value)
        self.refine_to(_rel_width(self.lo, self.hi, 60))
        return _to_float((self.lo + self.hi) / 2)

    def decimal(self, digits: int = 20) -> str:
        """Decimal value with ``digits`` significant digits, error below one unit in the last place.

        A rational with a terminating expansion that fits is printed exactly.
        """
        if digits < 1 or digits > 10000:
            raise ValueError(f"digits must be in 1..10000, got {digits}")
        if self.value is not None:
            exact = _exact_decimal(self.value, digits)
            if exact is not None:
                return exact
        # refine until the interval is below 1/10 of a unit in the last place
        while True:
            lo, hi = self.lo, self.hi
            big = max(abs(lo), abs(hi))
            if big == 0:
                return "0"
            e = floor_log10(big)
            ulp = _pow10(e - digits + 1)
            if self.value is not None or hi - lo < ulp / 10:
                break
            self.refine_to(ulp / 20)
        mid = self.value if self.value is not None else (self.lo + self.hi) / 2
        return _round_decimal(mid, digits)

    def to_dict(self, digits: int = 20) -> dict[str, Any]:
        """The JSON form of a real algebraic number (the one form: events, intervals, witnesses).

        ``value``: the decimal to ``digits`` significant digits; ``approx``: a float (None when
        it overflows); ``exact``: "p/q" when rational, else None; ``isolating``: [lo, hi] as
        "p/q" strings, an interval that holds this root of ``polynomial`` and no other root
        ([v, v] for a rational v); ``polynomial``: the integer coefficients, ascending, of a
        squarefree polynomial it is a root of (None when rational).

        Examples:
            >>> d = RealAlgebraic.isolating(fmpz_poly([-2, 0, 1]), fmpq(1), fmpq(2)).to_dict(5)
            >>> d["value"], d["approx"], d["exact"], d["polynomial"]       # sqrt(2); isolating: refined
            ('1.4142', 1.4142135623730951, None, ['-2', '0', '1'])
            >>> RealAlgebraic.rational(fmpq(1, 3)).to_dict(3)
            {'value': '0.333', 'approx': 0.3333333333333333, 'exact': '1/3', 'isolating': ['1/3', '1/3'], 'polynomial': None}
        """
        value = self.decimal(digits)
        approx = float(self)
        out: dict[str, Any] = {"value": value, "approx": approx if approx - approx == 0 else None}
        if self.value is not None:
            v = str(self.value)
            out.update(exact=v, isolating=[v, v], polynomial=None)
        else:
            out.update(exact=None, isolating=[str(self.lo), str(self.hi)], polynomial=[str(c) for c in self.poly.numer().coeffs()])
        return out

    def __repr__(self) -> str:
        if self.value is not None:
            return f"RealAlgebraic({self.value})"
        return f"RealAlgebraic(root of {self.poly} in ({self.lo}, {self.hi}))"


def _rel_width(lo: fmpq, hi: fmpq, bits: int) -> fmpq:
    big = max(abs(lo), abs(hi), fmpq(1, 2**bits))
    return big / fmpq(2) ** bits


def _pow10(k: int) -> fmpq:
    return fmpq(10**k) if k >= 0 else fmpq(1, 10 ** (-k))


def _round_decimal(x: fmpq, digits: int) -> str:
    """X rounded to ``digits`` significant digits, as a plain or scientific decimal string."""
    if x == 0:
        return "0"
    neg = x < 0
    a = -x if neg else x
    e = floor_log10(a)
    shift = digits - 1 - e
    scaled = a * _pow10(shift)
    n = (scaled.p * 2 + scaled.q) // (scaled.q * 2)  # round half up
    s = str(n)  # an fmpz: decimal text at any length (str(int) stops at 4300 digits)
    if len(s) > digits:  # rounding carried into a new digit
        e += 1
        s = s[:digits]
    if -6 <= e < digits + 6:
        if e >= 0:
            if e + 1 >= len(s):
                out = s + "0" * (e + 1 - len(s))
            else:
                out = s[: e + 1] + "." + s[e + 1 :]
        else:
            out = "0." + "0" * (-e - 1) + s
    else:
        out = s[0] + ("." + s[1:] if len(s) > 1 else "") + f"e{e}"
    return ("-" if neg else "") + out


def _exact_decimal(x: fmpq, digits: int) -> str | None:
    """X exactly as a terminating decimal of at most ``digits`` significant digits, else None."""
    k = decimal_exponent(x)  # x 10^k is an integer, and k is the least such power
    if k is None:
        return None
    a = -x if x < 0 else x
    if a == 0:
        return "0"
    # n = a 10^k ends in a nonzero digit (k is least): it has floor_log10(a) + k + 1 digits, all
    # significant; decide before writing any (a value like 10^5000 never becomes text here)
    e = floor_log10(a)
    if e + k + 1 > digits:
        return None
    s = str((a * fmpq(10) ** k).p)  # an fmpz: no 4300-digit limit
    if not -6 <= e < digits + 6:  # far from 1: mantissa and exponent, as _round_decimal writes it
        s = s.rstrip("0")
        return ("-" if x < 0 else "") + s[0] + ("." + s[1:] if len(s) > 1 else "") + f"e{e}"
    if k == 0:
        out = s
    else:
        s = s.rjust(k + 1, "0")
        out = s[:-k] + "." + s[-k:]
    return ("-" if x < 0 else "") + out


def _arb_sign(v: QSqrtPoly, x: arb, prec: int) -> int | None:
    with working_precision(prec):
        val = _arb_poly(v.p, prec)(x)
        if not v.q.is_zero():
            val = val + _arb_poly(v.q, prec)(x) * arb(v.d).sqrt()
        if val > 0:
            return 1
        if val < 0:
            return -1
        if val.is_zero():
            return 0
        return None


def _is_root_of(alpha: RealAlgebraic, g: fmpq_poly) -> bool:
    """Whether alpha is a root of g, where g divides alpha.poly (or is zero)."""
    if g.is_zero():
        return True
    if g.degree() < 1:
        return False
    if alpha.value is not None:
        return g(alpha.value) == 0
    return _sgn(g(alpha.lo)) != _sgn(g(alpha.hi))


def _vanishes_at(v: QSqrtPoly, alpha: RealAlgebraic) -> bool:
    if alpha.value is not None:
        return v.sign_at_rational(alpha.value) == 0
    F = alpha.poly
    if v.q.is_zero():
        return _is_root_of(alpha, F.gcd(v.p))
    if not _is_root_of(alpha, F.gcd(v.norm())):
        return False
    if _is_root_of(alpha, F.gcd(v.p.gcd(v.q))):
        return True
    # N(v)(alpha) = 0 and p, q do not both vanish: then neither does, and v(alpha) = 0
    # exactly when p(alpha) = -sqrt(d) q(alpha), i.e. when their signs are opposite
    sp = sign_at(QSqrtPoly(v.p), alpha)
    sq = sign_at(QSqrtPoly(v.q), alpha)
    return sp * sq < 0


def sign_at(v: QSqrtPoly, alpha: RealAlgebraic) -> int:
    """Exact sign of v(alpha) for v in Q(sqrt d)[t] and a real algebraic alpha.

    Examples:
        >>> a = RealAlgebraic.isolating(fmpz_poly([-2, 0, 1]), fmpq(1), fmpq(2))   # sqrt(2)
        >>> sign_at(QSqrtPoly(fmpq_poly([0, 1]), -1, 2), a)        # t - sqrt(2) at sqrt(2)
        0
        >>> sign_at(QSqrtPoly(fmpq_poly([0, 1]), 1, 2), a)         # t + sqrt(2)
        1
    """
    if v.is_zero():
        return 0
    if alpha.value is not None:
        return v.sign_at_rational(alpha.value)
    prec = 64
    tested_zero = False
    for _ in range(200):
        s = _arb_sign(v, alpha.enclosure(prec), prec)
        if s is not None:
            return s
        if not tested_zero:
            if _vanishes_at(v, alpha):
                return 0
            tested_zero = True
            if alpha.value is not None:
                return v.sign_at_rational(alpha.value)
        # nonzero: narrow alpha and raise the working precision until the ball excludes 0
        alpha.refine_to(alpha.width / 2**32)
        if alpha.value is not None:
            return v.sign_at_rational(alpha.value)
        prec += 32
    raise RuntimeError("sign_at did not converge (precision limit reached)")
