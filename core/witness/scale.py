"""The contact scale mu of a pair: how far from touching, certified (Perram-Wertheim).

Scale both shapes about their own centres by the same factor mu: they touch externally at one
mu = mu*, are separate below it and overlap above it. mu* > 1 means separate (both must grow by
mu* - 1 to touch), mu* = 1 tangent, mu* < 1 overlap (both must shrink by 1 - mu*). For two
spheres mu* = |c1 - c2| / (r1 + r2).

mu*^2 = s* = max of the concave contact function f (:mod:`core.witness.contact_function`). One
pair: a float estimate of the maximiser starts an exact rational bracket; concavity turns it into
rational bounds lo <= mu* <= hi, refined by exact Newton steps until they are within ``rtol`` and
on one side of 1, or proven equal to 1 (s* = 1 iff the factor of f' that vanishes at lambda* divides
N - D). So the relation reported is certified independently of the paper's decision tree (the
tests check that both agree). On request mu* is given exactly as a real algebraic number
(defining polynomial and isolating interval; :meth:`ContactScale.algebraic`).

Stacks of float pairs go to :func:`core.witness.batch.contact_scale_batch` (vectorised).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from flint import fmpq

from ..algebra.algebraic import RealAlgebraic
from ..relation import Relation
from .centred import centred_pair
from .contact_function import Bracket, ContactFunction
from .numbers import algebraic_dict, sqrt_bounds, to_float, value_at_root

__all__ = ["ContactScale", "contact_scale_pair", "solve_pair", "scale_from"]

_MAX_REFINEMENTS = 40


@dataclass
class ContactScale:
    """A certified bracket of the contact scale mu* of one pair.

    ``lo <= mu* <= hi`` (exact rationals, equal when mu* is known exactly, e.g. 1 for a tangent
    pair); ``relation`` is SEPARATE (mu* > 1), TANGENT (mu* = 1) or OVERLAP (mu* < 1).
    """

    lo: fmpq
    hi: fmpq
    relation: Relation
    _cf: ContactFunction | None = field(default=None, repr=False)
    _bracket: Bracket | None = field(default=None, repr=False)
    _algebraic: RealAlgebraic | None = field(default=None, repr=False)

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
                assert self._cf is not None and self._bracket is not None
                h = self._cf.root_factor(self._bracket)
                alpha = RealAlgebraic.isolating(h, self._bracket.lo, self._bracket.hi)
                N, D = self._cf.polynomials
                self._algebraic = value_at_root(alpha, N, D, square_root=True)
        return self._algebraic

    def decimal(self, digits: int = 20) -> str:
        """mu* to ``digits`` significant digits (exact computation, error below one unit in the last place)."""
        return self.algebraic().decimal(digits)

    def to_dict(self, digits: int | None = None) -> dict[str, Any]:
        """JSON form: exact bounds as strings, float approximation, relation.

        With ``digits``, also the exact algebraic value (decimal, polynomial, isolating interval).
        """
        out: dict[str, Any] = {
            "lo": str(self.lo),
            "hi": str(self.hi),
            "approx": self.approx,
            "margin": self.margin,
            "relation": str(self.relation),
        }
        if digits is not None:
            out["exact"] = algebraic_dict(self.algebraic(), digits)
        return out


def solve_pair(A: Any, B: Any, rtol: float = 1e-12) -> tuple[ContactFunction, Bracket | None]:
    """Validate a pair, build its contact function and a first exact bracket (None: same centre).

    The bracket of lambda* is about sqrt(rtol) wide: by concavity the bracket of s* = f(lambda*)
    it gives is about rtol wide.
    """
    cf = ContactFunction(*centred_pair(A, B))
    return cf, cf.first_bracket(bits=min(40, max(12, int(-math.log2(rtol) / 2) + 8)))


def _relation(cf: ContactFunction, br: Bracket, tangent: list[bool | None]) -> Relation | None:
    if br.s_lo > 1:
        return Relation.SEPARATE
    if br.s_hi < 1:
        return Relation.OVERLAP
    if tangent[0] is None:
        tangent[0] = cf.is_tangent(br)
    return Relation.TANGENT if tangent[0] else None


def _mu_bounds(br: Bracket, rel: Relation, bits: int) -> tuple[fmpq, fmpq]:
    """Rational bounds of sqrt(s*) from those of s*, precise enough to stay on the side of 1."""
    while True:
        lo, _ = sqrt_bounds(br.s_lo, bits)
        _, hi = sqrt_bounds(br.s_hi, bits)
        if (rel != Relation.SEPARATE or lo > 1) and (rel != Relation.OVERLAP or hi < 1):
            return lo, hi
        bits *= 2


def _contact_scale_pair(A: Any, B: Any, rtol: float) -> ContactScale:
    return scale_from(*solve_pair(A, B, rtol), rtol)


def scale_from(cf: ContactFunction, br: Bracket | None, rtol: float) -> ContactScale:
    """The contact scale from a pair's contact function and first bracket (see :func:`solve_pair`)."""
    if br is None:
        return ContactScale(fmpq(0), fmpq(0), Relation.OVERLAP, cf, None)
    bits = max(64, int(-math.log2(rtol)) + 16)
    tangent: list[bool | None] = [None]
    for _ in range(_MAX_REFINEMENTS):
        rel = _relation(cf, br, tangent)
        if rel == Relation.TANGENT:
            return ContactScale(fmpq(1), fmpq(1), rel, cf, br)
        if rel is not None:
            lo, hi = _mu_bounds(br, rel, bits)
            if br.exact or hi - lo <= hi * fmpq(*float(rtol).as_integer_ratio()):
                return ContactScale(lo, hi, rel, cf, br)
        br = cf.refine(br, 2 * max(bits, int(br.hi.q.bit_length())))
    raise RuntimeError("contact_scale: the bracket did not converge (please report this pair)")


def contact_scale_pair(A: Any, B: Any, *, rtol: float = 1e-12) -> ContactScale:
    """:func:`core.witness.contact_scale` of one pair (exact rational bracket)."""
    if not (rtol > 0 and math.isfinite(rtol)):
        raise ValueError(f"rtol must be a finite number > 0 (the exact value is .algebraic()), got {rtol!r}")
    return _contact_scale_pair(A, B, rtol)
