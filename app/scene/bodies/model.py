"""Many bodies in the scene: the model behind the view (no viser here).

A :class:`BodiesModel` holds the bodies of a file (:mod:`app.bodyfiles`), their certified
contacts (:func:`core.contacts`), each body's worst relation (its colour), float poses for
drawing, the pages of pairs shown in the GUI (filtered by relation or body), picking by a
click ray, and the
:class:`~app.scene.common.state.SceneConfig` that opens one pair in the two-body view.

What the two-body view certifies: it rebuilds both shapes from their parameters with
:func:`core.quadric_from_axes`, bit for bit the matrices the search classified, so an open pair
gets the same label. In a periodic box the second body is shown at its image centre c_j + v(k)
(k L, or the tilted box's lattice vector) rounded to a float, while the search classified the exact translate of its matrix; a pair at
the very edge of tangency may then read differently (the view says so). Bodies given as
matrices (NPZ ``Q``) are shown with parameters recovered in floats (approximate).

:class:`PairList` (the paged, filtered list of pairs, a body's partners, the lookup of a pair)
and :func:`pick_body`, :func:`relation_colours` serve the moving bodies too
(:class:`app.scene.bodies.sweep_model.SweepModel`, whose pairs are the contact events of a step).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np

from core import Box, Certifier, Contacts, PairTable, Relation, axes_from_quadric, contacts
from core.bodies.broadphase import TooManyPairs
from core.shapes.quadrics import rotations_from_orientations

from ...bodyfiles import BodySet
from ..common.mesh_detail import DRAWABLE
from ..common.state import SceneConfig

__all__ = ["BodiesModel", "UPLOAD_PAIRS", "UPLOAD_SECONDS", "UPLOAD_BYTES", "parse_box", "tab_bodies_job", "PairList", "PairEntry", "PairPage", "PAGE_SIZE", "RELATION_FILTERS", "pick_body", "relation_colours"]

PAGE_SIZE = 200
"""Pairs per page of the GUI's list (tangent first, then overlap, then by (i, j))."""

RELATION_FILTERS = ("all", "tangent", "overlap")
"""What the list can be filtered by (a contact is tangent or overlap; "undecided" is added
when a float-only search left some)."""


@dataclass(frozen=True)
class PairEntry:
    """One pair of the list: its index in the contacts and its label."""

    index: int
    label: str


@dataclass(frozen=True)
class PairPage:
    """One page of the pair list and where it sits in the whole (filtered) list."""

    entries: list[PairEntry]
    total: int
    """Pairs that pass the filter (all pages)."""
    start: int
    """0-based position of the first entry in the filtered list."""
    page: int
    """0-based page number."""
    pages: int
    """Number of pages (at least 1)."""

    def caption(self, what: str = "pairs") -> str:
        """"showing 1–200 of 2,228 pairs" (or "no pairs")."""
        if not self.entries:
            return f"no {what}"
        if len(self.entries) == self.total:
            return f"showing all {self.total:,} {what}"
        return f"showing {self.start + 1:,}–{self.start + len(self.entries):,} of {self.total:,} {what}"


UPLOAD_BYTES = 64 * 1024 * 1024
"""Largest file a tab may upload to the bodies view (about a million bodies as CSV)."""
UPLOAD_PAIRS = 5_000_000
"""Most pairs the broad phase may examine for bodies a tab brings (a file, or a box typed for
them): counted before any is built, so a crowded file is refused at once instead of filling the
server's memory (10,000 bodies at random give ~50,000; 10,000 at one point 49,995,000)."""
UPLOAD_SECONDS = 60.0
"""Time budget of reading a tab's file and finding its contacts (a worker process, killed then)."""


def parse_box(text: str, dim: int) -> Box | None:
    """The periodic box typed in the GUI ("10, 10, 10", or a tilted "10, 10, 10, 0.5, 0, 0"), or None when empty.

    The numbers are read here; what makes them a box for ``dim``-D bodies is
    :meth:`core.Box.from_any`'s to say (its message, as the field's).

    Examples:
        >>> parse_box("8, 8, 0.5", 2)
        Box(Lx=8.0, Ly=8.0, Lz=None, xy=0.5, xz=0.0, yz=0.0)
        >>> parse_box("10 10", 3)
        Traceback (most recent call last):
        ...
        ValueError: periodic box: expected 3 positive finite sides (Lx, Ly, Lz) or (Lx, Ly, Lz, xy, xz, yz) (a tilted box, HOOMD's tilt factors), got [10.0, 10.0]
    """
    parts = [p for p in str(text).replace(",", " ").split() if p]
    if not parts:
        return None
    try:
        numbers = [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"periodic box: expected {dim} numbers, got {text!r}") from None
    try:
        return Box.from_any(numbers, dim)
    except ValueError as e:
        raise ValueError(f"periodic box: {str(e).removeprefix('box: ')}") from None


def image_text(image: np.ndarray | None, k: int, box: Box | None) -> str:
    """" [+x -y]": the image of pair k's second body ("" if none), by box vectors in a tilted box.

    In a tilted box the image counts box vectors, not axes: " [+a1 -a2]" (j moved by a1 - a2).

    Examples:
        >>> image_text(np.array([[1, -1, 0]]), 0, Box(8, 8, 8))
        ' [+x -y]'
        >>> image_text(np.array([[0, -1, 0]]), 0, Box(8, 8, 8, xy=0.5))
        ' [-a2]'
        >>> image_text(np.array([[2, 0, -1]]), 0, None)
        ' [+2x -z]'
    """
    if image is None or not image[k].any():
        return ""
    names = ("a1", "a2", "a3") if box is not None and box.tilted else ("x", "y", "z")
    return " [" + " ".join(f"{'+' if v > 0 else '-'}{abs(int(v)) if abs(v) > 1 else ''}{names[a]}" for a, v in enumerate(image[k]) if v) + "]"


def box_phrase(box: Box | None) -> str:
    """" in a periodic box 10 × 10 × 10" (tilted: "... tilted (xy, xz, yz) = (0.5, 0, 0)"); "" in open space.

    Examples:
        >>> box_phrase(Box(8.0, 8.0, xy=0.5))
        ' in a periodic box 8 × 8 tilted (xy) = (0.5)'
    """
    return "" if box is None else " in a periodic box " + box.describe().replace(" x ", " × ")


def tab_bodies_job(source: bytes | BodySet, name: str, box_text: str, max_pairs: int | None = UPLOAD_PAIRS) -> BodiesModel:
    """The model of bodies a tab brings: the bytes of an uploaded file, or bodies with a typed box.

    Run in a worker process under :data:`UPLOAD_SECONDS` (the scene's
    :meth:`app.scene.pair.analysis.AnalysisCache.run`), with :data:`UPLOAD_PAIRS`: the file is
    the tab's, its work must not be the server's. A file's own box (GSD, LAMMPS, extxyz) wins
    over the typed one. ``max_pairs`` None: the bodies are the server's own (``--bodies``), only
    the box is the tab's.

    Raises:
        ValueError: an unreadable file, a bad box, or too many pairs to examine.
    """
    from ...bodyfiles import read_bodies_bytes

    if isinstance(source, bytes | bytearray):
        bodies = read_bodies_bytes(bytes(source), name)
        box = bodies.box if bodies.box is not None else parse_box(box_text, bodies.dim)
    else:
        bodies, box = source, parse_box(box_text, source.dim)
    return BodiesModel(bodies, box, name=name, max_pairs=max_pairs)


class PairList(ABC):
    """The pairs of a set of bodies as the GUI lists them: pages, filters, partners, lookup.

    Subclasses set ``result`` (``.i``, ``.j`` sorted by (i, j), ``.relation``, ``.pairs_of``),
    ``order`` (the list order: indices into the result), ``bodies`` (a
    :class:`~app.readers.BodySet`), ``dim`` and ``pair_label``.
    """

    result: PairTable
    order: np.ndarray
    bodies: BodySet
    dim: int

    @abstractmethod
    def pair_label(self, k: int) -> str:
        """The text of pair k in the list (every subclass names its pairs its own way)."""

    def relation_filters(self) -> tuple[str, ...]:
        """The relation filters that make sense for this set ("undecided" only if present)."""
        extra = ("undecided",) if np.any(self.result.relation == Relation.UNDECIDED) else ()
        return RELATION_FILTERS + extra

    def matching(self, relation: str = "all", body: int | None = None) -> np.ndarray:
        """Indices of the contacts that pass the filter, in list order.

        Args:
            relation: "all", or a relation name ("tangent", "overlap", "undecided").
            body: only the pairs of this body (None: every body).

        Raises:
            ValueError: an unknown relation, or a body index out of range.
        """
        res, idx = self.result, self.order
        if body is not None:
            if not 0 <= body < len(self.bodies):
                raise ValueError(f"no body {body}: the bodies are numbered 0 to {len(self.bodies) - 1:,}")
            idx = idx[np.isin(idx, res.pairs_of(body), assume_unique=True)]
        if relation != "all":
            code = Relation.parse(relation)
            idx = idx[res.relation[idx] == code]
        return idx

    def page(self, relation: str = "all", body: int | None = None, page: int = 0, size: int = PAGE_SIZE) -> PairPage:
        """One page of the filtered pair list (the page number is clamped to the pages there are)."""
        idx = self.matching(relation, body)
        pages = max(1, -(-len(idx) // size))
        page = min(max(0, page), pages - 1)
        chunk = idx[page * size : (page + 1) * size]
        return PairPage([PairEntry(int(k), self.pair_label(int(k))) for k in chunk], len(idx), page * size, page, pages)

    def partners(self, body: int) -> list[int]:
        """The bodies that ``body`` touches or overlaps, ascending."""
        res = self.result
        k = res.pairs_of(body)
        return sorted({int(res.j[q]) if int(res.i[q]) == body else int(res.i[q]) for q in k})

    def pair_between(self, a: int, b: int) -> int | None:
        """Index of the pair of bodies a and b in the list's result, or None (not a pair)."""
        i, j = min(a, b), max(a, b)
        res = self.result
        lo = int(np.searchsorted(res.i, i, side="left"))
        hi = int(np.searchsorted(res.i, i, side="right"))
        hit = lo + np.flatnonzero(res.j[lo:hi] == j)
        return int(hit[0]) if hit.size else None

    # ------------------------------------------------------------------ drawn bodies
    positions: np.ndarray
    """(N, 3) centres as drawn (2D: z = 0)."""
    wxyz: np.ndarray
    """(N, 4) unit quaternions as drawn."""
    scales: np.ndarray
    """(N, 3) semi-axes as drawn (2D: third = 1)."""
    worst: np.ndarray
    """(N,) int8 each body's worst relation (its colour)."""

    def extent(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners of what is drawn."""
        N = len(self.bodies)
        if N == 0:
            return np.zeros(3), np.ones(3)
        reach = self.scales.max(axis=1)[:, None]
        lo = (self.positions - reach).min(axis=0)
        hi = (self.positions + reach).max(axis=0)
        if self.dim == 2:
            lo[2], hi[2] = 0.0, 0.0
        return lo, hi

    def colours(self) -> np.ndarray:
        """(N, 3) uint8: each body in the colour of its worst certified relation (:func:`relation_colours`)."""
        return relation_colours(self.worst)

    def pick(self, origin: Any, direction: Any) -> int | None:
        """The body first hit by the ray (as drawn; 2D: the z = 0 plane), or None."""
        return pick_body(self.positions, self.wxyz, self.scales, self.dim, origin, direction)

    def _shape(self, k: int, shift: np.ndarray) -> dict[str, list[float]]:
        """Centre (moved by ``shift``), semi-axes and orientation of body k as the file gives them."""
        b = self.bodies
        if b.centers is not None and b.semi_axes is not None:
            center = [float(v) for v in np.asarray(b.centers[k], dtype=float) + shift]
            axes = [float(v) for v in b.semi_axes[k]]
            if self.dim == 3:
                o = [1.0, 0.0, 0.0, 0.0] if b.orientations is None else [float(v) for v in b.orientations[k]]
            else:
                o = [0.0 if b.orientations is None else float(np.asarray(b.orientations).reshape(-1)[k])]
            return {"center": center, "semi_axes": axes, "orientation": o}
        p = axes_from_quadric(b.Q[k], validate=False)
        return {
            "center": [float(v) for v in np.asarray(p.center) + shift],
            "semi_axes": [float(v) for v in p.semi_axes],
            "orientation": [float(v) for v in p.orientation],
        }


class BodiesModel(PairList):
    """Bodies, their certified contacts and what the view needs to draw and pick them.

    Args:
        bodies: the bodies read from a file.
        box: the periodic box (any form of :meth:`core.Box.from_any`), or None.
        name: what to call the set in the GUI (the file name).
        max_pairs: most pairs the broad phase may examine (None: no limit); the scene's limit
            for a file a tab uploads (:data:`UPLOAD_PAIRS`).

    Raises:
        ValueError: a bad box or a body too large for it (invalid bodies are marked, not fatal),
            or more pairs to examine than ``max_pairs`` (counted before any is built).
    """

    def __init__(self, bodies: BodySet, box: Any = None, name: str = "", *, max_pairs: int | None = None) -> None:
        self.bodies = bodies
        self.name = name or bodies.source
        self.dim = bodies.dim
        self.box: Box | None = Box.from_any(box, bodies.dim)
        try:
            self.result: Contacts = contacts(bodies.Q, box=self.box, on_invalid="mark", max_pairs=max_pairs)
        except TooManyPairs as e:
            raise ValueError(
                f"{self.name}: {len(bodies):,} bodies give {e.pairs:,} pairs to examine (bodies crowded together), over "
                f"the scene's limit of {e.limit:,}: find their contacts with `python -m app contacts` or `core.contacts`"
            ) from None
        self.invalid = {**self.result.invalid, **bodies.errors}
        self.worst = self.result.per_body()
        self.undrawn: dict[int, str] = {}
        """Valid bodies outside the scene's drawing range (:data:`~app.scene.common.mesh_detail.DRAWABLE`),
        by index, and why: listed with their contacts, drawn as a grey speck at the origin."""
        self.positions, self.wxyz, self.scales = self._poses()
        res = self.result
        self.order = np.lexsort((res.j, res.i, -(res.relation == Relation.TANGENT).astype(np.int8)))
        """Indices of the contacts in list order: tangent first, then by (i, j)."""

    # ------------------------------------------------------------------ drawing
    def _poses(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(N, 3) positions, (N, 4) unit quaternions and (N, 3) scales (2D: z = 0, scale z = 1)."""
        b, N, d = self.bodies, len(self.bodies), self.dim
        if b.centers is not None and b.semi_axes is not None:
            c, r = b.centers, b.semi_axes
            if d == 3:
                q = np.tile([1.0, 0.0, 0.0, 0.0], (N, 1)) if b.orientations is None else np.array(b.orientations, dtype=float)
            else:
                half = (np.zeros(N) if b.orientations is None else np.asarray(b.orientations, dtype=float).reshape(N)) / 2
                q = np.stack([np.cos(half), np.zeros(N), np.zeros(N), np.sin(half)], axis=1)
        else:  # matrices only: parameters recovered in floats (display)
            c, r, q = np.zeros((N, d)), np.ones((N, d)), np.tile([1.0, 0.0, 0.0, 0.0], (N, 1))
            for k in np.flatnonzero(self.worst != Relation.INVALID):
                p = axes_from_quadric(b.Q[k], validate=False)
                c[k], r[k] = p.center, p.semi_axes
                if d == 3:
                    q[k] = p.orientation
                else:
                    q[k] = (math.cos(p.orientation[0] / 2), 0.0, 0.0, math.sin(p.orientation[0] / 2))
        bad = ~np.isfinite(c).all(axis=1) | ~np.isfinite(r).all(axis=1) | ~(r > 0).all(axis=1) | ~np.isfinite(q).all(axis=1)
        self.undrawn = _undrawn(c, r, bad | (self.worst == Relation.INVALID))
        bad[list(self.undrawn)] = True
        c = np.where(bad[:, None], 0.0, c)
        r = np.where(bad[:, None], 1e-3, r)
        norm = np.linalg.norm(q, axis=1)
        q = np.where((bad | (norm == 0))[:, None], [1.0, 0.0, 0.0, 0.0], q / np.where(norm > 0, norm, 1.0)[:, None])
        if d == 2:
            c = np.concatenate([c, np.zeros((N, 1))], axis=1)
            r = np.concatenate([r, np.ones((N, 1))], axis=1)
        return c.astype(np.float64), q.astype(np.float64), r.astype(np.float64)

    def colours(self) -> np.ndarray:
        """(N, 3) uint8: each body in the colour of its worst certified relation; grey if not drawn."""
        rows = relation_colours(self.worst)
        if self.undrawn:
            rows[list(self.undrawn)] = relation_colours(np.array([Relation.INVALID]))[0]
        return rows

    def box_corner(self) -> np.ndarray:
        """Lower corner of the periodic box as drawn (the lowest centre)."""
        corner: np.ndarray = self.positions.min(axis=0)
        return corner

    def pair_label(self, k: int) -> str:
        """"3 – 17  tangent (exact)" (with the image in a box: "3 – 17 [+x]  overlap (float)")."""
        res = self.result
        rel = str(Relation(int(res.relation[k])))
        by = Certifier(int(res.certified_by[k]))
        return f"{res.i[k]} – {res.j[k]}{image_text(res.image, k, res.box)}  {rel} ({by})"

    def summary(self) -> str:
        """Markdown: the set, its contacts by relation and how they were certified."""
        res, c = self.result, self.result.counts
        kind = "ellipsoids" if self.dim == 3 else "ellipses"
        box = box_phrase(self.box)
        lines = [
            f"**{len(self.bodies):,} {kind}**{box}" + (f" from `{self.name}`" if self.name else ""),
            f"{len(res):,} contacts: **{c.get('tangent', 0):,} tangent**, **{c.get('overlap', 0):,} overlap** "
            f"({c.get('candidates', 0):,} candidate pairs; certified by the float filter {c.get('float', 0):,}, "
            f"by exact arithmetic {c.get('exact', 0):,})",
        ]
        if self.invalid:
            lines.append(f"{len(self.invalid)} invalid bodies (grey), e.g. {next(iter(self.invalid.values()))}")
        if self.undrawn:
            k, why = next(iter(self.undrawn.items()))
            lines.append(f"{_bodies(len(self.undrawn))} not drawn (a grey speck at the origin; their contacts are listed), "
                         f"e.g. body {k}: {why}")
        return "\n\n".join(lines)

    def contact_segments(self) -> np.ndarray:
        """(M, 2, 3) the centres of the two bodies of each contact (in a box: j's image)."""
        res = self.result
        a = self.positions[res.i]
        b = self.positions[res.j].copy()
        shifts = res.shifts()  # the lattice vectors v(k) the search moved j by
        if shifts is not None:
            b[:, : self.dim] += shifts
        if self.undrawn:  # a contact of a body not drawn: no line to its speck at the origin
            gone = np.zeros(len(self.bodies), dtype=bool)
            gone[list(self.undrawn)] = True
            a[gone[res.i]] = b[gone[res.i]]
            b[gone[res.j]] = a[gone[res.j]]
        return np.stack([a, b], axis=1)

    # ------------------------------------------------------------------ the two-body view
    def pair_config(self, k: int) -> tuple[SceneConfig, str]:
        """A static two-body configuration of pair k, and a note on what it shows."""
        res = self.result
        i, j = int(res.i[k]), int(res.j[k])
        shifts = res.shifts()  # the float lattice vectors v(k) the search moved j by
        shift = np.zeros(self.dim) if shifts is None else shifts[k]
        shapes = {"A": self._shape(i, np.zeros(self.dim)), "B": self._shape(j, shift)}
        cfg = SceneConfig.from_dict({"dim": self.dim, **shapes, "preset": None, "show_plots": False})
        rel = str(Relation(int(res.relation[k])))
        note = f"Bodies **{i}** (A) and **{j}** (B) of `{self.name or 'the set'}`: **{rel}** in the search ({Certifier(int(res.certified_by[k]))})."
        if shift.any():
            note += (
                f" B is the periodic image of body {j} moved by ({', '.join(f'{v:g}' for v in shift)}), its centre "
                "rounded to a float here; the search certified the exact translate."
            )
        if self.bodies.centers is None:
            note += " Parameters recovered from the matrices in floats (approximate)."
        return cfg, note


def _undrawn(centers: np.ndarray, axes: np.ndarray, skip: np.ndarray) -> dict[int, str]:
    """The bodies (not in ``skip``) outside the drawing range, and why (centre or semi-axes).

    Examples:
        >>> why = _undrawn(np.array([[0.0, 0.0], [1e300, 0.0], [0.0, 0.0], [0.0, 0.0]]),
        ...                np.array([[1.0, 1.0], [1.0, 1.0], [1e300, 1.0], [2.0, 1e-300]]), np.zeros(4, dtype=bool))
        >>> for k, text in why.items():
        ...     print(k, text)
        1 its centre (1e+300, 0) is beyond the scene's drawing range (|x| <= 1e+12)
        2 a semi-axis of 1e+300 is outside the scene's drawing range [1e-12, 1e+12]
        3 a semi-axis of 1e-300 is outside the scene's drawing range [1e-12, 1e+12]
    """
    out: dict[int, str] = {}
    with np.errstate(invalid="ignore", over="ignore"):
        far = ~(np.abs(centers) <= DRAWABLE).all(axis=1)
        odd = ~((axes >= 1 / DRAWABLE) & (axes <= DRAWABLE)).all(axis=1)
    for k in map(int, np.flatnonzero((far | odd) & ~skip)):
        if far[k]:
            out[k] = (f"its centre ({', '.join(f'{v:g}' for v in centers[k])}) is beyond the scene's drawing range "
                      f"(|x| <= {DRAWABLE:g})")
        else:
            worst = max((float(v) for v in axes[k]), key=lambda v: abs(math.log10(v)))
            out[k] = f"a semi-axis of {worst:g} is outside the scene's drawing range [{1 / DRAWABLE:g}, {DRAWABLE:g}]"
    return out


def _bodies(n: int) -> str:
    """'1 body', '3 bodies'."""
    return f"{n:,} bod{'y' if n == 1 else 'ies'}"


def relation_colours(worst: np.ndarray, pending: Any = None) -> np.ndarray:
    """(N, 3) uint8 colour of each body's relation code (grey: invalid or undecided).

    Args:
        worst: (N,) :class:`core.Relation` codes.
        pending: colour of UNDECIDED codes (None: the grey of invalid bodies).
    """
    from ..common.shapes import NEUTRAL, RELATION_COLORS

    # rows for the codes INVALID (-2), UNDECIDED (-1), SEPARATE, TANGENT, OVERLAP
    rows = [NEUTRAL, NEUTRAL if pending is None else pending, *(RELATION_COLORS[k] for k in ("separate", "tangent", "overlap"))]
    table = np.array(rows, dtype=np.uint8)
    return table[np.asarray(worst).astype(np.int64) + 2]


def pick_body(positions: np.ndarray, wxyz: np.ndarray, scales: np.ndarray, dim: int, origin: Any, direction: Any) -> int | None:
    """The body first hit by a ray (bodies as drawn: (N, 3) centres, unit quaternions, semi-axes).

    A display question (floats): in 2D the ray meets the plane z = 0 and the first ellipse
    containing that point is returned.
    """
    o = np.asarray(origin, dtype=float)
    u = np.asarray(direction, dtype=float)
    u = u / (np.linalg.norm(u) or 1.0)
    R = rotations_from_orientations(wxyz, len(wxyz), 3)  # body -> world
    lo = np.einsum("nji,nj->ni", R, o[None, :] - positions)  # ray in body frames
    du = np.einsum("nji,j->ni", R, u)
    if dim == 2:
        if abs(u[2]) < 1e-12:
            return None
        t = -o[2] / u[2]
        p = lo + t * du
        inside = (p[:, 0] / scales[:, 0]) ** 2 + (p[:, 1] / scales[:, 1]) ** 2 <= 1
        hits = np.flatnonzero(inside & (t > 0))
        return int(hits[0]) if hits.size else None
    a = (du / scales) ** 2
    b = (lo / scales) * (du / scales)
    A = a.sum(axis=1)
    B = 2 * b.sum(axis=1)
    C = ((lo / scales) ** 2).sum(axis=1) - 1
    disc = B * B - 4 * A * C
    ok = disc >= 0
    t = np.where(ok, (-B - np.sqrt(np.where(ok, disc, 0))) / (2 * A), np.inf)
    t = np.where(t > 0, t, np.inf)
    k = int(np.argmin(t))
    return k if np.isfinite(t[k]) else None
