"""Motions in the scene: loading presets / typed motions, running the exact analysis off the GUI
thread (cached by motion and interval), and the views the timeline draws from.

This module adapts ``core``'s motion analysis (``core.analyse``, ``core.moving.presets``) to what the
scene needs; it does no maths of its own beyond float evaluation for drawing.
"""

from __future__ import annotations

import json
import math
import threading
import time
from collections.abc import Hashable
from concurrent.futures import Executor, Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from core.shapes.limits import SERVER, Limits
from core.shapes.quadrics import axes_from_quadric

from .instant import SIGN_VALUE, RelationLookup, explain_at

__all__ = [
    "MotionError",
    "MotionModel",
    "EventView",
    "AnalysisView",
    "AnalysisCache",
    "list_presets",
    "load_motion",
    "read_motion_job",
    "MAX_MOTION_TEXT",
]


class MotionError(ValueError):
    """A typed motion or interval could not be read; ``field`` names the GUI field."""

    def __init__(self, message: str, field: str = "A") -> None:
        super().__init__(message)
        self.field = field


def _core_motion() -> Any:
    """``core.moving.presets`` when the motion API is available, else None."""
    try:
        import core.moving.analysis  # noqa: F401
        import core.moving.presets as presets
    except ImportError:
        return None
    return presets


def list_presets() -> list[str]:
    """Names of the motion presets (the paper's Examples 29-33 and the 2D presets)."""
    presets = _core_motion()
    if presets is None:
        return []
    return list(presets.preset_names())


@dataclass
class EventView:
    """One event of the analysis, for display."""

    t: float
    """Float approximation (display and slider position only)."""
    text: str
    """Decimal value with the certified digits, as core prints it."""
    relation: str
    """Relation at the event itself."""
    kind: str
    """What happens there (e.g. "touch", "change")."""


@dataclass
class AnalysisView:
    """What the timeline draws: events, intervals, sign table, plot samples, relation lookup."""

    degree: int
    events: list[EventView]
    segments: list[tuple[float, float, str]]
    """(lo, hi, relation) of the open intervals between events (floats)."""
    rows: list[dict[str, Any]]
    """Sign table rows (see :func:`app.scene.panels.sign_table_markdown`)."""
    samples_t: np.ndarray
    samples: dict[str, np.ndarray]
    """"a0".."a4", "s0", "s1", "s10" sampled at ``samples_t``."""
    seconds: float
    """Wall time of the analysis."""
    relation_fn: Any = None
    """Callable t -> relation name (certified; core's ``relation_at``)."""
    explain_fn: Any = None
    """Callable (t, event) -> explanation dict, or None."""
    window: tuple[float, float] = (0.0, 1.0)
    """Slider window: I when finite, else around the events."""
    default_t: float | None = None
    """Suggested start: just before the first event."""
    degrees: dict[str, Any] = field(default_factory=dict)
    """Degrees in t (core ``MotionAnalysis.degrees``: hat forms and the paper's s_j)."""
    _readout_cache: dict[Any, str] = field(default_factory=dict)

    @property
    def events_t(self) -> list[float]:
        """Event times (floats)."""
        return [e.t for e in self.events]

    def relation_at(self, t: Any) -> str:
        """Certified relation at the exact value of t (a float's binary value, or a rational)."""
        if self.relation_fn is not None:
            return str(self.relation_fn(t))
        for lo, hi, rel in self.segments:
            if lo <= float(t) <= hi:
                return rel
        return self.segments[-1][2]

    def coeff_series(self) -> list[tuple[str, np.ndarray]]:
        """(label, samples) of a_n..a_0."""
        return [(f"a{i}", self.samples[f"a{i}"]) for i in range(self.degree, -1, -1) if f"a{i}" in self.samples]

    def subres_series(self) -> list[tuple[str, np.ndarray]]:
        """(label, samples) of s0, s1, s1,0."""
        return [(k.replace("s10", "s1,0"), self.samples[k]) for k in ("s0", "s1", "s10") if k in self.samples]

    def explanation_at(self, t: float, event: int | None) -> dict[str, Any] | None:
        """Explanation dict at t (or at the event), when core can give it."""
        if self.explain_fn is None:
            return None
        return self.explain_fn(t, event)

    def readout(self, t: float, event: int | None, where: str) -> str:
        """Markdown readout at t (cached per (t, event): scrubbing back is free)."""
        from .panels import readout_markdown

        key = (t, event)
        text = self._readout_cache.get(key)
        if text is None:
            expl = self.explanation_at(t, event)
            if expl is None:
                text = readout_markdown(
                    {"n": self.degree, "relation": self.relation_at(t), "certified_by": "exact",
                     "coefficients": [], "var": 0, "rule_text": ""},
                    where=where,
                )
            else:
                text = readout_markdown(expl, where=where)
            if len(self._readout_cache) > 2000:
                self._readout_cache.clear()
            self._readout_cache[key] = text
        return text


def _pose_from_matrix(M: np.ndarray) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
    """(centre, semi-axes, orientation) of a float ellipse/ellipsoid matrix (drawing only).

    2D orientation is an angle, 3D a quaternion wxyz. Raises ValueError when the float matrix
    is not an ellipse/ellipsoid.
    """
    p = axes_from_quadric(M, validate=False)
    return p.center, p.semi_axes, p.orientation


class MotionModel:
    """A loaded motion: float evaluation for drawing, the cache key, the editor texts.

    Args:
        A, B: ``core.moving.motions.Motion`` of each shape.
        interval: (lo, hi) exact ends as core reads them (None = infinite).
        preset: preset name, or None for a typed motion.
        description: one line shown under the dropdown.
        texts: editor texts {"A", "B", "interval"}.
    """

    def __init__(self, A: Any, B: Any, interval: tuple[Any, Any], *, preset: str | None, description: str, texts: dict[str, str]) -> None:
        self.A, self.B = A, B
        self.interval = interval
        self.preset = preset
        self.description = description
        self._texts = texts
        self.dim = int(A.dim)
        lo, hi = interval
        flo = _to_float(lo)
        fhi = _to_float(hi)
        if flo is None and fhi is None:
            flo, fhi = -2.0, 2.0
        elif flo is None:
            flo = fhi - 4.0  # type: ignore[operator]
        elif fhi is None:
            fhi = flo + 4.0
        self.interval_floats: tuple[float, float] = (float(flo), float(fhi))  # type: ignore[arg-type]
        """Window of the slider (I itself when finite; around the events once analysed)."""
        self.key: Hashable = (json.dumps([A.source, B.source], sort_keys=True, default=str), str(lo), str(hi))
        self._default_t: float | None = None
        self._last_matrices: tuple[float, tuple[np.ndarray, np.ndarray]] | None = None

    @property
    def default_t(self) -> float:
        """Where the timeline starts: just before the first event (else 45 % into the window)."""
        if self._default_t is not None:
            return self._default_t
        lo, hi = self.interval_floats
        return lo + 0.45 * (hi - lo)

    def texts(self) -> dict[str, str]:
        """Editor texts: "A", "B" (motions, JSON form of core.moving.motions) and "interval"."""
        return dict(self._texts)

    def float_matrices(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Float matrices A(t), B(t) (display only).

        The last t is remembered: one t-step asks for them to draw, to place the contact point
        and for the readout.
        """
        from core.moving.motions import matrix_at

        last = self._last_matrices
        if last is not None and last[0] == t:
            return last[1]
        mats = (matrix_at(self.A, t), matrix_at(self.B, t))
        for M in mats:
            M.flags.writeable = False  # shared by the callers of this t
        self._last_matrices = (t, mats)
        return mats

    def shapes_at(self, t: float) -> tuple[Any, Any]:
        """ShapeStates of A and B at the float t (drawing only)."""
        from .state import ShapeState

        out = []
        for M in self.float_matrices(t):
            c, r, o = _pose_from_matrix(M)
            out.append(ShapeState(c, r, o))
        return out[0], out[1]

    def extent_points(self, around: float | None = None, span: float = 0.1) -> np.ndarray:
        """Points spanning where the shapes go (for framing the camera).

        Args:
            around: frame the motion on ``span`` of the window centred here (None: all of it;
                cubic motions like Example 30 leave the scene far away at the window's ends).
            span: fraction of the window.
        """
        lo, hi = self.interval_floats
        if around is not None:
            half = 0.5 * span * (hi - lo)
            lo, hi = max(lo, around - half), min(hi, around + half)
        pts = []
        for t in np.linspace(lo, hi, 9):
            try:
                shapes = self.shapes_at(float(t))
            except (ValueError, np.linalg.LinAlgError):
                continue
            for sh in shapes:
                pos, _, scale = sh.float_pose()
                rad = max(scale[:2] if self.dim == 2 else scale)
                pts.append(np.array(pos) + rad)
                pts.append(np.array(pos) - rad)
        return np.array(pts) if pts else np.zeros((1, 3))


def _to_float(x: Any) -> float | None:
    if x is None:
        return None
    from core.shapes.numbers import to_fmpq

    q = to_fmpq(x)
    return float(q.p) / float(q.q)


def _interval_text(iv: Any) -> str:
    lo, hi = iv
    return f"{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}"


MAX_MOTION_TEXT = 32 * (SERVER.expression_chars or 2000)
"""Longest motion text (JSON) typed in one field: room for every entry of a motion at the
longest expression length of :data:`core.shapes.limits.SERVER`."""


def _read_interval(text: str, limits: Limits | None = None) -> tuple[Any, Any]:
    from core.shapes.numbers import parse_number

    parts = [p.strip() for p in str(text).replace(";", ",").split(",")]
    if len(parts) != 2 or not all(parts):
        raise MotionError("interval: expected 'lo, hi' (use -inf / inf for an open end)", "interval")
    out: list[Any] = []
    floats: list[float] = []
    for p, infs in zip(parts, (("-inf", "none"), ("inf", "+inf", "none")), strict=True):
        if p.lower() in infs:
            out.append(None)
            continue
        try:
            q = parse_number(p, limits)
        except ValueError as e:
            raise MotionError(f"interval: {e}", "interval") from None
        try:
            floats.append(int(q.p) / int(q.q))  # correctly rounded, 0.0 for a tiny value
        except OverflowError:
            floats.append(math.inf)
        if not math.isfinite(floats[-1]):
            raise MotionError(f"interval: {p[:40]} is beyond the range of the time slider (|t| < 1.8e308)", "interval")
        out.append((p, q))
    if out[0] is not None and out[1] is not None:
        if out[0][1] >= out[1][1]:
            raise MotionError("interval: need lo < hi", "interval")
        if floats[0] >= floats[1]:
            raise MotionError("interval: lo and hi are too close for the time slider (the same as floats)", "interval")
    return tuple(None if e is None else e[0] for e in out)  # type: ignore[return-value]


def load_motion(*, preset: str | None, motion: dict[str, Any] | None, dim: int, limits: Limits | None = None) -> MotionModel:
    """Load a preset by name or a typed motion ({"A": text/dict, "B": text/dict, "interval": text}).

    Args:
        preset: a preset name (when ``motion`` is None).
        motion: the typed texts {"A", "B", "interval"} (or dicts).
        dim: dimension shown now (the motion's own wins).
        limits: size limits of the text (:mod:`core.shapes.limits`); typed motions from a browser are
            read with :data:`core.shapes.limits.SERVER` in a worker process
            (:meth:`AnalysisCache.read_typed`).

    Raises:
        MotionError: unknown preset, or a typed motion/interval core cannot read (the error
            names the field it belongs to: "A", "B" or "interval").
    """
    presets = _core_motion()
    if presets is None:
        raise MotionError("motion analysis is not available in this version of core", "A")
    from core.moving.motions import motion_from_dict

    if motion is None:
        if preset is None:
            raise MotionError("no motion given", "A")
        try:
            p = presets.preset(preset)
        except ValueError as e:
            raise MotionError(str(e), "A") from None
        raw: dict[str, Any] = {"A": p["A"], "B": p["B"], "interval": _interval_text(p["interval"])}
        description = p.get("description", "")
    else:
        raw = dict(motion)
        description = "Typed motion."
    parsed: dict[str, Any] = {}
    texts: dict[str, str] = {}
    for key in ("A", "B"):
        value = raw.get(key)
        if value is None or value == "":
            raise MotionError(f"motion of {key} is missing", key)
        if isinstance(value, str):
            texts[key] = value
            if len(value) > MAX_MOTION_TEXT:
                raise MotionError(f"motion of {key} is too long ({len(value)} > {MAX_MOTION_TEXT} characters)", key)
            try:
                value = json.loads(value)
            except json.JSONDecodeError as e:
                raise MotionError(f"motion of {key} is not valid JSON: {e.msg} (line {e.lineno}, column {e.colno})", key) from None
            except RecursionError:
                raise MotionError(f"motion of {key} is nested too deeply", key) from None
        else:
            texts[key] = json.dumps(value)
        try:
            parsed[key] = motion_from_dict(value, limits=limits)
        except ValueError as e:
            raise MotionError(f"motion of {key}: {e}", key) from None
    iv = raw.get("interval", "-inf, inf")
    if not isinstance(iv, str):
        iv = _interval_text(iv)
    texts["interval"] = iv
    interval = _read_interval(iv, limits)
    if parsed["A"].dim != parsed["B"].dim:
        raise MotionError("A and B must both be ellipses (2D) or both ellipsoids (3D)", "B")
    return MotionModel(
        parsed["A"], parsed["B"], interval, preset=preset if motion is None else None, description=description, texts=texts
    )


def read_motion_job(motion: dict[str, Any], dim: int) -> MotionModel | tuple[str, str]:
    """Read a typed motion under :data:`core.shapes.limits.SERVER` (runs in a worker process).

    Returns:
        The loaded model (it pickles with its exact matrices), or (message, field) for a
        MotionError (an exception would lose its field on the way back).
    """
    try:
        return load_motion(preset=None, motion=motion, dim=dim, limits=SERVER)
    except MotionError as e:
        return str(e), e.field


class AnalysisCache:
    """Analyses by motion key, shared by the tabs of one server; each runs once, off the GUI thread.

    With ``processes=True`` each analysis runs in a child process (``app.workers.WorkerPool``:
    forkserver, killed after ``budget`` seconds), so a long exact computation never holds the
    GIL of the process serving the tabs; results come back as plain data. Otherwise it runs in
    a worker thread of ``executor``.
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
        self.read_budget = read_budget
        """Seconds a worker may spend reading one typed motion."""
        self.max_entries = 64
        """Analyses kept (the oldest is dropped first)."""
        self._pool: Any = None
        if processes:
            try:
                from app.workers import WorkerPool

                self._pool = WorkerPool(2, memory_mb=memory_mb)
            except ImportError:  # API package absent: threads only
                self._pool = None

    def read_typed(self, motion: dict[str, Any], dim: int) -> MotionModel:
        """A typed motion, read in a worker process under a time and memory budget.

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
            out = read_motion_job(motion, dim)
        else:
            from app.workers import WorkerBusy, WorkerDied, WorkerFailed, WorkerTimeout

            try:
                out = self._pool.run(read_motion_job, motion, dim, timeout=self.read_budget)
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
        """Start (or join) the analysis of ``model``; the future resolves to an AnalysisView."""
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
        args = (model.A.source, model.B.source, model.interval)
        try:
            if self._pool is not None:
                from app.workers import WorkerBusy

                while True:
                    try:
                        plain = self._pool.run(analyse_plain, *args, timeout=self.budget)
                        break
                    except WorkerBusy:
                        if self._pool.closed:  # the server is stopping
                            raise
                        time.sleep(0.2)  # other tabs' analyses hold the slots: wait our turn
            else:
                plain = analyse_plain(*args)
            view = _view_from_plain(model, plain)
            view.seconds = time.perf_counter() - t0
            with self._lock:
                self._done[model.key] = view
                while len(self._done) > self.max_entries:  # oldest first (dicts keep order)
                    self._done.pop(next(iter(self._done)))
            return view
        finally:
            with self._lock:
                self._running.pop(model.key, None)

    def shutdown(self) -> None:
        """Kill running analysis processes."""
        if self._pool is not None:
            self._pool.shutdown()


PLOT_SAMPLES = 300
"""Samples per curve in the plots (resampled only when the analysis changes)."""


def analyse_plain(A_source: Any, B_source: Any, interval: tuple[Any, Any], digits: int = 20) -> dict[str, Any]:
    """Run ``core.analyse`` and return plain, picklable data (runs in a worker process).

    Returns:
        {"result": MotionAnalysis.to_dict(polynomials=False), "samples": .samples(PLOT_SAMPLES),
        "polys": .polynomials()} (the exact a_i, ŝ_j: the readout evaluates them at t).
    """
    from core.moving.analysis import analyse
    from core.moving.motions import motion_from_dict

    A, B = (motion_from_dict(m, limits=SERVER) for m in (A_source, B_source))
    an = analyse(A, B, interval, digits=digits)
    return {
        "result": an.to_dict(polynomials=False),
        "samples": an.samples(PLOT_SAMPLES),
        "polys": an.polynomials(),
        "degrees": an.degrees(),
    }


def _view_from_plain(model: MotionModel, plain: dict[str, Any]) -> AnalysisView:
    """Turn the worker's plain data into what the timeline draws."""
    result, samples = plain["result"], plain["samples"]
    ts = np.asarray(samples["t"], dtype=float)
    window = (float(ts[0]), float(ts[-1]))
    model.interval_floats = window
    n = int(result["dimension"]) + 1
    series: dict[str, np.ndarray] = {f"a{i}": np.asarray(v, dtype=float) for i, v in enumerate(samples["a"])}
    for k in ("s0", "s1", "s10"):
        series[k] = np.asarray(samples[k], dtype=float)
    events = [
        EventView(t=float(e["approx"]), text=e["value"], relation=e["relation"], kind=e["kind"]) for e in result["events"]
    ]
    lo, hi = window
    segs: list[tuple[float, float, str]] = []
    for iv in result["intervals"]:
        a = lo if iv["lo"] is None else max(lo, float(iv["lo"]["approx"]))
        b = hi if iv["hi"] is None else min(hi, float(iv["hi"]["approx"]))
        if b > a:
            segs.append((a, b, iv["relation"]))
    ev_by_value = {e["value"]: k for k, e in enumerate(result["events"], start=1)}
    rows = []
    for r in result["sign_table"]:
        if r["where"] == "point":
            k = ev_by_value.get(r["t"])
            label = f"α{k} ≈ {_short(r['t'])}" if k else f"root ≈ {_short(r['t'])}"
        else:
            label = f"t = {_short_rational(r['t'])}"
        signs = {f"a{n - i}": SIGN_VALUE[x] for i, x in enumerate(r["a"])}
        signs.update(s0=SIGN_VALUE[r["s0"]], s1=SIGN_VALUE[r["s1"]], s10=SIGN_VALUE[r["s10"]])
        rows.append({"where": label, "signs": signs, "var": r["var"], "relation": r["relation"]})
    default_t = None
    inner = [e.t for e in events if lo < e.t < hi]
    if inner:
        default_t = max(lo, inner[0] - 0.03 * (hi - lo))
    model._default_t = default_t if model._default_t is None else model._default_t
    lookup = RelationLookup(result, plain["polys"])
    return AnalysisView(
        degree=n,
        events=events,
        segments=segs,
        rows=rows,
        samples_t=ts,
        samples=series,
        seconds=0.0,
        relation_fn=lookup,
        explain_fn=lambda t, event: explain_at(model, result, plain["polys"], t, event),
        window=window,
        default_t=default_t,
        degrees=dict(plain.get("degrees") or {}),
    )


def _short(decimal: str) -> str:
    return decimal if len(decimal) <= 12 else decimal[:12] + "…"


def _short_rational(text: str) -> str:
    if len(text) <= 10:
        return text
    from core.shapes.numbers import to_fmpq

    q = to_fmpq(text)
    return f"{float(q.p) / float(q.q):.6g}"
