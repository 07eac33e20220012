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

Work and memory: sorting the cell keys (numpy), then per occupied cell its 13 "forward"
neighbour cells (or all 26 plus an index test when a periodic axis has fewer than 3 cells). In
open space the forward cells of a body are 5 ranges of positions in the sorted order (3D; 2 in
2D: :func:`_forward_ranges`), each pair built with a few array operations. The
pairs to examine are *counted* before any is built (:attr:`BroadPhase.pairs`, O(cells): the
sizes of the neighbouring cells multiplied), so a caller can refuse a crowded set (``max_pairs``:
:class:`TooManyPairs`) before spending memory on it; they are then built in chunks of at most
``_PAIRS_PER_CHUNK`` (a cell holding 10,000 bodies is cut inside its row of pairs), each chunk
tested and handed over before the next ones are built (:meth:`BroadPhase.chunks`). O(N) pairs for
bodies of similar size at any density; the memory beyond the candidates kept is a few chunks.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Generator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from ..fixed.compiled import get_threads

__all__ = ["BroadPhase", "Candidates", "TooManyPairs", "candidate_pairs", "LEVEL_RATIO"]

LEVEL_RATIO = 2.0
"""Radii within one level differ by at most this factor (a level's cells are 2 x its largest)."""
_CELL_SLACK = 1.0 + 2.0**-20
_MAX_CELLS = 2**30
"""Most cells per axis: keeps the float cell coordinates exact to well under one cell."""
_PAD = 2.0**-40
_DENSE_CELLS_PER_BODY = 8
"""Open space: a table of every cell (8 bytes each) when there are at most this many per body."""
_PAIRS_PER_CHUNK = 1 << 19
"""Pairs built at once before the sphere test (bounded memory: ~25 MB of temporaries; arrays
of 8 MB are recycled by the allocator, where larger ones would fault in fresh pages)."""


class TooManyPairs(ValueError):
    """The broad phase would examine more pairs than the caller's ``max_pairs``.

    Raised after counting (cheap) and before any pair is built.

    Attributes:
        pairs: the pairs of bodies the broad phase would examine (an upper bound on the
            candidates: every pair whose bounding spheres meet is among them).
        limit: the caller's ``max_pairs``.
    """

    def __init__(self, pairs: int, limit: int) -> None:
        self.pairs = pairs
        self.limit = limit
        super().__init__(
            f"{pairs:,} pairs of bodies to examine (bodies close enough that their bounding spheres "
            f"may meet), over the limit of {limit:,} (max_pairs)"
        )


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

    @staticmethod
    def concatenate(parts: list[Candidates], d: int, periodic: bool) -> Candidates:
        """One :class:`Candidates` of several (d: dimension, for an empty periodic result)."""
        i = np.concatenate([p.i for p in parts]) if parts else np.zeros(0, np.int64)
        j = np.concatenate([p.j for p in parts]) if parts else np.zeros(0, np.int64)
        if not periodic:
            return Candidates(i, j, None)
        k = np.concatenate([p.image for p in parts if p.image is not None]) if parts else np.zeros((0, d), np.int8)
        return Candidates(i, j, k)


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
    body_keys: np.ndarray
    """Cell key of each body, in the sorted order (positions 0, 1, ...)."""


@dataclass
class _Side:
    """Bodies in some order: their ids, centres and radii at positions 0, 1, ...

    The centres are kept by axis (``axes[a]`` contiguous): the sphere test gathers 1D columns,
    which numpy does several times faster than rows of a 2D array.
    """

    ids: np.ndarray
    axes: np.ndarray
    """(d, N) float64 centre coordinates, one contiguous row per axis."""
    radii: np.ndarray

    @staticmethod
    def of(ids: np.ndarray, centers: np.ndarray, radii: np.ndarray) -> _Side:
        """The bodies ``ids`` (positions 0, 1, ... in this order)."""
        return _Side(ids, np.take(np.ascontiguousarray(centers.T), ids, axis=1), radii.take(ids))


@dataclass
class _Block:
    """The pairs of one grid offset: per row, positions [sa, sa + ca) of ``a`` x [sb, sb + cb) of ``b``.

    ``upper``: each row is one cell with itself, and only p < q is a pair (c (c - 1) / 2 per
    row). ``dedupe``: the full shell of a tiny periodic grid meets a pair from both cells; it is
    kept once (a.ids[p] < b.ids[q]). ``total`` counts the pairs built (an upper bound on the
    candidates of the block).
    """

    a: _Side
    b: _Side
    sa: np.ndarray
    ca: np.ndarray
    sb: np.ndarray
    cb: np.ndarray
    upper: bool = False
    dedupe: bool = False
    single: bool = False
    """Every row is one body (ca = 1): its pairs are built with two repeats and an arange (sa,
    sb and cb may then be int32: the plan of a million bodies holds a few million rows)."""
    _ends: np.ndarray | None = field(default=None, repr=False)

    def sizes(self) -> np.ndarray:
        """Pairs of each row (int64)."""
        if self.single:
            return self.cb
        out: np.ndarray = self.ca * (self.ca - 1) // 2 if self.upper else self.ca * self.cb
        return out

    @property
    def total(self) -> int:
        return int(self.ends()[-1]) if self.sa.size else 0

    def ends(self) -> np.ndarray:
        """Cumulative pairs of the rows (computed once: every chunk searches it)."""
        if self._ends is None:
            self._ends = np.cumsum(self.sizes(), dtype=np.int64)
        return self._ends


class BroadPhase:
    """The grids of a set of bodies, and the pairs to examine: counted first, built in chunks.

    Args:
        centers: (N, d) float64 sphere centres.
        radii: (N,) float64 radii; NaN marks a body to leave out (invalid).
        box: periodic box sides (d,), or None for open space (a tilted box, the six numbers of
            :func:`core.bodies.periodic.read_box`: :mod:`core.bodies.ghosts`). The caller has checked
            (:mod:`core.bodies.periodic`) that the centres span at most one box side per axis and
            that the two largest radii sum to less than half the smallest side (so the minimum
            image is the only image that can touch).

    Planning (building the grids and finding the neighbouring occupied cells) is O(N log N) and
    builds no pair; :attr:`pairs` is then known, and :meth:`chunks` builds and tests them.

    Examples:
        >>> c = np.zeros((1000, 3))                 # a crowd: 1000 bodies at one point
        >>> BroadPhase(c, np.ones(1000)).pairs      # every pair, counted, none built
        499500
    """

    def __init__(self, centers: np.ndarray, radii: np.ndarray, *, box: np.ndarray | None = None) -> None:
        centers = np.asarray(centers, dtype=np.float64)
        self.d = centers.shape[1]
        self.ghosts = None
        if box is not None and box.size != self.d:  # a tilted box (its six numbers): ghost images, then open space
            from .ghosts import Ghosts

            self.ghosts = Ghosts(centers, radii, box)
            centers, radii, box = self.ghosts.centers, self.ghosts.radii, None
        self.box = box
        """The box of the grids (None for a tilted box: its ghosts are searched in open space)."""
        self.blocks: list[_Block] = []
        self.pad = 0.0
        self.scale: float | None = None
        """A power of two the sphere test multiplies its lengths by before squaring them, for
        bodies whose squares would leave the float range (sizes beyond about 2^±400); None: 1."""
        valid = np.flatnonzero(np.isfinite(radii))
        plans: list[Callable[[], _Block | None]] = []
        if valid.size >= 2:
            big = float(np.max(radii[valid]))
            span = float(np.max(np.abs(centers[valid]))) + (float(np.max(box)) if box is not None else 0.0)
            self.pad = _PAD * (span + big)
            reach = 2 * big + self.pad
            if not 2.0**-400 <= reach <= 2.0**400:  # lengths near 1 after it (reach < 1, and every pair's >= pad > 2^-44)
                self.scale = math.ldexp(1.0, -math.frexp(reach)[1])
            levels = _levels(radii, valid, big)
            lo, hi = centers[valid].min(axis=0), centers[valid].max(axis=0)
            for a, members in enumerate(levels):
                grid = _grid(centers, members, 2 * float(np.max(radii[members])) * _CELL_SLACK, lo, hi, box)
                # positions in the grid's cell order: neighbouring cells are near in memory
                mine = _Side.of(grid.order, centers, radii)
                half = not grid.periodic or bool((grid.n >= 3).all())
                if not grid.periodic:  # every forward neighbour cell as position ranges
                    plans.extend(_forward_ranges(grid, mine))
                else:
                    plans.append(partial(_inside_cells, grid, mine))
                    for off in [o for o in _offsets(grid, half) if any(o)]:
                        plans.append(partial(_same_level, grid, mine, off, half))
                for finer in levels[a + 1 :]:
                    coords = _coords(centers[finer], grid.lo, grid.h, grid.n, grid.periodic)
                    fkeys = _encode(coords, grid.n)
                    o = np.argsort(fkeys)
                    theirs = _Side.of(finer[o], centers, radii)
                    for off in _offsets(grid, half=False):
                        plans.append(partial(_query, grid, coords[o], fkeys[o], off, theirs, mine))
        self.blocks = [b for b in _map(plans) if b is not None and b.total]
        self.pairs = sum(b.total for b in self.blocks)
        """Pairs of bodies the broad phase examines: every candidate is among them."""

    def chunks(self, size: int | None = None) -> Generator[tuple[Candidates, int], None, None]:
        """The candidates, chunk by chunk, with the pairs examined so far.

        Each chunk comes from at most ``size`` pairs examined (built, sphere-tested, dropped;
        default ``_PAIRS_PER_CHUNK``).
        Chunks are built in rounds on every core (:func:`core.fixed.compiled.get_threads`), a
        round of at most ``threads x size`` pairs at a time, and nothing is built while the
        consumer works on a round's chunks (the narrow phase then has the cores to itself): the
        memory stays at one round whatever the number of pairs. Stopping the iteration
        (``close()``, or an exception in the consumer) stops the building.

        Yields:
            (candidates of the chunk, pairs examined so far); the last count is :attr:`pairs`.
        """
        size = size or _PAIRS_PER_CHUNK
        units = [(b, g, min(g + size, b.total)) for b in self.blocks for g in range(0, b.total, size)]
        threads = min(get_threads(), len(units))
        examined = 0
        if threads <= 1:
            for block, g0, g1 in units:
                examined += g1 - g0
                yield self._test(block, g0, g1), examined
            return
        with ThreadPoolExecutor(threads, thread_name_prefix="broadphase") as pool:
            k = 0
            while k < len(units):
                start, pairs = k, 0
                while k < len(units) and k - start < 4 * threads and pairs < threads * size:
                    pairs += units[k][2] - units[k][1]
                    k += 1
                for cand, (_, g0, g1) in zip(pool.map(lambda u: self._test(*u), units[start:k]), units[start:k], strict=True):
                    examined += g1 - g0
                    yield cand, examined

    def _test(self, block: _Block, g0: int, g1: int) -> Candidates:
        """Pairs g0 .. g1 - 1 of ``block`` built, sphere-tested: the candidates among them."""
        p, q = _build(block, g0, g1)
        if block.dedupe:
            keep = block.a.ids[p] < block.b.ids[q]
            p, q = p[keep], q[keep]
        with np.errstate(over="ignore"):  # squares past 1e308 (bodies near 1e154): inf, and the test stays conservative
            cand = _keep(block.a, p, block.b, q, self.box, self.pad, self.d, self.scale)
        if self.ghosts is not None:  # bodies and ghosts -> pairs of bodies with images
            return Candidates(*self.ghosts.resolve(cand.i, cand.j))
        return cand


def candidate_pairs(
    centers: np.ndarray,
    radii: np.ndarray,
    *,
    box: np.ndarray | None = None,
    max_pairs: int | None = None,
) -> Candidates:
    """All pairs (i < j) of valid bodies whose bounding spheres meet (conservative).

    Args:
        centers: (N, d) float64 sphere centres.
        radii: (N,) float64 radii; NaN marks a body to leave out (invalid).
        box: periodic box sides (d,), or None for open space (see :class:`BroadPhase`).
        max_pairs: most pairs to examine (None: no limit); over it, :class:`TooManyPairs`
            before any pair is built.

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
        >>> candidate_pairs(np.zeros((100, 2)), np.ones(100), max_pairs=1000)
        Traceback (most recent call last):
        ...
        core.bodies.broadphase.TooManyPairs: 4,950 pairs of bodies to examine (bodies close enough that their bounding spheres may meet), over the limit of 1,000 (max_pairs)
    """
    plan = BroadPhase(centers, radii, box=box)
    if max_pairs is not None and plan.pairs > max_pairs:
        raise TooManyPairs(plan.pairs, max_pairs)
    return Candidates.concatenate([c for c, _ in plan.chunks() if len(c)], plan.d, box is not None)


def _map(plans: list[Callable[[], _Block | None]]) -> list[_Block | None]:
    """Run the planning steps on every core (numpy releases the GIL inside each operation)."""
    threads = min(get_threads(), len(plans))
    if threads <= 1:
        return [plan() for plan in plans]
    with ThreadPoolExecutor(threads, thread_name_prefix="broadphase") as pool:
        return list(pool.map(lambda plan: plan(), plans))


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
    o = np.argsort(keys)  # any order inside a cell will do (the default sort is the fastest)
    sk = keys[o]
    first = np.flatnonzero(np.r_[True, sk[1:] != sk[:-1]])
    count = np.diff(np.r_[first, sk.size])
    return _Grid(origin, h_axis, n, periodic, members[o], sk[first], first, count, coords[o[first]], sk)


def _coords(c: np.ndarray, origin: np.ndarray, h: np.ndarray, n: np.ndarray, periodic: bool) -> np.ndarray:
    x = np.floor((c - origin) / h).astype(np.int64)
    out: np.ndarray = np.clip(x, 0, n - 1) if periodic else x
    return out


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


def _neighbour_keys(grid: _Grid, coords: np.ndarray, keys: np.ndarray, off: tuple[int, ...]) -> np.ndarray:
    """Keys of the cells at ``off`` from the cells ``coords`` (whose keys are ``keys``).

    In open space the coordinates start at 1 and stop 2 short of the radix, so a neighbour's
    coordinates stay in [0, n_a) and the mixed-radix key is linear in them: the neighbour's key
    is the cell's key plus the key of the offset (one addition, the same integer as encoding
    the shifted coordinates). In a box the coordinates wrap around: encoded after the modulo.
    """
    if grid.periodic:
        x = coords + np.array(off, dtype=np.int64)
        x %= grid.n
        return _encode(x, grid.n)
    step = 0
    for a in range(len(off)):
        step = step * int(grid.n[a]) + off[a]
    return keys + step


def _inside_cells(grid: _Grid, mine: _Side) -> _Block | None:
    """The pairs p < q inside each occupied cell."""
    multi = np.flatnonzero(grid.count >= 2)
    if not multi.size:
        return None
    s, c = grid.start[multi], grid.count[multi]
    return _Block(mine, mine, s, c, s, c, upper=True)


def _forward_ranges(grid: _Grid, mine: _Side) -> list[Callable[[], _Block | None]]:
    """Open space: each body with every body in its forward neighbour cells, as position ranges.

    The keys are mixed radix with the last axis fastest, and a cell's last coordinate is at
    least 1 and at most n - 2 (open space): the three cells at last-axis offsets -1, 0, +1 of a
    column are consecutive keys, so their bodies are one range of positions in the sorted
    order. The 13 forward offsets of 3D (4 in 2D) and the cell itself are then: the bodies
    after p in its own cell and in the next cell along the last axis (one range), and one range
    per lexicographically positive column offset (4 in 3D, 1 in 2D). The same pairs as the
    cell-by-cell offsets, each once, built with a few operations per pair (:func:`_build`,
    ``single``).

    A range's ends are the first positions of keys k + s - 1 and k + s + 2: from a dense table
    of the first position of every key when the grid has at most a few cells per body (one
    lookup per body), else by binary search among the occupied cells. Keys past the last cell
    are clipped to it (no body lies there: the range is the same).

    Returns one planning step per range (a block each: arrays of at most N rows, never one
    concatenation of all: fresh large arrays cost page faults).
    """
    d = grid.n.size
    cells = int(np.prod(grid.n))
    if cells <= _DENSE_CELLS_PER_BODY * grid.body_keys.size + 4096:
        first = np.zeros(cells + 1, dtype=np.int64)  # first[k]: bodies with a key below k
        np.cumsum(np.bincount(grid.body_keys, minlength=cells), out=first[1:])
        where: Callable[[np.ndarray], np.ndarray] = lambda k: first[np.minimum(k, cells)]  # noqa: E731
        keys = grid.body_keys
    else:
        S = np.append(grid.start, grid.start[-1] + grid.count[-1])  # S[c]: first position of cell c
        cell_of = np.repeat(np.arange(grid.keys.size), grid.count)
        where = lambda k: S[np.searchsorted(grid.keys, k)][cell_of]  # noqa: E731
        keys = grid.keys
    radix = [int(v) for v in grid.n]
    steps: list[int | None] = [None]  # None: the own range
    for col in itertools.product((-1, 0, 1), repeat=d - 1):
        if col > (0,) * (d - 1):
            step = 0
            for a in range(d - 1):
                step = step * radix[a] + col[a]
            steps.append(step * radix[-1])
    return [partial(_forward_range, mine, keys, where, step) for step in steps]


def _forward_range(
    mine: _Side, keys: np.ndarray, where: Callable[[np.ndarray], np.ndarray], step: int | None
) -> _Block | None:
    """The block of one range of :func:`_forward_ranges` (``step``: the column offset's key)."""
    if step is None:  # the bodies after p in its cell and the next one along the last axis
        hi = where(keys + 2)
        lo = np.arange(1, hi.size + 1, dtype=np.int64)
    else:
        lo = where(keys + (step - 1))
        hi = where(keys + (step + 2))
    hi -= lo
    keep = np.flatnonzero(hi > 0)
    if not keep.size:
        return None
    small = np.int32 if mine.ids.size < 2**31 else np.int64  # positions: half the memory of int64
    rows = keep.astype(small)
    return _Block(mine, mine, rows, np.broadcast_to(np.int64(1), rows.shape), lo[keep].astype(small), hi[keep].astype(small), single=True)


def _same_level(grid: _Grid, mine: _Side, off: tuple[int, ...], half: bool) -> _Block | None:
    """Pairs between each occupied cell and its neighbour at ``off`` (nonzero).

    With ``half`` (the 13 forward offsets), each unordered pair of bodies comes once over all
    offsets; otherwise (full shell) a pair is met from both cells and kept once.
    """
    nk = _neighbour_keys(grid, grid.coords, grid.keys, off)
    pos = np.minimum(np.searchsorted(grid.keys, nk), grid.keys.size - 1)
    hit = np.flatnonzero(grid.keys[pos] == nk)
    if not hit.size:
        return None
    b = pos[hit]
    return _Block(mine, mine, grid.start[hit], grid.count[hit], grid.start[b], grid.count[b], dedupe=not half)


def _query(
    grid: _Grid, coords: np.ndarray, keys: np.ndarray, off: tuple[int, ...], theirs: _Side, mine: _Side
) -> _Block | None:
    """Pairs (position of a finer body, position in this grid) in neighbouring cells.

    The finer body's cell (``coords``: its coordinates in this grid, ``keys`` their keys) and
    the grid's cell at ``off`` from it.
    """
    nk = _neighbour_keys(grid, coords, keys, off)
    pos = np.minimum(np.searchsorted(grid.keys, nk), grid.keys.size - 1)
    hit = np.flatnonzero(grid.keys[pos] == nk)
    if not hit.size:
        return None
    b = pos[hit]
    return _Block(theirs, mine, hit, np.ones(hit.size, dtype=np.int64), grid.start[b], grid.count[b])


def _build(block: _Block, g0: int, g1: int) -> tuple[np.ndarray, np.ndarray]:
    """Positions (p, q) of the pairs g0 .. g1 - 1 of ``block`` (rows in order, row-major inside).

    A row may be cut anywhere: a cell of 10,000 bodies is 50 M pairs, built a chunk at a time.
    """
    tot = block.sizes()
    ends = block.ends()
    r0 = int(np.searchsorted(ends, g0, side="right"))
    r1 = int(np.searchsorted(ends, g1 - 1, side="right"))
    if block.single:  # one body per row: p repeated, q = sb + (pair index - the row's first)
        first = ends[r0 : r1 + 1] - tot[r0 : r1 + 1]  # int64: the rows' first pair indices
        t = np.minimum(ends[r0 : r1 + 1], g1) - np.maximum(first, g0)
        p = np.repeat(block.sa[r0 : r1 + 1].astype(np.int64), t)
        q = np.arange(g0, g1, dtype=np.int64)
        q -= np.repeat(first - block.sb[r0 : r1 + 1], t)
        return p, q
    t = tot[r0 : r1 + 1].copy()
    skip = g0 - (int(ends[r0]) - int(tot[r0]))  # pairs of row r0 before g0
    t[-1] -= int(ends[r1]) - g1  # pairs of row r1 from g1 on
    t[0] -= skip
    rows = np.repeat(np.arange(r0, r1 + 1), t)
    local = np.arange(g1 - g0, dtype=np.int64) - np.repeat(np.cumsum(t) - t, t)
    local[: t[0]] += skip
    if block.upper:
        first, second = _triangle(local, block.ca[rows])
        s = block.sa[rows]
        return s + first, s + second
    cbr = block.cb[rows]
    return block.sa[rows] + local // cbr, block.sb[rows] + local % cbr


def _triangle(k: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The k-th pair (p, q), 0 <= p < q < c, in row-major order (k < c (c - 1) / 2).

    Row p starts at S(p) = p (2c - p - 1) / 2; p is the root of S(p) = k rounded down, from a
    float square root corrected in exact integers (the float error is far below one row).

    Examples:
        >>> p, q = _triangle(np.arange(6), np.full(6, 4))
        >>> list(zip(p.tolist(), q.tolist()))
        [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    """
    m = 2 * c - 1
    p = np.floor((m - np.sqrt(np.maximum(m.astype(np.float64) ** 2 - 8.0 * k, 0.0))) / 2).astype(np.int64)
    p = np.clip(p, 0, c - 2)
    for _ in range(2):
        p -= (p * (m - p) // 2 > k).astype(np.int64)
        p += ((p + 1) * (m - p - 1) // 2 <= k).astype(np.int64)
    return p, k - p * (m - p) // 2 + p + 1


def _keep(
    a: _Side, p: np.ndarray, b: _Side, q: np.ndarray, box: np.ndarray | None, pad: float, d: int,
    scale: float | None = None,
) -> Candidates:
    """Sphere test (padded, minimum image in a box) of positions p of ``a`` against q of ``b``.

    ``scale``: a power of two both lengths are multiplied by before squaring (exact for the
    reach, which stays above 2^-44 after it; a distance that underflows only comes out shorter:
    conservative). Returns the survivors as body ids i < j (and j's image).
    """
    reach = a.radii.take(p)
    reach += b.radii.take(q)
    reach += pad
    if scale is not None:
        reach *= scale
    reach *= reach
    dist = np.zeros(p.size)
    ks = []
    for ax in range(d):
        diff = b.axes[ax].take(q)
        diff -= a.axes[ax].take(p)
        if box is not None:
            k = np.rint(diff / box[ax])
            np.negative(k, out=k)
            diff += k * box[ax]
            ks.append(k)
        if scale is not None:
            diff *= scale
        diff *= diff
        dist += diff
    near = np.flatnonzero(dist <= reach)
    i, j = a.ids.take(p.take(near)), b.ids.take(q.take(near))
    swap = i > j
    lo, hi = np.where(swap, j, i).astype(np.int64), np.where(swap, i, j).astype(np.int64)
    if box is None:
        return Candidates(lo, hi, None)
    kk = np.stack([k.take(near) for k in ks], axis=1).astype(np.int8).reshape(-1, d)
    return Candidates(lo, hi, np.where(swap[:, None], -kk, kk))
