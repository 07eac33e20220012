"""Keyboard and camera: play/pause, step, jump to events, frame and follow the shapes.

Space plays/pauses, the arrows step t, N / P jump to the next / previous event, F frames the
shapes; the camera can follow the moving shapes.

Hotkeys are viser commands (``gui.add_command``, also listed in the command palette); they do
not fire while the user types in a field. Each changes the state through the timeline controller,
so the picture and the certificate stay one.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import viser

from .gui import ignoring_event

if TYPE_CHECKING:
    from .session_view import SessionView

__all__ = ["KeyControl", "STEPS_PER_WINDOW"]

STEPS_PER_WINDOW = 200
"""An arrow key moves t by this fraction of the slider window (1/200)."""


class KeyControl:
    """Hotkeys of one session, the "Frame the shapes" button and camera following."""

    FOLLOW_PERIOD = 0.1
    """Seconds between camera moves while following."""

    def __init__(self, session: SessionView) -> None:
        self.s = session
        gui = session.gui_api
        self.commands: list[viser.CommandHandle] = []
        for label, key, action in (
            ("Play / pause", "space", self.play_pause),
            ("Step t forward", "arrowright", lambda: self.step(+1)),
            ("Step t back", "arrowleft", lambda: self.step(-1)),
            ("Next event", "N", lambda: self.event(+1)),
            ("Previous event", "P", lambda: self.event(-1)),
            ("Frame the shapes", "F", session.frame_camera),
        ):
            cmd = gui.add_command(label, hotkey=key)  # type: ignore[arg-type]
            cmd.on_trigger(ignoring_event(action))
            self.commands.append(cmd)
        session.ui.view.frame.on_click(lambda _ev: session.frame_camera())
        session.ui.view.follow.on_update(lambda _ev: self.on_follow())
        self._last_follow = 0.0

    def play_pause(self) -> None:
        """Toggle Play (a motion only)."""
        s = self.s
        if s.state.motion is None:
            return
        # runs the Play callback; ignored: writable, viser defines the setter apart from the getter (mypy sees read-only)
        s.ui.timeline.play.value = not s.ui.timeline.play.value  # type: ignore[misc]

    def step(self, direction: int) -> None:
        """Move t by 1/STEPS_PER_WINDOW of the window."""
        s = self.s
        with s.lock:
            an = s.state.analysis
            if an is None:
                return
            lo, hi = an.window
            s.state.auto_t = False
            s.timeline_ctl.set_t(min(max(s.state.t + direction * (hi - lo) / STEPS_PER_WINDOW, lo), hi))

    def event(self, direction: int) -> None:
        """Jump to the next (previous) event after (before) the t shown."""
        s = self.s
        with s.lock:
            an = s.state.analysis
            if an is None or not an.events:
                return
            k = s.state.event
            if k is not None:
                target = k + direction
            elif direction > 0:
                target = next((e.k for e in an.events if e.t > s.state.t), 0)
            else:
                target = next((e.k for e in reversed(an.events) if e.t < s.state.t), 0)
            if 1 <= target <= len(an.events):
                s.timeline_ctl.jump_to_event(target)

    def on_follow(self) -> None:
        """"Camera follows the shapes" switched: store it; on, frame now."""
        s = self.s
        if s.syncing.active:
            return
        s.state.follow = bool(s.ui.view.follow.value)
        if s.state.follow:
            s.frame_camera()

    def follow(self) -> None:
        """While following, aim the camera(s) at the shapes drawn (at most every FOLLOW_PERIOD)."""
        now = time.monotonic()
        if now - self._last_follow >= self.FOLLOW_PERIOD:
            self._last_follow = now
            self.s.frame_camera(grid=False, around_shapes=True)
