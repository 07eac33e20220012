"""Certified float sign of an exact polynomial at a float time: the filter in front of flint.

The timeline's readout evaluates a_i(t), ŝ_j(t) at the float t of the slider. Exact evaluation of
Example 30's degree-84 ŝ0 in Q(sqrt 2) costs ~80 us; a float Horner step with a proven forward
error bound decides the sign in a few microseconds and abstains (None) when it cannot, and
the caller then evaluates exactly. Same idea as the static filter (:mod:`core.fixed.errorbound`).

Coefficients ``c_i = p_i + q_i sqrt(d)`` are enclosed once, in exact integer arithmetic, after an
exact power-of-two scaling that brings the largest near 1: a float ``f_i`` and a float ``e_i``
with ``|c_i - f_i| <= e_i`` (sqrt(d) to 2^-200 by ``math.isqrt``), so cancellation inside a
coefficient of Q(sqrt d) costs nothing at evaluation time. Horner at the exact float t then has
(Higham, *Accuracy and Stability*, 5.1)::

    |computed - c(t)| <= gamma(2n) S + E (+ underflow),  S = sum |f_i| |t|^i,  E = sum e_i |t|^i

with ``gamma(k) = k u / (1 - k u)``; the computed S and E are inflated for their own rounding,
and ``(2n + 2) 2^-1074 max(1, |t|)^n`` covers products rounded below the normal range.
"""

from __future__ import annotations

import math
from fractions import Fraction

from flint import fmpq_poly

__all__ = ["FloatPoly"]

_U = 2.0**-53
_TINY = 2.0**-1074
_SQRT_BITS = 200


def _gamma(k: int) -> float:
    return k * _U / (1.0 - k * _U)


def _round_up(x: Fraction) -> float:
    """A float >= x >= 0 (correctly rounded, then one step up)."""
    f = x.numerator / x.denominator if x else 0.0
    return math.nextafter(f, math.inf) if x else 0.0


def _coeffs(p: fmpq_poly) -> list[Fraction]:
    return [Fraction(int(c.p), int(c.q)) for c in p.coeffs()]


class FloatPoly:
    """Float enclosure of ``p(t) + q(t) sqrt(d)`` (exact rational p, q), scaled by 2^-scale_exp."""

    __slots__ = ("coeffs", "errs", "n", "exact_zero", "scale_exp")

    def __init__(self, p: fmpq_poly, q: fmpq_poly | None = None, d: int = 1) -> None:
        pc = _coeffs(p)
        qc = _coeffs(q) if q is not None and d != 1 else []
        n = max(len(pc), len(qc))
        pc += [Fraction(0)] * (n - len(pc))
        qc += [Fraction(0)] * (n - len(qc))
        # sqrt(d) in [r_lo, r_lo + 2^-B]
        r_lo = Fraction(math.isqrt(d << (2 * _SQRT_BITS)), 1 << _SQRT_BITS)
        r_w = Fraction(1, 1 << _SQRT_BITS)
        mids, halfw = [], []
        for a, b in zip(pc, qc, strict=True):
            if b == 0:
                mids.append(a)
                halfw.append(Fraction(0))
            else:
                mids.append(a + b * r_lo + abs(b) * r_w / 2 * (1 if b > 0 else -1))
                halfw.append(abs(b) * r_w / 2)
        self.n = max(n - 1, 0)
        self.exact_zero = all(m == 0 and w == 0 for m, w in zip(mids, halfw, strict=True))
        self.scale_exp = 0
        """The floats enclose the coefficients of (p + q sqrt d) * 2^-scale_exp."""
        self.coeffs: list[float] = []
        self.errs: list[float] = []
        if self.exact_zero:
            return
        big = max(abs(m) + w for m, w in zip(mids, halfw, strict=True))
        e = big.numerator.bit_length() - big.denominator.bit_length()
        self.scale_exp = e
        scale = Fraction(1, 1 << e) if e >= 0 else Fraction(1 << -e)
        for m, w in zip(mids, halfw, strict=True):
            ms, ws = m * scale, w * scale
            f = ms.numerator / ms.denominator  # correctly rounded (Python int division)
            self.coeffs.append(f)
            self.errs.append(_round_up(abs(ms - Fraction(f)) + ws))

    def value_bound(self, t: float) -> tuple[float, float] | None:
        """(computed scaled value at the float t, proven bound on its error), or None on overflow."""
        r = s = err = 0.0
        at = abs(t)
        for c, e in zip(reversed(self.coeffs), reversed(self.errs), strict=True):
            r = r * t + c
            s = s * at + abs(c)
            err = err * at + e
        n = self.n
        try:
            under = (2 * n + 2) * _TINY * max(1.0, at) ** n
        except OverflowError:
            return None
        bound = (_gamma(2 * n + 2) * s + err) * (1.0 + _gamma(4 * n + 8)) + under
        if not (math.isfinite(r) and math.isfinite(bound)):
            return None
        return r, bound

    def sign_at(self, t: float) -> int | None:
        """Certified sign at the float t, or None when the bound cannot tell."""
        if self.exact_zero:
            return 0
        vb = self.value_bound(t)
        if vb is None:
            return None
        val, bound = vb
        if val > bound:
            return 1
        if -val > bound:
            return -1
        return None
