"""The timeline of the moving-bodies view: t, Play, the certified colours at t, opening an event.

Part of :class:`app.scene.bodies.bodies_view.BodiesView` when its model is a
:class:`app.scene.bodies.sweep_model.SweepModel` (``serve --bodies START --to END``):

* **t** (slider over the step [0, 1]) and **Play**, as the two-body timeline
  (:mod:`app.scene.pair.control_timeline`): a t-step draws the bodies at once at their float poses,
  coloured by what the sweep decides at the exact t (:meth:`SweepModel.moment`: vectorised,
  milliseconds); the pairs it leaves open are decided by exact arithmetic in this view's worker
  thread, their bodies drawn "deciding" meanwhile, and the colours are sent again when they are
  certified (and every :attr:`SweepTimeline.PUBLISH` seconds while it works). A newer t stops
  the work for an older one. Playback waits (at most :attr:`SweepTimeline.PLAY_WAIT` s) for
  each step's certified colours, so it slows down rather than show a guess.
* **Events**: the view's list (the "Contact events" folder) holds the pairs' first contacts in
  exact time order; their labels show t* exactly (closed form) once computed here, in the same
  worker. Picking one jumps the timeline to t* (the exact algebraic time: colours certified
  there) and opens the pair in the two-body view on its exact motion, at the analysis' event
  equal to t* (:meth:`SweepTimeline.open_event`).
"""

from __future__ import annotations

import html
import threading
import time
from typing import TYPE_CHECKING, Any

from core import Relation

from .sweep_model import Moment, SweepModel, Time

if TYPE_CHECKING:
    from .bodies_view import BodiesView

__all__ = ["SweepTimeline"]


class SweepTimeline:
    """The Timeline folder of a moving-bodies view, its playback thread and its exact-arithmetic worker.

    Args:
        view: the bodies view (its model is a :class:`SweepModel`); the folder is added to its GUI.
    """

    PUBLISH = 0.3
    """Seconds between partial colour updates while exact arithmetic decides a t."""
    PLAY_WAIT = 1.0
    """Longest wait of playback for one step's certified colours (seconds)."""
    PLAY_DT = 0.05
    """Seconds between playback steps (when the colours are ready at once)."""

    def __init__(self, view: BodiesView) -> None:
        self.view = view
        model = view.model
        assert isinstance(model, SweepModel)
        self.model: SweepModel = model
        gui = view.gui
        self.folder: Any = gui.add_folder("Timeline")
        with self.folder:
            self.slider: Any = gui.add_slider("t", min=0.0, max=1.0, step=0.001, initial_value=model.current.tf,
                                         hint="time in the step: START at 0, END at 1")
            self.play: Any = gui.add_checkbox("Play", False, hint="play the step (waits for each step's certified colours)")
            self.speed: Any = gui.add_slider("Speed (step per 10 s)", min=0.1, max=5.0, step=0.1, initial_value=1.0)
            self.status: Any = gui.add_markdown("")
        self.slider.on_update(lambda ev: view._from_client(ev, lambda: self.set_time(float(self.slider.value))))
        self.play.on_update(lambda ev: view._from_client(ev, self._on_play))
        self._cond: threading.Condition = threading.Condition()
        self._closed: bool = False
        self._drawn_final: Moment | None = None
        self._label_todo: list[int] = []
        self._play_thread: threading.Thread | None = None
        self.opening: str = ""
        """What the view is opening (a message shown with the status), or ""."""
        self._worker = threading.Thread(target=self._work, name="sweep-colours", daemon=True)
        self._worker.start()
        self._drawn(model.current)

    # ------------------------------------------------------------------ time
    def set_time(self, t: Time, *, event: int | None = None) -> Moment:
        """Show the bodies at t (a float in [0, 1], or an event's exact time): poses now, colours certified.

        Returns:
            The :class:`Moment` shown (``.done`` is set once every colour at t is certified).

        Raises:
            ValueError: a float t outside [0, 1].
        """
        view = self.view
        with view._lock:
            m = self.model.moment(t, event=event)
            self.model.current = m
            view._syncing = True
            try:
                self.slider.value = m.tf
            finally:
                view._syncing = False
            self._draw(m)
        with self._cond:
            self._cond.notify_all()
        return m

    def _draw(self, m: Moment) -> None:
        """Send the bodies of moment m (view lock held): points, solids, the selected body's label.

        Nothing once the view is closed: the worker may finish a moment after its tab went away,
        and messages to a closed connection are never delivered (viser warns about each).
        """
        if self._closed:
            return
        view = self.view
        if view.layers is not None:
            model = self.model
            view.layers.set_bodies(model.positions, model.wxyz, model.scales, model.colours(), model.worst)
            view._show_drawn()
        if view.selected is not None and view.labels and view.pair is None:
            view._label(view.selected)
        self._drawn(m)

    def _drawn(self, m: Moment) -> None:
        if m.done.is_set():
            self._drawn_final = m
        self._show_status()

    def busy(self) -> bool:
        """True until the current t's certified colours are all drawn (or an event label is due)."""
        m = self.model.current
        return self._drawn_final is not m or bool(self._label_todo)

    def wait_certified(self, timeout: float = 120.0) -> bool:
        """Block until the current t's colours are certified and drawn; False on timeout."""
        deadline = time.monotonic() + timeout
        while self.busy():
            if time.monotonic() > deadline:
                return False
            time.sleep(0.01)
        return True

    def _show_status(self) -> None:
        m = self.model.current
        res = self.model.result
        worst = self.model.worst_at(m)
        n_over = int((worst == Relation.OVERLAP).sum())
        n_tan = int((worst == Relation.TANGENT).sum())
        n_wait = int((worst == Relation.UNDECIDED).sum())
        if m.event is not None:
            i, j = int(res.i[m.event]), int(res.j[m.event])
            when = f"t = t\\* of {i} – {j} {self.model.time_text(m.event, exact=False)} (exactly)"
        else:
            when = f"t = {m.tf:.6g}"
        text = f"{when}: {n_over:,} bodies overlap, {n_tan:,} touch"
        if n_wait:
            text += f"; deciding {len(m.pending):,} pairs exactly ({n_wait:,} bodies, pale grey)…"
        else:
            text += f" (certified: {m.by_sweep:,} pairs by the sweep's first and last contacts, {m.exact:,} by exact arithmetic at t)"
        if self.opening:
            text = f"{self.opening}\n\n{text}"
        self.status.content = text

    # ------------------------------------------------------------------ the worker
    def want_labels(self, ks: list[int]) -> None:
        """Compute the exact t* of these events (their labels) in the worker, then relist them."""
        todo = [k for k in ks if not self.model.labelled(k)]
        with self._cond:
            self._label_todo = todo
            self._cond.notify_all()

    def _work(self) -> None:
        model = self.model
        while True:
            with self._cond:
                while not self._closed and model.current.done.is_set() and not self._label_todo:
                    self._cond.wait(0.5)
                if self._closed:
                    return
            m = model.current
            if not m.done.is_set():
                self._decide(m)
                continue
            todo, self._label_todo = self._label_todo, []
            if todo and model.exact_labels(todo, stop=lambda: self._closed or not model.current.done.is_set()):
                with self.view._lock:
                    if self.view.pair is None:
                        self.view._refresh_list()
            elif todo:
                with self._cond:
                    self._label_todo = todo + self._label_todo  # interrupted by a new t: later

    def _decide(self, m: Moment) -> None:
        model = self.model
        last = [time.monotonic()]

        def stop() -> bool:
            return self._closed or model.current is not m

        def progress() -> None:
            if time.monotonic() - last[0] >= self.PUBLISH and not stop():
                last[0] = time.monotonic()
                with self.view._lock:
                    if model.current is m:
                        self._draw(m)

        try:
            finished = model.decide(m, stop=stop, progress=progress)
        except Exception as e:  # noqa: BLE001 - shown, never a dead worker (those bodies stay "deciding")
            m.pending.clear()
            m.done.set()
            with self.view._lock:
                self._draw(m)
                self.status.content += f'\n\n<span style="color:#d62728">⚠ exact decision failed: {html.escape(str(e))}</span>'
            return
        if finished:
            with self.view._lock:
                if model.current is m:
                    self._draw(m)

    # ------------------------------------------------------------------ playback
    def _on_play(self) -> None:
        if not self.play.value or (self._play_thread is not None and self._play_thread.is_alive()):
            return
        self._play_thread = threading.Thread(target=self._play_loop, name="sweep-play", daemon=True)
        self._play_thread.start()

    def stop_playing(self) -> None:
        """Uncheck Play (the loop ends at its next step)."""
        if self.play.value:
            self.view._syncing = True
            try:
                self.play.value = False
            finally:
                self.view._syncing = False

    def _play_loop(self) -> None:
        while self.play.value and not self._closed:
            t0 = time.monotonic()
            t = self.model.current.tf + float(self.speed.value) * self.PLAY_DT / 10.0
            m = self.set_time(0.0 if t > 1.0 else t)
            m.done.wait(self.PLAY_WAIT)
            time.sleep(max(0.0, self.PLAY_DT - (time.monotonic() - t0)))

    # ------------------------------------------------------------------ events
    def open_event(self, k: int) -> Any:
        """Jump to pair k's first contact t* and open the pair in the two-body view on its exact motion.

        The two-body view analyses the same exact A(t), B(t) the sweep certified over [0, 1]
        (shared analysis cache: it is computed once) and shows its event equal to t* exactly
        (at t = 0 when the pair already overlaps there: no event).

        Returns:
            The two-body :class:`~app.scene.pair.session.Session`.
        """
        model, view = self.model, self.view
        self.stop_playing()
        res = model.result
        i, j = int(res.i[k]), int(res.j[k])
        self.opening = f"Opening bodies {i} and {j}: analysing their motion exactly…"
        self.set_time(model.time(k), event=k)
        motion = model.pair_motion(k)
        cache = view.analysis_cache()
        target: dict[str, Any] | None
        error = ""
        try:
            analysis = cache.submit(motion, view.executor).result()
            target = model.open_target(k, analysis)
        except Exception as e:  # noqa: BLE001 - the pair is opened at t = 0 with the reason
            target, error = None, str(e)
        self.opening = ""
        cfg, note = model.pair_config(k)
        if target is None:
            note += f" Its motion could not be analysed ({html.escape(error)}): shown at t = 0 as static shapes."
        self._show_status()
        return view._open_two_body(k, cfg, note, motion=motion if target is not None else None, target=target)

    def close(self) -> None:
        """Stop playback and the worker (the tab went away, or the view was rebuilt)."""
        self._closed = True
        with self._cond:
            self._cond.notify_all()
