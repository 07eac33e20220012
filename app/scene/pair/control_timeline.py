"""What the user does to time: scrub the slider, type an exact t, play, jump to an event.

:meth:`TimelineControl.set_t` is the hot path of scrubbing (one t-step): the session redraws
the shapes at once with the relation looked up in the analysis; the panels follow at most every
``Session.PANEL_PERIOD`` while scrubbing or playing. The t box takes exact values: a number or a
fraction ("2/3" is certified at 2/3 itself, not at its float), a closed form with square roots
("(12-2*sqrt(2))/17", certified at that algebraic number, which is the event there if there is
one), or "α1" / "alpha1"; a t outside I is refused with a message, never clamped silently.
"""

from __future__ import annotations

import math
import re
import threading
import time
from typing import TYPE_CHECKING, Any

from flint import fmpq

from core.shapes.numbers import to_fmpq

from ..common.texts import read_time, time_float

if TYPE_CHECKING:
    from .session_view import SessionView

__all__ = ["TimelineControl"]

_EVENT = re.compile(r"(?:α|alpha)\s*([0-9]+)", flags=re.IGNORECASE)


def _float(t: Any) -> float:
    return time_float(t)


class TimelineControl:
    """Callbacks of the Timeline folder of one session, and its playback thread."""

    def __init__(self, session: SessionView) -> None:
        self.s = session
        tg = session.ui.timeline
        tg.slider.on_update(lambda _ev: self.on_slider())
        tg.t_box.on_update(lambda _ev: self.on_t_text())
        tg.play.on_update(lambda _ev: self.on_play())
        self._thread: threading.Thread | None = None
        self._ending = False
        """The playback thread paused at an event and is returning (Play may be checked again at once)."""

    # ------------------------------------------------------------------ time
    def set_t(self, t: Any, *, event: int | None = None, defer_panels: bool = False, text: str | None = None) -> str | None:
        """Move the motion to time t (one timeline step: hot path, no analysis).

        Args:
            t: a float (its exact binary value), or an exact rational / RealAlgebraic (the
                relation and readout are then certified at that value; the shapes drawn at its
                float). A float outside the window is clamped (slider, playback).
            event: show the exact event k instead (set by "jump to").
            defer_panels: coalesce the panel updates (slider and playback).
            text: how the t box shows t: the text the user typed (None: the number itself).

        Returns:
            The certified relation drawn at t (None while the analysis is running).
        """
        s = self.s
        with s.lock:
            st = s.state
            model = st.motion
            if model is None:
                return None
            exact = None if isinstance(t, float) else t
            tf = _float(t)
            lo, hi = st.analysis.window if st.analysis is not None else model.interval_floats
            if exact is None and not lo <= tf <= hi:
                tf = min(max(tf, lo), hi)
            st.t, st.t_exact, st.event = tf, exact, event
            st.t_text = text
            st.errors.pop("t", None)
            return s.refresh(defer=defer_panels)

    def jump_to_event(self, k: int) -> str | None:
        """Show the k-th event (1-based) exactly: shapes at alpha_k, relation of the event."""
        s = self.s
        with s.lock:
            an = s.state.analysis
            if an is None or not 1 <= k <= len(an.events):
                return None
            s.state.auto_t = False
            ev = an.events[k - 1]
            self.set_t(ev.t, event=k)
            return ev.relation

    # ------------------------------------------------------------------ callbacks
    def on_slider(self) -> None:
        """The slider moved (a float t)."""
        s = self.s
        if s.syncing.active:
            return
        s.state.auto_t = False
        self.set_t(float(s.ui.timeline.slider.value), defer_panels=True)

    def on_t_text(self) -> None:
        """The t box: an event name, or an exact time inside I (else an error next to the box)."""
        s = self.s
        if s.syncing.active or s.state.motion is None:
            return
        error = self.apply_text(str(s.ui.timeline.t_box.value))
        if error is not None:
            s.field_error("t", error)

    def apply_text(self, text: str) -> str | None:
        """Go to the time ``text`` names exactly; returns the error message instead, if any.

        "α2"/"alpha2" is the event; a number, fraction or closed form inside I is certified at
        that exact value (the event, if it is one); a float's exact value takes the float path.
        """
        s = self.s
        text = text.strip()
        shown = text if len(text) <= 40 else text[:40] + "…"
        with s.lock:
            an = s.state.analysis
            if an is None:
                return "t: the motion is being analysed; try again in a moment"
            m = _EVENT.fullmatch(text)
            if m is not None:  # "α1" / "alpha1": the exact event
                n_ev = len(an.events)
                if not 1 <= int(m.group(1)) <= n_ev:
                    return f"t: there are {n_ev} events (α1..α{n_ev})" if n_ev else "t: this motion has no events"
                self.jump_to_event(int(m.group(1)))
                return None
            try:
                t = read_time(text)
            except ValueError as e:
                why = f"not a number: {shown!r}" if "unexpected" in str(e) or "empty" in str(e) else str(e)
                return f"t: {why}; expected e.g. 0.7, 2/3, (12-2*sqrt(2))/17, or α1, α2, … for an event"
            if not an.contains(t):
                lo, hi = an.result.interval
                return f"t = {shown} is outside I = [{'-∞' if lo is None else lo}, {'∞' if hi is None else hi}]"
            tf = _float(t)
            if not math.isfinite(tf):
                return f"t = {shown} is too large to draw (the scene draws |t| < 1e308)"
            wlo, whi = an.window
            if not wlo <= tf <= whi:  # inside an unbounded I, outside the slider: the slider widens to show it
                s.state.analysis = an = an.widened(tf)
            s.state.auto_t = False
            k = an.event_at(t)
            if k is not None:  # exactly an event: show it as the event
                self.jump_to_event(k)
            elif isinstance(t, fmpq) and to_fmpq(tf) == t:
                self.set_t(tf, text=text if len(text) <= 40 else None)  # a float's exact value typed: the float path
            else:
                self.set_t(t, text=text if len(text) <= 40 else None)
            return None

    # ------------------------------------------------------------------ playback
    def on_play(self) -> None:
        """Play checkbox: start the playback thread (it stops when unchecked)."""
        s = self.s
        if s.syncing.active or not s.ui.timeline.play.value:
            return
        if self._thread is not None and self._thread.is_alive() and not self._ending:
            return  # playing already (a thread that paused at an event is ending: start anew)
        self._ending = False
        self._thread = threading.Thread(target=self._play_loop, name="play", daemon=True)
        self._thread.start()

    def stop_playing(self) -> None:
        """Uncheck Play (the thread ends at its next step)."""
        play = self.s.ui.timeline.play
        if play.value:
            with self.s.syncing():
                play.value = False  # type: ignore[misc]  # writable: viser defines the setter apart from the getter, mypy sees read-only

    def _play_loop(self) -> None:
        s = self.s
        dt = 0.05
        while s.ui.timeline.play.value and not s.closed and s.state.motion is not None:
            an = s.state.analysis
            lo, hi = an.window if an is not None else s.state.motion.interval_floats
            t0 = s.state.t
            t = t0 + (hi - lo) * float(s.ui.timeline.speed.value) * dt / 10.0
            if an is not None and s.ui.timeline.pause_at_events.value:
                after = s.state.event or 0  # sitting on an event: the next one
                hit = next((e for e in an.events if e.k > after and t0 <= e.t <= min(t, hi)), None)
                if hit is not None:  # stop exactly on it (its exact relation, drawn at its float);
                    self.jump_to_event(hit.k)  # the event first: Play reads unchecked only once it is shown
                    self._ending = True
                    self.stop_playing()
                    return
            if t > hi:
                t = lo
            s.state.auto_t = False
            self.set_t(t, defer_panels=True)
            time.sleep(dt)
