"""Broad phase in a tilted (triclinic) periodic box: ghost images, then the open-space grid.

The open-space broad phase (:func:`core.bodies.broadphase.candidate_pairs` with no box, handed
in by it: that function sends a tilted box here) is run on the bodies together with *ghosts*: copies of the bodies near the faces of the region the
centres occupy, moved by the lattice vectors v(k), k in {-1, 0, 1}^d, k != 0
(:func:`core.bodies.periodic.lattice_shifts`). A pair (body i, ghost of j moved by v(k)) is the
pair (i, j) with image k; pairs of two ghosts are dropped (they repeat a pair of a body and a
ghost), and (i, ghost of j, k) and (j, ghost of i, -k) are one pair.

Conservative, and why. Let body i touch the image of body j moved by v(K). Then
|c_i - (c_j + v(K))| <= r_i + r_j <= 2R (R the largest bounding radius), so along every box
vector a the fractional coordinates (c = f1 a1 + f2 a2 + f3 a3) satisfy
|f_i,a - (f_j,a + K_a + e_a)| <= 2R / h_a, where h_a is the cell's height across the faces of a
(a vector x has fractional coordinate (x . n_a) / h_a, n_a the faces' unit normal) and e the
fractional coordinates of the rounding v(K) - (K1 a1 + ...), at most :func:`shift_error` / h_a.
The centres lie in one box (:func:`core.bodies.periodic.check_box`: fractional coordinates span
at most 1) and 2R < h / 2, so |K_a| <= 1 + 1/2 + (rounding): K is in {-1, 0, 1}^d; and
f_j,a + K_a lies within delta_a = (2R + shift error) / h_a of the range [lo_a, hi_a] of the
bodies' fractional coordinates. Every ghost passing that test (with the fractional
coordinates' own error bound added, :func:`core.bodies.periodic.fractional`) is made, so the
pair meets the ghost in the open search, whose sphere test keeps it: the ghost's centre is the
float sum c_j + v(K), off by at most half an ulp per component, which its radius absorbs
(padded by 2^-50 (|c| + |v|), more than sqrt(3) half-ulps).

Cost: the ghosts are the bodies within ~2R of the faces (a few % of N for large N); the rest is
the open-space grid (levels, threads) as it is.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any

import numpy as np

from .periodic import cell_heights, fractional, lattice_shifts, shift_error

__all__ = ["tilted_pairs"]

Pairs = tuple[np.ndarray, np.ndarray, np.ndarray]

_SLACK = 1.0 + 2.0**-30
"""Widens the ghost test (roundings of delta itself)."""
_GHOST_PAD = 2.0**-50
"""Relative padding of a ghost's radius: covers the rounding of c_j + v(k) (module docstring)."""


def tilted_pairs(centers: np.ndarray, radii: np.ndarray, box: np.ndarray, open_search: Callable[[np.ndarray, np.ndarray], Any]) -> Pairs:
    """All pairs (i < j, image k of j) of valid bodies whose bounding spheres meet, in a tilted box.

    Args:
        centers: (N, d) float64 sphere centres.
        radii: (N,) float64 radii; NaN marks a body to leave out (invalid).
        box: the six numbers of a tilted box (:func:`core.bodies.periodic.read_box`); the caller
            has run :func:`core.bodies.periodic.check_box`.
        open_search: the open-space broad phase, ``open_search(centers, radii)`` with ``.i``,
            ``.j`` (:func:`core.bodies.broadphase.candidate_pairs`, which calls this module).

    Returns:
        (i, j, image): int64 i < j and the (M, d) int8 images; j is taken at c_j + v(image).

    Examples:
        >>> from core.bodies.broadphase import candidate_pairs
        >>> from core.bodies.periodic import read_box
        >>> box = read_box((10, 10, 0.5), 2)          # a2 = (5, 10): the cell is sheared
        >>> c = np.array([[1.0, 1.0], [5.5, 9.5]])    # body 1's image moved by -a2 is at (0.5, -0.5)
        >>> i, j, image = tilted_pairs(c, np.array([1.0, 1.0]), box, candidate_pairs)
        >>> i.tolist(), j.tolist(), image.tolist()
        ([0], [1], [[0, -1]])
    """
    centers = np.asarray(centers, dtype=np.float64)
    N, d = centers.shape
    valid = np.flatnonzero(np.isfinite(radii))
    if valid.size < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, d), np.int8)
    f, eps = fractional(centers[valid], box)
    lo, hi = f.min(axis=0), f.max(axis=0)
    big = float(np.max(radii[valid]))
    reach = (2 * big + shift_error(box, d)) * _SLACK
    delta = reach / cell_heights(box, d) * _SLACK + 2 * eps
    offsets = [k for k in itertools.product((-1, 0, 1), repeat=d) if any(k)]
    shifts = lattice_shifts(box, np.array(offsets, dtype=np.int64))
    pad = _GHOST_PAD * (float(np.max(np.abs(centers[valid]))) + float(np.max(np.abs(shifts))))
    ghost_rows, ghost_image, ghost_centers = [], [], []
    for k, v in zip(offsets, shifts, strict=True):
        g = f + np.array(k, dtype=np.float64)
        near = np.flatnonzero(((g >= lo - delta) & (g <= hi + delta)).all(axis=1))
        if near.size:
            ghost_rows.append(valid[near])
            ghost_image.append(np.broadcast_to(np.array(k, dtype=np.int8), (near.size, d)))
            ghost_centers.append(centers[valid[near]] + v)
    if not ghost_rows:
        plain = open_search(centers, radii)
        return plain.i, plain.j, np.zeros((plain.i.size, d), np.int8)
    rows = np.concatenate(ghost_rows)
    image = np.concatenate(ghost_image)
    all_centers = np.concatenate([centers, *ghost_centers])
    all_radii = np.concatenate([radii, radii[rows] + pad])
    found = open_search(all_centers, all_radii)
    p, q = found.i, found.j  # p < q; the ghosts come after the N bodies
    both = q < N
    mixed = (p < N) & (q >= N)
    i = np.concatenate([p[both], p[mixed]])
    j = np.concatenate([q[both], rows[q[mixed] - N]])
    img = np.concatenate([np.zeros((int(both.sum()), d), np.int8), image[q[mixed] - N]])
    keep = i != j
    i, j, img = i[keep], j[keep], img[keep]
    swap = i > j
    i, j = np.where(swap, j, i), np.where(swap, i, j)
    img = np.where(swap[:, None], -img, img).astype(np.int8)
    code = np.zeros(i.size, dtype=np.int64)
    for a in range(d):
        code = code * 3 + (img[:, a].astype(np.int64) + 1)
    key = (i * N + j) * 3**d + code
    _, first = np.unique(key, return_index=True)
    return i[first].astype(np.int64), j[first].astype(np.int64), img[first]
