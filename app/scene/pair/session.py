"""One browser tab: its state, the controllers that change it and the views that draw it.

A :class:`Session` owns an :class:`~app.scene.common.state.AppState` (what the tab shows), the views
(:class:`~app.scene.common.shapes.EllipsoidView` per shape, :class:`~app.scene.common.markers.WitnessMarkers`,
the GUI panel filled by :class:`~app.scene.pair.panel_view.PanelView`) and three controllers
(:mod:`app.scene.pair.control_shapes`, :mod:`app.scene.pair.control_motion`,
:mod:`app.scene.pair.control_timeline`). Callbacks change the state and call :meth:`Session.refresh`,
the one path from state to screen: it derives the :class:`~app.scene.pair.picture.Picture` (the
shapes and their certified relation, together), draws it, and fills the panel now or, while
dragging or scrubbing, at most every :attr:`Session.PANEL_PERIOD`.

The two hot paths have entry points that need no browser (the benchmark's): :meth:`apply_drag`
(a gizmo drag event) and :meth:`set_t` (one t step); :func:`app.scene.pair.costs.measure_update_costs`
times both and counts the websocket messages they queue.
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable, Collection, Iterable
from concurrent.futures import Executor
from contextlib import AbstractContextManager, nullcontext
from typing import Any

import viser

from ..common import wire
from ..common.camera import Framing, extent_of, frame_cameras
from ..common.lighting import light_scene
from ..common.markers import WitnessMarkers
from ..common.mesh_detail import SPHERE_SUBDIVISIONS, check_sphere_subdivisions
from ..common.shapes import PALETTES, EllipsoidView
from ..common.state import AppState, SceneConfig
from ..common.threads import later, soon
from .analysis import AnalysisCache
from .control_keys import KeyControl
from .control_motion import MotionControl
from .control_shapes import ShapeControl
from .control_share import ShareControl
from .control_timeline import TimelineControl
from .gui import build_gui
from .history import History
from .motion import MotionError, MotionModel, list_presets, load_motion
from .panel_view import PanelView, Syncing
from .picture import Picture, motion_picture, static_picture

__all__ = ["Session"]


class Session:
    """The scene and GUI of one tab (or of the shared presenter scene).

    Args:
        target: ``viser.ClientHandle`` (one tab) or ``viser.ViserServer`` (shared scene).
        config: what to open on.
        cache: analysis cache shared by the sessions of one server (keyed by motion + interval).
        executor: where analyses are waited for (off the GUI thread).
        count_messages: count queued websocket messages in :attr:`messages` (benchmarks).
        cameras: the cameras to frame (presenter mode: every connected tab's); default the
            target's own camera, if it has one.
        defer_load: build the scene but load nothing yet (the caller loads, e.g. a link).
        sphere_subdivisions: of the icosphere the solids are drawn with
            (:data:`app.scene.common.mesh_detail.SPHERE_SUBDIVISIONS_RANGE`; fewer draw faster in software WebGL).
        uploads: the server's :class:`~app.scene.common.wire.UploadGuard` (the configuration upload's
            limit is set on it, and a refused file is shown next to the button), or None.
        open_folders: the panel's folders shown open (a lesson step's); None: the usual ones.
        answer_hidden: open with the relation kept back (a lesson step's open question; see
            :meth:`hold_question`, :meth:`reveal`).
        guide: address of the documentation site (``http://host:port/guide/``) the panel links to, or None.
    """

    PANEL_PERIOD = 0.05
    """Seconds between panel refreshes while dragging, scrubbing or playing."""

    PICTURE_FIRST = 0.15
    """Seconds the panel waits after a new motion's picture (a preset, a link, an analysis).

    The browser applies a picture in two frames (the update, then the committed mesh props);
    the panel's update is 40-90 ms of page work, and landing between those frames it pushed
    the certified shapes back by as much. Two frames are ~100 ms in software WebGL
    (headless Chromium at 1200x800), ~30 ms with a GPU.
    """

    def __init__(
        self,
        target: viser.ClientHandle | viser.ViserServer,
        config: SceneConfig | None = None,
        *,
        cache: AnalysisCache | None = None,
        executor: Executor | None = None,
        count_messages: bool = False,
        cameras: Callable[[], Iterable[viser.CameraHandle]] | None = None,
        defer_load: bool = False,
        sphere_subdivisions: int = SPHERE_SUBDIVISIONS,
        uploads: wire.UploadGuard | None = None,
        open_folders: Collection[str] | None = None,
        answer_hidden: bool = False,
        guide: str | None = None,
    ) -> None:
        self.sphere_subdivisions = check_sphere_subdivisions(sphere_subdivisions)
        self.uploads = uploads
        self.target = target
        self.scene: viser.SceneApi = target.scene
        self.gui_api: viser.GuiApi = target.gui
        self.config = config or SceneConfig()
        self.cache = cache or AnalysisCache()
        self.executor = executor
        self._cameras = cameras
        self._counter = wire.MessageCounter(self.scene) if count_messages else None
        self.lock = threading.RLock()
        """Held while the state changes and is drawn (callbacks come from several threads)."""
        self.syncing = Syncing()
        self.closed = False
        self.ready = threading.Event()
        """Set when the configuration is loaded and (for a motion) analysed and drawn."""
        self.camera_chosen = False
        """A camera was given (a lesson step's): the tab's first view report does not frame the shapes again."""
        a, b = self.config.shapes()
        self.state = AppState(dim=self.config.dim, shapes={"A": a, "B": b}, answer_hidden=answer_hidden)
        self.question: dict[str, Any] | None = None
        """The configuration the open question is about (:meth:`hold_question`): showing another one reveals."""
        self.on_reveal: Callable[[], object] | None = None
        """Called (lock held) when the relation is shown again (the lesson's Reveal button goes)."""
        light_scene(self.scene)
        self.ui = build_gui(
            self.gui_api,
            dim=self.config.dim,
            presets=list_presets(),
            show_plots=self.config.show_plots,
            gizmos=self.config.gizmos,
            plane=self.config.separating_plane,
            open_folders=open_folders,
            guide=guide,
        )
        self.timeline_ctl = TimelineControl(self)
        self.panel = PanelView(self.ui, self.gui_api, self.syncing, on_event=self.timeline_ctl.jump_to_event)
        self.markers = WitnessMarkers(self.scene)
        self.views: dict[str, EllipsoidView] = {}
        self.shapes_ctl = ShapeControl(self)
        self.motion_ctl = MotionControl(self)
        self.share_ctl = ShareControl(self)
        self.keys_ctl = KeyControl(self)
        self.history = History(self)
        """Undo / redo of what the tab shows (:mod:`app.scene.pair.history`)."""
        self._build_views()
        self._timer: threading.Timer | None = None
        self.grid: tuple[viser.GridHandle, tuple[float, float, float, float]] | None = None
        """The grid under the shapes and its :meth:`Framing.grid_key` (None before the first framing)."""
        self._panels_due = self._plots_due = self._witness_due = False
        if not defer_load:
            self.load(self.config)

    # ------------------------------------------------------------------ building
    @property
    def messages(self) -> int:
        """Websocket messages queued so far (only with ``count_messages=True``)."""
        return self._counter.count if self._counter else 0

    def _build_views(self) -> None:
        for v in self.views.values():
            v.remove()
        gizmo = self.state.gizmos and self.state.motion is None
        self.views = {
            name: EllipsoidView(self.scene, name, self.state.dim, gizmo=gizmo, subdivisions=self.sphere_subdivisions)
            for name in ("A", "B")
        }
        self.shapes_ctl.attach_gizmos()

    def set_dimension(self, dim: int) -> None:
        """Show ``dim`` (2 or 3): the shape views turn into discs or solids in place."""
        self.state.dim = dim
        for v in self.views.values():
            v.set_dim(dim)

    def batch(self) -> AbstractContextManager[None]:
        """One websocket batch for an update (viser's ``atomic``).

        The browser applies the poses, colours and panels of one step together.
        """
        atomic = getattr(self.target, "atomic", None)
        return atomic() if atomic is not None else nullcontext()

    # ------------------------------------------------------------------ loading
    def load(self, config: SceneConfig) -> None:
        """Show a configuration: static shapes, or a motion (analysed in the background)."""
        with self.lock:
            self.config = config
            self.ready.clear()
            st = self.state
            st.errors.clear()
            st.status = ""
            st.show_plots, st.separating_plane, st.gizmos = config.show_plots, config.separating_plane, config.gizmos
            st.palette = config.palette or next(iter(PALETTES))
            a, b = config.shapes()
            st.shapes = {"A": a, "B": b}
            if config.motion is not None or config.preset is not None:
                try:
                    model = load_motion(preset=config.preset if config.motion is None else None, motion=config.motion)
                except MotionError as e:
                    self.motion_ctl.leave()
                    self.set_dimension(config.dim)
                    st.errors[e.field] = str(e)
                    st.status = ""
                    self.refresh()
                    self.ready.set()
                    return
                self.motion_ctl.start(model, t=config.t, event=config.event)
            else:
                self.motion_ctl.leave()
                st.status = ""
                self.set_dimension(config.dim)
                self.refresh()
                self.ready.set()

    def show_motion(self, model: MotionModel, *, t: float | str | None = None, event: int | None = None) -> None:
        """Show a motion the app built itself (trusted, e.g. a pair of moving bodies), analysed as a preset is.

        Args:
            model: the motion (its exact A(t), B(t) as given: nothing is re-read).
            t: time to show (None: the analysis' default).
            event: event to show instead (1-based).
        """
        with self.lock:
            self.ready.clear()
            self.state.errors.clear()
            self.motion_ctl.start(model, t=t, event=event)

    def load_untrusted(self, data: dict[str, Any]) -> None:
        """Show a configuration from a link or an uploaded file (user input).

        It is checked first (an error is shown, the tab keeps what it shows); a typed motion in
        it is read and analysed in worker processes, as if typed in the motion editor.
        """
        try:
            if set(data) == {"error"}:
                raise ValueError(str(data["error"]))
            config = SceneConfig.from_dict(data)
        except ValueError as e:
            with self.lock:
                if not self.ready.is_set() and self.state.motion is None and not self.state.explanation:
                    self.load(self.config)  # a tab opened on a bad link: the default, with the message
                self.state.errors["config"] = str(e)
                self.refresh()
            return
        motion, config.motion = config.motion, None
        if motion is None:
            self.load(config)
            return
        static = dataclasses.replace(config, preset=None)
        self.load(static)
        self.ready.clear()

        def read() -> None:  # in a worker process, waited for on the scene's pool (off the thread that called)
            try:
                model = self.cache.read_typed(motion)
            except MotionError as e:
                self.motion_ctl.show_error(e)
                self.ready.set()
                return
            self.motion_ctl.analyse_pending(model, t=config.t, event=config.event)

        soon(read)

    def snapshot(self) -> SceneConfig:
        """What the tab shows, as a configuration (kept for a reload; the file to download)."""
        with self.lock:
            st = self.state
            cfg = SceneConfig(
                dim=st.dim,
                A=st.shapes["A"],
                B=st.shapes["B"],
                preset=None,
                show_plots=st.show_plots,
                separating_plane=st.separating_plane,
                gizmos=st.gizmos,
                palette=st.palette if st.palette != next(iter(PALETTES)) else None,
            )
            model = st.motion
            if model is not None:
                if model.preset is not None:
                    cfg.preset = model.preset
                else:
                    cfg.motion = model.texts()
                if st.event is not None:
                    cfg.event = st.event
                elif st.t_text is not None:  # the text typed in the t box ("3/4", a closed form)
                    cfg.t = st.t_text
                else:
                    cfg.t = st.t
            return cfg

    def field_error(self, field: str, message: str) -> None:
        """Show ``message`` next to ``field`` (a key of :attr:`AppState.errors`) and redraw."""
        with self.lock:
            self.state.errors[field] = message
            self.refresh()

    # ------------------------------------------------------------------ a lesson's question
    def hold_question(self) -> None:
        """The configuration shown now is the one the open question is about (once it is drawn).

        Until :meth:`reveal`, the relation stays hidden while the tab shows this configuration; a
        different one (an edit, a drag, t moved, Play, a preset) reveals: the student is exploring.
        """
        with self.lock:
            if self.state.answer_hidden:
                self.question = self.snapshot().to_dict()

    def reveal(self) -> None:
        """Show the relation again: colours, labels, readout, sign table ("Reveal the answer")."""
        with self.lock:
            if not self.state.answer_hidden:
                return
            self.state.answer_hidden = False
            self.question = None
            if self.on_reveal is not None:
                self.on_reveal()
            if not self.closed:
                self.refresh()

    def _edited(self) -> bool:
        """The tab shows another configuration than the open question's (lock held)."""
        return self.question is not None and self.ready.is_set() and self.snapshot().to_dict() != self.question

    # ------------------------------------------------------------------ the one refresh
    def refresh(self, *, dragged: str | None = None, defer: bool = False, panel_delay: float | None = None) -> str | None:
        """Draw the state: the picture now, the panel now or (``defer``, drags) within PANEL_PERIOD.

        Args:
            dragged: the shape a gizmo is dragging (its pose is already in the browser; the
                relation comes from ``classify`` at once, explanation and witnesses follow).
            defer: coalesce the panel update (slider, playback).
            panel_delay: seconds before a deferred panel update (default PANEL_PERIOD), if none
                is pending already.

        Returns:
            The certified relation drawn (None: unknown).
        """
        with self.lock, self.batch():
            st = self.state
            if self.closed:  # the tab went away: messages to it would never be delivered
                return st.relation
            self.history.changed()
            if st.answer_hidden and self._edited():
                st.answer_hidden, self.question = False, None
                if self.on_reveal is not None:
                    self.on_reveal()
            if st.motion is None:
                pic = static_picture(st.shapes, quick=dragged is not None, plane=st.separating_plane)
            else:
                pic = motion_picture(st.motion, st.analysis, st.t, st.t_exact, st.event, plane=st.separating_plane)
            self._draw(pic, dragged)
            if pic.quick:
                self._witness_due = True
            if defer or pic.quick:
                self._panels_due = True
            else:
                self._panels_due = False
                self.panel.show(st, plots=False)
                self._plots_due = True  # the plot cursor (the heaviest message) follows at 20 Hz
            self._schedule(self.PANEL_PERIOD if panel_delay is None else panel_delay)
            return st.relation

    def _draw(self, pic: Picture, dragged: str | None = None) -> None:
        st = self.state
        if pic.shapes is not None:
            st.shapes = pic.shapes
        if pic.poses is not None:
            for name, pose in pic.poses.items():
                self.views[name].set_pose(*pose, from_drag=name == dragged)
        st.relation = pic.relation
        palette = PALETTES.get(st.palette, next(iter(PALETTES.values())))
        shown = None if st.answer_hidden else pic.relation  # an open question: neutral grey, labels "A", "B"
        for v in self.views.values():
            v.set_relation(shown, palette)
            v.set_gizmo(st.gizmos and st.motion is None)
        if st.follow and st.motion is not None and pic.poses is not None:
            self.keys_ctl.follow()
        if pic.quick:
            return
        if st.motion is None:
            st.explanation, st.witness = pic.explanation, pic.witness
            if pic.error is None:
                st.errors.pop("shapes", None)
            else:
                st.errors["shapes"] = pic.error
        else:
            st.explanation = st.witness = None
        if st.answer_hidden:  # a contact point or a separating plane would answer the question
            self.markers.show_point(None)
            self.markers.show_plane(None)
        else:
            self.markers.show_point(pic.point, pic.point_label, pic.normal)
            self.markers.show_plane(pic.plane, *(pic.matrices or (None, None)))

    def pending(self) -> bool:
        """True while a coalesced refresh (panel, witnesses, plot cursor) is due."""
        return self._timer is not None

    def _schedule(self, delay: float) -> None:
        if self._timer is None and (self._panels_due or self._plots_due or self._witness_due):
            self._timer = later(delay, self._flush)  # on a long-lived thread: a thread each kept FLINT's caches

    def _flush(self) -> None:
        """The coalesced part of refresh: witnesses after a drag, the panel, the plot cursor."""
        try:
            with self.lock:
                drawn = False
                try:
                    with self.batch():
                        self._flush_due()
                    drawn = True
                finally:
                    # pending() stays true until the panel is drawn (a caller waiting for the
                    # refresh must not see it done while the timer's thread is still drawing)
                    self._timer = None
                    if drawn and not self.closed:
                        self._schedule(self.PANEL_PERIOD)  # something asked again meanwhile
        except RuntimeError as e:  # the tab or the server went away while the timer waited
            if "removed" not in str(e) and "closed" not in str(e):
                raise
            self.closed = True

    def show_panel(self) -> None:
        """Draw the whole panel now, under the lock (the timer's thread may be drawing it too)."""
        with self.lock:
            self.panel.show(self.state)

    def _flush_due(self) -> None:
        """What :meth:`_flush` draws: the due witnesses, panel and plot cursor (lock held)."""
        if self.closed:
            return
        st = self.state
        if self._witness_due:
            self._witness_due = False
            if st.motion is None:
                self._draw(static_picture(st.shapes, quick=False, plane=st.separating_plane))
        if self._panels_due:
            self._panels_due = self._plots_due = False
            self.panel.show(st)
        elif self._plots_due:
            self._plots_due = False
            self.panel.show_plots(st)

    # ------------------------------------------------------------------ entry points
    def apply_drag(self, name: str, position: tuple[float, ...], wxyz: tuple[float, ...]) -> str | None:
        """A gizmo moved shape ``name`` to this pose: update, classify, recolour (hot path).

        Returns:
            The certified relation after the drag ("separate", "tangent", "overlap"), or None.
        """
        return self.shapes_ctl.drag(name, position, wxyz)

    def set_shape(self, name: str, **fields: Any) -> str | None:
        """Set shape parameters from text/numbers (as the GUI fields do); returns the relation.

        Raises:
            ValueError: a bad value (the same message the GUI shows next to the field).
        """
        return self.shapes_ctl.set_shape(name, **fields)

    def set_t(self, t: Any, *, event: int | None = None, defer_panels: bool = False) -> str | None:
        """Move the motion to time t (one timeline step; see :meth:`TimelineControl.set_t`)."""
        return self.timeline_ctl.set_t(t, event=event, defer_panels=defer_panels)

    def jump_to_event(self, k: int) -> str | None:
        """Show the k-th event (1-based) exactly: shapes at alpha_k, relation of the event."""
        return self.timeline_ctl.jump_to_event(k)

    # ------------------------------------------------------------------ camera / lifecycle
    def cameras(self) -> list[viser.CameraHandle]:
        """The cameras to frame: this tab's, or every connected tab's (presenter mode)."""
        if self._cameras is not None:
            return list(self._cameras())
        cam = getattr(self.target, "camera", None)
        return [cam] if cam is not None else []

    def frame_camera(self, *, grid: bool = True, around_shapes: bool = False) -> None:
        """Point the camera(s) at the shapes (2D: from above); a motion: where it goes around t.

        Args:
            grid: lay the grid under them anew.
            around_shapes: frame the shapes drawn now only (following a motion).
        """
        with self.lock:
            if self.closed:  # the tab went away (close() holds the lock while it marks that)
                return
            st = self.state
            if st.motion is not None and not around_shapes:
                an = st.analysis
                lo, hi = an.window if an is not None else st.motion.interval_floats
                half = 0.05 * (hi - lo)
                pts = st.motion.extent_points((max(lo, st.t - half), min(hi, st.t + half)))
            else:
                pts = extent_of((sh.float_pose() for sh in st.shapes.values()), st.dim)
            framing = Framing(pts, st.dim)
            if grid:
                self.grid = frame_cameras(self.scene, self.cameras(), framing, self.grid)
            else:
                for cam in self.cameras():
                    framing.aim(cam)

    def close(self) -> None:
        """Stop playback and ignore pending analyses (the tab went away).

        Returns once a deferred draw the timer's thread has begun is sent (it holds the lock): the
        caller may stop the server next, and messages queued after that go nowhere (viser warns).
        """
        self.closed = True
        self.history.close()
        timer = self._timer
        if timer is not None:
            timer.cancel()
        with self.lock:  # a draw in flight ends; any later one sees `closed` and draws nothing
            pass
