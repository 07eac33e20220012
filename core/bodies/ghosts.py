"""Broad phase in a tilted (triclinic) periodic box: ghost images, then the open-space grid.

:class:`core.bodies.broadphase.BroadPhase` given a tilted box searches, in open space, the
bodies together with *ghosts*: copies of the bodies near the faces of the region the centres
occupy, moved by the lattice vectors v(k), k in {-1, 0, 1}^d, k != 0
(:func:`core.bodies.periodic.lattice_shifts`). A pair (body i, ghost of j moved by v(k)) is the
pair (i, j) with image k (:meth:`Ghosts.resolve`); a pair of two ghosts is dropped, and so is a
pair (i, ghost of j) with i > j: it is the mirror of (j, ghost of i moved by v(-k)), which the
search also meets (below), so each pair is kept once, chunk by chunk, with no global sort.

Conservative, and why. Let body i touch the image of body j moved by v(K). Then
|c_i - (c_j + v(K))| <= r_i + r_j <= 2R (R the largest bounding radius), so along every box
vector a the fractional coordinates (c = f1 a1 + f2 a2 + f3 a3) satisfy
|f_i,a - (f_j,a + K_a + e_a)| <= 2R / h_a, where h_a is the cell's height across the faces of a
(a vector x has fractional coordinate (x . n_a) / h_a, n_a the faces' unit normal) and e the
fractional coordinates of the rounding v(K) - (K1 a1 + ...), at most
:func:`core.bodies.periodic.shift_error` / h_a. The centres lie in one box
(:func:`core.bodies.periodic.check_box`: fractional coordinates span at most 1) and
2R < h / 2, so |K_a| <= 1 + 1/2 + (rounding): K is in {-1, 0, 1}^d; and f_j,a + K_a lies
within delta_a = (2R + shift error) / h_a of the range [lo_a, hi_a] of the bodies' fractional
coordinates. Every ghost passing that test (with the fractional coordinates' own error bound
added, :func:`core.bodies.periodic.fractional`) is made, so the pair meets the ghost in the open
search, whose sphere test keeps it: the ghost's centre is the float sum c_j + v(K), off by at
most half an ulp per component, which its radius absorbs (padded by 2^-50 (|c| + |v|), more
than sqrt(3) half-ulps). The same holds with i and j exchanged and -K (v(-K) = -v(K) exactly:
rounding to nearest is symmetric), so the mirror form is met too and dropping one is safe.

Cost: the ghosts are the bodies within ~2R of the faces (a few % of N for large N); the rest is
the open-space grid (levels, threads, counting and chunks) as it is.
"""

from __future__ import annotations

import itertools

import numpy as np

from .periodic import cell_heights, fractional, lattice_shifts, shift_error

__all__ = ["Ghosts"]

_SLACK = 1.0 + 2.0**-30
"""Widens the ghost test (roundings of delta itself)."""
_GHOST_PAD = 2.0**-50
"""Relative padding of a ghost's radius: covers the rounding of c_j + v(k) (module docstring)."""


class Ghosts:
    """The bodies of a tilted box and their ghosts near the faces, as one open-space set.

    Args:
        centers: (N, d) float64 sphere centres.
        radii: (N,) float64 radii; NaN marks a body to leave out (invalid).
        box: the six numbers of a tilted box (:func:`core.bodies.periodic.read_box`); the caller
            has run :func:`core.bodies.periodic.check_box`.

    Examples:
        >>> from core.bodies.broadphase import candidate_pairs
        >>> from core.bodies.periodic import read_box
        >>> box = read_box((10, 10, 0.5), 2)          # a2 = (5, 10): the cell is sheared
        >>> c = np.array([[1.0, 1.0], [5.5, 9.5]])    # body 1's image moved by -a2 is at (0.5, -0.5)
        >>> g = Ghosts(c, np.array([1.0, 1.0]), box)
        >>> len(g.centers) > 2                        # the two bodies, then their ghosts
        True
        >>> p = candidate_pairs(c, np.array([1.0, 1.0]), box=box)
        >>> p.i.tolist(), p.j.tolist(), p.image.tolist()
        ([0], [1], [[0, -1]])
    """

    def __init__(self, centers: np.ndarray, radii: np.ndarray, box: np.ndarray) -> None:
        centers = np.asarray(centers, dtype=np.float64)
        N, d = centers.shape
        self.n = N
        """Bodies (the first n rows of :attr:`centers`); the ghosts follow."""
        self.rows = np.zeros(0, np.int64)
        """The body each ghost copies."""
        self.image = np.zeros((0, d), np.int8)
        """The image k of each ghost: it stands at c + v(k)."""
        self.centers = centers
        self.radii = np.asarray(radii, dtype=np.float64)
        valid = np.flatnonzero(np.isfinite(radii))
        if valid.size < 2:
            return
        f, eps = fractional(centers[valid], box)
        lo, hi = f.min(axis=0), f.max(axis=0)
        big = float(np.max(radii[valid]))
        reach = (2 * big + shift_error(box, d)) * _SLACK
        delta = reach / cell_heights(box, d) * _SLACK + 2 * eps
        offsets = [k for k in itertools.product((-1, 0, 1), repeat=d) if any(k)]
        shifts = lattice_shifts(box, np.array(offsets, dtype=np.int64))
        pad = _GHOST_PAD * (float(np.max(np.abs(centers[valid]))) + float(np.max(np.abs(shifts))))
        rows, image, moved = [], [], []
        for k, v in zip(offsets, shifts, strict=True):
            g = f + np.array(k, dtype=np.float64)
            near = np.flatnonzero(((g >= lo - delta) & (g <= hi + delta)).all(axis=1))
            if near.size:
                rows.append(valid[near])
                image.append(np.broadcast_to(np.array(k, dtype=np.int8), (near.size, d)))
                moved.append(centers[valid[near]] + v)
        if rows:
            self.rows = np.concatenate(rows)
            self.image = np.concatenate(image)
            self.centers = np.concatenate([centers, *moved])
            self.radii = np.concatenate([self.radii, self.radii[self.rows] + pad])

    def resolve(self, p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pairs p < q of the open-space set as pairs of bodies: (i < j, image k of j).

        Two bodies: image 0. A body p and a ghost of j (image k): kept when p < j (its mirror,
        body j and the ghost of p, image -k, is kept instead when j < p); a body and its own
        ghost, and two ghosts, are dropped (module docstring).
        """
        d = self.image.shape[1]
        both = q < self.n
        mixed = np.flatnonzero((p < self.n) & (q >= self.n))
        j = self.rows[q[mixed] - self.n]
        keep = mixed[p[mixed] < j]
        j = self.rows[q[keep] - self.n]
        i = np.concatenate([p[both], p[keep]])
        j = np.concatenate([q[both], j])
        image = np.concatenate([np.zeros((int(np.count_nonzero(both)), d), np.int8), self.image[q[keep] - self.n]])
        return i.astype(np.int64), j.astype(np.int64), image
