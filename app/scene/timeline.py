"""The motion timeline of a tab: t slider, exact t box, play/pause, jump to events, panels at t.

:meth:`TimelineMixin.set_t` is the hot path of scrubbing (one t-step): shapes move and recolour at
once from the certified relation looked up in the analysis; the panels follow at most every
:attr:`TimelineMixin.PANEL_PERIOD` seconds while scrubbing or playing. Mixed into
:class:`app.scene.session.Session`, whose state and handles it uses.
"""

from __future__ import annotations

import math
import re
import threading
import time
from typing import Any

import numpy as np

from core import Relation
from core.formulae.pencil import pencil_coefficients

from . import plots
from .analysis import AnalysisView, MotionModel
from .panels import intervals_bar_html, readout_markdown
from .state import AppState, parse_vector

__all__ = ["TimelineMixin"]


class TimelineMixin:
    """Timeline behaviour of :class:`~app.scene.session.Session` (see the module docstring)."""

    state: AppState
    model: MotionModel | None
    analysis: AnalysisView | None

    def jump_to_event(self, k: int) -> str | None:
        """Show the k-th event (1-based) exactly: shapes at alpha_k, relation of the event."""
        with self._lock:
            if self.analysis is None or not 1 <= k <= len(self.analysis.events):
                return None
            ev = self.analysis.events[k - 1]
            self.set_t(ev.t, event=k)
            return ev.relation

    def set_t(self, t: float, *, event: int | None = None, defer_panels: bool = False) -> str | None:
        """Move the motion to time t (one timeline step: hot path, no analysis).

        The shapes move and recolour at once. The panels (readout, intervals-bar cursor, t box)
        follow immediately, or with ``defer_panels`` at most every :attr:`PANEL_PERIOD` seconds
        (what the slider and playback do: scrubbing stays cheap). The plot cursor always
        follows within :attr:`PANEL_PERIOD` (it resends the plot data: the heaviest message).

        Args:
            t: time (clamped to the window of I); a float, or an exact rational (typed in the t
                box: the relation and readout are then certified at that exact value).
            event: show the exact event k instead of the float t (set by "jump to").
            defer_panels: coalesce panel updates (see above).

        Returns:
            The certified relation drawn at t (None while the analysis is running).
        """
        with self._lock, self._batch():
            model = self.model
            if model is None:
                return None
            lo, hi = model.interval_floats
            exact = None if isinstance(t, float) else t
            try:
                t = float(t)
            except OverflowError:  # a typed 1e400: beyond every float, clamped like any t outside
                t = math.inf if t > 0 else -math.inf
            if not lo <= t <= hi:
                t, exact = min(max(t, lo), hi), None
            self.state.t = t
            self.state.t_exact = exact
            self.state.event = event
            try:
                a, b = model.shapes_at(t)
            except (ValueError, ArithmeticError, np.linalg.LinAlgError):
                a = b = None  # not drawable in floats at this t (extreme coefficients): keep the last pose
            if a is not None and b is not None:
                self.state.shapes = {"A": a, "B": b}  # a drag from here starts where they are drawn
                for name, sh in (("A", a), ("B", b)):
                    pos, wxyz, scale = sh.float_pose()
                    self.views[name].set_pose(pos, wxyz, scale)
            an = self.analysis
            if an is None:
                self._set_relation(None)
                self._set_md(self.readout, readout_markdown(None, error="analysing the motion…"))
                return None
            relation = an.events[event - 1].relation if event is not None else an.relation_at(t if exact is None else exact)
            self._set_relation(relation)
            if a is None:  # the float matrices are not ellipses here: no contact point or plane
                self._update_contact(None, None, None)
            elif relation == str(Relation.TANGENT):
                A, B = model.float_matrices(t)
                coeffs = [{"approx": float(v)} for v in pencil_coefficients(A, B)]
                self._update_contact(A, B, {"relation": relation, "coefficients": coeffs})
            else:
                self._update_contact(None, None, None)
            if a is not None and (self.show_plane.value or self._plane_on):
                A, B = model.float_matrices(t)
                self._update_plane(A, B, relation)
            if defer_panels:
                self._panels_due = True
                self._schedule_flush()
            else:
                self._panels_now(plots=False)
                self._plots_due = True  # the plot cursor (the heaviest message) follows at 20 Hz
                self._schedule_flush()
            return relation

    PANEL_PERIOD = 0.05
    """Seconds between panel refreshes while scrubbing or playing."""

    def _schedule_flush(self) -> None:
        if self._panel_timer is None:
            self._panel_timer = threading.Timer(self.PANEL_PERIOD, self._flush_panels)
            self._panel_timer.daemon = True
            self._panel_timer.start()

    def _flush_panels(self) -> None:
        try:
            with self._lock, self._batch():
                self._panel_timer = None
                if self._closed:
                    return
                if self._static_due and self.model is None:
                    self._static_panels()
                if self._panels_due:
                    self._panels_now()
                elif self._plots_due:
                    self._plots_due = False
                    self._refresh_plots()
        except RuntimeError as e:  # the tab or the server went away while the timer waited
            if "removed" not in str(e) and "closed" not in str(e):
                raise
            self._closed = True

    def _panels_now(self, *, plots: bool = True) -> None:
        """Readout, bar, slider/t box and (with ``plots``) the plot cursor for the current t."""
        self._panels_due = False
        model, an = self.model, self.analysis
        if model is None or an is None:
            return
        t, event = self.state.t, self.state.event
        lo, hi = model.interval_floats
        self._set_value(self.t_slider, min(max(t, self.t_slider.min), self.t_slider.max))
        if event is not None:
            ev = an.events[event - 1]
            where = f"at t = α{event} = {ev.text}"
            self._set_value(self.t_number, ev.text)
        elif self.state.t_exact is not None:
            where = f"at t = {self.state.t_exact}"
            self._set_value(self.t_number, str(self.state.t_exact))
        else:
            where = f"at t = {t:.6g}"
            self._set_value(self.t_number, repr(t) if len(repr(t)) < 12 else f"{t:.6g}")
        self._set_md(self.bar, intervals_bar_html(lo, hi, an.segments, [(e.t, e.relation) for e in an.events], t))
        at = t if self.state.t_exact is None or event is not None else self.state.t_exact
        self._set_md(self.readout, an.readout(at, event, where))
        if plots:
            self._plots_due = False
            self._refresh_plots()

    def _on_slider(self, ev: Any) -> None:
        if self._syncing:
            return
        self._auto_t = False
        self.set_t(self.t_slider.value, defer_panels=True)

    def _on_t_text(self, ev: Any) -> None:
        if self._syncing or self.model is None:
            return
        text = self.t_number.value.strip()
        m = re.fullmatch(r"(?:α|alpha)\s*([0-9]+)", text, flags=re.IGNORECASE)
        if m is not None:  # "α1" / "alpha1": the exact event
            n_ev = len(self.analysis.events) if self.analysis else 0
            if not 1 <= int(m.group(1)) <= n_ev:
                self._field_error(self.t_error, f"t: there are {n_ev} events (α1..α{n_ev})")
                return
            self._field_error(self.t_error, None)
            self.jump_to_event(int(m.group(1)))
            return
        try:
            (t,) = parse_vector(text, 1, "t")
        except ValueError as e:
            self._field_error(self.t_error, f"{e}; or type α1, α2, … for an event")
            return
        self._field_error(self.t_error, None)
        self.set_t(t)  # exact when typed: "1/3" is certified at 1/3, drawn at its float

    def _on_play(self) -> None:
        if self._syncing or not self.play.value:
            return
        if self._play_thread is not None and self._play_thread.is_alive():
            return
        self._play_thread = threading.Thread(target=self._play_loop, daemon=True)
        self._play_thread.start()

    def _play_loop(self) -> None:
        dt = 0.05
        while self.play.value and not self._closed and self.model is not None:
            lo, hi = self.model.interval_floats
            t = self.state.t + (hi - lo) * self.speed.value * dt / 10.0
            if t > hi:
                t = lo
            self.set_t(t, defer_panels=True)
            time.sleep(dt)

    def _refresh_plots(self, force: bool = False) -> None:
        """Resample only when the analysis changed; move the cursor otherwise; skip when off."""
        on = bool(self.plots_on.value) and self.analysis is not None
        if not on:
            if force:
                self.plot_coeffs.visible = False
                self.plot_subres.visible = False
                self._plot_index = -2
            return
        an = self.analysis
        assert an is not None
        idx = int(np.searchsorted(an.samples_t, self.state.t))
        if idx == self._plot_index and not force:
            return
        self._plot_index = idx
        fresh = self._plot_data is None or self._plot_data[0] is not an
        if fresh:
            self._plot_data = (
                an,
                plots.PlotData(an.samples_t, an.coeff_series(), an.events_t),
                plots.PlotData(an.samples_t, an.subres_series(), an.events_t),
            )
        assert self._plot_data is not None
        plots.update_plot(self.plot_coeffs, self._plot_data[1], idx, labels=fresh or force)
        plots.update_plot(self.plot_subres, self._plot_data[2], idx, labels=fresh or force)
