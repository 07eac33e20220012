"""Trajectories of hard bodies for the audit benchmark: a dense packing that moves, and a tangent lattice.

:func:`fcc_trajectory`: nearly aligned ellipsoids at the sites of a stretched face-centred cubic
lattice in a periodic box (packing fraction 0.5), each frame jittered around its site and turned
a little, the whole packing drifting so that bodies cross the box's faces between frames; frames
are wrapped, as a simulation stores them. No pair overlaps, yet many bounding spheres meet.

:func:`touching_pairs`: pairs of axis-aligned ellipsoids of different shapes touching exactly, a
fraction of them moved by +-2^-40 (overlaps and gaps of ~1e-12): the contacts a float overlap check
cannot settle. Their true relations are known by construction (:attr:`TouchingPairs.truth`).

Examples:
    >>> t = fcc_trajectory((2, 2, 2), frames=2, seed=1)
    >>> len(t.centers), t.centers[0].shape, t.semi_axes.shape, round(t.fraction, 6)
    (2, (32, 3), (32, 3), 0.5)
    >>> pairs = touching_pairs(50, seed=0)
    >>> pairs.centers.shape, sorted(set(pairs.truth.values()))
    ((100, 3), ['overlap', 'tangent'])
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["FCC_AXES", "Trajectory", "fcc_trajectory", "write_gsd", "TouchingPairs", "touching_pairs"]

FCC_AXES = (1.0, 0.88, 0.8)
"""Semi-axes of every ellipsoid of :func:`fcc_trajectory` (the largest is 1)."""


@dataclass
class Trajectory:
    """Frames of N rigid bodies in one periodic box (wrapped positions)."""

    centers: list[np.ndarray]
    """Per frame, (N, 3) float64 centres wrapped into [-L/2, L/2)."""
    orientations: list[np.ndarray]
    """Per frame, (N, 4) unit quaternions wxyz."""
    semi_axes: np.ndarray
    """(N, 3), the same in every frame."""
    box: tuple[float, float, float]
    """Sides of the orthogonal periodic box."""

    @property
    def fraction(self) -> float:
        """Packing fraction: the bodies' volume over the box's."""
        return float((4 / 3 * math.pi * self.semi_axes.prod(axis=1)).sum() / np.prod(self.box))


def fcc_trajectory(cells: tuple[int, int, int], frames: int, *, fraction: float = 0.5, jitter: float = 0.04,
                   turn: float = 0.03, drift: float = 0.37, seed: int = 0) -> Trajectory:
    """Nearly aligned ellipsoids on a stretched FCC lattice over ``frames`` frames (module docstring).

    The packing is the image of an FCC packing of spheres of radius 1 under the map
    diag(:data:`FCC_AXES`): aligned ellipsoids that never overlap when the spheres do not, at the
    spheres' packing fraction ``fraction`` (the map keeps volume ratios). Each frame every body is
    jittered (at most ``jitter`` in the spheres' space) and turned by a random rotation of at most
    ``turn`` radians about a random axis; the lattice leaves gaps of about 0.28 between the spheres
    at fraction 0.5, far more than the jitter and the turns take, so no pair overlaps, while many
    bounding spheres (radius 1) meet: a dense candidate set, as in a real hard-particle fluid.

    Args:
        cells: unit cells along x, y, z (4 bodies each: 100,000 bodies = (25, 40, 25)).
        frames: how many frames.
        fraction: packing fraction (at most FCC's 0.7405).
        jitter: each centre lies within this distance (spheres' space) of its drifting site.
        turn: largest rotation angle per frame, radians.
        drift: how far the whole packing moves along (1, 0.5, 0.25) per frame (wrapped).
        seed: random seed.
    """
    rng = np.random.default_rng(seed)
    a = 2 * math.sqrt(2.0) * (0.7404804896930609 / fraction) ** (1 / 3)  # the spheres' lattice constant
    basis = np.array([[0, 0, 0], [0, 0.5, 0.5], [0.5, 0, 0.5], [0.5, 0.5, 0]])
    grid = np.stack(np.meshgrid(*(np.arange(c) for c in cells), indexing="ij"), axis=-1).reshape(-1, 1, 3)
    axes3 = np.array(FCC_AXES)
    sites = ((grid + basis[None]) * a).reshape(-1, 3)
    box = tuple(float(c * a * s) for c, s in zip(cells, axes3, strict=True))
    L = np.array(box)
    n = len(sites)
    direction = np.array([1.0, 0.5, 0.25])
    centers, orientations = [], []
    for k in range(frames):
        u = rng.normal(size=(n, 3))
        u *= (jitter * rng.uniform(0, 1, n) ** (1 / 3) / np.linalg.norm(u, axis=1))[:, None]
        c = (sites + u) * axes3 + k * drift * direction
        centers.append(c - L * np.floor(c / L + 0.5))  # wrapped into [-L/2, L/2)
        axis = rng.normal(size=(n, 3))
        axis /= np.linalg.norm(axis, axis=1)[:, None]
        half = rng.uniform(0, turn / 2, n)
        orientations.append(np.concatenate([np.cos(half)[:, None], np.sin(half)[:, None] * axis], axis=1))
    return Trajectory(centers, orientations, np.tile(axes3, (n, 1)), box)  # type: ignore[arg-type]


def write_gsd(path: str, traj: Trajectory) -> None:
    """Write the trajectory as a HOOMD GSD file (one Ellipsoid type; float32, as HOOMD stores it).

    The float32 positions keep the bodies apart: they move each centre by at most 2^-20 of the box,
    far less than the gaps the lattice leaves.
    """
    import gsd.hoomd

    a, b, c = FCC_AXES
    with gsd.hoomd.open(path, "w") as f:
        for k in range(len(traj.centers)):
            frame = gsd.hoomd.Frame()
            frame.configuration.step = k
            frame.configuration.box = [*traj.box, 0.0, 0.0, 0.0]
            frame.particles.N = len(traj.semi_axes)
            frame.particles.types = ["E"]
            frame.particles.typeid = np.zeros(frame.particles.N, dtype=np.uint32)
            frame.particles.type_shapes = [{"type": "Ellipsoid", "a": a, "b": b, "c": c}]
            frame.particles.position = traj.centers[k].astype(np.float32)
            frame.particles.orientation = traj.orientations[k].astype(np.float32)
            f.append(frame)


@dataclass
class TouchingPairs:
    """Pairs of bodies whose true relations are known by construction."""

    centers: np.ndarray
    """(2m, 3) centres: body 2k and body 2k + 1 form pair k."""
    semi_axes: np.ndarray
    """(2m, 3) semi-axes (powers of two: every float matrix is exact)."""
    truth: dict[tuple[int, int], str]
    """(2k, 2k + 1) -> "tangent" or "overlap" (the separate pairs are absent)."""


def touching_pairs(m: int, *, planted: float = 0.25, offset: float = 2.0**-40, seed: int = 0) -> TouchingPairs:
    """m pairs of axis-aligned ellipsoids touching exactly along x, a fraction moved by +-``offset``.

    Semi-axes are powers of two between 1/8 and 4; body 2k + 1 stands at x = a_x + b_x from body 2k
    (every coordinate a float exactly): the plane x = a_x separates them and both touch it at one
    point (tangent). A fraction ``planted`` of the pairs is moved by -offset
    (overlap by ``offset``) or +offset (a gap of ``offset``: separate). Pairs stand 40 apart.
    """
    rng = np.random.default_rng(seed)
    a = 2.0 ** rng.integers(-3, 3, (m, 3)).astype(np.float64)
    b = 2.0 ** rng.integers(-3, 3, (m, 3)).astype(np.float64)
    side = int(math.ceil(m ** (1 / 3)))
    grid = np.stack(np.meshgrid(*(np.arange(side),) * 3, indexing="ij"), axis=-1).reshape(-1, 3)[:m] * 40.0
    shift = np.zeros(m)
    moved = rng.uniform(size=m) < planted
    shift[moved] = np.where(rng.uniform(size=int(moved.sum())) < 0.5, -offset, offset)
    second = grid.copy()
    second[:, 0] += a[:, 0] + b[:, 0] + shift
    centers = np.empty((2 * m, 3))
    centers[0::2], centers[1::2] = grid, second
    axes = np.empty((2 * m, 3))
    axes[0::2], axes[1::2] = a, b
    truth = {(2 * k, 2 * k + 1): ("tangent" if shift[k] == 0 else "overlap") for k in range(m) if shift[k] <= 0}
    return TouchingPairs(centers, axes, truth)
