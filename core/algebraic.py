"""Exact polynomials in Q(sqrt d)[t] and their signs at real algebraic numbers (paper 3.4, 4.4).

Example 30 of the paper moves an ellipsoid by a rotation with sqrt(2) entries, so the pencil
coefficients a_i(t) and the subresultants s0, s1, s1,0 live in Q(sqrt d)[t]. They are kept
exactly as pairs ``p + q r`` of ``fmpq_poly`` with ``r = sqrt(d)`` (:class:`QSqrtPoly`); the class
supports ``+ - *`` and integer multiplication, so :func:`core.pencil.pencil_coefficients` and the
``hat_*`` functions of :mod:`core.subresultants` run on it unchanged.

Real roots of ``s = p + q r`` are among the real roots of the norm ``N = p^2 - d q^2`` in Q[t].
They are isolated on the squarefree part of N (flint ``complex_roots``: real roots come with an
exactly zero imaginary part) and kept as :class:`RealAlgebraic` numbers: the unique root of a
squarefree integer polynomial F in an interval ``(lo, hi)`` with rational ends and
``F(lo) F(hi) < 0``. The sign of any ``v`` in Q(sqrt d)[t] at such a number is decided by
:func:`sign_at`: ball arithmetic (arb) at increasing precision when it is nonzero, and an exact
zero test otherwise: v(alpha) = 0 iff alpha is a root of gcd(F, N(v)) and p(alpha) = -sqrt(d)
q(alpha), i.e. p, q both vanish at alpha (gcd test) or have opposite signs there. No floating
approximation of sqrt(d) ever decides a sign.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from flint import arb, arb_poly, ctx, fmpq, fmpq_poly, fmpz, fmpz_poly

__all__ = [
    "QSqrtPoly",
    "RealAlgebraic",
    "real_roots",
    "sign_at",
    "sign_qsqrt",
    "squarefree_decomposition",
]


def squarefree_decomposition(n: int) -> tuple[int, int]:
    """Write a positive integer as ``k^2 * d`` with d squarefree; returns (k, d).

    Examples:
        >>> squarefree_decomposition(8), squarefree_decomposition(4), squarefree_decomposition(2)
        ((2, 2), (2, 1), (1, 2))
    """
    if n <= 0:
        raise ValueError(f"need a positive integer, got {n}")
    k, d = 1, 1
    for p, e in fmpz(n).factor():
        k *= int(p) ** (int(e) // 2)
        if int(e) % 2:
            d *= int(p)
    return k, d


def _sgn(x: Any) -> int:
    return (x > 0) - (x < 0)


def sign_qsqrt(a: fmpq, b: fmpq, d: int) -> int:
    """Exact sign of ``a + b sqrt(d)`` for rationals a, b and a positive integer d.

    Examples:
        >>> sign_qsqrt(fmpq(-7, 5), fmpq(1), 2), sign_qsqrt(fmpq(3, 2), fmpq(-1), 2)
        (1, 1)
    """
    sa, sb = _sgn(a), _sgn(b)
    if sb == 0 or d == 1:
        return _sgn(a + b) if d == 1 else sa
    if sa == 0 or sa == sb:
        return sb
    # opposite signs: compare a^2 with d b^2
    return sa * _sgn(a * a - b * b * d)


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

    __slots__ = ("p", "q", "d")

    def __init__(self, p: Any = 0, q: Any = 0, d: int = 1) -> None:
        self.p = _poly(p)
        self.q = _poly(q)
        self.d = int(d)
        if self.d == 1 and not self.q.is_zero():
            self.p = self.p + self.q
            self.q = fmpq_poly()

    # --- ring structure -------------------------------------------------------------------
    def _coerce(self, other: Any) -> QSqrtPoly:
        if isinstance(other, QSqrtPoly):
            return other
        if isinstance(other, int | fmpz | fmpq | fmpq_poly | fmpz_poly):
            return QSqrtPoly(other, 0, self.d)
        return NotImplemented  # type: ignore[return-value]

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

    def coefficients_float(self) -> list[float]:
        """Ascending float coefficients (display only; may overflow to inf for huge values)."""
        r = math.sqrt(self.d)
        n = self.degree() + 1
        pc = list(self.p.coeffs()) + [fmpq(0)] * (n - len(self.p.coeffs()))
        qc = list(self.q.coeffs()) + [fmpq(0)] * (n - len(self.q.coeffs()))
        return [_to_float(a) + _to_float(b) * r for a, b in zip(pc, qc)]

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


# --------------------------------------------------------------------------------------------
# real algebraic numbers


@contextmanager
def _workprec(bits: int) -> Iterator[None]:
    # ctx.prec is process-global in python-flint; arb balls stay rigorous whatever the
    # precision, so a concurrent change can only cost an extra refinement round, never a sign.
    old = ctx.prec
    ctx.prec = bits
    try:
        yield
    finally:
        ctx.prec = old


def _arb_to_fmpq(x: arb) -> tuple[fmpq, fmpq]:
    m, e = x.mid().man_exp()
    r, f = x.rad().man_exp()
    mid = fmpq(m) * (fmpq(2) ** e if e >= 0 else fmpq(1, 2 ** (-e)))
    rad = fmpq(r) * (fmpq(2) ** f if f >= 0 else fmpq(1, 2 ** (-f)))
    return mid, rad


def _simplest_between(lo: fmpq, hi: fmpq) -> fmpq:
    """Simplest rational (smallest denominator) in the closed interval [lo, hi], lo <= hi."""
    if lo <= 0 <= hi:
        return fmpq(0)
    if hi < 0:
        return -_simplest_between(-hi, -lo)
    # Stern-Brocot descent on continued fractions
    fl = lo.p // lo.q
    if fmpq(fl) == lo:
        return lo
    if fl + 1 <= hi:
        return fmpq(fl + 1)
    # lo, hi in (fl, fl+1): recurse on the reciprocals of the fractional parts
    return fmpq(fl) + 1 / _simplest_between(1 / (hi - fl), 1 / (lo - fl))


_ARB_POLY_CACHE: dict[tuple[int, int], tuple[fmpq_poly, arb_poly]] = {}


def _arb_poly(F: fmpq_poly, prec: int) -> arb_poly:
    """arb_poly of F at ``prec`` bits, cached (keyed by identity; the entry keeps F alive)."""
    key = (id(F), prec)
    hit = _ARB_POLY_CACHE.get(key)
    if hit is not None and hit[0] is F:
        return hit[1]
    if len(_ARB_POLY_CACHE) > 4096:
        _ARB_POLY_CACHE.clear()
    with _workprec(prec):
        ap = arb_poly(F)
    _ARB_POLY_CACHE[key] = (F, ap)
    return ap


def _poly_sign_at(F: fmpq_poly, x: fmpq) -> int:
    """Exact sign of F(x) at a rational x: ball arithmetic first, exact evaluation if unsure."""
    for prec in (64, 256, 1024):
        with _workprec(prec):
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
        c = _simplest_between(self.lo, self.hi)
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
        with _workprec(bits):
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
            xm, _ = _arb_to_fmpq(x)
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
        with _workprec(prec):
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
            e = _floor_log10(big)
            ulp = _pow10(e - digits + 1)
            if self.value is not None or hi - lo < ulp / 10:
                break
            self.refine_to(ulp / 20)
        mid = self.value if self.value is not None else (self.lo + self.hi) / 2
        return _round_decimal(mid, digits)

    def __repr__(self) -> str:
        if self.value is not None:
            return f"RealAlgebraic({self.value})"
        return f"RealAlgebraic(root of {self.poly} in ({self.lo}, {self.hi}))"


def _rel_width(lo: fmpq, hi: fmpq, bits: int) -> fmpq:
    big = max(abs(lo), abs(hi), fmpq(1, 2**bits))
    return big / fmpq(2) ** bits


def _pow10(k: int) -> fmpq:
    return fmpq(10**k) if k >= 0 else fmpq(1, 10 ** (-k))


def _floor_log10(x: fmpq) -> int:
    """floor(log10(x)) for a positive rational, exactly."""
    e = len(str(int(x.p))) - len(str(int(x.q)))
    while _pow10(e) > x:
        e -= 1
    while _pow10(e + 1) <= x:
        e += 1
    return e


def _round_decimal(x: fmpq, digits: int) -> str:
    """x rounded to ``digits`` significant digits, as a plain or scientific decimal string."""
    if x == 0:
        return "0"
    neg = x < 0
    a = -x if neg else x
    e = _floor_log10(a)
    shift = digits - 1 - e
    scaled = a * _pow10(shift)
    n = int((scaled.p * 2 + scaled.q) // (scaled.q * 2))  # round half up
    s = str(n)
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
    q = int(x.q)
    while q % 2 == 0:
        q //= 2
    while q % 5 == 0:
        q //= 5
    if q != 1:
        return None
    a = -x if x < 0 else x
    k = 0
    while (a * fmpq(10) ** k).q != 1:
        k += 1
    n = int(a * fmpq(10) ** k)
    s = str(n)
    if len(s.lstrip("0")) > digits:
        return None
    if k == 0:
        out = s
    else:
        s = s.rjust(k + 1, "0")
        out = s[:-k] + "." + s[-k:]
    return ("-" if x < 0 else "") + out


def _squarefree_integer(f: fmpq_poly) -> fmpz_poly:
    """Primitive squarefree integer polynomial with the roots of f."""
    g = f.gcd(f.derivative())
    sq = f if g.degree() < 1 else _exact_div(f, g)
    num = sq.numer()
    c = num.content()
    out = fmpz_poly([v // c for v in num.coeffs()])
    if out.coeffs() and out.coeffs()[-1] < 0:
        out = -out
    return out


def _exact_div(f: fmpq_poly, g: fmpq_poly) -> fmpq_poly:
    q, r = divmod(f, g)
    assert r.is_zero()
    return q


def _variations(coeffs: list[fmpz]) -> int:
    last, count = 0, 0
    for c in coeffs:
        if c == 0:
            continue
        s = 1 if c > 0 else -1
        if last and s != last:
            count += 1
        last = s
    return count


_X_PLUS_1 = fmpz_poly([1, 1])


def _positive_root_boxes(f: fmpz_poly) -> list[tuple[fmpq, fmpq]]:
    """Isolating intervals of the roots of squarefree f in (0, inf), f(0) != 0 (Descartes).

    Collins-Akritas bisection: the roots in (0, B) with B = 2^k a Cauchy bound are mapped to
    (0, 1); a box whose Descartes count (sign variations of (x+1)^n h(1/(x+1))) is 0 has no
    root, 1 has exactly one; otherwise it is halved. Returns (lo, hi), or (r, r) for an exact
    rational root met at a bisection point.
    """
    coeffs = f.coeffs()
    n = len(coeffs) - 1
    if n < 1 or _variations(coeffs) == 0:
        return []
    # Fujiwara's bound: every root has |x| < 2 max_i |a_{n-i}/a_n|^(1/i) <= 2^k (bit lengths)
    lead_bits = int(abs(coeffs[-1]).bit_length())
    k = 0
    for i in range(1, n + 1):
        c = coeffs[n - i]
        if c != 0:
            excess = int(abs(c).bit_length()) - lead_bits + 1 + (1 if i == n else 0)
            k = max(k, -(-excess // i))
    k += 1
    B = fmpq(2) ** k if k >= 0 else fmpq(1, 2 ** (-k))
    # h(x) = f(B x)
    if k >= 0:
        h = fmpz_poly([c * fmpz(2) ** (k * i) for i, c in enumerate(coeffs)])
    else:
        h = fmpz_poly([c * fmpz(2) ** (-k * (n - i)) for i, c in enumerate(coeffs)])
    out: list[tuple[fmpq, fmpq]] = []
    stack = [(h, 0, 0)]
    while stack:
        h, c, depth = stack.pop()
        scale = B / fmpq(2) ** depth
        hc = h.coeffs()
        if hc and hc[0] == 0:  # root exactly at the left end of this box
            r = scale * c
            out.append((r, r))
            h = fmpz_poly(hc[1:])
            hc = h.coeffs()
        m = len(hc) - 1
        if m < 1:
            continue
        v = _variations(fmpz_poly(hc[::-1])(_X_PLUS_1).coeffs())
        if v == 0:
            continue
        if v == 1:
            out.append((scale * c, scale * (c + 1)))
            continue
        left = fmpz_poly([a * fmpz(2) ** (m - i) for i, a in enumerate(hc)])  # 2^m h(x/2)
        right = left(_X_PLUS_1)
        stack.append((right, 2 * c + 1, depth + 1))
        stack.append((left, 2 * c, depth + 1))
    return out


def _isolate(F: fmpz_poly, lo: fmpq | None, hi: fmpq | None) -> list[RealAlgebraic]:
    """Real roots of a squarefree integer F in the closed interval [lo, hi] (None: infinite)."""
    if F.degree() < 1:
        return []
    out: list[RealAlgebraic] = []
    for f, _e in F.factor()[1]:
        fc = f.coeffs()
        if len(fc) == 2:  # linear factor: a rational root
            cands = [RealAlgebraic.rational(fmpq(-fc[0], fc[1]))]
        else:
            fq = fmpq_poly(f)
            cands = []
            neg = fmpz_poly([c if i % 2 == 0 else -c for i, c in enumerate(fc)])  # f(-x)
            for a, b in _positive_root_boxes(neg):
                cands.append(RealAlgebraic.rational(-a) if a == b else RealAlgebraic.isolating(fq, -b, -a))
            for a, b in _positive_root_boxes(f):
                cands.append(RealAlgebraic.rational(a) if a == b else RealAlgebraic.isolating(fq, a, b))
        for alpha in cands:
            if lo is not None and alpha.compare(lo) < 0:
                continue
            if hi is not None and alpha.compare(hi) > 0:
                continue
            out.append(alpha)
    return _sorted_disjoint(out)


def _sorted_disjoint(nums: list[RealAlgebraic]) -> list[RealAlgebraic]:
    """Sort distinct algebraic numbers, refining until consecutive intervals are disjoint."""
    while True:
        nums.sort(key=lambda a: (a.lo, a.hi))
        clash = False
        for a, b in zip(nums, nums[1:]):
            if not a.hi < b.lo and not (a.value is not None and a.value == b.value):
                clash = True
                (a if a.width >= b.width else b).bisect()
        if not clash:
            return nums


def real_roots(s: QSqrtPoly, lo: fmpq | None = None, hi: fmpq | None = None) -> list[RealAlgebraic]:
    """Distinct real roots of a nonzero ``s`` in [lo, hi] (None = unbounded), ascending.

    Examples:
        >>> s = QSqrtPoly(fmpq_poly([0, 1]), -1, 2)          # t - sqrt(2)
        >>> [r.decimal(12) for r in real_roots(s)]
        ['1.41421356237']
        >>> real_roots(QSqrtPoly(fmpq_poly([-1, 0, 4])), fmpq(0), None)   # 4t^2 - 1 on [0, inf)
        [RealAlgebraic(1/2)]
    """
    if s.is_zero():
        raise ValueError("the zero polynomial has every t as a root")
    F = _squarefree_integer(s.p if s.is_rational() else s.norm())
    cands = _isolate(F, lo, hi)
    if s.is_rational():
        return cands
    return [a for a in cands if sign_at(s, a) == 0]


def _arb_sign(v: QSqrtPoly, x: arb, prec: int) -> int | None:
    with _workprec(prec):
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
