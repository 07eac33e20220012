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


def demo_bodies(*, seed: int = 7) -> Bodies:
    """A small 3D scene with every relation: a layer of touching unit-diameter spheres (tangent
    neighbours, exactly: integer centres, radius 1/2) under a loose cloud of random ellipsoids
    (some overlap each other or dip into the layer, most are separate).

    Examples:
        >>> b = demo_bodies()
        >>> len(b.centers), b.centers.shape[1]
        (244, 3)
    """
    rng = np.random.default_rng(seed)
    grid = np.array([[x, y, 0.5] for x in range(12) for y in range(12)], dtype=float)
    cloud = random_bodies(100, fraction=0.08, ratio=2.5, size=0.8, seed=seed)
    scale = 11.0 / cloud.side
    centres = np.concatenate([grid, cloud.centers * np.array([scale, scale, 0.35]) + np.array([0.0, 0.0, 0.9])])
    axes = np.concatenate([np.full((len(grid), 3), 0.5), cloud.semi_axes])
    quats = np.concatenate([np.tile([1.0, 0.0, 0.0, 0.0], (len(grid), 1)), cloud.orientations])
    del rng
    return Bodies(centres, axes, quats, 12.0)
