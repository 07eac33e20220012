"""Motions in the scene: loading presets / typed motions, running the exact analysis off the GUI
thread (cached by motion and interval), and the views the timeline draws from.

This module adapts ``core``'s motion analysis (``core.analyse``, ``core.presets``) to what the
scene needs; it does no maths of its own beyond float evaluation for drawing.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Hashable
from concurrent.futures import Executor, Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "MotionError",
    "MotionModel",
    "EventView",
    "AnalysisView",
    "AnalysisCache",
    "list_presets",
    "load_motion",
]


class MotionError(ValueError):
    """A typed motion or interval could not be read; ``field`` names the GUI field."""

    def __init__(self, message: str, field: str = "A") -> None:
        super().__init__(message)
        self.field = field


def _core_motion() -> Any:
    """The motion API of ``core`` (None while it is not available)."""
    try:
        import core.presets as presets  # noqa: F401
        from core import analyse  # noqa: F401
    except ImportError:
        return None
    import core.presets as presets

    return presets


def list_presets() -> list[str]:
    """Names of the motion presets (the paper's Examples 29-33 and the 2D presets)."""
    presets = _core_motion()
    if presets is None:
        return []
    return list(presets.list_presets())


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
    _readout_cache: dict[Any, str] = field(default_factory=dict)

    @property
    def events_t(self) -> list[float]:
        """Event times (floats)."""
        return [e.t for e in self.events]

    def relation_at(self, t: float) -> str:
        """Certified relation at the exact value of the float t."""
        if self.relation_fn is not None:
            return str(self.relation_fn(t))
        for lo, hi, rel in self.segments:
            if lo <= t <= hi:
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


class MotionModel:
    """A loaded motion: float evaluation for drawing, the cache key, the editor texts."""

    def __init__(self, motion: Any, *, preset: str | None, description: str, texts: dict[str, str], dim: int) -> None:
        self.motion = motion
        self.preset = preset
        self.description = description
        self._texts = texts
        self.dim = dim
        lo, hi = motion.interval
        self.interval_floats = (float(lo), float(hi))
        self.default_t = float(getattr(motion, "default_t", None) or (self.interval_floats[0] + 0.45 * (self.interval_floats[1] - self.interval_floats[0])))
        self.key: Hashable = (texts.get("A"), texts.get("B"), texts.get("interval"), dim)

    def texts(self) -> dict[str, str]:
        """Editor texts: "A", "B" (motions) and "interval"."""
        return dict(self._texts)

    def shapes_at(self, t: float) -> tuple[Any, Any]:
        """ShapeStates of A and B at the float t (drawing only)."""
        from .state import ShapeState

        out = []
        for p in self.motion.shapes_at(t):
            out.append(ShapeState(tuple(p.center), tuple(p.semi_axes), tuple(p.orientation)))
        return out[0], out[1]

    def float_matrices(self, t: float) -> tuple[Any, Any]:
        """Float matrices A(t), B(t) (display only)."""
        return self.motion.matrices_at(t)

    def extent_points(self) -> np.ndarray:
        """Points spanning where the shapes go over I (for framing the camera)."""
        lo, hi = self.interval_floats
        pts = []
        for t in np.linspace(lo, hi, 9):
            for sh in self.shapes_at(float(t)):
                pos, _, scale = sh.float_pose()
                r = max(scale[:2] if self.dim == 2 else scale)
                pts.append(np.array(pos) + r)
                pts.append(np.array(pos) - r)
        return np.array(pts)


def load_motion(*, preset: str | None, motion: dict[str, Any] | None, dim: int) -> MotionModel:
    """Load a preset by name or a typed motion ({"A": text, "B": text, "interval": text}).

    Raises:
        MotionError: unknown preset, or a typed expression/interval core cannot read (the
            error names the field it belongs to).
    """
    presets = _core_motion()
    if presets is None:
        raise MotionError("motion analysis is not available in this version of core", "A")
    return _load_with_core(presets, preset=preset, motion=motion, dim=dim)


def _load_with_core(presets: Any, *, preset: str | None, motion: dict[str, Any] | None, dim: int) -> MotionModel:
    raise MotionError("motion analysis adapter not wired yet", "A")


class AnalysisCache:
    """Analyses by motion key, shared by the tabs of one server; each runs once, off the GUI thread."""

    def __init__(self, executor: Executor | None = None) -> None:
        self._executor = executor
        self._done: dict[Hashable, AnalysisView] = {}
        self._running: dict[Hashable, Future[AnalysisView]] = {}
        self._lock = threading.Lock()

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
        try:
            view = _analyse(model)
            view.seconds = time.perf_counter() - t0
            with self._lock:
                self._done[model.key] = view
            return view
        finally:
            with self._lock:
                self._running.pop(model.key, None)


def _analyse(model: MotionModel) -> AnalysisView:
    raise MotionError("motion analysis adapter not wired yet", "A")
