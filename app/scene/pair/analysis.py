"""The exact analysis of a loaded motion, run off the GUI thread and shown by the timeline.

:class:`AnalysisCache` runs ``core.analyse`` once per motion and interval, in worker processes
(:class:`app.workers.WorkerPool`, whose fork server preloads :data:`app.workers.JOB_MODULES`:
a job starts in milliseconds), and shares the results among the tabs of a server. The result
is ``core``'s own :class:`~core.moving.result.MotionAnalysis`, pickled back unchanged;
:class:`AnalysisView` adds only what drawing needs (floats of the event times, the window of the
slider, plot samples) and answers every question about relations with the result's own methods
(``relation_at``, the sign table, :func:`core.moving.signs.decide_at`).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Hashable, Iterable
from concurrent.futures import Executor, Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
from flint import fmpq

from core.algebra.algebraic import RealAlgebraic
from core.algebra.closedform import closed_form, polynomial_text
from core.moving.result import Event, MotionAnalysis
from core.shapes.numbers import format_rational, to_float, to_fmpq

from ...jobs import analyse_job
from .motion import MAX_MOTION_TEXT, MotionError, MotionModel, read_motion_job
from .readout import explanation_at

if TYPE_CHECKING:
    from app.workers import WorkerPool

T = TypeVar("T")

__all__ = ["AnalysisCache", "AnalysisView", "EventView", "PLOT_SAMPLES"]

PLOT_SAMPLES = 300
"""Samples per curve in the plots (computed once per analysis)."""


@dataclass(frozen=True)
class EventView:
    """One event of the analysis as the timeline shows it (the exact event is ``event``)."""

    k: int
    """1-based index (α_k)."""
    event: Event
    t: float
    """Float of the exact time (slider position and drawing only)."""
    relation: str
    kind: str
    exact: str
    """Exact form for reading: "1/3", "(12 − 2√2)/17", or the decimal with the analysis' digits."""
    typed: str
    """Exact form the t box reads back: "1/3", "(12 - 2*sqrt(2))/17", or "α2" (degree > 2)."""
    closed: bool
    """True when ``exact`` is a closed form (the defining factor has degree <= 2)."""
    origin: str = ""
    """Which polynomial of the paper α_k is a root of and of what degree, for a time with no
    closed form: "root of ŝ0(t) (degree 84 in t, coefficients in Q(√2)); over Q: a root of a
    factor of degree 166 of its norm" (the degree of the defining polynomial alone misleads)."""

    @property
    def shown(self) -> str:
        """How α_k reads after its name: "= (12 − 2√2)/17", or "≈ 0.900801131…" (marked rounding).

        A decimal is never shown as if it were the exact value: the exact one is
        :attr:`definition` (copy button).
        """
        if self.closed:
            return f"= {self.exact}"
        return f"≈ {_short(self.exact)}"

    @property
    def definition(self) -> str:
        """Closed form, or "root of F(t) in (lo, hi)" (minimal polynomial, isolating interval)."""
        if self.closed:
            return self.typed
        return polynomial_text(self.event.time)


CLOSED_FORM_CHARS = 80
"""Longest closed form shown as an event's exact value (longer ones: the defining polynomial)."""

_HAT = {"s0": "ŝ0", "s1": "ŝ1", "s10": "ŝ1,0"}


def event_origin(result: MotionAnalysis, time_: RealAlgebraic) -> str:
    """Which of the paper's hat forms ŝ0, ŝ1, ŝ1,0 vanishes at an event time, with the degrees.

    ŝ_j = -s_j / a_n are the forms the paper's examples print (Example 30: ŝ0 of degree 84 in t,
    coefficients in Q(√2)); the exact time is stored as a root of a polynomial over Q: a factor
    of the norm ŝ0·ŝ0' (degree 2·84 = 168 there, the factor 166), whose degree is told apart.
    """
    from core.algebra.algebraic import sign_at

    over_q = time_.poly.degree()
    for name in ("s0", "s1", "s10"):
        poly = getattr(result, name)
        if poly.is_zero() or sign_at(poly, time_) != 0:
            continue
        field_ = "Q" if poly.d == 1 else f"Q(√{poly.d})"
        text = f"root of {_HAT[name]}(t), of degree {poly.degree()} in t with coefficients in {field_}"
        if poly.d != 1:
            return text + f"; over Q, of a factor of degree {over_q} of its norm (degree {poly.norm().degree()})"
        return text + (f"; over Q, of its factor of degree {over_q}" if over_q != poly.degree() else "")
    return f"root of a polynomial of degree {over_q} over Q"


def _event_view(k: int, ev: Event, result: MotionAnalysis | None = None) -> EventView:
    form = closed_form(ev.time)
    if form is not None and len(form) <= CLOSED_FORM_CHARS:
        return EventView(k, ev, float(ev.time), str(ev.relation), ev.kind, closed_form(ev.time, unicode=True) or form, form, True)
    origin = event_origin(result, ev.time) if result is not None else ""
    return EventView(k, ev, float(ev.time), str(ev.relation), ev.kind, ev.value, f"α{k}", False, origin)


@dataclass
class AnalysisView:
    """A motion's :class:`MotionAnalysis` with what the timeline draws (floats are display only)."""

    result: MotionAnalysis
    seconds: float
    """Wall time from submission to the result (worker start, analysis, transfer)."""
    window: tuple[float, float] = (0.0, 1.0)
    """Slider window: I when finite, else around the events (``MotionAnalysis.samples``)."""
    events: list[EventView] = field(default_factory=list)
    segments: list[tuple[float, float, str]] = field(default_factory=list)
    """(lo, hi, relation) of the open intervals between events, clipped to the window (bar)."""
    samples_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    samples: dict[str, np.ndarray] = field(default_factory=dict)
    """"a0".."a{n}", "s0", "s1", "s10" sampled at ``samples_t`` (scaled: signs and zeros kept)."""
    polys: dict[str, Any] = field(default_factory=dict)
    """``result.polynomials()`` (exact a_i, ŝ_j), kept for the readout at t."""
    _readouts: dict[Any, dict[str, Any] | None] = field(default_factory=dict, repr=False)

    @classmethod
    def of(cls, result: MotionAnalysis, seconds: float = 0.0, window: tuple[float, float] | None = None) -> AnalysisView:
        """Prepare a result for drawing (event floats, samples: a few milliseconds).

        ``window``: the slider's (default: I when finite, else around the events).
        """
        samples = result.samples(PLOT_SAMPLES, *(window or (None, None)))
        ts = np.asarray(samples["t"], dtype=float)
        window = (float(ts[0]), float(ts[-1]))
        series: dict[str, np.ndarray] = {f"a{i}": np.asarray(v, dtype=float) for i, v in enumerate(samples["a"])}
        for k in ("s0", "s1", "s10"):
            series[k] = np.asarray(samples[k], dtype=float)
        lo, hi = window
        segments = []
        for iv in result.intervals:
            a = lo if iv.lo is None else max(lo, float(iv.lo))
            b = hi if iv.hi is None else min(hi, float(iv.hi))
            if b > a:
                segments.append((a, b, str(iv.relation)))
        return cls(
            result=result,
            seconds=seconds,
            window=window,
            events=[_event_view(k, e, result) for k, e in enumerate(result.events, start=1)],
            segments=segments,
            samples_t=ts,
            samples=series,
            polys=result.polynomials(),
        )

    def widened(self, t: float) -> AnalysisView:
        """The same analysis with a slider window that shows ``t`` (a typed t inside an unbounded I).

        The window grows on t's side by 5 % beyond t (never past a finite end of I); a new view,
        since views are shared by the tabs through the cache.
        """
        lo, hi = self.window
        if lo <= t <= hi:
            return self
        ilo, ihi = (None if e is None else float(e) for e in self.result.interval)
        pad = 0.05 * (max(hi, t) - min(lo, t))
        lo = min(lo, t - pad) if t < lo else lo
        hi = max(hi, t + pad) if t > hi else hi
        lo, hi = (lo if ilo is None else max(lo, ilo)), (hi if ihi is None else min(hi, ihi))
        return AnalysisView.of(self.result, self.seconds, window=(lo, hi))

    @property
    def n(self) -> int:
        """Degree of P(T): 3 (ellipses) or 4 (ellipsoids)."""
        return self.result.n

    @property
    def default_t(self) -> float:
        """Where the timeline starts: just before the first event inside the window, else 45 % in."""
        lo, hi = self.window
        inner = [e.t for e in self.events if lo < e.t < hi]
        if inner:
            return max(lo, inner[0] - 0.03 * (hi - lo))
        return lo + 0.45 * (hi - lo)

    def contains(self, t: Any) -> bool:
        """True when the exact t (rational or RealAlgebraic) lies in I."""
        lo, hi = self.result.interval
        if isinstance(t, RealAlgebraic):
            return (lo is None or t.compare(lo) >= 0) and (hi is None or t.compare(hi) <= 0)
        tq = to_fmpq(t)
        return (lo is None or tq >= lo) and (hi is None or tq <= hi)

    def inside(self, t: float) -> float | fmpq:
        """A float t, or the nearest end of I when the float lies outside it (rounding of the window)."""
        lo, hi = self.result.interval
        tq = to_fmpq(t)
        if lo is not None and tq < lo:
            return lo
        if hi is not None and tq > hi:
            return hi
        return t

    def relation_at(self, t: Any) -> str:
        """Certified relation at the exact value of t.

        ``MotionAnalysis.relation_at`` for a rational t (a float is its binary value), the
        event's relation or exact signs at an algebraic t.
        """
        if isinstance(t, RealAlgebraic):
            k = self.event_at(t)
            if k is not None:
                return self.events[k - 1].relation
            return str(explanation_at(self.result, self.polys, _no_matrices, t, float(t))["relation"])  # type: ignore[index]
        return str(self.result.relation_at(t))

    def event_at(self, t: Any) -> int | None:
        """The event exactly at t (1-based), or None (exact comparison)."""
        for e in self.events:
            time_ = e.event.time
            if isinstance(t, RealAlgebraic):
                if t.value is not None:
                    if time_.compare(t.value) == 0:
                        return e.k
                elif time_.value is None and t.poly.gcd(time_.poly).degree() > 0:
                    # a common factor: equal iff the common root lies in both intervals
                    g = t.poly.gcd(time_.poly)
                    lo, hi = max(t.lo, time_.lo), min(t.hi, time_.hi)
                    if lo < hi and g(lo) * g(hi) < 0:
                        return e.k
            elif time_.compare(to_fmpq(t)) == 0:
                return e.k
        return None

    def readout_at(self, model: MotionModel, t: Any, t_float: float, event: int | None) -> dict[str, Any] | None:
        """Explanation dict at t or at an event (cached per (t, event): scrubbing back is free)."""
        key = (repr(t), event)
        if key not in self._readouts:
            if len(self._readouts) > 2000:
                self._readouts.clear()
            self._readouts[key] = explanation_at(self.result, self.polys, model.float_matrices, t, t_float, event)
        return self._readouts[key]

    def coeff_series(self) -> list[tuple[str, np.ndarray]]:
        """(label, samples) of a_n..a_0 (descending, as Var and the sign table list them)."""
        return [(f"a{i}", self.samples[f"a{i}"]) for i in range(self.n, -1, -1)]

    def subres_series(self) -> list[tuple[str, np.ndarray]]:
        """(label, samples) of s0, s1, s1,0."""
        return [(k.replace("s10", "s1,0"), self.samples[k]) for k in ("s0", "s1", "s10")]

    def sign_rows(self) -> list[dict[str, Any]]:
        """Rows of the sign table for :func:`app.scene.pair.panels.sign_table_markdown`."""
        by_value = {e.event.value: e for e in self.events}
        rows = []
        for r in self.result.sign_table:
            if r.where == "point":
                e = by_value.get(r.t)
                label = f"α{e.k} = {e.exact}" if e is not None and e.closed else (f"α{e.k} ≈ {_short(r.t)}" if e else f"root ≈ {_short(r.t)}")
            else:
                label = f"t = {_short_rational(r.t)}"
            n = self.n
            signs = {f"a{n - i}": s for i, s in enumerate(r.a)}
            signs.update(s0=r.s0, s1=r.s1, s10=r.s10)
            rows.append({"where": label, "signs": signs, "var": r.var, "relation": str(r.relation)})
        return rows


def _no_matrices(t: float) -> tuple[np.ndarray, np.ndarray]:
    raise ValueError("no float values")


def _short(decimal: str) -> str:
    return decimal if len(decimal) <= 12 else decimal[:12] + "…"  # always marked "≈" where shown


def _short_rational(text: str) -> str:
    if len(text) <= 10:
        return text
    q = to_fmpq(text)
    f = to_float(q)
    if not math.isfinite(f) or (f == 0 and q != 0):  # beyond the float range: exact mantissa, exponent
        return format_rational(q)
    return f"{f:.6g}"


class AnalysisCache:
    """Analyses by motion key, shared by the tabs of one server; each runs once, off the GUI thread.

    With ``processes=True`` each analysis (and each typed motion's reading) runs in a child
    process of a :class:`app.workers.WorkerPool` (forkserver with :data:`app.workers.JOB_MODULES`
    preloaded; killed after its budget), so a long exact computation never
    holds the GIL of the process serving the tabs. Otherwise it runs in a worker thread.
    """

    def __init__(
        self,
        executor: Executor | None = None,
        *,
        processes: bool = False,
        budget: float = 300.0,
        read_budget: float = 10.0,
        memory_mb: int | None = 2048,
    ) -> None:
        self._executor = executor
        self._done: dict[Hashable, AnalysisView] = {}
        self._running: dict[Hashable, Future[AnalysisView]] = {}
        self._lock = threading.Lock()
        self.budget = budget
        """Seconds one analysis may take."""
        self.read_budget = read_budget
        """Seconds a worker may spend reading one typed motion."""
        self.max_entries = 64
        """Analyses kept besides the prefetched ones (the oldest is dropped first)."""
        self._pinned: set[Hashable] = set()
        self.closed = False
        """Set by :meth:`shutdown`: background prefetching stops."""
        self._pool: WorkerPool | None = None
        if processes:
            from app.workers import WorkerPool

            self._pool = WorkerPool(2, memory_mb=memory_mb)

    def warm(self) -> None:
        """Start the worker pool's fork server now, in the background.

        The first analysis a tab asks for then does not pay its start (half a second).
        """
        pool = self._pool
        if pool is None:
            return
        from app.workers import WorkerBusy

        def run() -> None:
            try:
                pool.run(read_motion_job, {}, timeout=30)
            except (WorkerBusy, RuntimeError, ValueError):
                pass

        threading.Thread(target=run, name="warm-workers", daemon=True).start()

    def prefetch(self, models: Callable[[], Iterable[MotionModel]]) -> threading.Thread:
        """Analyse ``models()`` into the cache in the background, one at a time.

        For the presets: their analyses are fixed, so they are computed once when the server
        starts (well under a second in all) and a tab's pick is drawn without waiting. One at a
        time, so a tab's own analysis always finds a free worker; a failure is left for the tab
        that asks (it gets the error then).
        """

        def run() -> None:
            try:
                todo = list(models())
            except Exception:  # noqa: BLE001 - the tab that picks it reports the error
                return
            for model in todo:
                if self.closed:
                    return
                with self._lock:
                    self._pinned.add(model.key)
                try:
                    self.submit(model).result()
                except Exception:  # noqa: BLE001 - same: reported to the tab that asks
                    pass

        thread = threading.Thread(target=run, name="prefetch-analyses", daemon=True)
        thread.start()
        return thread

    def read_typed(self, motion: dict[str, Any]) -> MotionModel:
        """A typed motion, read (matrices built) in a worker process under a time and memory budget.

        The tab's text never reaches the parser in the process that serves every tab; a busy
        pool is answered at once, before anything is read.

        Raises:
            MotionError: bad text (named field), over a limit, busy, or over the budget.
        """
        for key in ("A", "B"):
            value = motion.get(key)
            if isinstance(value, str) and len(value) > MAX_MOTION_TEXT:
                raise MotionError(f"motion of {key} is too long ({len(value)} > {MAX_MOTION_TEXT} characters)", key)
        if self._pool is None:
            out = read_motion_job(motion)
        else:
            from app.workers import WorkerBusy, WorkerDied, WorkerFailed, WorkerTimeout

            try:
                out = self._pool.run(read_motion_job, motion, timeout=self.read_budget)
            except WorkerBusy as e:
                raise MotionError(f"{e}: try again in a moment", "A") from None
            except WorkerTimeout:
                raise MotionError(f"reading the motion took over {self.read_budget:g} s: simplify the expressions", "A") from None
            except (WorkerDied, WorkerFailed) as e:
                raise MotionError(f"the motion could not be read: {e}", "A") from None
        if isinstance(out, tuple):
            raise MotionError(*out)
        return out

    def get(self, key: Hashable) -> AnalysisView | None:
        """The finished analysis of this motion, or None."""
        with self._lock:
            return self._done.get(key)

    def submit(self, model: MotionModel, executor: Executor | None = None) -> Future[AnalysisView]:
        """Start (or join) the analysis of ``model``.

        Returns:
            A future resolving to the :class:`AnalysisView`, or raising :class:`MotionError`
            (field "A": core's message, e.g. a shape that stops being an ellipsoid in I; or
            over the budget).
        """
        with self._lock:
            fut = self._running.get(model.key)
            if fut is not None:
                return fut
            ex = executor or self._executor
            if ex is None:
                ex = self._executor = ThreadPoolExecutor(max_workers=2, thread_name_prefix="analysis")
            fut = ex.submit(self._run, model)
            self._running[model.key] = fut
            return fut

    def _run(self, model: MotionModel) -> AnalysisView:
        t0 = time.perf_counter()
        try:
            result = self._analyse(model)
            view = AnalysisView.of(result, time.perf_counter() - t0)
            with self._lock:
                self._done[model.key] = view
                evictable = [k for k in self._done if k not in self._pinned]  # oldest first
                for old in evictable[: max(0, len(evictable) - self.max_entries)]:
                    self._done.pop(old)
            return view
        finally:
            with self._lock:
                self._running.pop(model.key, None)

    def _analyse(self, model: MotionModel) -> MotionAnalysis:
        args = (model.A, model.B, model.interval)
        try:
            if self._pool is None:
                return analyse_job(*args)
            from app.workers import WorkerBusy, WorkerDied, WorkerFailed, WorkerTimeout

            while True:
                try:
                    return self._pool.run(analyse_job, *args, timeout=self.budget)
                except WorkerBusy:
                    if self._pool.closed:  # the server is stopping
                        raise
                    time.sleep(0.05)  # other tabs' analyses hold the slots: wait our turn
                except WorkerTimeout:
                    raise MotionError(f"the analysis took over {self.budget:g} s and was stopped", "A") from None
                except (WorkerDied, WorkerFailed) as e:
                    raise MotionError(f"the analysis failed: {e}", "A") from None
        except MotionError:
            raise
        except ValueError as e:  # core's message: the motion cannot be analysed on I
            raise MotionError(str(e), "A") from None

    def run(self, fn: Callable[..., T], *args: Any, timeout: float, what: str) -> T:
        """``fn(*args)`` in a worker process under a time and memory budget (here without a pool).

        For work a tab brings that is not a motion (a file of bodies): its ValueError comes back
        as it is; a busy pool, the budget spent, or the worker dying becomes a ValueError that
        says so, naming ``what`` ("reading bodies.csv").
        """
        if self._pool is None:
            return fn(*args)
        from app.workers import WorkerBusy, WorkerDied, WorkerFailed, WorkerTimeout

        try:
            return self._pool.run(fn, *args, timeout=timeout)
        except WorkerBusy as e:
            raise ValueError(f"{e}: try again in a moment") from None
        except WorkerTimeout:
            raise ValueError(f"{what} took over {timeout:g} s and was stopped") from None
        except (WorkerDied, WorkerFailed) as e:  # e.g. "the job ran out of memory (limit 2048 MB)"
            raise ValueError(f"{what} failed: {e}") from None

    def shutdown(self) -> None:
        """Kill running analysis processes."""
        self.closed = True
        if self._pool is not None:
            self._pool.shutdown()
