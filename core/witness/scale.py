"""The contact scale mu of a pair: how far from touching, certified (Perram-Wertheim).

Scale both shapes about their own centres by the same factor mu: they touch externally at one
mu = mu*, are separate below it and overlap above it. mu* > 1 means separate (both must grow by
mu* - 1 to touch), mu* = 1 tangent, mu* < 1 overlap (both must shrink by 1 - mu*). For two
spheres mu* = |c1 - c2| / (r1 + r2).

mu*^2 = s* = max of the concave contact function f (:mod:`core.witness.contact_function`). One
pair: a float estimate of the maximiser (taken at unit size, so any scale starts well) starts an
exact rational bracket; concavity turns it into rational bounds lo <= mu* <= hi, refined by
safeguarded exact Newton steps until they are within ``rtol`` and on the side of 1 that the
certified relation (:func:`core.classify`) names; a tangent pair is mu* = 1 exactly. The bits
used grow with the accuracy reached, not with the size of the numbers. If the bracket ever
crossed 1 on the wrong side the two certified computations would disagree: a RuntimeError
(never seen; the tests check the bracket against an independent oracle). On request mu* is
given exactly as a real algebraic number (defining polynomial and isolating interval;
:meth:`ContactScale.algebraic`).

This module holds the exact stage (:func:`scale_exact`) and the float stage (:func:`scale_float`,
vectorised certificates of :mod:`core.witness.floatcert`) that :func:`core.witness.contact_scale`
runs through the one filtered evaluation of :mod:`core.witness.filtered`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from flint import fmpq

from ..algebra.algebraic import RealAlgebraic
from ..fixed.classify import Certifier, classify
from ..relation import Relation
from .centred import centred_pair
from .contact_function import Bracket, ContactFunction
from .floatcert import scale_brackets
from .numbers import algebraic_dict, sqrt_bounds, to_float, value_at_root

if TYPE_CHECKING:
    from .filtered import Pairs

__all__ = ["ContactScale", "contact_scale_pair", "scale_from", "scale_exact", "scale_float", "check_rtol"]

_MAX_STEPS = 400
"""Narrowing steps at most (each at least halves the bracket; a handful are needed): a safety net."""


@dataclass
class ContactScale:
    """A certified bracket of the contact scale mu* of one pair.

    ``lo <= mu* <= hi`` (exact rationals, equal when mu* is known exactly, e.g. 1 for a tangent
    pair); ``relation`` is SEPARATE (mu* > 1), TANGENT (mu* = 1) or OVERLAP (mu* < 1);
    ``certified_by`` says which arithmetic proved the bracket (float with directed rounding, or
    exact rationals; the bounds are exact rationals either way).
    """

    lo: fmpq
    hi: fmpq
    relation: Relation
    certified_by: Certifier = Certifier.EXACT
    _pair: tuple[Any, Any] | None = field(default=None, repr=False, compare=False)
    """The pair's matrices as given, for the exact value on demand."""
    _cf: ContactFunction | None = field(default=None, repr=False, compare=False)
    _bracket: Bracket | None = field(default=None, repr=False, compare=False)
    _algebraic: RealAlgebraic | None = field(default=None, repr=False, compare=False)

    @property
    def approx(self) -> float:
        """A float inside [lo, hi] (the midpoint, rounded)."""
        return to_float((self.lo + self.hi) / 2)

    @property
    def margin(self) -> float:
        """mu* - 1 as a float: > 0 apart, 0 touching, < 0 overlapping (relative to the sizes)."""
        return to_float((self.lo + self.hi) / 2 - 1)

    @property
    def is_exact(self) -> bool:
        """True when lo = hi = mu*."""
        return self.lo == self.hi

    def algebraic(self) -> RealAlgebraic:
        """mu* exactly: a rational, or a root of an integer polynomial in an isolating interval.

        Examples:
            >>> circle = lambda x, r: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - r * r]]
            >>> contact_scale_pair(circle(0, 1), circle(3, 0.5)).algebraic()   # 3 / (1 + 1/2)
            RealAlgebraic(2)
        """
        if self._algebraic is None:
            if self.lo == self.hi:
                self._algebraic = RealAlgebraic.rational(self.lo)
            else:
                if self._cf is None or self._bracket is None:  # a float bracket: the exact one now
                    assert self._pair is not None
                    self._cf = ContactFunction(*centred_pair(*self._pair))
                    self._bracket = self._cf.start()
                    assert self._bracket is not None  # lo < hi: the centres differ
                h, br = self._cf.root_factor(self._bracket)
                alpha = RealAlgebraic.rational(br.lo) if br.exact else RealAlgebraic.isolating(h, br.lo, br.hi)
                N, D = self._cf.polynomials
                self._algebraic = value_at_root(alpha, N, D, square_root=True)
        return self._algebraic

    def decimal(self, digits: int = 20) -> str:
        """mu* to ``digits`` significant digits (exact computation, error below one unit in the last place)."""
        return self.algebraic().decimal(digits)

    def to_dict(self, digits: int | None = None) -> dict[str, Any]:
        """JSON form: exact bounds as strings, float approximation, relation, certifier.

        With ``digits``, also the exact algebraic value (decimal, polynomial, isolating interval).
        """
        out: dict[str, Any] = {
            "lo": str(self.lo),
            "hi": str(self.hi),
            "approx": self.approx,
            "margin": self.margin,
            "relation": str(self.relation),
            "certified_by": str(self.certified_by),
        }
        if digits is not None:
            out["exact"] = algebraic_dict(self.algebraic(), digits)
        return out


def _mu_bounds(br: Bracket, rel: Relation, bits: int) -> tuple[fmpq, fmpq]:
    """Rational bounds of sqrt(s*) from those of s*, precise enough to stay on the side of 1."""
    while True:
        lo, _ = sqrt_bounds(br.s_lo, bits)
        _, hi = sqrt_bounds(br.s_hi, bits)
        if (rel != Relation.SEPARATE or lo > 1) and (rel != Relation.OVERLAP or hi < 1):
            return lo, hi
        bits *= 2


def scale_from(cf: ContactFunction, rel: Relation, rtol: float) -> ContactScale:
    """The contact scale of a pair from its contact function and its certified relation.

    The relation (from :func:`core.classify`) says on which side of 1 mu* lies (= 1 exactly for
    a tangent pair); the bracket of the contact function is narrowed until it is on that side
    and within ``rtol``. Every step at least halves the bracket, and Newton steps double the
    bits gained, so this ends after a handful of steps; should it ever not, the bracket reached
    (clipped to the certified side of 1) is returned: certified, only wider than asked.
    """
    if rel == Relation.TANGENT:
        return ContactScale(fmpq(1), fmpq(1), rel, Certifier.EXACT, None, cf, None)
    br = cf.start()
    if br is None:  # same centre: scaled down to a point each, they still share it
        return ContactScale(fmpq(0), fmpq(0), Relation.OVERLAP, Certifier.EXACT, None, cf, None)
    tol = fmpq(*float(rtol).as_integer_ratio())
    bits = max(64, int(-math.log2(rtol)) + 16)
    for _ in range(_MAX_STEPS):
        if br.s_lo > 1 and rel == Relation.OVERLAP or br.s_hi < 1 and rel == Relation.SEPARATE:
            raise RuntimeError(f"contact scale and classify disagree ({rel}): please report this pair")
        on_side = br.s_lo > 1 if rel == Relation.SEPARATE else br.s_hi < 1
        if on_side or br.exact:
            lo, hi = _mu_bounds(br, rel, bits) if on_side else sqrt_bounds(br.s_lo, bits)
            if br.exact or hi - lo <= hi * tol:
                return _clipped(lo, hi, rel, cf, br)
        br = cf.step(br)
    lo, _ = sqrt_bounds(br.s_lo, bits)
    _, hi = sqrt_bounds(br.s_hi, bits)
    return _clipped(lo, hi, rel, cf, br)


def _clipped(lo: fmpq, hi: fmpq, rel: Relation, cf: ContactFunction, br: Bracket) -> ContactScale:
    """The bracket [lo, hi] intersected with the side of 1 that the relation certifies."""
    if rel == Relation.SEPARATE:
        lo = max(lo, fmpq(1))
    else:
        hi = min(hi, fmpq(1))
    return ContactScale(lo, hi, rel, Certifier.EXACT, None, cf, br)


def contact_scale_pair(A: Any, B: Any, *, rtol: float = 1e-12) -> ContactScale:
    """The exact contact scale of one pair (the exact stage alone; :func:`core.witness.contact_scale` is the public form)."""
    check_rtol(rtol)
    rel = classify(A, B)
    return scale_from(ContactFunction(*centred_pair(A, B)), rel, rtol)


def scale_exact(pairs: Pairs, i: int, rtol: float) -> ContactScale:
    """The exact stage: pair i's bracket in exact rationals (within ``rtol``)."""
    rel = Relation(int(pairs.relation[i]))
    if rel == Relation.TANGENT:
        return ContactScale(fmpq(1), fmpq(1), rel, Certifier.EXACT, (pairs.a[i], pairs.b[i]))
    out = scale_from(pairs.contact_function(i), rel, rtol)
    out._pair = (pairs.a[i], pairs.b[i])
    return out


_SIMPLE = fmpq(1, 2**10)
"""A simple rational c in a float bracket is tried as mu* itself when den(c)^2 (hi - lo) is below
this: always for brackets around simple values (3/2 for two spheres, 2 at rtol 1e-6), by chance
for about one bracket in a thousand (a random bracket of width w holds a rational of denominator
q or less with probability about q^2 w): an exact check then, a fraction of a millisecond."""


def scale_float(pairs: Pairs, todo: np.ndarray, rtol: float) -> dict[int, ContactScale]:
    """The float stage: certified float brackets (vectorised); tangent pairs are mu* = 1 exactly.

    A bracket is kept only when it lies strictly on the side of 1 of the relation (lo > 1 for a
    separate pair, hi < 1 for an overlapping one), as the exact stage's always does.

    Under ``method="adaptive"`` a bracket around a simple rational c is tested exactly: the
    pair scaled by c is classified, and tangent there means mu* = c exactly.
    """
    fp = pairs.floats
    assert fp is not None
    out: dict[int, ContactScale] = {}
    for i in np.flatnonzero(todo & (pairs.relation == Relation.TANGENT)):
        out[int(i)] = ContactScale(fmpq(1), fmpq(1), Relation.TANGENT, Certifier.EXACT, (pairs.a[i], pairs.b[i]))
    lo, hi, _, ok = scale_brackets(fp, pairs.relation, rtol, pairs.method)
    for i in np.flatnonzero(todo & ok & (pairs.relation != Relation.TANGENT)):
        rel = Relation(int(pairs.relation[i]))
        flo, fhi = fmpq(*float(lo[i]).as_integer_ratio()), fmpq(*float(hi[i]).as_integer_ratio())
        if (flo <= 1) if rel == Relation.SEPARATE else (fhi >= 1):
            continue  # the bracket must show the side of 1 by itself (as the exact one does)
        cs = ContactScale(flo, fhi, rel, Certifier.FLOAT, (pairs.a[i], pairs.b[i]))
        if pairs.method == "adaptive":
            c = _simple_in(float(lo[i]), float(hi[i]), flo, fhi)
            if c is not None and _is_contact_scale(pairs.contact_function(int(i)), c):
                cs = ContactScale(c, c, rel, Certifier.EXACT, cs._pair)
        out[int(i)] = cs
    return out


def _simple_in(lo: float, hi: float, flo: fmpq, fhi: fmpq) -> fmpq | None:
    """The rational c in [lo, hi] with den(c)^2 (hi - lo) < _SIMPLE, if there is one (at most one is).

    Such a c is within (hi - lo) / 2 < 1 / (2 den(c)^2) of the midpoint m, so by Legendre's
    theorem it is a convergent of m's continued fraction: the last convergent with a
    denominator small enough is the only candidate (integer Euclid, a few steps).
    """
    w = hi - lo
    if not w > 0:
        return None
    qmax = int(math.sqrt(float(_SIMPLE) / w))
    if qmax < 1:
        return None
    a, b = (0.5 * lo + 0.5 * hi).as_integer_ratio()
    p0, q0, p1, q1 = 0, 1, 1, 0  # convergents p/q of a/b
    while b:
        t, r = divmod(a, b)
        p0, q0, p1, q1 = p1, q1, t * p1 + p0, t * q1 + q0
        if q1 > qmax:
            p1, q1 = p0, q0
            break
        a, b = b, r
    if q1 == 0:
        return None
    c = fmpq(p1, q1)
    if c > 0 and flo <= c <= fhi and c.q * c.q * (fhi - flo) < _SIMPLE:
        return c
    return None


def _is_contact_scale(cf: ContactFunction, mu: fmpq) -> bool:
    """Exactly whether mu* = mu: the pair scaled about its centres by mu is tangent."""
    s = mu * mu
    mats = []
    for shape in (cf.A, cf.B):
        M = shape.matrix
        n = M.nrows()
        rows = [[M[i, j] for j in range(n)] for i in range(n)]
        rows[n - 1][n - 1] += shape.k * (1 - s)  # scaled about its centre: 1 becomes s in q
        mats.append(rows)
    return bool(classify(mats[0], mats[1]) == Relation.TANGENT)


def check_rtol(rtol: float) -> None:
    """ValueError unless rtol is a finite number > 0."""
    if not (isinstance(rtol, int | float) and rtol > 0 and math.isfinite(rtol)):
        raise ValueError(f"rtol must be a finite number > 0 (the exact value is .algebraic()), got {rtol!r}")
