"""Random bodies for the contact-search benchmark, the tests and the demo files.

:func:`random_bodies` places N ellipsoids (ellipses) uniformly at random in a cube (square) whose
size gives the requested packing fraction; overlaps are allowed (a benchmark of the contact search,
not a packing generator). Semi-axes: the largest is ``size``, the others uniform in
[size / ratio, size]; orientations uniform (random unit quaternions; angles in 2D).

Examples:
    >>> b = random_bodies(5, dim=2, seed=1)
    >>> b.centers.shape, b.semi_axes.shape, b.orientations.shape
    ((5, 2), (5, 2), (5,))
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Bodies", "random_bodies"]


@dataclass
class Bodies:
    """Parameters of N bodies and the side of their cube (square)."""

    centers: np.ndarray
    semi_axes: np.ndarray
    orientations: np.ndarray
    side: float


def random_bodies(n: int, *, fraction: float = 0.3, dim: int = 3, ratio: float = 2.0, size: float = 1.0, seed: int = 0) -> Bodies:
    """N random bodies at packing fraction ``fraction`` (sum of volumes / volume of the cube).

    Args:
        n: number of bodies.
        fraction: packing fraction (0.3: a loose liquid; overlaps allowed).
        dim: 3 (ellipsoids, quaternions) or 2 (ellipses, angles).
        ratio: largest / smallest semi-axis is at most this.
        size: the largest semi-axis of every body.
        seed: random seed.
    """
    rng = np.random.default_rng(seed)
    axes = np.empty((n, dim))
    axes[:, 0] = size
    axes[:, 1:] = rng.uniform(size / ratio, size, (n, dim - 1))
    axes = rng.permuted(axes, axis=1)
    unit = 4.0 / 3.0 * math.pi if dim == 3 else math.pi
    volume = float((unit * axes.prod(axis=1)).sum())
    side = (volume / fraction) ** (1.0 / dim)
    centers = rng.uniform(0.0, side, (n, dim))
    if dim == 3:
        q = rng.normal(size=(n, 4))
        orientations = q / np.linalg.norm(q, axis=1)[:, None]
    else:
        orientations = rng.uniform(-math.pi, math.pi, n)
    return Bodies(centers, axes, orientations, side)
