"""The motion panel of a tab: preset dropdown, motion editor with errors next to the fields,
analysis off the GUI thread (cached by motion and interval), events and sign table.

Mixed into :class:`app.scene.session.Session`, whose state and handles it uses.
"""

from __future__ import annotations

import html
from concurrent.futures import Future
from typing import Any

from .analysis import AnalysisView, MotionError, MotionModel, load_motion
from .panels import degrees_text, sign_table_markdown
from .state import AppState, SceneConfig

__all__ = ["MotionPanelMixin", "STATIC"]

STATIC = "(static shapes)"
"""Dropdown entry for no motion."""


class MotionPanelMixin:
    """Motion-editor behaviour of :class:`~app.scene.session.Session` (see the module docstring)."""

    state: AppState
    model: MotionModel | None
    analysis: AnalysisView | None

    def _show_motion_error(self, e: Exception) -> None:
        field = getattr(e, "field", None) or "A"
        for key, md in self.motion_errors.items():
            self._field_error(md, str(e) if key == field else None)

    def _show_motion_fields(self) -> None:
        assert self.model is not None
        texts = self.model.texts()
        for key, handle in self.motion_fields.items():
            self._set_value(handle, texts.get(key, ""))
            self._field_error(self.motion_errors[key], None)
        self._set_md(self.preset_md, self.model.description)

    def _leave_motion(self) -> None:
        """A drag or typed shape turns the scene static (keeps the shapes where they are)."""
        self.model = None
        self.timeline_folder.visible = False
        self.plots_folder.visible = False
        self.analysis = None
        self.state.motion_key = None
        self.state.event = None
        self._set_value(self.preset, STATIC)
        self._set_md(self.status, "Static shapes: drag them or type their parameters.")
        self._set_md(self.bar, "")
        self._set_md(self.events_md, "")
        self._set_md(self.sign_table, "")
        for b in self._event_buttons:
            b.remove()
        self._event_buttons = []
        self._set_value(self.play, False)
        self._refresh_plots(force=True)
        self._sync_shape_fields()

    def _on_preset(self, ev: Any) -> None:
        if self._syncing:
            return
        name = self.preset.value
        if name == STATIC:
            self._leave_motion()
            self._refresh_static()
            return
        cfg = SceneConfig(dim=self.state.dim, preset=name, gizmos=self.show_gizmos.value, show_plots=self.plots_on.value)
        self.load(cfg)
        self._frame_camera()

    def _on_analyse_click(self) -> None:
        texts = {k: h.value for k, h in self.motion_fields.items()}
        try:
            model = load_motion(preset=None, motion=texts, dim=self.state.dim)
        except MotionError as e:
            self._show_motion_error(e)
            return
        for md in self.motion_errors.values():
            self._field_error(md, None)
        with self._lock:
            self.model = model
            if model.dim != self.state.dim:
                self.state.dim = model.dim
                self._make_views()
            self._set_value(self.preset, STATIC if model.preset is None else model.preset)
            self.state.t = model.default_t
            self.state.event = None
            self._analyse()

    def _analyse(self) -> None:
        """Analyse the loaded motion off the GUI thread (cached); draw t meanwhile."""
        model = self.model
        assert model is not None
        self.state.motion_key = model.key
        self.timeline_folder.visible = True
        self.plots_folder.visible = True
        lo, hi = model.interval_floats
        self.t_slider.min, self.t_slider.max = lo, hi
        self.t_slider.step = (hi - lo) / 1000 or 1e-3
        self._update_gizmos()
        cached = self.cache.get(model.key)
        if cached is not None:
            self._analysis_done(model, cached)
            return
        self.analysis = None
        self._set_md(self.status, "Analysing the motion (exact)…")
        self.progress.visible = True
        self.progress.value = 10.0
        pending_event = self.state.event
        self.set_t(self.state.t)
        self.state.event = pending_event  # shown exactly once the analysis knows the events
        fut = self.cache.submit(model, self.executor)
        self._pending = fut

        def done(f: Future[Any]) -> None:
            if self._closed or self.model is not model:
                return
            try:
                result = f.result()
            except Exception as e:  # noqa: BLE001 - shown next to the field, never a crash
                self.progress.visible = False
                self._set_md(self.status, f'<span style="color:#d62728">⚠ analysis failed: {html.escape(str(e))}</span>')
                self.ready.set()
                return
            self._analysis_done(model, result)

        fut.add_done_callback(done)

    def _analysis_done(self, model: MotionModel, result: AnalysisView) -> None:
        try:
            self._show_analysis(model, result)
        except Exception as e:  # noqa: BLE001 - a display bug must not leave the tab waiting
            self._set_md(self.status, f'<span style="color:#d62728">⚠ could not show the analysis: {html.escape(str(e))}</span>')
            self.ready.set()
            raise

    def _show_analysis(self, model: MotionModel, result: AnalysisView) -> None:
        with self._lock:
            if self.model is not model:
                return
            model.interval_floats = result.window
            if result.default_t is not None:
                model._default_t = result.default_t
            self.analysis = result
            self.progress.visible = False
            n_ev = len(result.events)
            self._set_md(
                self.status,
                f"Analysed in {result.seconds:.2f} s: {n_ev} event{'s' * (n_ev != 1)}, "
                f"{len(result.segments)} interval{'s' * (len(result.segments) != 1)}."
                + degrees_text(result.degrees),
            )
            for b in self._event_buttons:
                b.remove()
            self._event_buttons = []
            lines = []
            for k, ev in enumerate(result.events, start=1):
                lines.append(f"α{k} = {ev.text} ({ev.relation}, {ev.kind})")
                with self.events_folder:
                    btn = self.gui.add_button(f"Jump to α{k} ≈ {ev.t:.6f}")
                btn.on_click(lambda _e, k=k: self.jump_to_event(k))
                self._event_buttons.append(btn)
            self._set_md(self.events_md, "<br>".join(lines) if lines else "No events: one relation on all of I.")
            self._set_md(self.sign_table, sign_table_markdown(result.rows, result.degree))
            self._plot_index = -2
            self._refresh_plots(force=True)
            lo, hi = model.interval_floats
            self.t_slider.min, self.t_slider.max = lo, hi
            self.t_slider.step = (hi - lo) / 1000 or 1e-3
            if self._auto_t:
                self.state.t = model.default_t
            if self.state.event is not None and 1 <= self.state.event <= n_ev:
                self.jump_to_event(self.state.event)
            else:
                self.state.event = None
                self.set_t(self.state.t)
            # frame the motion around the t shown (the window of an infinite I is known only now)
            self._frame_camera()
            self.ready.set()
