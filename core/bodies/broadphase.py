"""Broad phase: every pair of bodies that might touch, from uniform grids over bounding spheres.

Conservative, and why (what bounds what):

1. Each valid body lies in its certified bounding sphere (c_k, rho_k) (:mod:`core.bodies.bounds`).
   Two bodies that share a point x therefore satisfy |c_i - c_j| <= |c_i - x| + |x - c_j|
   <= rho_i + rho_j (in a periodic box: for the image of j that contains x).
2. Size classes ("levels"): level l holds the bodies with rho in (R / 2^(l+1), R / 2^l], R the
   largest radius; its grid has cells of side h_l >= 2 * (largest rho of level l) * (1 + 2^-20).
   A pair is looked for in the grid of its *larger* body's level, where both radii are at most
   h_l / 2 / (1 + 2^-20): so |c_i - c_j| < h_l / (1 + 2^-20) on every axis.
3. Cell coordinates floor((c - lo) / h) are computed in floats: each of c - lo and the division
   rounds once (relative 2^-53), so with at most 2^30 cells per axis (the cell side is enlarged
   if needed) the computed coordinates of two centres less than h / (1 + 2^-20) apart differ by
   at most 1: their cells are neighbours (in a periodic box, neighbours modulo the cell count).
4. All pairs in neighbouring cells are enumerated (each unordered pair once), then kept when
   |d|^2 <= (rho_i + rho_j + pad)^2, d the float difference of the centres (minimum image in a
   box). Computing d and the squares rounds by far less than pad = 2^-40 * (largest |centre|
   coordinate + box side + R), so no pair with |c_i - c_j| <= rho_i + rho_j is ever dropped.

Work: sorting the cell keys (numpy), then per occupied cell its 13 "forward" neighbour cells
(or all 26 plus an index test when a periodic axis has fewer than 3 cells), expanded to pairs in
chunks of a few million; O(N) pairs for bodies of similar size at any density.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial

import numpy as np

from ..fixed.compiled import get_threads

__all__ = ["Candidates", "candidate_pairs", "LEVEL_RATIO"]

LEVEL_RATIO = 2.0
"""Radii within one level differ by at most this factor (a level's cells are 2 x its largest)."""
_CELL_SLACK = 1.0 + 2.0**-20
_MAX_CELLS = 2**30
"""Most cells per axis: keeps the float cell coordinates exact to well under one cell."""
_PAD = 2.0**-40
_PAIRS_PER_CHUNK = 1 << 22
"""Pairs expanded at once before the sphere test (bounded memory: ~100 MB of temporaries)."""


@dataclass
class Candidates:
    """Pairs of bodies whose bounding spheres meet (the only pairs that can touch)."""

    i: np.ndarray
    """int64 body indices, i < j."""
    j: np.ndarray
    """int64 body indices."""
    image: np.ndarray | None
    """(M, d) int8 lattice image of j in a periodic box: j is taken at c_j + image * L (the
    minimum image); None in open space."""

    def __len__(self) -> int:
        return int(self.i.size)


@dataclass
class _Grid:
    """Cell keys of a set of bodies, sorted, with the occupied cells and their ranges."""

    lo: np.ndarray
    h: np.ndarray
    """Cell side per axis."""
    n: np.ndarray
    """Cells per axis (key radix)."""
    periodic: bool
    order: np.ndarray
    """Body indices sorted by cell key."""
    keys: np.ndarray
    """Occupied cell keys, sorted (unique)."""
    start: np.ndarray
    count: np.ndarray
    coords: np.ndarray
    """(cells, d) integer coordinates of the occupied cells."""


def candidate_pairs(
    centers: np.ndarray,
    radii: np.ndarray,
    *,
    box: np.ndarray | None = None,
) -> Candidates:
    """All pairs (i < j) of valid bodies whose bounding spheres meet (conservative).

    Args:
        centers: (N, d) float64 sphere centres.
        radii: (N,) float64 radii; NaN marks a body to leave out (invalid).
        box: periodic box sides (d,), or None for open space (a tilted box, the six numbers of
            :func:`core.bodies.periodic.read_box`, goes to :mod:`core.bodies.ghosts`). The caller has checked
            (:mod:`core.bodies.periodic`) that the centres span at most one box side per axis and
            that the two largest radii sum to less than half the smallest side (so the minimum
            image is the only image that can touch).

    Returns:
        :class:`Candidates`, in no particular order.

    Examples:
        >>> c = np.array([[0.0, 0.0], [1.9, 0.0], [5.0, 0.0]])
        >>> p = candidate_pairs(c, np.array([1.0, 1.0, 1.0]))
        >>> p.i.tolist(), p.j.tolist()
        ([0], [1])
        >>> q = candidate_pairs(c, np.array([1.0, 1.0, 1.0]), box=np.array([6.0, 6.0]))
        >>> sorted(zip(q.i.tolist(), q.j.tolist(), q.image.tolist()))
        [(0, 1, [0, 0]), (0, 2, [-1, 0])]
    """
    centers = np.asarray(centers, dtype=np.float64)
    N, d = centers.shape
    if box is not None and box.size != d:  # a tilted box (its six numbers): ghost images, then open space
        from .ghosts import tilted_pairs

        return Candidates(*tilted_pairs(centers, radii, box, candidate_pairs))
    valid = np.flatnonzero(np.isfinite(radii))
    tasks: list[Callable[[], list[tuple[np.ndarray, ...]]]] = []
    if valid.size >= 2:
        big = float(np.max(radii[valid]))
        span = float(np.max(np.abs(centers[valid]))) + (float(np.max(box)) if box is not None else 0.0)
        pad = _PAD * (span + big)
        levels = _levels(radii, valid, big)
        lo, hi = centers[valid].min(axis=0), centers[valid].max(axis=0)
        for a, members in enumerate(levels):
            grid = _grid(centers, members, 2 * float(np.max(radii[members])) * _CELL_SLACK, lo, hi, box)
            # positions in the grid's cell order: neighbouring cells are near in memory
            mine = _Side(grid.order, centers[grid.order], radii[grid.order])
            half = not grid.periodic or bool((grid.n >= 3).all())
            for off in [(0,) * d] + [o for o in _offsets(grid, half) if any(o)]:
                tasks.append(partial(_run, _same_level(grid, off, half), mine, mine, box, pad))
            for finer in levels[a + 1 :]:
                coords = _coords(centers[finer], grid.lo, grid.h, grid.n, grid.periodic)
                o = np.argsort(_encode(coords, grid.n), kind="stable")
                theirs = _Side(finer[o], centers[finer[o]], radii[finer[o]])
                for off in _offsets(grid, half=False):
                    tasks.append(partial(_run, _query(grid, coords[o], off), theirs, mine, box, pad))
    threads = min(get_threads(), len(tasks))
    if threads > 1:  # numpy releases the GIL inside each operation: offsets run side by side
        with ThreadPoolExecutor(threads, thread_name_prefix="broadphase") as pool:
            parts = [part for result in pool.map(lambda task: task(), tasks) for part in result]
    else:
        parts = [part for task in tasks for part in task()]
    i = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, np.int64)
    j = np.concatenate([p[1] for p in parts]) if parts else np.zeros(0, np.int64)
    if box is None:
        return Candidates(i, j, None)
    k = np.concatenate([p[2] for p in parts]) if parts else np.zeros((0, d), np.int8)
    return Candidates(i, j, k)


def _levels(radii: np.ndarray, valid: np.ndarray, big: float) -> list[np.ndarray]:
    """Valid bodies grouped by size class, largest first (level l: rho in (R/2^(l+1), R/2^l])."""
    r = radii[valid]
    small = float(np.min(r))
    if big <= LEVEL_RATIO * small or small <= 0:
        return [valid]
    with np.errstate(divide="ignore"):
        lev = np.floor(np.log2(big / r) / math.log2(LEVEL_RATIO)).astype(np.int64)
    lev = np.clip(lev, 0, 60)
    return [valid[lev == v] for v in np.unique(lev)]


def _grid(
    centers: np.ndarray, members: np.ndarray, h: float, lo: np.ndarray, hi: np.ndarray, box: np.ndarray | None
) -> _Grid:
    """The grid of one level: cells of side >= h (per axis) over [lo, hi] (all levels), keys sorted."""
    d = centers.shape[1]
    if box is None:
        ext = np.maximum(hi - lo, 0.0)
        h_axis = np.maximum(np.full(d, h), ext / _MAX_CELLS)
        origin = lo - h_axis  # coordinates start at 1: a neighbour at -1 stays >= 0
        n = np.floor(ext / h_axis).astype(np.int64) + 3
        periodic = False
    else:
        n = np.maximum(np.floor(box / h), 1).astype(np.int64)
        n = np.minimum(n, _MAX_CELLS)
        h_axis = box / n
        origin = lo
        periodic = True
    coords = _coords(centers[members], origin, h_axis, n, periodic)
    keys = _encode(coords, n)
    o = np.argsort(keys, kind="stable")
    sk = keys[o]
    first = np.flatnonzero(np.r_[True, sk[1:] != sk[:-1]])
    count = np.diff(np.r_[first, sk.size])
    return _Grid(origin, h_axis, n, periodic, members[o], sk[first], first, count, coords[o][first])


def _coords(c: np.ndarray, origin: np.ndarray, h: np.ndarray, n: np.ndarray, periodic: bool) -> np.ndarray:
    x = np.floor((c - origin) / h).astype(np.int64)
    return np.clip(x, 0, n - 1) if periodic else x


def _encode(coords: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Mixed-radix key of integer cell coordinates (each in [0, n_a))."""
    if float(np.prod(n.astype(float))) >= 2.0**62:
        raise ValueError(
            "the bodies are spread too thinly for one grid (more than 2^62 cells): "
            "split the set into clusters"
        )
    key = coords[:, 0].copy()
    for a in range(1, coords.shape[1]):
        key = key * n[a] + coords[:, a]
    return key


def _offsets(grid: _Grid, half: bool) -> list[tuple[int, ...]]:
    """Neighbour offsets: distinct modulo the cell counts (periodic), or the 13 forward ones."""
    d = grid.n.size
    per_axis = []
    for a in range(d):
        choices: tuple[int, ...] = (-1, 0, 1)
        if grid.periodic and grid.n[a] < 3:
            choices = (0, 1) if grid.n[a] == 2 else (0,)
        per_axis.append(choices)
    all_off = [o for o in itertools.product(*per_axis)]
    if half:
        return [o for o in all_off if o > (0,) * d]  # lexicographically positive
    return all_off


def _neighbour_keys(grid: _Grid, coords: np.ndarray, off: tuple[int, ...]) -> np.ndarray:
    x = coords + np.array(off, dtype=np.int64)
    if grid.periodic:
        x %= grid.n
    return _encode(x, grid.n)


def _same_level(grid: _Grid, off: tuple[int, ...], half: bool) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Position pairs between each occupied cell and its neighbour at ``off``.

    Each unordered pair of bodies comes once over all offsets; ``off`` = 0 gives the pairs
    p < q inside a cell.
    """
    if not any(off):
        multi = np.flatnonzero(grid.count >= 2)
        yield from _expand(grid.start[multi], grid.count[multi], grid.start[multi], grid.count[multi], upper=True)
        return
    nk = _neighbour_keys(grid, grid.coords, off)
    pos = np.minimum(np.searchsorted(grid.keys, nk), grid.keys.size - 1)
    hit = np.flatnonzero(grid.keys[pos] == nk)
    b = pos[hit]
    for p, q in _expand(grid.start[hit], grid.count[hit], grid.start[b], grid.count[b]):
        if half:
            yield p, q
        else:  # full shell: the pair is met from both cells; keep it once
            keep = grid.order[p] < grid.order[q]
            yield p[keep], q[keep]


def _query(grid: _Grid, coords: np.ndarray, off: tuple[int, ...]) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Pairs (position of a finer body, position in this grid) in neighbouring cells.

    The finer body's cell (``coords``: its coordinates in this grid) and the grid's cell at
    ``off`` from it.
    """
    nk = _neighbour_keys(grid, coords, off)
    pos = np.minimum(np.searchsorted(grid.keys, nk), grid.keys.size - 1)
    hit = np.flatnonzero(grid.keys[pos] == nk)
    b = pos[hit]
    yield from _expand(hit, np.ones(hit.size, dtype=np.int64), grid.start[b], grid.count[b])


def _expand(
    sa: np.ndarray, ca: np.ndarray, sb: np.ndarray, cb: np.ndarray, *, upper: bool = False
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """All (p, q) with p in [sa, sa + ca) and q in [sb, sb + cb), per row; chunked.

    ``upper``: only p < q (rows are one range paired with itself).
    """
    tot = ca * cb
    if not tot.size:
        return
    ends = np.cumsum(tot)
    begin = 0
    while begin < tot.size:
        base = ends[begin - 1] if begin else 0
        stop = int(np.searchsorted(ends, base + _PAIRS_PER_CHUNK, side="right"))
        stop = max(stop, begin + 1)
        t = tot[begin:stop]
        rows = np.repeat(np.arange(begin, stop), t)
        local = np.arange(int(t.sum()), dtype=np.int64) - np.repeat(np.cumsum(t) - t, t)
        cbr = cb[rows]
        p = sa[rows] + local // cbr
        q = sb[rows] + local % cbr
        if upper:
            keep = p < q
            p, q = p[keep], q[keep]
        yield p, q
        begin = stop


@dataclass
class _Side:
    """Bodies in some order: their ids, centres and radii at positions 0, 1, ..."""

    ids: np.ndarray
    centers: np.ndarray
    radii: np.ndarray


def _run(
    pairs: Iterator[tuple[np.ndarray, np.ndarray]], a: _Side, b: _Side, box: np.ndarray | None, pad: float
) -> list[tuple[np.ndarray, ...]]:
    """The sphere test on every chunk of position pairs: surviving (i, j[, image]) arrays."""
    return [kept for p, q in pairs if (kept := _keep(a, p, b, q, box, pad)) is not None]


def _keep(
    a: _Side, p: np.ndarray, b: _Side, q: np.ndarray, box: np.ndarray | None, pad: float
) -> tuple[np.ndarray, ...] | None:
    """Sphere test (padded, minimum image in a box) of positions p of ``a`` against q of ``b``.

    Returns the survivors as body ids i < j (and j's image), or None.
    """
    if not p.size:
        return None
    diff = b.centers[q] - a.centers[p]
    k = None
    if box is not None:
        k = -np.rint(diff / box)
        diff = diff + k * box
    reach = a.radii[p] + b.radii[q] + pad
    near = np.flatnonzero(np.einsum("ij,ij->i", diff, diff) <= reach * reach)
    i, j = a.ids[p[near]], b.ids[q[near]]
    swap = i > j
    lo, hi = np.where(swap, j, i), np.where(swap, i, j)
    if k is None:
        return lo, hi
    kk = k[near].astype(np.int8)
    return lo, hi, np.where(swap[:, None], -kk, kk)
