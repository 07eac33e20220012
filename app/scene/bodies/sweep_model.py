"""Moving bodies in the scene: the model behind the timeline of ``serve --bodies START --to END`` (no viser).

A :class:`SweepModel` holds N bodies moving over one step t in [0, 1] (the exact motion of
:func:`core.sweep_contacts`: :mod:`core.moving.linear`), their certified contact events (the
sweep's first contacts, listed in exact time order), and, for the timeline, a :class:`Moment`:
the bodies at one time t, drawn at float poses and coloured by their certified relation at the
exact t.

What decides a colour (each body: its worst relation over its pairs at t):

* the sweep, forward: a pair is separate at every t < t* (t* its first contact, t_lo <= t*):
  separate for t < t_lo; at t = t* exactly, its relation there;
* the sweep run backwards (the same motion with t -> 1 - t: the same bodies, the same path):
  the last contact t** of the pair; separate for t > t** (an upper bound of t** rounded up);
* in between (the pair's contact window), nothing the sweep returns decides: exact arithmetic
  at the exact t, only for the pairs a colour needs (a pair whose two bodies already overlap
  another body changes no colour): ``core.classify`` of the bodies' exact matrices A(t), B(t)
  (the very motions the sweep certified, evaluated at t: :meth:`LinearMotions.matrix_at`) at a
  rational t, or at an event's algebraic t* the paper's tree on the exact signs of the pair's
  pencil there (``core.analyse`` on a rational bracket of t*, :mod:`core.moving.signs`).

Until a pair is decided its bodies are "deciding" (a grey of their own), never a guess; the
view decides them in the background (:mod:`app.scene.bodies.sweep_view`). The two-body view opens a
pair on the same exact motions (:meth:`SweepModel.pair_motion`), so its analysis finds the
same first event time.
"""

from __future__ import annotations

import copy
import functools
import json
import math
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from flint import fmpq

from core import Box, Certifier, Relation, analyse, classify, sweep_contacts
from core.algebra.algebraic import RealAlgebraic
from core.algebra.closedform import closed_form
from core.bodies.sweep_result import SweepContacts
from core.moving.motions import Motion, motion_to_dict
from core.moving.signs import Signs, decide_with

from ..common.state import SceneConfig
from ..pair.motion import MotionModel
from .model import PairList, box_phrase, image_text

if TYPE_CHECKING:
    from ...sweep_cli import MovingBodies
    from ..pair.analysis import AnalysisView

__all__ = ["SweepModel", "Moment", "same_time", "compare_times", "PENDING_COLOUR", "CLOSED_FORM_CHARS"]

PENDING_COLOUR = (205, 205, 225)
"""Colour of a body whose relation at t is being decided (exact arithmetic running)."""
CLOSED_FORM_CHARS = 48
"""Longest closed form shown for t* in the event list (longer: a marked rounding)."""
_MOTIONS_KEPT = 4096
"""Exact motions kept (built on first use: a few milliseconds each)."""
_EXACT_KEPT = 200_000
"""Exact relations at past times kept (scrubbing back costs nothing)."""

Time = float | RealAlgebraic
"""A time of the step: a float (its exact binary value) or an event's exact algebraic t*."""


@dataclass
class Moment:
    """The bodies at one time t: float poses for drawing, and each pair's certified relation at t."""

    t: Time
    """The exact time: a float (its binary value) or an event time (a real algebraic number)."""
    tf: float
    """t as a float (poses, slider)."""
    event: int | None
    """The event (pair index) whose exact first contact time t is, or None."""
    positions: np.ndarray
    """(N, 3) centres at tf (2D: z = 0)."""
    wxyz: np.ndarray
    """(N, 4) unit quaternions at tf."""
    relation: np.ndarray
    """(M,) int8 per pair of the sweep result: its certified relation at t, or UNDECIDED (not yet)."""
    by_sweep: int
    """Pairs decided by the sweep's first and last contacts alone."""
    pending: list[int] = field(default_factory=list)
    """Pairs that exact arithmetic still has to decide (those a colour needs), in order."""
    exact: int = 0
    """Pairs decided by exact arithmetic at t (including those remembered from before)."""
    done: threading.Event = field(default_factory=threading.Event)
    """Set once every colour at t is certified."""
    _matrices: dict[tuple[int, tuple[int, ...]], Any] = field(default_factory=dict, repr=False)

    def key(self) -> tuple[Any, ...]:
        """Hashable form of t (a float, or the event it is the time of)."""
        return ("event", self.event) if isinstance(self.t, RealAlgebraic) else ("float", self.t)


class SweepModel(PairList):
    """N moving bodies, their certified contact events, and the bodies at the timeline's t.

    Args:
        moving: START and END read and checked (:func:`app.sweep_cli.read_moving_bodies`).
        name: what to call the set in the GUI.

    Raises:
        ValueError: a bad box or bodies too large for it (bad rows are marked, not fatal).
    """

    moving = True
    """Tells the view (:class:`app.scene.bodies.bodies_view.BodiesView`) to show the timeline."""
    title = "**Moving bodies** — certified first contacts over one step t ∈ [0, 1]"

    def __init__(self, moving: MovingBodies, *, name: str = "") -> None:
        self.files = moving
        self.bodies = moving.start
        self.dim = moving.dim
        self.name = name or f"{_base(moving.names[0])} → {_base(moving.names[1])}"
        self.box: Box | None = moving.box
        c0, c1, r, o0, o1 = moving.arguments()
        self.result: SweepContacts = sweep_contacts(c0, c1, r, o0, o1, box=self.box, on_invalid="mark")
        back = sweep_contacts(c1, c0, r, o1 if o1 is not None else o0, None if o1 is None else o0, box=self.box, on_invalid="mark")
        self.invalid = {**self.result.invalid, **moving.errors}
        res = self.result
        M = len(res)
        self.last_hi = np.ones(M)
        """(M,) float64: the pair is separate at every t > last_hi (its last contact is <= it)."""
        self.end_relation = np.full(M, Relation.UNDECIDED, np.int8)
        """(M,) relation at t = 1 when the backward sweep found it (contact at its start), else UNDECIDED."""
        N = max(1, res.n_bodies)
        where = np.searchsorted(res.i * N + res.j, back.i * N + back.j)
        hit = (where < M) & ((res.i * N + res.j)[np.minimum(where, max(M - 1, 0))] == back.i * N + back.j) if M else np.zeros(0, bool)
        s_lo = back.t_lo[hit]
        # last contact t** = 1 - s* <= 1 - s_lo; the float of 1 - s_lo is exact for s_lo >= 1/2
        # (Sterbenz) or s_lo = 0, else within half an ulp: one float up is >= 1 - s_lo
        up = 1.0 - s_lo
        exact_diff = (s_lo >= 0.5) | (s_lo == 0.0)
        self.last_hi[where[hit]] = np.where(exact_diff, up, np.nextafter(up, 2.0))
        at_end = back.t_hi[hit] == 0.0
        self.end_relation[where[hit][at_end]] = back.relation[hit][at_end]
        self.order = self._time_order()
        """Indices of the pairs in exact time order of their first contact (ties: by (i, j))."""
        self._lock = threading.RLock()
        self._motions: OrderedDict[tuple[int, tuple[int, ...]], Motion] = OrderedDict()
        self._exact: dict[tuple[Any, ...], int] = {}
        self._labels: dict[int, str] = {}
        self.current: Moment = self.moment(0.0)

    def for_view(self) -> SweepModel:
        """This model for one more tab: its own current t; the sweep, the caches and the labels shared."""
        other = copy.copy(self)
        other.current = self.moment(0.0)
        return other

    # ------------------------------------------------------------------ events
    def _time_order(self) -> np.ndarray:
        """Pairs by (t_lo, t_hi, i, j); runs whose brackets overlap are put in exact order."""
        res = self.result
        o = np.lexsort((res.j, res.i, res.t_hi, res.t_lo))
        out: list[int] = []
        k = 0
        while k < len(o):
            group = [int(o[k])]
            hi = res.t_hi[o[k]]
            k += 1
            while k < len(o) and res.t_lo[o[k]] <= hi:
                group.append(int(o[k]))
                hi = max(hi, res.t_hi[o[k]])
                k += 1
            if len(group) > 1 and any(res.t_lo[g] != res.t_hi[g] for g in group):

                def cmp(a: int, b: int) -> int:
                    c = compare_times(res.time(a), res.time(b))
                    return c if c else (-1 if (res.i[a], res.j[a]) < (res.i[b], res.j[b]) else 1)

                group.sort(key=functools.cmp_to_key(cmp))
            out += group
        return np.array(out, dtype=np.int64)

    def time(self, k: int) -> RealAlgebraic:
        """t* of pair k exactly (:meth:`core.bodies.sweep_result.SweepContacts.time`)."""
        with self._lock:
            return self.result.time(k)

    def time_text(self, k: int, *, exact: bool = True) -> str:
        """t* of pair k for people: "= 1/3", "= (3 − √3)/4" (closed forms), "≈ 0.382683432365…".

        Args:
            k: the pair.
            exact: compute t* exactly if needed (else a bracket's rounding "≈ …" until it is known).
        """
        if k in self._labels:
            return self._labels[k]
        res = self.result
        lo, hi = float(res.t_lo[k]), float(res.t_hi[k])
        if lo == hi or exact:
            alpha = self.time(k)
            form = closed_form(alpha, unicode=True)
            text = f"= {form}" if form is not None and len(form) <= CLOSED_FORM_CHARS else f"≈ {alpha.decimal(12)}…"
            self._labels[k] = text
            return text
        return f"≈ {(lo + hi) / 2:.8f}…"

    def exact_labels(self, ks: Any, stop: Callable[[], bool] = lambda: False) -> bool:
        """Compute t* of the pairs ``ks`` exactly (for their labels); False if stopped early."""
        for k in ks:
            if stop():
                return False
            self.time_text(int(k))
        return True

    def labelled(self, k: int) -> bool:
        """True when pair k's label shows its exact t* (closed form or its marked rounding)."""
        return k in self._labels or self.result.t_lo[k] == self.result.t_hi[k]

    def pair_label(self, k: int) -> str:
        """"3 – 17  t* = 1/3  tangent" (a box image: "3 – 17 [+x]  t* ≈ 0.4187…  tangent")."""
        res = self.result
        text = f"{res.i[k]} – {res.j[k]}{image_text(res.image, k, res.box)}"
        return f"{text}  t* {self.time_text(k, exact=False)}  {Relation(int(res.relation[k]))}"

    def summary(self) -> str:
        """Markdown: the set, its contact events and how they were certified."""
        res, c = self.result, self.result.counts
        kind = "ellipsoids" if self.dim == 3 else "ellipses"
        box = box_phrase(self.box)
        at0 = int(np.count_nonzero(res.t_hi == 0.0))
        lines = [
            f"**{len(self.bodies):,} moving {kind}**{box}" + (f" from `{self.name}`" if self.name else ""),
            f"{len(res):,} pairs meet during the step: **{len(res) - at0:,} first touch at t\\* > 0**, "
            f"**{at0:,} already touch or overlap at t = 0** ({c.get('candidates', 0):,} candidate pairs; "
            f"certified by the float filter {c.get('float', 0):,}, by exact arithmetic {c.get('exact', 0):,})",
        ]
        if self.invalid:
            lines.append(f"{len(self.invalid)} invalid bodies (grey), e.g. {next(iter(self.invalid.values()))}")
        return "\n\n".join(lines)

    def box_corner(self) -> np.ndarray:
        """Lower corner of the periodic box as drawn (START's lowest centre)."""
        corner: np.ndarray = self._poses(0.0)[0].min(axis=0)
        return corner

    # ------------------------------------------------------------------ the bodies at t
    @property
    def positions(self) -> np.ndarray:  # type: ignore[override]
        """(N, 3) centres at the current t."""
        return self.current.positions

    @property
    def wxyz(self) -> np.ndarray:  # type: ignore[override]
        """(N, 4) unit quaternions at the current t."""
        return self.current.wxyz

    @property
    def scales(self) -> np.ndarray:  # type: ignore[override]
        """(N, 3) semi-axes (2D: third = 1)."""
        b = self.result.bodies
        r = np.where(self._bad[:, None], 1e-3, b.semi_axes)
        return r if self.dim == 3 else np.concatenate([r, np.ones((len(r), 1))], axis=1)

    @property
    def worst(self) -> np.ndarray:  # type: ignore[override]
        """(N,) int8 each body's worst certified relation at the current t (UNDECIDED: deciding)."""
        return self.worst_at(self.current)

    @functools.cached_property
    def _bad(self) -> np.ndarray:
        bad = np.zeros(self.result.n_bodies, dtype=bool)
        bad[list(self.invalid)] = True
        return bad

    def colours(self) -> np.ndarray:
        """(N, 3) uint8 colours at the current t (deciding: :data:`PENDING_COLOUR`)."""
        from .model import relation_colours

        return relation_colours(self.worst, pending=PENDING_COLOUR)

    def _poses(self, tf: float) -> tuple[np.ndarray, np.ndarray]:
        """(N, 3) float centres and (N, 4) unit quaternions at the float tf (drawing only)."""
        b = self.result.bodies
        c = b.centers0 + tf * (b.centers1 - b.centers0)
        q = (1.0 - tf) * b.q0 + tf * b.q1
        q = q / np.linalg.norm(q, axis=1)[:, None]
        N = len(c)
        if self.dim == 2:
            c = np.concatenate([c, np.zeros((N, 1))], axis=1)
            q = np.stack([q[:, 0], np.zeros(N), np.zeros(N), q[:, 1]], axis=1)
        return c, q

    def worst_at(self, m: Moment) -> np.ndarray:
        """(N,) each body's worst relation at the moment's t; UNDECIDED where a pair is still pending.

        A body with a certified overlap is OVERLAP whatever its pending pairs are (nothing is worse).
        """
        res = self.result
        N = res.n_bodies
        worst = np.full(N, Relation.SEPARATE, np.int8)
        known = m.relation >= 0
        np.maximum.at(worst, res.i[known], m.relation[known])
        np.maximum.at(worst, res.j[known], m.relation[known])
        open_ = np.zeros(N, dtype=bool)
        wait = ~known
        open_[res.i[wait]] = True
        open_[res.j[wait]] = True
        worst[open_ & (worst != Relation.OVERLAP)] = Relation.UNDECIDED
        worst[self._bad] = Relation.INVALID
        return worst

    def moment(self, t: Time, *, event: int | None = None) -> Moment:
        """The bodies at t: poses, and every pair's relation as far as the sweep decides it (fast).

        Args:
            t: a float in [0, 1] (its exact binary value), or an event's exact time.
            event: the pair whose first contact t is (when t is an event time).

        Returns:
            A :class:`Moment` whose ``pending`` pairs need exact arithmetic
            (:meth:`decide`); pairs decided before at the same t are remembered.
        """
        if isinstance(t, RealAlgebraic) and t.value is not None and _float_value(t.value) is not None:
            t = float(_float_value(t.value))  # type: ignore[arg-type]  # a rational event time that is a float: the float path
        res = self.result
        M = len(res)
        rel = np.full(M, Relation.UNDECIDED, np.int8)
        if isinstance(t, RealAlgebraic):
            t.refine_to(fmpq(1, 2**60))
            lo_f, hi_f = _float_below(t.lo), _float_above(t.hi)
            tf = float(t)
            before = hi_f < res.t_lo
            after = lo_f > self.last_hi
            rel[before | after] = Relation.SEPARATE
            if event is not None:
                rel[event] = res.relation[event]
        else:
            t = tf = float(t)
            if not 0.0 <= tf <= 1.0:
                raise ValueError(f"t = {tf} is outside the step [0, 1]")
            rel[(tf < res.t_lo) | (tf > self.last_hi)] = Relation.SEPARATE
            at_first = (res.t_lo == tf) & (res.t_hi == tf)  # t* is this float exactly
            rel[at_first] = res.relation[at_first]
            if tf == 1.0:
                end = self.end_relation >= 0
                rel[end] = self.end_relation[end]
        by_sweep = int(np.count_nonzero(rel >= 0))
        positions, wxyz = self._poses(tf)
        m = Moment(t, tf, event, positions, wxyz, rel, by_sweep)
        key = m.key()
        for k in np.flatnonzero(rel < 0).tolist():
            got = self._exact.get((k, *key))
            if got is not None:
                rel[k] = got
                m.exact += 1
        m.pending = self._needed(m)
        if not m.pending:
            m.done.set()
        return m

    def _needed(self, m: Moment) -> list[int]:
        """The undecided pairs a colour depends on (not both bodies already certified overlapping)."""
        res = self.result
        und = np.flatnonzero(m.relation < 0)
        if und.size == 0:
            return []
        over = np.zeros(res.n_bodies, dtype=bool)
        hit = m.relation == Relation.OVERLAP
        over[res.i[hit]] = True
        over[res.j[hit]] = True
        need = und[~(over[res.i[und]] & over[res.j[und]])]
        rows: list[int] = need.tolist()
        return rows

    def decide(self, m: Moment, stop: Callable[[], bool] = lambda: False, progress: Callable[[], None] | None = None) -> bool:
        """Decide the moment's pending pairs exactly (module docstring); False if ``stop`` said so.

        Pairs whose two bodies are already certified overlapping are skipped (no colour changes).
        ``progress()`` is called after each pair decided.
        """
        res = self.result
        over = np.zeros(res.n_bodies, dtype=bool)
        hit = m.relation == Relation.OVERLAP
        over[res.i[hit]] = True
        over[res.j[hit]] = True
        key = m.key()
        while m.pending:
            if stop():
                return False
            k = m.pending[0]
            i, j = int(res.i[k]), int(res.j[k])
            if not (over[i] and over[j]):
                code = self.exact_relation(k, m)
                m.relation[k] = code
                m.exact += 1
                with self._lock:
                    if len(self._exact) > _EXACT_KEPT:
                        self._exact.clear()
                    self._exact[(k, *key)] = code
                if code == Relation.OVERLAP:
                    over[i] = over[j] = True
            m.pending.pop(0)
            if progress is not None:
                progress()
        m.done.set()
        return True

    def exact_relation(self, k: int, m: Moment) -> int:
        """Pair k's relation at the moment's exact t, by exact arithmetic (module docstring)."""
        res = self.result
        i, j = int(res.i[k]), int(res.j[k])
        image = () if res.image is None else tuple(int(v) for v in res.image[k])
        t = m.t
        tq = t.value if isinstance(t, RealAlgebraic) else fmpq(*float(t).as_integer_ratio())
        if tq is not None or not isinstance(t, RealAlgebraic):  # a rational t: classify there
            assert tq is not None
            A = self._matrix_at(m, i, (), tq)
            B = self._matrix_at(m, j, image, tq)
            return int(classify(A, B))
        hi = fmpq(*float(res.t_hi[k]).as_integer_ratio())
        if t.compare(hi) <= 0:  # t is in or before pair k's bracket: compare with its t*
            c = compare_times(t, self.time(k))
            if c < 0:
                return int(Relation.SEPARATE)
            if c == 0:
                return int(res.relation[k])
        a, b = max(t.lo, fmpq(0)), min(t.hi, fmpq(1))  # an irrational t in (0, 1): a < t < b
        r = analyse(self.motion(i), self.motion(j, image), interval=(a, b))
        for e in (*r.events, *r.roots):  # t is an instant the analysis decided itself
            if same_time(e.time, t):
                return int(e.relation)
        polys = r.polynomials()
        zero = {name for name, p in polys.items() if p.is_zero()}
        return int(decide_with(r.n, Signs(polys, t, zero)).relation)

    def _matrix_at(self, m: Moment, body: int, image: tuple[int, ...], tq: fmpq) -> Any:
        """Body's exact A(t) at the moment's rational t (the motion's matrix at t, built directly).

        :meth:`core.moving.linear.LinearMotions.matrix_at`, equal to ``matrix_at_exact(motion, t)``.
        """
        key = (body, image)
        if key not in m._matrices:
            m._matrices[key] = self.result.bodies.matrix_at(body, tq, self._shift(image))
        return m._matrices[key]

    def motion(self, body: int, image: tuple[int, ...] = ()) -> Motion:
        """Body's exact motion (moved by the lattice vector of ``image`` in a box): the sweep's own (kept, LRU)."""
        key = (body, tuple(image))
        with self._lock:
            got = self._motions.get(key)
            if got is not None:
                self._motions.move_to_end(key)
                return got
        m = self.result.bodies.motion(body, self._shift(image))
        with self._lock:
            self._motions[key] = m
            while len(self._motions) > _MOTIONS_KEPT:
                self._motions.popitem(last=False)
        return m

    def _shift(self, image: tuple[int, ...]) -> np.ndarray | None:
        """The lattice vector v(image) the sweep moves a body's path by (None: no image, or open space)."""
        if not any(image) or self.result.box is None:
            return None
        shift: np.ndarray = self.result.box.shifts([image])[0]
        return shift

    # ------------------------------------------------------------------ the two-body view
    def pair_config(self, k: int) -> tuple[SceneConfig, str]:
        """The pair at t = 0 as static shapes (the two-body view is then given its motion), and a note."""
        res = self.result
        i, j = int(res.i[k]), int(res.j[k])
        shifts = res.shifts()  # the lattice vectors v(k) the sweep moved j's path by
        shift = np.zeros(self.dim) if shifts is None else shifts[k]
        shapes = {"A": self._shape(i, np.zeros(self.dim)), "B": self._shape(j, shift)}
        cfg = SceneConfig.from_dict({"dim": self.dim, **shapes, "preset": None, "show_plots": False})
        rel = Relation(int(res.relation[k]))
        when = "at t = 0 (they already meet)" if res.t_hi[k] == 0.0 else f"first touch at t* {self.time_text(k)}"
        note = (
            f"Bodies **{i}** (A) and **{j}** (B) of `{self.name or 'the set'}` moving over the step t ∈ [0, 1], the exact "
            f"motion the sweep certified: {when}, **{rel}** there ({Certifier(int(res.certified_by[k]))}; "
            f"{float(res.t_lo[k])!r} ≤ t* ≤ {float(res.t_hi[k])!r})."
        )
        if shift.any():
            note += f" B is the periodic image of body {j} moved by ({', '.join(f'{v:g}' for v in shift)}), exactly."
        return cfg, note

    def pair_motion(self, k: int) -> MotionModel:
        """Pair k's exact motion over [0, 1] as the two-body view's motion (the sweep's own A(t), B(t))."""
        res = self.result
        i, j = int(res.i[k]), int(res.j[k])
        image = () if res.image is None else tuple(int(v) for v in res.image[k])
        A, B = self.motion(i), self.motion(j, image)
        texts = {"A": json.dumps(motion_to_dict(A)), "B": json.dumps(motion_to_dict(B)), "interval": "0, 1"}
        return MotionModel(
            A, B, ("0", "1"), preset=None, texts=texts,
            description=f"Bodies {i} and {j} of {self.name or 'the set'} over one step (core.sweep_contacts' motion).",
        )

    def open_target(self, k: int, analysis: AnalysisView) -> dict[str, Any]:
        """Where the two-body view opens pair k: ``{"event": n}`` at t* (1-based), or ``{"t": 0.0}``.

        The analysis' event equal to t* exactly; t = 0 when the pair overlaps there (no event).
        """
        tk = self.time(k)
        for e in analysis.events:
            if same_time(e.event.time, tk):
                return {"event": e.k}
        return {"t": 0.0}


# -------------------------------------------------------------------------------------------
# exact comparison of times


def compare_times(a: RealAlgebraic, b: RealAlgebraic) -> int:
    """Exact sign of a - b for two real algebraic numbers (isolating intervals refined as needed).

    Equal numbers are recognised by a common root of their polynomials inside both intervals
    (the gcd: each interval isolates its number's polynomial, so a root of the gcd there is it).

    Examples:
        >>> from flint import fmpz_poly
        >>> r2 = RealAlgebraic.isolating(fmpz_poly([-2, 0, 1]), fmpq(1), fmpq(2))
        >>> r2b = RealAlgebraic.isolating(fmpz_poly([-4, 0, 2]), fmpq(14, 10), fmpq(3, 2))
        >>> compare_times(r2, r2b), compare_times(r2, RealAlgebraic.rational(fmpq(3, 2)))
        (0, -1)
    """
    if a.value is not None:
        return -b.compare(a.value)
    if b.value is not None:
        return a.compare(b.value)
    g = a.poly.gcd(b.poly)
    while True:
        if a.value is not None or b.value is not None:
            return compare_times(a, b)
        if a.hi <= b.lo:
            return -1
        if b.hi <= a.lo:
            return 1
        if g.degree() > 0:
            lo, hi = max(a.lo, b.lo), min(a.hi, b.hi)
            glo, ghi = g(lo), g(hi)
            if glo != 0 and ghi != 0 and (glo > 0) != (ghi > 0):
                return 0
        (a if a.width >= b.width else b).bisect()


def same_time(a: RealAlgebraic, b: RealAlgebraic) -> bool:
    """True when two real algebraic numbers are equal (exact)."""
    return compare_times(a, b) == 0


def _float_value(q: fmpq) -> float | None:
    f = int(q.p) / int(q.q)
    return f if fmpq(*f.as_integer_ratio()) == q else None


def _float_below(x: fmpq) -> float:
    f = int(x.p) / int(x.q)
    return f if fmpq(*f.as_integer_ratio()) <= x else math.nextafter(f, -math.inf)


def _float_above(x: fmpq) -> float:
    f = int(x.p) / int(x.q)
    return f if fmpq(*f.as_integer_ratio()) >= x else math.nextafter(f, math.inf)


def _base(name: str) -> str:
    return str(name).rsplit("/", 1)[-1]
