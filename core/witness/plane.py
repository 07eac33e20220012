"""A separating plane with exact rational coefficients, verified exactly before it is returned.

For a separate pair the contact function (:mod:`core.witness.contact_function`) gives, at its
maximiser lambda*, the common normal y of the two shapes scaled to touch (scale mu* > 1); the
plane with that normal through the touching point separates the scaled shapes, hence strictly the
original ones. A rational normal close to y (the simplest that works: (1, 0, 0) rather than
0.99999999999999989, 1.1e-17, 0) and a rational offset between the two support values are
checked with an independent formula, the dual quadric: the plane pi = (n, -d) misses the
ellipsoid A iff pi^T A^-1 pi < 0, and A lies on the side n.x < d iff (A^-1 pi)_last > 0. If the
check fails (tiny gaps), lambda* is refined exactly and the construction repeated; an unverified
plane is never returned. This is the exact stage (:func:`plane_exact`); the float stage
(:func:`plane_float`) certifies float planes with directed rounding (:mod:`core.witness.floatcert`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from flint import fmpq, fmpq_mat

from ..fixed.classify import Certifier, classify
from ..relation import Relation
from .centred import CentredShape, centred_pair, column, dot
from .contact_function import Bracket, ContactFunction, log2_abs
from .floatcert import planes
from .numbers import simplest_between, sqrt_bounds, to_float

if TYPE_CHECKING:
    from .filtered import Pairs

__all__ = ["SeparatingPlane", "separating_plane_pair", "plane_separates", "plane_from", "plane_exact", "plane_float", "no_plane", "supports"]

_TOLERANCES = (fmpq(1, 2**6), fmpq(1, 2**14), fmpq(1, 2**30), fmpq(1, 2**52), fmpq(0))
_MAX_STEPS = 400
"""Narrowing steps at most (a handful are needed): a safety net."""


@dataclass
class SeparatingPlane:
    """The plane n.x = d: A lies strictly in n.x < d and B strictly in n.x > d (certified).

    ``certified_by``: exact rationals (the dual-quadric test) or floats with directed rounding
    (:mod:`core.witness.floatcert`); the plane's numbers are exact rationals either way.
    """

    normal: tuple[fmpq, ...]
    """n (not unit length; its largest component is +-1 when it could be simplified)."""
    offset: fmpq
    """d."""
    certified_by: Certifier = Certifier.EXACT
    _supports: tuple[fmpq, fmpq] | None = field(default=None, repr=False, compare=False)
    _pair: tuple[Any, Any] | None = field(default=None, repr=False, compare=False)

    @property
    def relation(self) -> Relation:
        """SEPARATE (only a separate pair has a separating plane)."""
        return Relation.SEPARATE

    @property
    def support_a(self) -> fmpq:
        """An upper bound of max n.x over A (< d)."""
        return self._bounds()[0]

    @property
    def support_b(self) -> fmpq:
        """A lower bound of min n.x over B (> d)."""
        return self._bounds()[1]

    def _bounds(self) -> tuple[fmpq, fmpq]:
        """The support bounds, computed exactly on first use for a float-certified plane."""
        if self._supports is None:
            assert self._pair is not None
            A, B = centred_pair(*self._pair)
            n = column(list(self.normal))
            bits = 64
            while True:  # the plane is strictly between: precise enough bounds are too
                ha, hb = supports(A, B, n, bits)
                if ha < self.offset < hb:
                    break
                bits *= 2
            self._supports = (ha, hb)
        return self._supports

    @property
    def gap(self) -> float:
        """A lower bound of the Euclidean distance between A and B.

        (support_b - support_a) / |n|, rounded down: the plane's width of empty space.
        """
        norm2 = sum((v * v for v in self.normal), fmpq(0))
        _, upper = sqrt_bounds(norm2, 64)
        g = (self.support_b - self.support_a) / upper
        f = to_float(g)
        return f if not np.isfinite(f) or fmpq(*f.as_integer_ratio()) <= g else float(np.nextafter(f, -np.inf))

    def unit(self) -> tuple[np.ndarray, float]:
        """(unit normal, offset) as floats, for drawing (not certified)."""
        big = max(abs(v) for v in self.normal)  # exact: the largest component becomes +-1
        n = np.array([to_float(v / big) for v in self.normal])
        s = float(np.linalg.norm(n))
        return n / s, to_float(self.offset / big) / s

    def to_dict(self) -> dict[str, Any]:
        """JSON form: exact strings and float approximations."""
        n, d = self.unit()
        return {
            "normal": [str(v) for v in self.normal],
            "offset": str(self.offset),
            "unit_normal_approx": n.tolist(),
            "offset_approx": d,
            "support_a": str(self.support_a),
            "support_b": str(self.support_b),
            "gap_lower_bound": self.gap,
            "certified_by": str(self.certified_by),
        }


def plane_separates(A: CentredShape, B: CentredShape, normal: fmpq_mat, offset: fmpq) -> bool:
    """Exactly: A strictly in n.x < d and B strictly in n.x > d (dual-quadric test)."""
    pi = fmpq_mat([[normal[i, 0]] for i in range(normal.nrows())] + [[-offset]])
    last = normal.nrows()
    for shape, side in ((A, -1), (B, 1)):
        z = shape.matrix.solve(pi)
        if not dot(pi, z) < 0 or not z[last, 0] * side < 0:
            return False
    return True


def supports(A: CentredShape, B: CentredShape, n: fmpq_mat, bits: int) -> tuple[fmpq, fmpq]:
    """(upper bound of max n.x over A, lower bound of min n.x over B): n.c +- sqrt(n^T S n)."""
    _, ua = sqrt_bounds(dot(n, A.S * n), bits)
    _, ub = sqrt_bounds(dot(n, B.S * n), bits)
    return dot(n, A.centre) + ua, dot(n, B.centre) - ub


def _simplified(y: fmpq_mat, tol: fmpq) -> fmpq_mat:
    """Y scaled to largest component +-1, each component replaced by the simplest rational within tol."""
    d = y.nrows()
    big = max(abs(y[i, 0]) for i in range(d))
    v = [y[i, 0] / big for i in range(d)]
    return column([simplest_between(x - tol, x + tol) if tol else x for x in v])


def _try_normal(cf: ContactFunction, n: fmpq_mat, bits: int) -> SeparatingPlane | None:
    ha, hb = supports(cf.A, cf.B, n, bits)
    if not ha < hb:
        return None
    mid, w = (ha + hb) / 2, (hb - ha) / 4
    d = simplest_between(mid - w, mid + w)
    if not plane_separates(cf.A, cf.B, n, d):
        return None
    return SeparatingPlane(tuple(n[i, 0] for i in range(n.nrows())), d, Certifier.EXACT, (ha, hb))


def _try_all(cf: ContactFunction, y: fmpq_mat, gap: fmpq | None) -> SeparatingPlane | None:
    """The simplest verified plane with a normal near y (tolerances from coarse to none).

    A normal tilted by tol misses the other shape only if tol is about the relative gap or
    less, so coarser tolerances are skipped once the gap is known (``gap`` = s_lo - 1 > 0).
    """
    bits = 64 if gap is None else max(64, 24 - log2_abs(gap))
    for tol in _TOLERANCES:
        if gap is not None and tol and tol > 4 * gap:
            continue
        plane = _try_normal(cf, _simplified(y, tol), bits)
        if plane is not None:
            return plane
    return None


def plane_from(cf: ContactFunction, br: Bracket | None = None) -> SeparatingPlane:
    """The verified plane of a separate pair from its contact function (and bracket, if known).

    The normal at the float estimate of lambda* is tried first (no exact bracket needed when it
    works, the usual case); then the normal at the best lambda of the exact bracket, narrowed a
    step at a time until a plane verifies. It does: at lambda* the normal's plane through the
    contact of the shapes scaled by mu* > 1 separates them strictly, and each step at least
    halves the bracket (Newton steps double the bits), so the tilt soon falls below the gap.
    """
    if br is None:
        plane = _try_all(cf, cf.normal(fmpq(*cf.float_guess.as_integer_ratio())), None)
        if plane is not None:
            return plane
        br = cf.start()
    assert br is not None  # separate shapes have distinct centres
    for _ in range(_MAX_STEPS):
        gap = br.s_lo - 1 if br.s_lo > 1 else None
        plane = _try_all(cf, cf.normal(br.best), gap)
        if plane is not None:
            return plane
        if br.exact:
            break
        br = cf.step(br)
    raise RuntimeError("separating_plane: no verified plane found (please report this pair)")


def separating_plane_pair(A: Any, B: Any) -> SeparatingPlane:
    """The exact plane of one pair (the exact stage alone; :func:`core.witness.separating_plane` is the public form)."""
    rel = classify(A, B)
    if rel != Relation.SEPARATE:
        raise ValueError(no_plane(rel))
    return plane_from(ContactFunction(*centred_pair(A, B)))


def no_plane(rel: Relation) -> str | None:
    """Why a pair with relation ``rel`` has no separating plane (None: it has one)."""
    if rel == Relation.TANGENT:
        return "A and B are tangent: they touch, so no plane separates them strictly (contact_point gives where)"
    if rel == Relation.OVERLAP:
        return "A and B overlap: their interiors meet, so no plane separates them (contact_point gives a common point)"
    return None


def plane_exact(pairs: Pairs, i: int) -> SeparatingPlane:
    """The exact stage: pair i's plane, verified exactly."""
    plane = plane_from(pairs.contact_function(i))
    plane._pair = (pairs.a[i], pairs.b[i])
    return plane


def plane_float(pairs: Pairs, todo: np.ndarray) -> dict[int, SeparatingPlane]:
    """The float stage: float planes certified with directed rounding (vectorised)."""
    fp = pairs.floats
    assert fp is not None
    normal, offset, ok = planes(fp, todo)
    out: dict[int, SeparatingPlane] = {}
    for i in np.flatnonzero(ok):
        n = tuple(fmpq(*float(v).as_integer_ratio()) for v in normal[i])
        out[int(i)] = SeparatingPlane(n, fmpq(*float(offset[i]).as_integer_ratio()), Certifier.FLOAT, None, (pairs.a[i], pairs.b[i]))
    return out
