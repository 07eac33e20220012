"""``BodyIndex``: a reusable index of N bodies, asked about new bodies (Monte Carlo, packing).

The inner loop of a Monte Carlo or packing code tries a move and asks whether the moved body
overlaps anything. ``index = BodyIndex(Q, box=None)`` indexes the bodies once;
``index.query(Qnew)`` answers, for every new body (row of ``Qnew``), every indexed body it is
not separate from, with the certified relation (the same answer, pair for pair, as
:func:`core.contacts` on the union of the indexed and the new bodies); ``index.update(rows,
Qrows)`` moves indexed bodies in place (an accepted move) without rebuilding anything.

How. Every indexed body has a certified bounding sphere (:mod:`core.bodies.bounds`). The spheres
sit in a uniform grid: in open space over the region of the bodies (cells of side >= 2 R (1 +
2^-20), R the largest radius; a centre outside the region goes to the nearest border cell, which
keeps neighbours neighbours), in a periodic box over the fractional coordinates (c = f1 a1 + f2
a2 + f3 a3; n_a cells across the box vector a, each at least 2 R thick across its faces), each
cell a row of a table of body ids (slots grow by doubling when a cell fills). A new body of
radius r looks in the cells within (r + R) of its own (one ring of 3^d cells when r <= R), keeps
the bodies whose sphere meets its own (padded for rounding; in a box, the image k of the
indexed body is the one nearest in fractional coordinates: the only one that can touch, by the
size rule of :mod:`core.bodies.periodic`), and classifies those candidates with the certified
classifier, exactly as :func:`core.contacts` does: the indexed body as A, the new body as B,
moved by the lattice vector v(-k) in a box (:func:`core.bodies.periodic.classify_images`).

One new body (a Monte Carlo move) is kept cheap: its bounding sphere is the float proof of
:mod:`core.bodies.bounds` run in C on its matrix (:func:`core.fixed.compiled.spheres`: a few
microseconds; exact arithmetic only for a body that proof does not certify), the grid lookup
and the sphere test are a handful of numpy operations on one table of centres and radii, and
the narrow phase is one call of the compiled filter (:func:`core.fixed.classify.classify_pairs`).
New bodies may be given as :class:`core.Bodies` (parameters, e.g. a trial move's centre,
semi-axes and orientation): their matrices are built by :func:`core.bodies_from_axes` and the
same certified spheres bound the bodies those matrices describe.
"""

from __future__ import annotations

import itertools
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..filtered import predicate
from ..fixed import compiled
from ..fixed.classify import Certifier, classify_pairs
from ..fixed.compiled import get_threads, warm_up
from ..fixed.filters import _RELATION_OF
from ..options import check_options
from ..relation import Relation
from .bodies import Bodies, unpack
from .bounds import bounding_spheres
from .box import Box
from .periodic import (
    _GAMMA,
    _TINY,
    box_vectors_exact,
    cell_heights,
    check_sizes,
    classify_images,
    fractional,
    fractional_point,
    is_tilted,
    lattice_shifts,
    shift_error,
)
from .search import read_bodies

__all__ = ["BodyIndex", "IndexPairs"]

_SLACK = 1.0 + 2.0**-16
"""Cells are this much thicker than twice the largest radius: a new body no larger than the
largest indexed one then looks one cell away (its m_a is 1 with the 2^-19 allowance)."""
_PAD = 2.0**-40
"""Relative padding of the sphere test (its roundings are far smaller)."""
_CELL_ERROR = 2.0**-19
"""Error allowed in a cell coordinate computed in floats (module docstring of broadphase)."""
_MAX_CELLS_PER_BODY = 2
"""The grid has at most this many cells per indexed body (larger cells beyond)."""
_MAX_PERIODIC_CELLS = 1024
"""Most cells across a periodic box per axis (keeps the float cell coordinates' error < 2^-20)."""
_FAR = 2.0**20
"""Centres within this many boxes of the origin (fractional coordinates, see _place)."""
_FRAC_ERROR = 2.0**-30
"""Fractional coordinates must be this accurate (see _place)."""
_FAR_MESSAGE = "a body lies too far from the periodic box for float64 fractional coordinates: wrap the centres into the box"
_IMAGES_MESSAGE = "a body lies more than 127 boxes from another: wrap the centres into the box"
_MARGIN = 1.0 - 2.0**-20
_C_ONE = compiled.query_one_available()
_C_SPHERES = compiled.spheres_available()
"""New bodies' spheres from the compiled float proof where it certifies them (:func:`_certified_spheres`)."""
_SPHERES_PER_THREAD = 8192
"""A batch of new bodies' spheres is split over the filter's threads in ranges of at least this many."""
"""One new body takes the extension's spheres and grid lookup (else the general path in numpy)."""
_NO_IMAGES = np.zeros((0, 3), dtype=np.int8)
_BODIES_PER_THREAD = 2048
"""A batch of new bodies is split over the filter's threads in ranges of at least this many."""
_NONE = np.zeros(0)
"""An empty buffer: no matrices for the compiled lookup (it then classifies nothing)."""
_CLASSIFY = predicate("classify")
"""The counters of classify (:func:`core.filter_stats`), which the one-body path's filter calls feed too."""


def _certified_spheres(Q: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict[int, str]]:
    """(centres, radii, body k -> why it is no shape) of new bodies: :func:`bounding_spheres`, short where it can be.

    The compiled float proof (:func:`core.fixed.compiled.spheres`) first: where it proves a tight
    sphere that is the very sphere :func:`bounding_spheres` gives (its first, fast stage), without
    that function's stages and threads (~40 us for one body, against 2 us here; an accepted move
    updates one). The other bodies (none proven, a loose sphere, a matrix not exactly symmetric,
    no shape) go to :func:`bounding_spheres`, which names the invalid ones ("body k", k the row here).
    """
    if not _C_SPHERES or not Q.shape[0]:
        s = bounding_spheres(Q)
        return s.centers, s.radii, s.invalid
    if Q.shape[0] < _SPHERES_PER_THREAD or get_threads() == 1:
        centers, radii, status = compiled.spheres(Q)
    else:  # ranges side by side (the compiled proof releases the GIL)
        k = min(get_threads(), Q.shape[0] // _SPHERES_PER_THREAD)
        bounds = np.linspace(0, Q.shape[0], k + 1).astype(np.int64).tolist()
        futures = [compiled.pool(k - 1).submit(compiled.spheres, Q[lo:hi]) for lo, hi in zip(bounds[1:-1], bounds[2:], strict=True)]
        parts = [compiled.spheres(Q[: bounds[1]])] + [f.result() for f in futures]
        centers, radii, status = (np.concatenate(x) for x in zip(*parts, strict=True))
    rest = np.flatnonzero((status != compiled.SPHERE_TIGHT) | ~np.isfinite(radii))
    invalid: dict[int, str] = {}
    if rest.size:
        s = bounding_spheres(Q[rest])
        centers[rest], radii[rest] = s.centers, s.radii
        invalid = {int(rest[k]): why.replace(f"body {k}", f"body {int(rest[k])}", 1) for k, why in s.invalid.items()}
    return centers, radii, invalid


@dataclass
class IndexPairs:
    """Every (new body, indexed body) pair that is not separate, with its certified relation.

    Sorted by (i, j). In a periodic box the pair is new body i with the image of indexed body j
    moved by the lattice vector v(``image``) (:meth:`shifts`).
    """

    i: np.ndarray
    """int64 row of the new bodies (``Qnew``)."""
    j: np.ndarray
    """int64 indexed body."""
    relation: np.ndarray
    """int8 :class:`~core.Relation` codes: TANGENT or OVERLAP (UNDECIDED only with
    ``method="float"``)."""
    certified_by: np.ndarray
    """int8 :class:`~core.Certifier` code of each pair (float filter or exact)."""
    image: np.ndarray | None = None
    """(M, d) int8 lattice image k of j (periodic box), else None."""
    box: Box | None = None
    """The index's box (:class:`core.Box`), or None."""
    invalid: dict[int, str] = field(default_factory=dict)
    """New body -> why it is not an ellipse/ellipsoid (``on_invalid="mark"``)."""
    counts: dict[str, int] = field(default_factory=dict)
    """``candidates`` (pairs whose bounding spheres meet), ``float``, ``exact`` (who certified
    the candidates), ``undecided``."""

    def __len__(self) -> int:
        return int(self.i.size)

    def shifts(self) -> np.ndarray | None:
        """(M, d) float64 lattice vectors v(k) of the images (None in open space)."""
        if self.image is None or self.box is None:
            return None
        return self.box.shifts(self.image)

    def any(self) -> np.ndarray:
        """(number of new bodies,) bool: whether each new body touches or overlaps an indexed one."""
        out = np.zeros(self.counts.get("queries", int(self.i.max()) + 1 if self.i.size else 0), dtype=bool)
        out[self.i] = True
        return out


class BodyIndex:
    """An index of bodies (ellipses or ellipsoids) asked which of them new bodies touch.

    Args:
        Q: (N, 4, 4) ellipsoids or (N, 3, 3) ellipses (float matrices, e.g. from
            :func:`core.bodies_from_axes`), or :class:`core.Bodies` (their matrices, and their
            box unless ``box`` is given).
        box: None (open space), periodic box sides, or a tilted box (HOOMD's
            ``(Lx, Ly, Lz, xy, xz, yz)``; 2D ``(Lx, Ly, xy)``): as :func:`core.contacts`.
        method: "adaptive" (default), "float" (may report UNDECIDED) or "exact".
        on_invalid: "raise" a ValueError naming the first body that is no ellipse/ellipsoid, or
            "mark": leave it out of the index (listed in ``.invalid``); the same for new bodies.

    Raises:
        ValueError: bad shapes or options, an invalid body, a bad box or a body too large for it.

    The grid is sized when the index is built (its region, its largest body): bodies that later
    move far outside that region, or grow much larger, keep every answer right but make queries
    slower; ``BodyIndex(index.Q, box=index.box)`` builds a fresh one. The indexed bodies may stand anywhere
    (also outside the box: the image of a pair is found by rounding fractional coordinates).

    Examples:
        >>> from core import bodies_from_axes, Relation
        >>> index = BodyIndex(bodies_from_axes([[0, 0], [3, 0]], [[1, 1], [1, 1]]))
        >>> hits = index.query(bodies_from_axes([[1.5, 0], [0, 5]], [[0.5, 0.5], [1, 1]]))
        >>> [(int(i), int(j), str(Relation(r))) for i, j, r in zip(hits.i, hits.j, hits.relation)]
        [(0, 0, 'tangent'), (0, 1, 'tangent')]
        >>> index.update([1], bodies_from_axes([[2.5, 0]], [[1, 1]]))   # body 1 moved
        >>> [str(Relation(r)) for r in index.query(bodies_from_axes([[1.5, 0]], [[0.5, 0.5]])).relation]
        ['tangent', 'overlap']
    """

    def __init__(self, Q: Any, *args: Any, box: Any = None, method: str = "adaptive", on_invalid: str = "raise") -> None:
        if args:  # BodyIndex(Q, box): the box is keyword-only, as in contacts and sweep_contacts
            if len(args) > 1 or box is not None:
                raise TypeError("BodyIndex(Q, *, box=None, method=..., on_invalid=...): give the box as box=")
            warnings.warn("BodyIndex(Q, box): pass the box as a keyword, BodyIndex(Q, box=box)", DeprecationWarning, stacklevel=2)
            box = args[0]
        check_options(method, on_invalid)
        Q, box, _ = unpack(Q, box)
        warm_up(wait=False)
        self.method = method
        self.on_invalid = on_invalid
        Q = read_bodies(Q)
        self._Q = np.array(Q, dtype=np.float64, order="C")
        self.n = int(self._Q.shape[-1])
        self.d = self.n - 1
        self.box: Box | None = Box.from_any(box, self.d)
        """The periodic box (:class:`core.Box`), or None (open space)."""
        self._L = None if self.box is None else self.box.array
        spheres = bounding_spheres(self._Q)
        if spheres.invalid and on_invalid == "raise":
            raise ValueError(next(iter(spheres.invalid.values())))
        self.invalid: dict[int, str] = dict(spheres.invalid)
        """Indexed body -> why it is no ellipse/ellipsoid (left out of the index)."""
        if self._L is not None:  # the size rule; the centres may lie anywhere (images by rounding)
            check_sizes(spheres.radii, self._L, self.d)
        self._cr = np.empty((len(self._Q), self.d + 1))
        """Centre and radius of each indexed body's sphere in one row: a query gathers both at once."""
        self._centers = self._cr[:, : self.d]
        self._radii = self._cr[:, self.d]
        self._centers[:] = spheres.centers
        self._radii[:] = spheres.radii
        valid = np.isfinite(self._radii)
        self._big = float(np.max(self._radii[valid])) if valid.any() else 0.0
        self._span = self._extent(self._centers[valid])
        self._build_grid()

    # ------------------------------------------------------------------ the grid
    def _build_grid(self) -> None:
        """Cells sized for the largest radius, and the table of body ids per cell."""
        d = self.d
        valid = np.flatnonzero(np.isfinite(self._radii))
        N = max(valid.size, 1)
        width = 2 * max(self._big, 1e-300) * _SLACK
        if self._L is not None:
            self._vectors = box_vectors_exact(self._L, d)
            self._tilted = is_tilted(self._L)
            self._heights = cell_heights(self._L, d)
            self._limit = (float(np.min(self._heights)) / 2 - shift_error(self._L, d)) * _MARGIN
            """A new body's radius plus the largest indexed one must stay below this (the size rule)."""
            n = np.clip(np.floor(self._heights / width), 1, _MAX_PERIODIC_CELLS).astype(np.int64)
            while float(np.prod(n.astype(float))) > _MAX_CELLS_PER_BODY * N + 27:
                n = np.maximum(n // 2, 1)
            self._n = n
            self._cell = self._heights / n  # thickness of a cell across its faces
            self._origin = np.zeros(d)
        else:
            c = self._centers[valid] if valid.size else np.zeros((1, d))
            lo, hi = c.min(axis=0), c.max(axis=0)
            ext = np.maximum(hi - lo, 0.0)
            h = np.full(d, width)
            cells = float(np.prod(np.floor(ext / h) + 1))
            if cells > _MAX_CELLS_PER_BODY * N:
                h = h * (cells / (_MAX_CELLS_PER_BODY * N)) ** (1.0 / d)
            h = np.maximum(h, ext / 2**30)
            self._n = (np.floor(ext / h) + 3).astype(np.int64)  # one empty cell of margin on each side
            self._cell = h
            self._origin = lo - h
        self._offset_cache: dict[tuple[int, ...], np.ndarray] = {}
        self._strides = np.r_[np.cumprod(self._n[::-1])[::-1][1:], 1].astype(np.int64)  # axis 0 slowest
        self._nl, self._cell_l, self._origin_l = self._n.tolist(), self._cell.tolist(), self._origin.tolist()
        self._strides_l = self._strides.tolist()
        ncells = int(np.prod(self._n))
        coords, frac = self._place(np.where(np.isfinite(self._centers), self._centers, 0.0))
        self._frac = frac
        """Fractional coordinates of the indexed bodies (periodic box), for their images."""
        flat = coords @ self._strides
        self._body_cell = np.full(self._Q.shape[0], -1, dtype=np.int64)
        self._body_slot = np.full(self._Q.shape[0], -1, dtype=np.int64)
        cell_of = flat[valid]
        order = np.argsort(cell_of, kind="stable")
        sorted_cells = cell_of[order]
        count = np.bincount(sorted_cells, minlength=ncells).astype(np.int64)
        start = np.cumsum(count) - count
        rank = np.arange(valid.size) - start[sorted_cells]
        cap = max(int(count.max()) if count.size else 1, 1) + 1
        self._table = np.full((ncells, cap), -1, dtype=np.int32)
        bodies = valid[order]
        self._table[sorted_cells, rank] = bodies
        self._count = count
        self._live = int(valid.size)
        """Bodies in the grid (valid ones)."""
        self._body_cell[bodies] = sorted_cells
        self._body_slot[bodies] = rank
        self._pack_geometry()

    def _pack_geometry(self) -> None:
        """The grid's numbers as the compiled lookup of one body reads them (core/fixed/_near.h)."""
        d = self.d
        pad = [0] * (3 - d)
        self._geo_i = np.array(
            [d, self._table.shape[1], self._L is not None, self._L is not None and self._tilted, *self._nl, *pad, *self._strides_l, *pad],
            dtype=np.int64,
        )
        geo_d = np.zeros(27)
        if self._L is not None and not self._tilted:
            geo_d[:d] = self._L[:d]
        if self._L is not None:
            geo_d[3 : 3 + d * d] = np.array(self._vectors, dtype=np.float64).reshape(-1)  # rows: components, columns: vectors
        geo_d[12 : 12 + d] = self._origin
        geo_d[15 : 15 + d] = self._cell
        geo_d[18:] = (self._big, self._span, self._limit if self._L is not None else 0.0, _PAD, _CELL_ERROR, _FAR, _FRAC_ERROR, _GAMMA, _TINY)
        self._geo_d = geo_d
        self._frac_buf = self._frac if self._frac is not None and self._tilted else self._cr
        self._one_size = 3**d * self._table.shape[1]

    def _place(self, centers: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """(M, d) int64 cell coordinates, and the fractional coordinates in a periodic box.

        Periodic: floor(f n) modulo n; f off by at most 2^-30 (checked) and |f| <= 2^20, so
        f n is off by less than 2^10 2^-30 + 2^30 2^-52 < 2^-20 (n <= 1024 cells). Open space:
        floor((c - origin) / h), clamped to the grid without its margin (both roundings are
        relative 2^-53 of at most 2^30 cells). Either way each coordinate is off by < 2^-20.
        """
        if self._L is not None:
            f, eps = fractional(centers, self._L)
            if not ((eps < _FRAC_ERROR).all() and (np.abs(f) <= _FAR).all()):
                raise ValueError(_FAR_MESSAGE)
            return np.floor(f * self._n).astype(np.int64) % self._n, f
        u = np.floor((centers - self._origin) / self._cell)
        return np.clip(u, 1, self._n - 2).astype(np.int64), None  # the margins stay empty

    def _place_one(self, c: list[float]) -> tuple[list[int], list[float] | None]:
        """:meth:`_place` of one centre in Python floats (the same operations)."""
        d = self.d
        if self._L is not None:
            f, eps = fractional_point(c, self._vectors)
            if not all(e < _FRAC_ERROR and abs(x) <= _FAR for x, e in zip(f, eps, strict=True)):
                raise ValueError(_FAR_MESSAGE)
            return [math.floor(f[a] * self._nl[a]) % self._nl[a] for a in range(d)], f
        o, h, n = self._origin_l, self._cell_l, self._nl
        return [min(max(math.floor((c[a] - o[a]) / h[a]), 1), n[a] - 2) for a in range(d)], None

    def _offsets(self, m: tuple[int, ...]) -> np.ndarray:
        """(K, d) distinct cell offsets within m[a] cells along each axis (cached)."""
        out = self._offset_cache.get(m)
        if out is None:
            per_axis: list[Sequence[int]] = []
            for a in range(self.d):
                n = int(self._n[a])
                if self._L is not None and 2 * m[a] + 1 >= n:
                    per_axis.append(range(n))  # every cell of the axis, once
                else:
                    per_axis.append(range(-m[a], m[a] + 1))
            out = np.array(list(itertools.product(*per_axis)), dtype=np.int64).reshape(-1, self.d)
            self._offset_cache[m] = out
        return out

    # ------------------------------------------------------------------ queries
    def __len__(self) -> int:
        return int(self._Q.shape[0])

    @property
    def Q(self) -> np.ndarray:
        """The indexed matrices (read-only view; change them with :meth:`update`)."""
        v = self._Q.view()
        v.setflags(write=False)
        return v

    def query(self, Qnew: Any, *, exclude: Any = None) -> IndexPairs:
        """Every indexed body each new body is not separate from, certified.

        Args:
            Qnew: (M, n, n) new bodies (or one (n, n) matrix: M = 1), or :class:`core.Bodies`
                (their matrices, built from the parameters by :func:`core.bodies_from_axes`;
                a row whose parameters are no shape is an invalid new body).
            exclude: None, or one indexed body per new body to leave out (an int for all, or
                an (M,) array; -1: none), e.g. the body's own old place in a Monte Carlo move.

        Returns:
            :class:`IndexPairs`: pairs (i, j) sorted by (i, j), i a row of ``Qnew``, j an
            indexed body; the same pairs, relations, certifiers and images (j's image k here is
            minus the image of the new body in ``contacts``) as :func:`core.contacts` on the
            union ``Q + Qnew``.

        Raises:
            ValueError: bad shapes, an invalid new body (``on_invalid="raise"``), or a new body
                too large for the periodic box.
        """
        Qn, errors = self._matrices(Qnew, "new body")
        M = Qn.shape[0]
        if M == 1 and not errors and (exclude is None or type(exclude) is int or np.ndim(exclude) == 0):
            one = self._query_one(Qn, -1 if exclude is None else int(exclude))
            if one is not None:
                return one
        centers, radii, invalid = self._spheres(Qn, "new body", errors=errors)
        ex = None
        if exclude is not None:
            ex = np.broadcast_to(np.asarray(exclude, dtype=np.int64), (M,))
        if _C_ONE and M > 1:
            many = self._query_many(Qn, centers, radii, ex)
            if many is not None:
                many.invalid = invalid
                return many
        if M == 1 and np.isfinite(radii[0]):
            bj, image = self._near_one(centers[0].tolist(), float(radii[0]), -1 if ex is None else int(ex[0]))
            qi = np.zeros(bj.size, dtype=np.int64)
        else:
            qi, bj, image = self._candidates(centers, radii, ex)
        rel, by = self._classify(Qn, qi, bj, image)
        keep = np.flatnonzero(rel != Relation.SEPARATE)
        tally = np.bincount(by, minlength=3).tolist()
        counts = {
            "queries": M,
            "candidates": int(qi.size),
            "float": tally[Certifier.FLOAT],
            "exact": tally[Certifier.EXACT],
            "undecided": int(np.count_nonzero(rel == Relation.UNDECIDED)) if self.method == "float" else 0,
        }
        return IndexPairs(
            qi[keep], bj[keep], rel[keep], by[keep], None if image is None else image[keep], self.box, invalid, counts
        )

    def _matrices(self, bodies: Any, what: str) -> tuple[np.ndarray, dict[int, str]]:
        """(M, n, n) float64 matrices of new bodies (or of :class:`core.Bodies`), and the rows that are no shape.

        The rows whose parameters are no shape come with their reasons (:attr:`core.Bodies.errors`).
        """
        errors: dict[int, str] = {}
        if isinstance(bodies, Bodies):
            Qn = bodies.matrices
            errors = {k: f"{what} {k}: {why}" for k, why in bodies.errors.items()} if bodies.has_parameters else {}
        else:
            Qn = bodies
        if not (type(Qn) is np.ndarray and Qn.dtype == np.float64 and Qn.ndim == 3 and Qn.shape[1] == Qn.shape[2]):
            Qn = np.asarray(Qn)
            Qn = read_bodies(Qn[None] if Qn.ndim == 2 else Qn)
        if Qn.shape[-1] != self.n:
            raise ValueError(f"new bodies are {Qn.shape[-1]}x{Qn.shape[-1]} matrices but the index holds {self.n}x{self.n}")
        if errors and self.on_invalid == "raise":
            raise ValueError(next(iter(errors.values())))
        return Qn, errors

    def _query_one(self, Qn: np.ndarray, exclude: int) -> IndexPairs | None:
        """:meth:`query` of one new body, with as few array operations as it takes.

        One compiled call (:func:`core.fixed.compiled.query_one`, ``core/fixed/_near.h``): the
        body's certified sphere (the float proof of :mod:`core.bodies.bounds`), its cell, the
        bodies whose spheres meet its own (the steps of :meth:`_place_one` and
        :meth:`_near_one`), and the pairs without a lattice image through the float filter.
        What that leaves (pairs the filter does not decide, pairs with an image, a method other
        than "adaptive") is classified as :meth:`_classify` does. None when the short path does
        not apply (no extension, a body the float proof does not certify, or one too large for
        the box): the general path then answers (or raises).
        """
        if not _C_ONE:
            return None
        adaptive = self.method == "adaptive"
        size = self._one_size
        while True:
            out = np.empty(size, dtype=np.int64)
            kout = _NO_IMAGES if self._L is None else np.empty((size, self.d), dtype=np.int8)
            codes, by = np.empty(size, dtype=np.int8), np.empty(size, dtype=np.int8)
            found, kept, left = compiled.query_one(self._geo_i, self._geo_d, self._table, self._cr, self._frac_buf,
                                                   self._Q if adaptive else _NONE, Qn, _RELATION_OF, out, kout, codes, by, exclude)
            if found > compiled.QUERY_SPACE:
                break
            size = compiled.QUERY_SPACE - found  # a body reaching further than one ring of cells
        if found < 0:
            if found == compiled.QUERY_GENERAL:
                return None
            raise ValueError(_FAR_MESSAGE if found == compiled.QUERY_FAR_BOX else _IMAGES_MESSAGE)
        bj, image = out[:kept], None if self._L is None else kout[:kept]
        counts = {"queries": 1, "candidates": found, "float": found - left, "exact": 0, "undecided": 0}
        if found > left:
            _CLASSIFY.count(found - left, 0, 0)
        if not left:  # the filter decided every pair (the separate ones are dropped)
            return IndexPairs(np.zeros(kept, dtype=np.int64), bj, codes[:kept], by[:kept], image, self.box, {}, counts)
        first = codes[:kept] if adaptive else None  # what the filter decided in C (None: nothing)
        rel, cert = self._classify_found(Qn, bj, image, first)
        counts["float"] += int(np.count_nonzero((cert if first is None else cert[first < 0]) == Certifier.FLOAT))
        counts["exact"] = int(np.count_nonzero(cert == Certifier.EXACT))
        counts["undecided"] = int(np.count_nonzero(rel == Relation.UNDECIDED)) if self.method == "float" else 0
        keep = np.flatnonzero(rel)  # not SEPARATE (0)
        if keep.size != kept:
            bj, rel, cert = bj[keep], rel[keep], cert[keep]
            image = None if image is None else image[keep]
        return IndexPairs(np.zeros(keep.size, dtype=np.int64), bj, rel, cert, image, self.box, {}, counts)

    def _query_many(self, Qn: np.ndarray, centers: np.ndarray, radii: np.ndarray, exclude: np.ndarray | None) -> IndexPairs | None:
        """:meth:`query` of a batch with its certified spheres, new body by new body in C.

        The steps of :meth:`_query_one` after the sphere, for every new body in one compiled loop
        (:func:`core.fixed.compiled.query_many`, the GIL released), its pairs appended in order of
        the new bodies (sorted by (i, j)); the outputs grow when full. What the filter leaves
        (images, undecided pairs, a method other than "adaptive") is classified as
        :meth:`_classify` does, in the thread of its range of new bodies (a periodic box's image
        pairs then go through the numpy filter while the other range is still in C). None where
        the compiled loop cannot answer (out of memory in it): the numpy path then does.

        The new bodies are asked in the order of the grid cells their centres fall in (the
        answers do not depend on it): neighbouring new bodies then read the same cells and
        indexed bodies from cache. Trial moves drawn at random over 100,000 bodies ran 2-3x
        faster so (bench/bench_index.py).
        """
        M, d = Qn.shape[0], self.d
        adaptive = self.method == "adaptive"
        c = np.where(np.isfinite(centers), centers, 0.0)
        order = np.argsort(self._cell_key(c), kind="stable")
        spheres = np.empty((M, d + 1))
        spheres[:, :d] = c[order]
        spheres[:, d] = radii[order]
        ex = np.full(M, -1, dtype=np.int64) if exclude is None else np.asarray(exclude, dtype=np.int64)[order]
        Qc = np.ascontiguousarray(Qn[order], dtype=np.float64)
        Q = self._Q if adaptive else _NONE

        def run(lo: int, hi: int) -> tuple[tuple[np.ndarray, ...], list[int]]:
            """Bodies [lo, hi): their pairs (rows in cell order), and [candidates, left, float, exact, undecided, status].

            The pairs the compiled loop leaves (images, undecided) are classified here, in the
            range's own thread: while one range is in Python the other's compiled loop runs on.
            """
            size, start, candidates, left = max(4096, 8 * (hi - lo)), lo, 0, 0
            parts: list[tuple[np.ndarray, ...]] = []
            status = 0
            while start < hi:
                qout, out = np.empty(size, dtype=np.int64), np.empty(size, dtype=np.int64)
                kout = _NO_IMAGES if self._L is None else np.empty((size, d), dtype=np.int8)
                codes, by = np.empty(size, dtype=np.int8), np.empty(size, dtype=np.int8)
                done, found, kept, open_, status = compiled.query_many(
                    self._geo_i, self._geo_d, self._table, self._cr, self._frac_buf, Q, Qc[:hi], _RELATION_OF,
                    spheres[:hi], ex[:hi], qout, out, kout, codes, by, start,
                )
                parts.append((qout[:kept], out[:kept], kout[:kept], codes[:kept], by[:kept]))
                candidates, left, start = candidates + found, left + open_, done
                if status == 0 or status > compiled.QUERY_SPACE:
                    break
                size = max(2 * size, compiled.QUERY_SPACE - status)  # full: more room, from the body that did not fit
            qi, bj, image, rel, cert = (np.concatenate(x) if len(parts) > 1 else x[0] for x in zip(*parts, strict=True))
            tally = [candidates, left, candidates - left, 0, 0, status]
            if left and not status:
                first = rel if adaptive else None
                rel, cert = self._classify_found(Qc, bj, None if self._L is None else image, first, qi)
                tally[2] += int(np.count_nonzero((cert if first is None else cert[first < 0]) == Certifier.FLOAT))
                tally[3] = int(np.count_nonzero(cert == Certifier.EXACT))
                tally[4] = int(np.count_nonzero(rel == Relation.UNDECIDED)) if self.method == "float" else 0
                keep = np.flatnonzero(rel)
                if keep.size != rel.size:
                    qi, bj, rel, cert = qi[keep], bj[keep], rel[keep], cert[keep]
                    image = image if self._L is None else image[keep]
            return (qi, bj, image, rel, cert), tally

        k = min(get_threads(), max(1, M // _BODIES_PER_THREAD))
        bounds = np.linspace(0, M, k + 1).astype(np.int64).tolist()
        if k == 1:
            results = [run(0, M)]
        else:  # ranges of new bodies side by side (the compiled loop releases the GIL), in order
            # pool(k): a worker stays free for what a range's classification hands to the pool (leaf tasks)
            futures = [compiled.pool(k).submit(run, lo, hi) for lo, hi in zip(bounds[1:-1], bounds[2:], strict=True)]
            results = [run(bounds[0], bounds[1])] + [f.result() for f in futures]
        status = next((r[1][5] for r in results if r[1][5]), 0)
        if status == compiled.QUERY_GENERAL:
            return None
        if status:
            raise ValueError(_FAR_MESSAGE if status == compiled.QUERY_FAR_BOX else _IMAGES_MESSAGE)
        candidates, left, n_float, n_exact, n_undecided = (sum(r[1][t] for r in results) for t in range(5))
        parts = [r[0] for r in results]
        qi, bj, image, rel, cert = (np.concatenate(x) if len(parts) > 1 else x[0] for x in zip(*parts, strict=True))
        qi = order[qi]  # back to the rows of Qnew; each body's pairs are sorted by j, so a stable sort by i sorts by (i, j)
        by_row = np.argsort(qi, kind="stable")
        qi, bj, rel, cert = qi[by_row], bj[by_row], rel[by_row], cert[by_row]
        image = None if self._L is None else image[by_row]
        counts = {"queries": M, "candidates": candidates, "float": n_float, "exact": n_exact, "undecided": n_undecided}
        if candidates > left:
            _CLASSIFY.count(candidates - left, 0, 0)
        return IndexPairs(qi, bj, rel, cert, image, self.box, {}, counts)

    def _classify_found(
        self, Qn: np.ndarray, bj: np.ndarray, image: np.ndarray | None, rel: np.ndarray | None, qi: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(relations, certifiers) of candidates beyond what the compiled lookup decided.

        ``rel``: its codes (a relation where the filter decided, UNDECIDED where it did not,
        :data:`core.fixed.compiled.QUERY_MOVED` for a pair with an image), or None (nothing
        classified yet); ``qi``: the new body of each pair (None: all the first).
        """
        qi = np.zeros(bj.size, dtype=np.int64) if qi is None else qi
        if rel is None:
            return self._classify(Qn, qi, bj, image)
        rel, by = rel.copy(), (rel >= 0).view(np.int8)  # Certifier.FLOAT where decided
        rest = np.flatnonzero(rel < 0)
        rel[rest], by[rest] = self._classify(Qn, qi[rest], bj[rest], None if image is None else image[rest])
        return rel, by

    def update(self, rows: Any, Qrows: Any) -> None:
        """Replace indexed bodies ``rows`` by ``Qrows`` (moved, turned or reshaped), in place.

        Args:
            rows: indexed body numbers (distinct).
            Qrows: (len(rows), n, n) their new matrices (or one (n, n) matrix for one row), or
                :class:`core.Bodies` of len(rows) bodies.

        Raises:
            ValueError: bad rows or shapes, an invalid body (``on_invalid="raise"``; with
                "mark" it leaves the index and is listed in ``.invalid``), or a body too large
                for the periodic box. On an error the index is unchanged.
        """
        r = np.atleast_1d(np.asarray(rows))
        if r.dtype.kind not in "iu" or r.ndim != 1:
            raise ValueError(f"rows must be integer body numbers, got {rows!r}")
        errors: dict[int, str] = {}
        if isinstance(Qrows, Bodies):
            if Qrows.has_parameters and Qrows.errors and len(Qrows) == r.size:
                errors = {k: f"body {int(r[k])}: {why}" for k, why in Qrows.errors.items()}
            Qrows = Qrows.matrices
        Qr = np.asarray(Qrows)
        if Qr.ndim == 2:
            Qr = Qr[None]
        Qr = read_bodies(Qr)
        if Qr.shape[0] != r.size or Qr.shape[-1] != self.n:
            raise ValueError(f"update: {r.size} rows but Qrows has shape {Qr.shape} (expected ({r.size}, {self.n}, {self.n}))")
        if r.size and (r.min() < 0 or r.max() >= len(self)):
            raise ValueError(f"update: rows must be in [0, {len(self)}), got {r.tolist()}")
        if r.size > 1 and np.unique(r).size != r.size:
            raise ValueError("update: rows must be distinct")
        if errors and self.on_invalid == "raise":
            raise ValueError(next(iter(errors.values())))
        centers, radii, invalid = self._spheres(Qr, "body", names=r, errors=errors)
        ok = np.isfinite(radii)
        placed = np.where(ok[:, None], centers, 0.0)
        if r.size == 1:  # an accepted move: its centre placed in Python floats (the same operations)
            u, f = self._place_one(placed[0].tolist())
            flat_l = [sum(x * s for x, s in zip(u, self._strides_l, strict=True))]
            frac = None if f is None else np.array([f])
        else:
            coords, frac = self._place(placed)
            flat_l = (coords @ self._strides).tolist()
        for k, b in enumerate(r.tolist()):
            self._remove(b)
            self._Q[b] = Qr[k]
            self._cr[b, : self.d] = centers[k]
            self._cr[b, self.d] = radii[k]
            if frac is not None and self._frac is not None:
                self._frac[b] = frac[k]
            self.invalid.pop(b, None)
            if ok[k]:
                self._insert(b, flat_l[k])
            else:
                self.invalid[b] = invalid[k]
        if ok.any():
            self._big = max(self._big, float(np.max(radii[ok])))
            self._span = max(self._span, self._extent(centers[ok]))
            self._geo_d[18:20] = (self._big, self._span)

    def _extent(self, centers: np.ndarray) -> float:
        """Largest |centre coordinate| (plus 2 x the box's largest number): scales the sphere test's padding."""
        big = float(np.max(np.abs(centers))) if centers.size else 0.0
        return big + (2 * float(np.abs(self._L).max()) if self._L is not None else 0.0)

    def _remove(self, b: int) -> None:
        c = int(self._body_cell[b])
        if c < 0:
            return
        s = int(self._body_slot[b])
        last = int(self._count[c]) - 1
        moved = int(self._table[c, last])
        self._table[c, s] = moved
        self._body_slot[moved] = s
        self._table[c, last] = -1
        self._count[c] = last
        self._live -= 1
        self._body_cell[b] = -1
        self._body_slot[b] = -1

    def _insert(self, b: int, c: int) -> None:
        s = int(self._count[c])
        if s == self._table.shape[1]:  # the cell is full: twice the slots for every cell
            grown = np.full((self._table.shape[0], 2 * s), -1, dtype=np.int32)
            grown[:, :s] = self._table
            self._table = grown
            self._geo_i[1] = 2 * s
            self._one_size = 3**self.d * 2 * s
        self._table[c, s] = b
        self._count[c] = s + 1
        self._live += 1
        self._body_cell[b] = c
        self._body_slot[b] = s

    # ------------------------------------------------------------------ steps of a query
    def _cell_key(self, centers: np.ndarray) -> np.ndarray:
        """(M,) int64: a key of the grid cell of each centre in Cartesian coordinates, for ordering only.

        Nearby centres get nearby keys (axis 0 slowest); a periodic box is not wrapped here, as
        only locality matters.
        """
        u = np.clip(np.floor((centers - self._origin) / self._cell), 1 - 2.0**20, 2.0**20 - 1).astype(np.int64) + 2**20
        key = u[:, 0]
        for a in range(1, self.d):
            key = key * 2**21 + u[:, a]
        return key

    def _spheres(
        self, Qn: np.ndarray, what: str, names: Any = None, errors: dict[int, str] | None = None
    ) -> tuple[np.ndarray, np.ndarray, dict[int, str]]:
        """Certified spheres of new bodies; invalid ones raise or are marked; the box's size rule.

        ``errors``: rows already known to be no shape (:attr:`core.Bodies.errors`, named), marked
        with that reason (the caller raised for them under "raise").
        """
        centers, radii, found = _certified_spheres(Qn)
        invalid: dict[int, str] = {}
        for k, why in found.items():
            msg = why.replace(f"body {k}", f"{what} {k if names is None else int(names[k])}", 1)
            if self.on_invalid == "raise" and not (errors and k in errors):
                raise ValueError(msg)
            invalid[k] = msg
        for k, why in (errors or {}).items():
            centers[k], radii[k] = np.nan, np.nan
            invalid[k] = why
        if self._L is not None:
            ok = np.isfinite(radii)
            too = np.flatnonzero(ok & ~(radii + max(self._big, 0.0) < self._limit))
            if too.size:
                k = int(too[0])
                row = k if names is None else int(names[k])
                raise ValueError(
                    f"{what} {row} is too large for the periodic box: its bounding radius {radii[k]:.6g} plus the largest "
                    f"indexed one, {self._big:.6g}, must be less than half the smallest height of the cell "
                    f"({float(np.min(self._heights)):.6g} / 2), so that only the nearest image of a body can touch another"
                )
        return centers, radii, dict(sorted(invalid.items()))

    def _candidates(
        self, centers: np.ndarray, radii: np.ndarray, exclude: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """(new row, indexed body, image of the indexed body) of every pair whose spheres meet.

        Sorted by (new row, indexed body). A new body of radius r looks m_a cells away along
        axis a, m_a = ceil((r + R) / cell_a + 2^-19): two centres within r + R have cell
        coordinates (computed in floats, each off by less than 2^-20) at most that far apart.
        """
        d = self.d
        ok = np.flatnonzero(np.isfinite(radii))
        if not ok.size or not self._live:
            return np.zeros(0, np.int64), np.zeros(0, np.int64), None if self._L is None else np.zeros((0, d), np.int8)
        coords, frac = self._place(centers[ok])
        reach = radii[ok] + self._big
        m = np.ceil(reach[:, None] / self._cell * (1 + 2.0**-40) + _CELL_ERROR).astype(np.int64)
        if ok.size == 1:  # one new body: a few small operations
            offsets = self._offsets(tuple(m[0].tolist()))
            nb = coords[0] + offsets
            if self._L is not None:
                nb %= self._n
            elif m.max() > 1:  # beyond the margin: leave out cells off the grid
                nb = nb[((nb >= 0) & (nb < self._n)).all(axis=1)]
            ids = self._table[nb @ self._strides].ravel()
            body = ids[ids >= 0].astype(np.int64)
            qi = np.full(body.size, ok[0], dtype=np.int64)
        else:
            first = m[0]
            same = bool((m == first).all())
            groups = [np.arange(ok.size)] if same else [np.flatnonzero((m == row).all(axis=1)) for row in np.unique(m, axis=0)]
            members = self._table[self._table >= 0]  # the bodies cell by cell (slots [0, count) are filled)
            start = np.cumsum(self._count) - self._count
            q_parts, b_parts = [], []
            for g in groups:
                cells = self._cells(coords[g], tuple(int(x) for x in m[g[0]]))  # (q, K)
                cnt = self._count[cells]
                ends = np.cumsum(cnt.reshape(-1))
                # position in ``members`` of the t-th pair: t + (start of its cell - pairs before its cell)
                jump = np.repeat((start[cells].reshape(-1) - ends + cnt.reshape(-1)).astype(np.int64), cnt.reshape(-1))
                b_parts.append(members[np.arange(jump.size) + jump])
                q_parts.append(np.repeat(ok[g], cnt.sum(axis=1)))
            qi = q_parts[0] if len(q_parts) == 1 else np.concatenate(q_parts)
            body = (b_parts[0] if len(b_parts) == 1 else np.concatenate(b_parts)).astype(np.int64)
        if exclude is not None:
            keep = body != exclude[qi]
            qi, body = qi[keep], body[keep]
        diff = self._centers[body] - centers[qi]
        k = None
        if self._L is not None:
            if is_tilted(self._L):
                assert frac is not None and self._frac is not None
                fq = np.empty((centers.shape[0], d))
                fq[ok] = frac
                k = -np.rint(self._frac[body] - fq[qi])
            else:  # fractional coordinates of the difference: as the open broad phase does
                k = -np.rint(diff / self._L)
            moved = np.flatnonzero(k.any(axis=1))
            if moved.size:
                diff[moved] += lattice_shifts(self._L, self._images(k[moved]))
        scale = float(np.max(np.abs(centers[ok]))) + self._span + float(np.max(reach))
        r = radii[qi] + self._radii[body] + _PAD * scale
        with np.errstate(over="ignore"):  # squares past 1e308 (bodies near 1e154): inf, and the test stays conservative
            near = np.flatnonzero(np.einsum("ij,ij->i", diff, diff) <= r * r)
        if near.size > 1:
            near = near[np.argsort(qi[near] * len(self) + body[near], kind="stable")]
        return qi[near], body[near], None if k is None else k[near].astype(np.int8)

    def _near_one(self, c: list[float], r: float, exclude: int) -> tuple[np.ndarray, np.ndarray | None]:
        """:meth:`_candidates` for one new body (centre c, radius r): (indexed bodies, images).

        The same cells, images and padded sphere test as :meth:`_candidates` in a few array
        operations (the general path of one body; the short one does this in C:
        ``core/fixed/_near.h``).
        """
        d = self.d
        reach = r + self._big
        m = tuple(math.ceil(reach / self._cell_l[a] * (1 + 2.0**-40) + _CELL_ERROR) for a in range(d))
        u, f = self._place_one(c)
        rpad = r + _PAD * (max(abs(x) for x in c) + self._span + reach)
        if self._L is None and max(m) == 1:  # within the margin: no cell leaves the grid
            ids = self._table[sum(u[a] * self._strides_l[a] for a in range(d)) + self._offsets_flat(m)]
        elif self._L is not None:
            ids = self._table[((np.array(u) + self._offsets(m)) % self._n) @ self._strides]
        else:
            nb = np.array(u) + self._offsets(m)
            ids = self._table[nb[((nb >= 0) & (nb < self._n)).all(axis=1)] @ self._strides]
        ids = ids[ids >= 0]
        if exclude >= 0:
            ids = ids[ids != exclude]
        P = self._cr[ids]
        diff = P[:, :d] - c
        k = None
        if self._L is not None:  # k = -image: the fractional difference rounded (as in _candidates)
            if self._tilted:
                assert self._frac is not None and f is not None
                k = np.rint(self._frac[ids] - np.array(f))
            else:
                k = np.rint(diff / self._L)
            if k.any():
                diff -= lattice_shifts(self._L, self._images(k))  # v(-k) = -v(k)
        rr = P[:, d] + rpad
        with np.errstate(over="ignore"):  # as in _candidates
            near = np.flatnonzero(np.einsum("ij,ij->i", diff, diff) <= rr * rr)
        found_ids = ids[near].astype(np.int64)
        order = np.argsort(found_ids, kind="stable")
        return found_ids[order], None if k is None else (-k[near][order]).astype(np.int8)

    def _cells(self, coords: np.ndarray, m: tuple[int, ...]) -> np.ndarray:
        """(q, K) flat cells within m[a] cells of each cell coordinate row, axis by axis.

        Periodic: modulo the counts (the offsets are distinct modulo them). Open space: clipped
        to the grid, whose outer rows are the empty margin (a clipped cell holds nobody).
        """
        q, d = coords.shape
        total = np.zeros((q,) + (1,) * d, dtype=np.int64)
        for a in range(d):
            n = int(self._n[a])
            if self._L is not None and 2 * m[a] + 1 >= n:
                steps = np.arange(n)
            else:
                steps = np.arange(-m[a], m[a] + 1)
            u = coords[:, a, None] + steps
            u = u % n if self._L is not None else np.clip(u, 0, n - 1)
            shape = [q] + [1] * d
            shape[1 + a] = steps.size
            total = total + (u * self._strides_l[a]).reshape(shape)
        return total.reshape(q, -1)

    def _offsets_flat(self, m: tuple[int, ...]) -> np.ndarray:
        """Offsets as flat cell steps (open space: within the margin, no wrap)."""
        key = (-1, *m)
        out = self._offset_cache.get(key)
        if out is None:
            out = self._offsets(m) @ self._strides
            self._offset_cache[key] = out
        return out

    def _images(self, k: np.ndarray) -> np.ndarray:
        """Images k = -rint(fractional difference) as int8 (they must fit).

        The one image that can touch has |df + k| below 1/2 by far more than the coordinates'
        errors (the size rule's margin), so rounding finds it.
        """
        if k.size and not np.abs(k).max() <= 127:
            raise ValueError(_IMAGES_MESSAGE)
        return k.astype(np.int8)

    def _classify(
        self, Qn: np.ndarray, qi: np.ndarray, bj: np.ndarray, image: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Certified relations, as :func:`core.contacts` computes them on the union.

        The indexed body is A, the new body B (moved by v(-k) in a box).
        """
        M = qi.size
        rel = np.full(M, Relation.UNDECIDED, dtype=np.int8)
        by = np.zeros(M, dtype=np.int8)
        if not M:
            return rel, by
        shifted = np.zeros(M, dtype=bool) if image is None else image.any(axis=1)
        plain = np.flatnonzero(~shifted)
        if plain.size == M:
            rel, by = classify_pairs(self._Q[bj], Qn[qi], self.method)  # type: ignore[arg-type]
        elif plain.size:
            rel[plain], by[plain] = classify_pairs(self._Q[bj[plain]], Qn[qi[plain]], self.method)  # type: ignore[arg-type]
        moved = np.flatnonzero(shifted)
        if moved.size:
            assert image is not None and self._L is not None
            shift = lattice_shifts(self._L, -image[moved].astype(np.int64))
            rel[moved], by[moved] = classify_images(self._Q[bj[moved]], Qn[qi[moved]], shift, self.method)
        return rel, by
