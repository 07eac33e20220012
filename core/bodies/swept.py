"""Swept broad phase: the pairs of moving bodies that might meet during the step t in [0, 1].

Conservative, and why (the rounding argument, as in :mod:`core.bodies.bounds`):

1. Body k at time t is the exact ellipsoid with centre c(t) = c0 + t (c1 - c0), semi-axes r and
   an exact rotation, so every point of it is within a_k = max(r) of c(t). Since
   |c(t) - m| <= |c1 - c0| / 2 for the midpoint m = (c0 + c1) / 2, the whole swept volume lies
   in the ball (m, a_k + |c1 - c0| / 2).
2. In floats: m~ = fl(fl(c0 + c1) / 2) is within U |m~| of m per coordinate (one rounding; the
   halving is exact), and the float |c1 - c0| is within (d + 3) U of the exact one; the radius
   R_k = (a_k + |fl(c1 - c0)| / 2) (1 + 2^-40) + 2^-40 |m~| + 2^-1022 (rounded up by the same
   margin; the last term for the underflow of halves and products) covers both, with room to
   spare (2^-40 >> (d + 3) U). These spheres go to the static broad
   phase (:class:`core.bodies.broadphase.BroadPhase`), which never drops a pair whose spheres
   meet; it counts the pairs it would examine before building any (:func:`swept_plan`,
   ``max_pairs``), then builds them in chunks.
3. Relative motion: bodies i and j can only meet when |d(t)| <= a_i + a_j for some t, with
   d(t) = c_j(t) + k L - c_i(t) = d0 + t e, e = d1 - d0 (a segment). A lower bound of its
   distance to the origin: the distance of the whole line, |d0 x e| / |e|, or |d0| when d0.e > 0
   (moving apart), or |d1| when d1.e < 0; the float d0, d1 are within eps = 4 U (|c0_i| + |c0_j|
   + |c1_i| + |c1_j| + |k L|) of the exact ones (per coordinate), and every float bound is
   lowered by 2^-40 of the lengths involved. Pairs whose lower bound exceeds a_i + a_j are
   dropped: exactly the pairs whose bounding spheres never meet at one same time
   (:func:`approaching`, chunk by chunk).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..moving.linear import LinearMotions
from .broadphase import BroadPhase, Candidates, TooManyPairs
from .periodic import lattice_shifts

__all__ = ["SweptSpheres", "swept_spheres", "swept_plan", "swept_pairs", "approaching"]

_U = 2.0**-52
_MARGIN = 2.0**-40
_UNDERFLOW = 2.0**-1022
"""Added to each swept radius: more than the underflow of its few roundings (each <= 2^-1075 when
a half or a product is subnormal); the smallest normal number, so bodies of size 2^-1000 keep
their own radii (an absolute 2^-1000 doubled them: 5x the candidate pairs)."""


@dataclass
class SweptSpheres:
    """Balls that hold each body during the whole step (NaN radius: invalid body)."""

    centers: np.ndarray
    """(N, d) float midpoints of the centres' paths."""
    radii: np.ndarray
    """(N,) radii: the body lies in the ball at every t in [0, 1]."""
    reach: np.ndarray
    """(N,) the largest semi-axis: the body lies within it of its centre c(t)."""


def swept_spheres(bodies: LinearMotions, valid: np.ndarray) -> SweptSpheres:
    """Certified balls around the swept volume of each body (module docstring, steps 1-2).

    Examples:
        >>> from core.moving.linear import read_linear_motions
        >>> b, _ = read_linear_motions([[0.0, 0.0]], [[2.0, 0.0]], [[1.0, 0.5]])
        >>> s = swept_spheres(b, np.array([True]))
        >>> s.centers.tolist(), bool(2.0 <= s.radii[0] <= 2.0 + 1e-9)
        ([[1.0, 0.0]], True)
    """
    c0, c1 = bodies.centers0, bodies.centers1
    with np.errstate(all="ignore"):
        m = c0 * 0.5 + c1 * 0.5  # halves first: (c0 + c1) overflows past 9e307
        half = _norm(c1 * 0.5 - c0 * 0.5)
        reach = bodies.semi_axes.max(axis=1)
        R = (reach + half) * (1 + _MARGIN) + _MARGIN * _norm(m) + _UNDERFLOW
    ok = valid & np.isfinite(R) & np.isfinite(m).all(axis=1)
    return SweptSpheres(np.where(ok[:, None], m, np.nan), np.where(ok, R, np.nan), reach)


def _norm(v: np.ndarray) -> np.ndarray:
    """|v| of each row, finite up to the float range.

    Computed at the power of 2 of the row's largest entry: an exact scaling, so the roundings are
    those of sqrt(sum v^2) wherever that does not overflow.
    """
    big = np.abs(v).max(axis=1)
    s = np.where((big > 0) & np.isfinite(big), np.ldexp(1.0, np.frexp(big)[1]), 1.0)
    out: np.ndarray = np.sqrt(((v / s[:, None]) ** 2).sum(axis=1)) * s
    return out


def swept_plan(spheres: SweptSpheres, box: np.ndarray | None, *, max_pairs: int | None = None) -> BroadPhase:
    """The static broad phase over the swept balls: its pairs counted, none built yet.

    Raises:
        TooManyPairs: it would examine more than ``max_pairs`` pairs (counted before any is
            built: a server's guard against crowded bodies).
    """
    if max_pairs is not None and (isinstance(max_pairs, bool) or not isinstance(max_pairs, int) or max_pairs < 0):
        raise ValueError(f"max_pairs must be a non-negative integer or None, got {max_pairs!r}")
    plan = BroadPhase(spheres.centers, spheres.radii, box=box)
    if max_pairs is not None and plan.pairs > max_pairs:
        raise TooManyPairs(plan.pairs, max_pairs)
    return plan


def swept_pairs(
    bodies: LinearMotions, spheres: SweptSpheres, box: np.ndarray | None, *, max_pairs: int | None = None
) -> tuple[Candidates, int]:
    """Pairs whose swept balls meet, then those whose centres come within a_i + a_j (step 3).

    Returns:
        (the candidates, i < j, with j's lattice image in a box; how many pairs the broad phase
        found before the relative-motion test).

    Raises:
        TooManyPairs: the broad phase would examine more than ``max_pairs`` pairs.
    """
    plan = swept_plan(spheres, box, max_pairs=max_pairs)
    parts: list[Candidates] = []
    found = 0
    for cand, _ in plan.chunks():
        found += len(cand)
        parts.append(approaching(bodies, spheres, cand, box))
    return Candidates.concatenate(parts, plan.d, box is not None), found


def approaching(bodies: LinearMotions, spheres: SweptSpheres, cand: Candidates, box: np.ndarray | None) -> Candidates:
    """The candidates whose centres come within a_i + a_j of each other at one same t (step 3).

    Lengths beyond 2^±200 are multiplied by a power of two per pair before they are squared
    (exact; an underflow moves a length by at most 2^-1074, within the 2^-1000 floor), so that a
    square or a squared cross product (a fourth power of lengths) past the float range cannot
    drop a pair, nor one that underflows keep every pair (bodies of size 1e-100: 12 % more).
    """
    found = len(cand)
    if not found:
        return cand
    i, j = cand.i, cand.j
    c0, c1 = bodies.centers0, bodies.centers1
    s = np.zeros((found, c0.shape[1])) if cand.image is None or box is None else lattice_shifts(box, cand.image)
    with np.errstate(all="ignore"):
        d0 = (c0[j] + s) - c0[i]
        d1 = (c1[j] + s) - c1[i]
        e = d1 - d0
        size = np.abs(c0[i]) + np.abs(c0[j]) + np.abs(c1[i]) + np.abs(c1[j]) + np.abs(s)
        reach = (spheres.reach[i] + spheres.reach[j]) * (1 + _MARGIN)
        big = np.maximum(np.maximum(np.abs(d0).max(axis=1), np.abs(d1).max(axis=1)), np.maximum(size.max(axis=1), reach))
        far = np.isfinite(big) & (big > 0) & ((big > 2.0**200) | (big < 2.0**-200))
        if far.any():  # in units of the pair's largest length
            sigma = np.where(far, np.ldexp(1.0, -np.frexp(np.where(far, big, 1.0))[1]), 1.0)
            d0, d1, e, size = d0 * sigma[:, None], d1 * sigma[:, None], e * sigma[:, None], size * sigma[:, None]
            reach = reach * sigma
        eps = 4 * _U * np.sqrt(np.einsum("ij,ij->i", size, size)) + 2.0**-1000
        n0 = np.sqrt(np.einsum("ij,ij->i", d0, d0))
        n1 = np.sqrt(np.einsum("ij,ij->i", d1, d1))
        ne = np.sqrt(np.einsum("ij,ij->i", e, e))
        if d0.shape[1] == 3:
            cx = d0[:, 1] * e[:, 2] - d0[:, 2] * e[:, 1]
            cy = d0[:, 2] * e[:, 0] - d0[:, 0] * e[:, 2]
            cz = d0[:, 0] * e[:, 1] - d0[:, 1] * e[:, 0]
            cross = np.sqrt(cx * cx + cy * cy + cz * cz)
        else:
            cross = np.abs(d0[:, 0] * e[:, 1] - d0[:, 1] * e[:, 0])
        line = np.where(ne > 0, cross / np.where(ne > 0, ne, 1.0), n0) - _MARGIN * (n0 + ne)
        tol = _MARGIN * (n0 + n1 + ne) * ne
        away0 = np.einsum("ij,ij->i", d0, e) > tol  # |d(t)| increases on [0, 1]: the minimum is |d0|
        toward1 = np.einsum("ij,ij->i", d1, e) < -tol  # decreases: the minimum is |d1|
        low = np.where(away0, n0, np.where(toward1, n1, line)) * (1 - _MARGIN) - eps
        keep = ~(low > reach)  # NaN (overflow) keeps the pair
    rows = np.flatnonzero(keep)
    return Candidates(i[rows], j[rows], None if cand.image is None else cand.image[rows])
