"""Moving bodies for the sweep benchmark and tests: random sets and exactly known first contacts.

Every set is a :class:`Motions` (float64 parameters, read exactly by :func:`core.sweep_contacts`).
Pair sets place pair k's two bodies (rows 2k, 2k + 1) far from every other pair (a spacing of
:data:`SPACING`), so only the pairs themselves can meet. The constructions with an exactly
known contact use dyadic numbers only, so the floats are the intended exact values:

* :func:`grazing_pairs`: A (semi-axes a1 > a2, a3) turns about its z axis from angle -phi0 to
  +phi1 along q(t) = (1 - t) (w, 0, 0, -s0) + t (w, 0, 0, s1); at t* = s0 / (s0 + s1) it is
  axis-aligned (q = (w, 0, 0, 0)) and its tip (a1, 0, 0) touches B, whose leftmost point is at
  (a1, 0, 0) (B: axis-aligned semi-axes, optionally turning about its own x axis, which keeps
  that point). For t != t*, A lies in {x < a1} and B in {x >= a1}: they touch exactly once
  (a "touch" event at a rational t*). Both may share a translation; the whole picture may be
  turned by a multiple of 90 degrees about a coordinate axis (exact). ``offset``: B moved
  outward by ``offset`` (> 0: a near miss by that gap, never touching; < 0: a shallow overlap
  around t*).
* :func:`start_pairs`: the same with s0 = 0: tangent at t = 0, then apart (t* = 0, tangent).

Examples:
    >>> m = grazing_pairs(3, seed=1)
    >>> m.centers0.shape, m.orientations1.shape
    ((6, 3), (6, 4))
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from bench.bodies_data import random_bodies
from core.shapes.rotation import rotation_numerator

__all__ = ["Motions", "SPACING", "random_pairs", "grazing_pairs", "start_pairs", "moving_bodies", "concat"]

SPACING = 64.0
"""Distance between consecutive pairs of a pair set (far beyond any body's reach)."""


@dataclass
class Motions:
    """Parameters of N moving bodies (as :func:`core.sweep_contacts` takes them)."""

    centers0: np.ndarray
    centers1: np.ndarray
    semi_axes: np.ndarray
    orientations0: np.ndarray
    orientations1: np.ndarray | None
    t_exact: list[Fraction | None] | None = None
    """Pair sets with a known answer: t* of pair k (None: never meets); None: not known."""

    def arguments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        """(centers0, centers1, semi_axes, orientations0, orientations1)."""
        return self.centers0, self.centers1, self.semi_axes, self.orientations0, self.orientations1


def _spread(c: np.ndarray) -> np.ndarray:
    """Offsets (k * SPACING, 0, ...) for the pairs, repeated for both bodies of a pair."""
    k = np.arange(c.shape[0]) // 2
    out = np.zeros_like(c)
    out[:, 0] = k * SPACING
    return out


def random_pairs(M: int, *, dim: int = 3, rotate: bool = False, seed: int = 0) -> Motions:
    """M pairs of random bodies that often meet (start ~1.2 apart, moving ~0.8 each).

    Semi-axes in [0.3, 1]; orientations random; with ``rotate`` a second random orientation
    (3D: q1 on q0's side, q0.q1 >= 0; 2D: angle turned by up to 2 radians).
    """
    rng = np.random.default_rng(seed)
    N = 2 * M
    c0 = rng.normal(size=(N, dim))
    c0[1::2] = c0[0::2] + rng.normal(size=(M, dim)) * 1.2
    c1 = c0 + rng.normal(size=(N, dim)) * 0.8
    r = rng.uniform(0.3, 1.0, (N, dim))
    if dim == 3:
        q0 = rng.normal(size=(N, 4))
        q1 = rng.normal(size=(N, 4)) if rotate else None
        if q1 is not None:
            q1 = np.where((q0 * q1).sum(axis=1)[:, None] < 0, -q1, q1)
    else:
        q0 = rng.uniform(-math.pi, math.pi, N)
        q1 = q0 + rng.uniform(-2.0, 2.0, N) if rotate else None
    off = _spread(c0)
    return Motions(c0 + off, c1 + off, r, q0, q1)


def _dyadic(rng: np.random.Generator, lo: float, hi: float, bits: int = 6) -> float:
    """A random multiple of 2^-bits in [lo, hi]."""
    return float(rng.integers(int(math.ceil(lo * 2**bits)), int(math.floor(hi * 2**bits)) + 1)) / 2**bits


def _qmul(p: tuple[float, ...], q: tuple[float, ...]) -> tuple[float, float, float, float]:
    """Hamilton product (wxyz); exact for the small dyadic numbers used here."""
    a1, b1, c1, d1 = p
    a2, b2, c2, d2 = q
    return (
        a1 * a2 - b1 * b2 - c1 * c2 - d1 * d2,
        a1 * b2 + b1 * a2 + c1 * d2 - d1 * c2,
        a1 * c2 - b1 * d2 + c1 * a2 + d1 * b2,
        a1 * d2 + b1 * c2 - c1 * b2 + d1 * a2,
    )


_TURNS = [(1.0, 0.0, 0.0, 0.0), (1.0, 1.0, 0.0, 0.0), (1.0, 0.0, 1.0, 0.0), (1.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 1.0), (1.0, -1.0, 0.0, 0.0)]
"""Quarter and half turns about coordinate axes (unnormalised quaternions: exact rotations)."""


def _turn(q: tuple[float, ...], v: tuple[float, float, float]) -> tuple[float, float, float]:
    """v rotated by the quarter/half turn q (one of _TURNS): entries 0, +-1 after division by |q|^2."""
    R, n = rotation_numerator(q)
    return tuple(sum(R[i][k] / n * v[k] for k in range(3)) for i in range(3))  # type: ignore[return-value]


def grazing_pairs(M: int, *, dim: int = 3, offset: float = 0.0, start: bool = False, seed: int = 0) -> Motions:
    """M pairs that touch exactly once, at a known rational t* (module docstring).

    Args:
        M: pairs.
        dim: 3 or 2.
        offset: B moved outward by this much (exact float): > 0 a near miss, < 0 a shallow overlap.
        start: t* = 0 (s0 = 0): tangent at the start, then apart.
        seed: random seed.
    """
    rng = np.random.default_rng(seed)
    c0, c1, r, q0, q1, truth = [], [], [], [], [], []
    for k in range(M):
        a1 = _dyadic(rng, 0.75, 1.0)
        a_rest = [_dyadic(rng, 0.3, a1 - 1 / 16) for _ in range(dim - 1)]
        b = [_dyadic(rng, 0.3, 1.0) for _ in range(dim)]
        w = _dyadic(rng, 0.5, 1.0)
        s0 = 0.0 if start else _dyadic(rng, 1 / 16, 0.75)
        s1 = _dyadic(rng, 1 / 16, 0.75)
        t_star = Fraction(s0) / (Fraction(s0) + Fraction(s1))
        v = [_dyadic(rng, -1.0, 1.0, 4) for _ in range(dim)]  # a common translation
        base = [k * SPACING] + [0.0] * (dim - 1)
        cA = list(base)
        cB = [base[0] + a1 + b[0] + offset] + base[1:]
        if dim == 3:
            qa0, qa1 = (w, 0.0, 0.0, -s0), (w, 0.0, 0.0, s1)
            wb, xb0, xb1 = _dyadic(rng, 0.5, 1.0), _dyadic(rng, -0.5, 0.5), _dyadic(rng, -0.5, 0.5)
            qb0, qb1 = (wb, xb0, 0.0, 0.0), (wb, xb1, 0.0, 0.0)
            g = _TURNS[int(rng.integers(len(_TURNS)))]
            # the whole picture turned by g about pair k's first body: centres and orientations
            rel = _turn(g, (a1 + b[0] + offset, 0.0, 0.0))
            cB = [base[0] + rel[0], rel[1], rel[2]]
            qa0, qa1, qb0, qb1 = (_qmul(g, q) for q in (qa0, qa1, qb0, qb1))
            q0 += [qa0, qb0]
            q1 += [qa1, qb1]
        else:
            q0 += [(w, -s0), (1.0, 0.0)]
            q1 += [(w, s1), (1.0, 0.0)]
        c0 += [cA, cB]
        c1 += [[x + dv for x, dv in zip(cA, v, strict=True)], [x + dv for x, dv in zip(cB, v, strict=True)]]
        r += [[a1] + a_rest, b]
        truth.append(None if offset > 0 else t_star)
    Q0, Q1 = np.array(q0, dtype=float), np.array(q1, dtype=float)
    if dim == 2:  # half-angle numbers (w, s) as quaternions (w, 0, 0, s)
        Q0 = np.stack([Q0[:, 0], 0 * Q0[:, 0], 0 * Q0[:, 0], Q0[:, 1]], axis=1)
        Q1 = np.stack([Q1[:, 0], 0 * Q1[:, 0], 0 * Q1[:, 0], Q1[:, 1]], axis=1)
    return Motions(np.array(c0), np.array(c1), np.array(r), Q0, Q1, truth if offset >= 0 else None)


def start_pairs(M: int, *, dim: int = 3, seed: int = 0) -> Motions:
    """M pairs tangent at t = 0 and separate after (t* = 0, relation tangent)."""
    return grazing_pairs(M, dim=dim, start=True, seed=seed)


def moving_bodies(n: int, *, fraction: float = 0.3, dim: int = 3, rotate: bool = True, seed: int = 0) -> Motions:
    """N random bodies (:func:`bench.bodies_data.random_bodies`: packing fraction, axis ratio <= 2,
    largest semi-axis 1) each moving by up to its own size (its largest semi-axis) in a random
    direction; with ``rotate`` each turns to an independent random orientation (3D: q1 on q0's
    side; 2D: by up to pi)."""
    b = random_bodies(n, fraction=fraction, dim=dim, seed=seed)
    rng = np.random.default_rng(seed + 1)
    v = rng.normal(size=(n, dim))
    v /= np.linalg.norm(v, axis=1)[:, None]
    c1 = b.centers + v * (rng.uniform(0.0, 1.0, n) * b.semi_axes.max(axis=1))[:, None]
    q1 = None
    if rotate:
        if dim == 3:
            q1 = rng.normal(size=(n, 4))
            q1 /= np.linalg.norm(q1, axis=1)[:, None]
            q1 = np.where((q1 * b.orientations).sum(axis=1)[:, None] < 0, -q1, q1)
        else:
            q1 = b.orientations + rng.uniform(-math.pi, math.pi, n)
    return Motions(b.centers, c1, b.semi_axes, b.orientations, q1)


def concat(*sets: Motions) -> Motions:
    """One set of all bodies (pair sets are moved apart along y so they stay independent)."""
    parts = []
    for k, m in enumerate(sets):
        shift = np.zeros(m.centers0.shape[1])
        shift[1] = 4 * SPACING * k
        o0 = m.orientations0
        o1 = m.orientations1 if m.orientations1 is not None else m.orientations0
        parts.append((m.centers0 + shift, m.centers1 + shift, m.semi_axes, o0, o1))
    return Motions(*(np.concatenate([p[n] for p in parts]) for n in range(5)))
