"""What the user does to the motion: pick a preset, type a motion and analyse it, leave the motion.

A preset (trusted, known to be valid) is shown at once and its analysis arrives within
milliseconds (cached, or run in the warm worker pool). A typed motion is read and analysed in
worker processes first; the tab switches to it only once its analysis exists, so a motion that
cannot be analysed (e.g. not an ellipsoid somewhere in I) leaves the previous scene on screen
with the reason next to the motion field, never a panel waiting forever.
"""

from __future__ import annotations

import time
from concurrent.futures import Future
from typing import TYPE_CHECKING

from ..common.state import SceneConfig, StatusError
from ..common.texts import SHOWN_DIGITS, read_time, time_float
from ..common.threads import later
from .analysis import AnalysisView
from .exact_shapes import exact_shapes_at
from .gui import STATIC
from .motion import MotionError, MotionModel
from .motion_form import form_text
from .panels import analysed_text
from .touch import touch_event, touch_motion

if TYPE_CHECKING:
    from .session_view import SessionView

__all__ = ["MotionControl"]

EDITOR_FIELDS = ("A", "B", "interval")


class MotionControl:
    """Callbacks of the Motion folder and the life cycle of a session's motion."""

    def __init__(self, session: SessionView) -> None:
        self.s = session
        ui = session.ui.motion
        ui.preset.on_update(lambda _ev: self.on_preset())
        ui.analyse.on_click(lambda _ev: self.on_analyse())
        ui.form_analyse.on_click(lambda _ev: self.on_form())
        session.ui.touch.on_click(lambda _ev: self.on_touch())
        self._pending: object = None
        self._then: tuple[float | str | None, int | str | None] = (None, None)
        """Time or event to show once the motion being analysed is known."""
        self._started = 0.0
        self.last_to_picture_s: float | None = None
        """Seconds from the last :meth:`start` to its certified picture sent (the benchmark's)."""

    # ------------------------------------------------------------------ callbacks
    def on_preset(self) -> None:
        """Preset dropdown: load it (or leave the motion for "(static shapes)")."""
        s = self.s
        if s.syncing.active:
            return
        name = str(s.ui.motion.preset.value)
        if name == STATIC:
            with s.lock:
                self.freeze()
                s.refresh()
            return
        if name not in s.ui.motion.presets:  # "(typed motion)", "(Touch …)": the motion shown already
            return
        st = s.state
        s.load(SceneConfig(dim=st.dim, preset=name, gizmos=st.gizmos, show_plots=st.show_plots,
                           separating_plane=st.separating_plane, palette=st.palette))
        s.frame_camera()

    def on_analyse(self) -> None:
        """"Analyse motion": read the typed texts in a worker, analyse, then show."""
        s = self.s
        texts = {k: str(h.value) for k, h in s.ui.motion.fields.items()}
        try:  # typed text is read in a worker process, never in the one serving every tab
            model = s.cache.read_typed(texts)
        except MotionError as e:
            self.show_error(e)
            return
        self.analyse_pending(model)

    def on_touch(self) -> None:
        """"Touch": slide B along the line of centres to the exact external tangency with A."""
        s = self.s
        with s.lock:
            s.state.errors.pop("touch", None)
            self.freeze()  # from a motion: the shapes as their fields show them, exactly
            try:
                texts = touch_motion(s.state.shapes["A"], s.state.shapes["B"])
            except ValueError as e:
                s.field_error("touch", str(e))
                return
        try:  # built and analysed in worker processes (the shapes may carry long exact numbers)
            model = s.cache.read_typed(texts)
        except MotionError as e:
            s.field_error("touch", f"Touch: {e}")
            return
        model.kind = "touch"
        model.description = (
            "Touch: B slides along the line of centres, from A's centre (t = 0) to where it was (t = 1) and "
            "beyond; the event shown is the exact external contact."
        )
        self.analyse_pending(model, event="touch")

    def on_form(self) -> None:
        """"Analyse the form": write the form's motion into the JSON boxes, then analyse them."""
        s = self.s
        ui = s.ui.motion
        try:
            texts = {name: form_text({k: str(h.value) for k, h in fields.items()}) for name, fields in ui.form.items()}
        except ValueError as e:
            s.field_error("form", str(e))
            return
        with s.lock:
            s.state.errors.pop("form", None)
            with s.syncing():
                for name, text in texts.items():
                    ui.fields[name].value = text  # type: ignore[misc]  # writable: viser defines the setter apart from the getter, mypy sees read-only
        self.on_analyse()

    # ------------------------------------------------------------------ life cycle
    def analyse_pending(self, model: MotionModel, *, t: float | str | None = None, event: int | str | None = None) -> None:
        """Analyse ``model`` while the tab keeps showing what it shows; switch when it is done.

        Args:
            model: the motion (read in a worker).
            t: time to show once analysed (a number or exact text; None: the default).
            event: event to show instead (1-based), or "touch": the external tangency
                (:func:`app.scene.pair.touch.touch_event`).
        """
        s = self.s
        with s.lock:
            for key in EDITOR_FIELDS:
                s.state.errors.pop(key, None)
            self._then = (t, event)
            cached = s.cache.get(model.key)
            if cached is not None:
                self.show(model, cached)
                return
            self._analyse(model, switch=True)

    def start(self, model: MotionModel, *, t: float | str | None, event: int | None) -> None:
        """Show a known-valid motion now (a preset, a configuration); its analysis follows.

        Args:
            model: the motion.
            t: time to show (a number, or exact text applied once the analysis is known).
            event: event to show instead (1-based).
        """
        s = self.s
        self._started = time.perf_counter()
        with s.lock:
            st = s.state
            st.motion = model
            st.analysis = None
            st.event = event
            st.t_exact = st.t_text = None
            st.auto_t = t is None and event is None
            self._then = (t, event)
            lo, hi = model.interval_floats
            if isinstance(t, str):
                t = time_float(read_time(t))
            st.t = min(max(float(t), lo), hi) if t is not None else lo + 0.45 * (hi - lo)
            same_views = s.views["A"].dim == model.dim and s.views["A"].drawn
            s.set_dimension(model.dim)
            cached = s.cache.get(model.key)
            if cached is not None:
                self._pending = None
                self._arrived(model, cached)
                return
            # the old picture and readout stay together on screen until the analysis arrives,
            # unless the shapes were rebuilt for another dimension (then draw at once)
            self._analyse(model, switch=False, quiet=same_views)

    QUIET = 0.15
    """Seconds an analysis may take before the tab shows "Analysing…" (the warm pool answers a
    preset within tens of milliseconds: the browser then draws once, the analysed motion)."""

    def _analyse(self, model: MotionModel, *, switch: bool, quiet: bool = False) -> None:
        """Run the analysis (lock held).

        Args:
            model: the motion.
            switch: show the motion only once it is analysed (the tab keeps its scene meanwhile).
            quiet: the picture on screen stays consistent until the analysis arrives (same
                shapes, same readout): show "Analysing…" only if it takes over :attr:`QUIET`.
        """
        s = self.s
        self._pending = model.key
        s.state.analysing = True
        s.state.status = "Analysing the motion (exact)…"
        if quiet:
            later(self.QUIET, self._still_analysing, model.key)
        else:
            s.refresh()
        fut = s.cache.submit(model, s.executor)
        fut.add_done_callback(lambda f: self._analysed(model, f, switch))

    def _still_analysing(self, key: object) -> None:
        s = self.s
        with s.lock:
            if not s.closed and self._pending == key:
                s.refresh()

    def _analysed(self, model: MotionModel, fut: Future[AnalysisView], switch: bool) -> None:
        s = self.s
        with s.lock:
            if s.closed or self._pending != model.key:
                return  # left, or another motion was asked for meanwhile
            self._pending = None
            s.state.analysing = False
            try:
                an = fut.result()
            except Exception as e:  # noqa: BLE001 - shown next to the field, never a crash
                self.show_error(e)
                s.ready.set()
                return
            if switch:
                self.show(model, an)
            else:
                self._arrived(model, an)

    def show(self, model: MotionModel, an: AnalysisView) -> None:
        """Switch the tab to an analysed motion (a typed motion once its analysis exists)."""
        s = self.s
        with s.lock:
            st = s.state
            t, event = self._then
            if event == "touch":
                event = touch_event(an.result.events)
                if event is None:
                    st.errors["touch"] = "Touch: no external contact along the line of centres"
            st.motion = model
            st.analysis = None  # the new motion's arrives below (never the old one with the new motion)
            st.event = event  # type: ignore[assignment]
            st.t_exact = st.t_text = None
            st.auto_t = t is None and event is None
            if isinstance(t, int | float):
                st.t = float(t)
            s.set_dimension(model.dim)
            self._arrived(model, an)

    def _arrived(self, model: MotionModel, an: AnalysisView) -> None:
        """The analysis of the shown motion is known: timeline, t, the picture."""
        s = self.s
        st = s.state
        st.analysis = an
        st.analysing = False
        st.status = analysed_text(an.seconds, len(an.events), len(an.segments), an.result.degrees())
        lo, hi = an.window
        event = st.event
        if event is not None and not 1 <= event <= len(an.events):
            st.errors["t"] = f"there are {len(an.events)} events (α1..α{len(an.events)})"
            event = st.event = None
        if st.auto_t:
            st.t = an.default_t
        elif event is None:
            st.t = min(max(st.t, lo), hi)
        if event is not None:
            st.t = an.events[event - 1].t
        t_text = self._then[0]
        self._then = (None, None)
        if isinstance(t_text, int | float) and not isinstance(t_text, bool) and not lo <= t_text <= hi:
            t_text = repr(float(t_text))  # outside the slider: widened (unbounded I) or refused, never clamped
        if isinstance(t_text, str) and event is None:  # an exact time from a configuration
            error = s.timeline_ctl.apply_text(t_text)
            if error is not None:
                st.errors["t"] = error
        # the picture at once; the panel (event list, sign table, plots: the heavy part for the
        # browser) follows once the browser has had time to draw the certified shapes
        s.refresh(defer=True, panel_delay=s.PICTURE_FIRST)
        self.last_to_picture_s = time.perf_counter() - self._started
        s.frame_camera()
        s.ready.set()

    FROZEN = (
        "Static shapes: the shapes as drawn at t, made exactly the decimals their fields show "
        f"({SHOWN_DIGITS} significant digits); the relation is certified for these numbers."
    )
    """Status after leaving a motion for static shapes (what is then certified)."""

    def freeze(self) -> None:
        """Leave the motion for static shapes: exactly the decimals the Shape fields show.

        The shapes drawn at t are floats (from the float matrices at the float t); they are
        rounded to :data:`~app.scene.common.texts.SHOWN_DIGITS` significant digits and taken as exact
        decimals, so the fields show exactly the numbers whose relation the readout certifies.
        A shape too thin for those digits keeps its floats (the field says "≈").
        """
        s = self.s
        st = s.state
        if st.motion is None:
            return
        exact = exact_shapes_at(st.motion, self.exact_t(), st.shapes)  # a tangency reached stays one
        shapes = {}
        for name, sh in st.shapes.items():
            try:
                shapes[name] = exact[name] if name in exact else sh.rationalised()
            except ValueError:
                shapes[name] = sh
        st.shapes = shapes
        self.leave()
        st.status = self.EXACT if len(exact) == len(shapes) else self.FROZEN

    EXACT = "Static shapes: exactly the shapes of the motion at the t shown; the relation is certified for them."
    """Status after leaving a motion whose shapes at t have a short exact form (:mod:`app.scene.pair.exact_shapes`)."""

    def exact_t(self) -> object:
        """The time shown, exactly: the event's, the typed one, or the float's binary value (or its end of I)."""
        st = self.s.state
        an = st.analysis
        if st.event is not None and an is not None:
            return an.events[st.event - 1].event.time
        if st.t_exact is not None:
            return st.t_exact
        return an.inside(st.t) if an is not None else st.t

    def leave(self) -> None:
        """Turn the scene static (a drag, a typed shape, "(static shapes)").

        The shapes stay where they are drawn.
        """
        s = self.s
        st = s.state
        self._pending = None
        st.motion = None
        st.analysis = None
        st.analysing = False
        st.event = None
        st.t_exact = st.t_text = None
        for key in (*EDITOR_FIELDS, "t"):
            st.errors.pop(key, None)
        st.status = "Static shapes: drag them or type their parameters."
        s.timeline_ctl.stop_playing()

    def show_error(self, e: Exception) -> None:
        """Show why a motion was not read or analysed, next to its field."""
        s = self.s
        with s.lock:
            st = s.state
            field = getattr(e, "field", None) or "A"
            for key in EDITOR_FIELDS:
                st.errors.pop(key, None)
            st.errors[field] = str(e)
            st.analysing = False
            st.status = StatusError("the motion was not analysed: see the message next to its field")
            s.refresh()
