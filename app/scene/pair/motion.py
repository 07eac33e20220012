"""A motion loaded in the scene: the two moving shapes, the interval, the editor texts.

:func:`load_motion` reads a preset by name or typed text (the JSON form of
:mod:`core.moving.motions`); :class:`MotionModel` evaluates the float matrices A(t), B(t) for
drawing only (a float never decides a relation: the analysis does,
:mod:`app.scene.pair.analysis`). The text is read by core's readers (one grammar for the scene, the
API and the library: :func:`core.moving.motions.read_motion`, :func:`core.moving.motions.read_interval`).
Imports only ``core`` and the scene's state: worker processes load it (:func:`read_motion_job`, the
scene's job, lives here beside the model it builds).
"""

from __future__ import annotations

import json
import math
from collections.abc import Hashable
from typing import Any

import numpy as np

from core.moving.motions import Motion, matrix_at, read_motion
from core.moving.motions import read_interval as read_exact_interval
from core.shapes.limits import SERVER, Limits
from core.shapes.numbers import to_fmpq
from core.shapes.quadrics import axes_from_quadric

from ..common.state import ShapeState

__all__ = ["MotionError", "MotionModel", "list_presets", "load_motion", "read_motion_job", "MAX_MOTION_TEXT"]

MAX_MOTION_TEXT = 32 * (SERVER.expression_chars or 2000)
"""Longest motion text (JSON) typed in one field: room for every entry of a motion at the
longest expression length of :data:`core.shapes.limits.SERVER`."""


class MotionError(ValueError):
    """A typed motion or interval could not be read, or not analysed; ``field`` names the GUI field."""

    def __init__(self, message: str, field: str = "A") -> None:
        super().__init__(message)
        self.field = field


def list_presets() -> list[str]:
    """Names of the motion presets (the paper's Examples 29-33 and the 2D presets)."""
    from core.moving.presets import preset_names

    return list(preset_names())


class MotionModel:
    """A loaded motion: what it is (exact, :class:`core.moving.motions.Motion`) and how to draw it.

    Args:
        A: motion of shape A.
        B: motion of shape B.
        interval: (lo, hi) exact end texts as typed (None = infinite).
        preset: preset name, or None for a typed motion.
        description: one line shown under the dropdown.
        texts: editor texts {"A", "B", "interval"}.
    """

    def __init__(
        self, A: Motion, B: Motion, interval: tuple[str | None, str | None], *, preset: str | None, description: str, texts: dict[str, str]
    ) -> None:
        self.A, self.B = A, B
        self.interval = interval
        self.preset = preset
        self.kind = "preset" if preset is not None else "typed"
        """"preset", "typed" (editor, form, link) or "touch" (set by "Touch: slide B to A")."""
        self.description = description
        self._texts = dict(texts)
        self.dim = int(A.dim)
        lo, hi = (None if e is None else _to_float(e) for e in interval)
        if lo is None and hi is None:
            lo, hi = -2.0, 2.0
        elif lo is None:
            lo = hi - 4.0  # type: ignore[operator]
        elif hi is None:
            hi = lo + 4.0
        self.interval_floats: tuple[float, float] = (float(lo), float(hi))  # type: ignore[arg-type]
        """I as floats (a guess around its finite end when it is unbounded: the analysis gives the
        window of the slider, :attr:`app.scene.pair.analysis.AnalysisView.window`)."""
        self.key: Hashable = (json.dumps([A.source, B.source], sort_keys=True, default=str), str(interval[0]), str(interval[1]))
        """Cache key of the analysis: the motion and the interval."""
        self._last: tuple[float, tuple[np.ndarray, np.ndarray]] | None = None

    def texts(self) -> dict[str, str]:
        """Editor texts: "A", "B" (motions, JSON form of core.moving.motions) and "interval"."""
        return dict(self._texts)

    def float_matrices(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Float matrices A(t), B(t) (display only).

        Read-only arrays; the last t is remembered: one t-step asks for them to draw, for the
        contact point and for the plane.
        """
        last = self._last
        if last is not None and last[0] == t:
            return last[1]
        mats = (matrix_at(self.A, t), matrix_at(self.B, t))
        for M in mats:
            M.flags.writeable = False
        self._last = (t, mats)
        return mats

    def shapes_at(self, t: float) -> tuple[ShapeState, ShapeState]:
        """Float ShapeStates of A and B at t (drawing only).

        Raises:
            ValueError, ArithmeticError, numpy.linalg.LinAlgError: the float matrices are not
                ellipses/ellipsoids at t (e.g. extreme coefficients).
        """
        out = []
        for M in self.float_matrices(t):
            p = axes_from_quadric(M, validate=False)
            out.append(ShapeState(tuple(p.center), tuple(p.semi_axes), tuple(p.orientation)))
        return out[0], out[1]

    def exact_matrix_text(self, name: str, t: Any) -> str:
        """The exact matrix of shape ``name`` at the exact time t, as text to copy.

        t rational (a float is its binary value): each entry exactly, "p/q" or "(a + b*sqrt(d))/c"
        over Q(√d). t algebraic (an event, a closed form): the entries as functions of t with the
        exact definition of t. Rows separated by ";" (the Matrix field's form).
        """
        from core.algebra.algebraic import RealAlgebraic
        from core.algebra.closedform import closed_form, polynomial_text

        rows = getattr(self, name).matrix()
        if isinstance(t, RealAlgebraic) and t.value is None:
            entries = "; ".join(", ".join(str(e) for e in row) for row in rows)
            definition = closed_form(t) or polynomial_text(t)
            return f"[{entries}] at t = {definition}"
        tq = to_fmpq(t.value if isinstance(t, RealAlgebraic) else t)
        out = []
        for row in rows:
            cells = []
            for e in row:
                den = e.den(tq)
                a, b = e.num.at(tq)
                cells.append(str(a / den) if b == 0 else f"({a / den} + ({b / den})*sqrt({e.num.d}))")
            out.append(", ".join(cells))
        return "; ".join(out)

    def extent_points(self, window: tuple[float, float]) -> np.ndarray:
        """Points spanning where the shapes go on ``window`` (for framing the camera), (k, 3)."""
        pts = []
        for t in np.linspace(window[0], window[1], 9):
            try:
                shapes = self.shapes_at(float(t))
            except (ValueError, ArithmeticError, np.linalg.LinAlgError):
                continue
            for sh in shapes:
                pos, _, scale = sh.float_pose()
                rad = max(scale[:2] if self.dim == 2 else scale)
                pts.append(np.array(pos) + rad)
                pts.append(np.array(pos) - rad)
        return np.array(pts) if pts else np.zeros((1, 3))


def _to_float(x: Any) -> float:
    q = to_fmpq(x)
    try:
        return int(q.p) / int(q.q)
    except OverflowError:
        return math.inf if q > 0 else -math.inf


def _interval_text(iv: Any) -> str:
    lo, hi = iv
    return f"{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}"


def read_interval(text: str, limits: Limits | None = None) -> tuple[str | None, str | None]:
    """I from "lo, hi": the end texts, checked, and drawable on the time slider.

    The grammar is core's (:func:`core.moving.motions.read_interval`): an open end is "none",
    "-inf"/"inf" or "-infinity"/"infinity" (on its side); a finite end is a number string.

    Raises:
        MotionError: (field "interval") unreadable, lo >= hi, or beyond the range of the slider.

    Examples:
        >>> read_interval("0, 1/2"), read_interval("-inf; 3"), read_interval("none, Infinity")
        (('0', '1/2'), (None, '3'), (None, None))
        >>> read_interval("1, 1")
        Traceback (most recent call last):
        ...
        app.scene.pair.motion.MotionError: empty interval: need lo < hi, got [1, 1]
    """
    try:
        ends = read_exact_interval(str(text), limits)
    except ValueError as e:
        raise MotionError(str(e), "interval") from None
    parts = [p.strip() for p in str(text).replace(";", ",").split(",")]  # the texts as typed (two: read above)
    floats = [None if q is None else _to_float(q) for q in ends]
    for p, f in zip(parts, floats, strict=True):
        if f is not None and not math.isfinite(f):
            raise MotionError(f"interval: {p[:40]} is beyond the range of the time slider (|t| < 1.8e308)", "interval")
    if floats[0] is not None and floats[1] is not None and floats[0] >= floats[1]:
        raise MotionError("interval: lo and hi are too close for the time slider (the same as floats)", "interval")
    return tuple(None if q is None else p for p, q in zip(parts, ends, strict=True))  # type: ignore[return-value]


def load_motion(*, preset: str | None, motion: dict[str, Any] | None, limits: Limits | None = None) -> MotionModel:
    """Load a preset by name or a typed motion ({"A": text/dict, "B": text/dict, "interval": text}).

    Args:
        preset: a preset name (when ``motion`` is None).
        motion: the typed texts {"A", "B", "interval"} (or dicts).
        limits: size limits of the text (:mod:`core.shapes.limits`); typed motions from a browser
            are read with :data:`core.shapes.limits.SERVER` in a worker process
            (:func:`read_motion_job`).

    Raises:
        MotionError: unknown preset, or a typed motion/interval core cannot read (the error
            names the field it belongs to: "A", "B" or "interval").
    """
    from core.moving.presets import preset as preset_named

    if motion is None:
        if preset is None:
            raise MotionError("no motion given", "A")
        try:
            p = preset_named(preset)
        except ValueError as e:
            raise MotionError(str(e), "A") from None
        raw: dict[str, Any] = {"A": p["A"], "B": p["B"], "interval": _interval_text(p["interval"])}
        from .preset_notes import preset_notes

        description = p.get("description", "") + preset_notes(preset)
    else:
        raw = dict(motion)
        description = "Typed motion."
    parsed: dict[str, Motion] = {}
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
            parsed[key] = read_motion(value, limits=limits)  # the exact matrix too: each expression parsed once
        except ValueError as e:
            raise MotionError(f"motion of {key}: {e}", key) from None
    iv = raw.get("interval", "-inf, inf")
    if not isinstance(iv, str):
        iv = _interval_text(iv)
    texts["interval"] = iv
    interval = read_interval(iv, limits)
    if parsed["A"].dim != parsed["B"].dim:
        raise MotionError("A and B must both be ellipses (2D) or both ellipsoids (3D)", "B")
    return MotionModel(
        parsed["A"], parsed["B"], interval, preset=preset if motion is None else None, description=description, texts=texts
    )


def read_motion_job(motion: dict[str, Any]) -> MotionModel | tuple[str, str]:
    """Read a scene's typed motion under :data:`core.shapes.limits.SERVER` and build its exact matrices.

    The scene's worker job (module-level: it pickles by reference to :class:`app.workers.WorkerPool`).

    Returns:
        The loaded model (it pickles with its exact matrices), or (message, field) for a
        :class:`MotionError` (an exception would lose its field on the way back).
    """
    try:
        return load_motion(preset=None, motion=motion, limits=SERVER)
    except MotionError as e:
        return str(e), e.field
