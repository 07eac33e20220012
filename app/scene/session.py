"""One browser tab: its own shapes, GUI, motion, timeline and plots (``client.scene``/``client.gui``).

A :class:`Session` owns an :class:`~app.scene.state.AppState` and the handles that show it.
Callbacks only update the state and call one refresh; the maths is in ``core``. The two hot
paths have cheap entry points that need no browser, for the benchmark helper:
:meth:`Session.apply_drag` (a gizmo drag event) and :meth:`Session.set_t` (one t step);
:func:`app.scene.costs.measure_update_costs` times both and counts the websocket messages
they queue. The timeline (:mod:`app.scene.timeline`) and the motion panel
(:mod:`app.scene.motion_panel`) are mixins of :class:`Session`.
"""

from __future__ import annotations

import html
import math
import threading
from concurrent.futures import Executor, Future
from contextlib import nullcontext
from typing import Any, ContextManager

import numpy as np

from core import Relation, classify, explain
from core.shapes.numbers import to_fmpq

from . import plots
from .analysis import (
    AnalysisCache,
    AnalysisView,
    MotionError,
    MotionModel,
    list_presets,
    load_motion,
)
from .contact import WitnessView, contact_point, witness_view
from .motion_panel import STATIC, MotionPanelMixin
from .panels import readout_markdown
from .shapes import EllipsoidView
from .state import AppState, SceneConfig, ShapeState, format_number
from .timeline import TimelineMixin

__all__ = ["Session"]


class _Counter:
    """Counts messages queued on a websocket interface (wraps ``queue_message`` of one object)."""

    def __init__(self, iface: Any) -> None:
        self.count = 0
        orig = iface.queue_message

        def counting(message: Any) -> None:
            self.count += 1
            orig(message)

        iface.queue_message = counting


class Session(MotionPanelMixin, TimelineMixin):
    """The scene and GUI of one tab.

    Args:
        target: ``viser.ClientHandle`` (one tab) or ``viser.ViserServer`` (shared scene); anything
            with ``.scene`` and ``.gui``.
        config: what to open on.
        cache: analysis cache shared by the sessions of one server (keyed by motion + interval).
        executor: where analyses run (off the GUI thread).
        count_messages: count queued websocket messages in :attr:`messages` (benchmarks).
    """

    def __init__(
        self,
        target: Any,
        config: SceneConfig | None = None,
        *,
        cache: AnalysisCache | None = None,
        executor: Executor | None = None,
        count_messages: bool = False,
    ) -> None:
        self.target = target
        self.scene = target.scene
        self.gui = target.gui
        self.config = config or SceneConfig()
        self.cache = cache or AnalysisCache()
        self.executor = executor
        self._counter = _Counter(self.scene._websock_interface) if count_messages else None
        self._lock = threading.RLock()
        self._syncing = False
        self._closed = False
        self._play_thread: threading.Thread | None = None
        self.model: MotionModel | None = None
        self.analysis: AnalysisView | None = None
        self._pending: Future[Any] | None = None
        self.ready = threading.Event()
        """Set when the configuration is loaded and (for a motion) analysed and drawn."""
        a, b = self.config.shapes()
        self.state = AppState(dim=self.config.dim, shapes={"A": a, "B": b})
        self.views: dict[str, EllipsoidView] = {}
        self._event_buttons: list[Any] = []
        self._plot_index = -2
        self._auto_t = False
        self._panels_due = False
        self._static_due = False
        self._plots_due = False
        self._panel_timer: threading.Timer | None = None
        self._plot_data: tuple[Any, Any, Any] | None = None
        self._last_text: dict[int, str] = {}
        self._build_scene()
        self._build_gui()
        self.timeline_folder.visible = False
        self.plots_folder.visible = False
        self.load(self.config)

    # ------------------------------------------------------------------ building
    @property
    def messages(self) -> int:
        """Websocket messages queued so far (only with ``count_messages=True``)."""
        return self._counter.count if self._counter else 0

    def _build_scene(self) -> None:
        self.scene.configure_environment_map(hdri=None)
        self.scene.set_up_direction("+z")
        self._make_views()
        self.contact = self.scene.add_icosphere(
            "/contact/point", radius=0.06, color=(20, 20, 20), visible=False
        )
        self.contact_label = self.scene.add_label("/contact/point/label", "contact", visible=False)
        self._contact_on = False
        square = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float32)
        self.plane = self.scene.add_mesh_simple(
            "/separating_plane",
            square,
            np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32),
            color=(60, 110, 200),
            opacity=0.35,
            side="double",
            cast_shadow=False,
            receive_shadow=False,
            visible=False,
        )
        self._plane_on = False

    def _make_views(self) -> None:
        for v in self.views.values():
            v.control.remove()
        self.views = {
            name: EllipsoidView(self.scene, name, self.state.dim, gizmo=self.config.gizmos) for name in ("A", "B")
        }
        for name, view in self.views.items():
            view.control.on_update(lambda ev, n=name: self._on_gizmo(n, ev))

    def _build_gui(self) -> None:
        gui = self.gui
        gui.configure_theme(control_width="large", show_share_button=False)
        self.title = gui.add_markdown("**Ellipse / ellipsoid interference** (certified)")
        self.readout = gui.add_markdown("")
        with gui.add_folder("Timeline") as self.timeline_folder:
            self.bar = gui.add_html("")
            self.t_slider = gui.add_slider("t", min=0.0, max=1.0, step=0.001, initial_value=0.0)
            self.t_number = gui.add_text("t (exact)", "0", hint="a number or fraction (3/4), or α1, α2, … for an event")
            self.t_error = gui.add_markdown("", visible=False)
            self.play = gui.add_checkbox("Play", False)
            self.speed = gui.add_slider("Speed (I per 10 s)", min=0.1, max=5.0, step=0.1, initial_value=1.0)
            self.events_md = gui.add_markdown("")
            self.events_folder = gui.add_folder("Events (jump to)")
        with gui.add_folder("Plots") as self.plots_folder:
            self.plots_on = gui.add_checkbox("Live plots", self.config.show_plots)
            self.plot_coeffs = plots.add_plot(gui, "a_i(t) (asinh)", 4)
            self.plot_subres = plots.add_plot(gui, "s0, s1, s1,0 (asinh)", 3)
        with gui.add_folder("Motion") as self.motion_folder:
            options = [STATIC, *list_presets()]
            self.preset = gui.add_dropdown("Preset", options, initial_value=STATIC)
            self.preset_md = gui.add_markdown("")
            self.motion_fields: dict[str, Any] = {}
            self.motion_errors: dict[str, Any] = {}
            for key, label in (("A", "Motion of A"), ("B", "Motion of B"), ("interval", "Interval I")):
                self.motion_fields[key] = gui.add_text(label, "", multiline=key != "interval")
                self.motion_errors[key] = gui.add_markdown("", visible=False)
            self.analyse_button = gui.add_button("Analyse motion")
            self.progress = gui.add_progress_bar(0.0, visible=False, animated=True)
            self.status = gui.add_markdown("")
        self.shape_fields: dict[str, dict[str, Any]] = {}
        self.shape_errors: dict[str, Any] = {}
        for name in ("A", "B"):
            with gui.add_folder(f"Shape {name}", expand_by_default=False) as folder:
                f = {
                    "center": gui.add_text("Centre", ""),
                    "semi_axes": gui.add_text("Semi-axes", ""),
                    "orientation": gui.add_text("Orientation", ""),
                }
                self.shape_errors[name] = gui.add_markdown("", visible=False)
            self.shape_fields[name] = f
            setattr(self, f"folder_{name}", folder)
            for key, handle in f.items():
                handle.on_update(lambda ev, n=name, k=key: self._on_shape_text(n, k, ev))
        with gui.add_folder("Sign table", expand_by_default=False):
            self.sign_table = gui.add_markdown("")
        with gui.add_folder("View", expand_by_default=False):
            self.dim_choice = gui.add_dropdown("Dimension", ["3D ellipsoids", "2D ellipses"], initial_value="3D ellipsoids" if self.state.dim == 3 else "2D ellipses")
            self.show_gizmos = gui.add_checkbox("Transform gizmos", self.config.gizmos)
            self.show_plane = gui.add_checkbox("Separating plane (when separate)", self.config.separating_plane)
        self.t_slider.on_update(lambda ev: self._on_slider(ev))
        self.t_number.on_update(lambda ev: self._on_t_text(ev))
        self.play.on_update(lambda ev: self._on_play())
        self.preset.on_update(lambda ev: self._on_preset(ev))
        self.analyse_button.on_click(lambda ev: self._on_analyse_click())
        self.plots_on.on_update(lambda ev: self._refresh_plots(force=True))
        self.dim_choice.on_update(lambda ev: self._on_dim(ev))
        self.show_gizmos.on_update(lambda ev: self._update_gizmos())
        self.show_plane.on_update(lambda ev: self._on_plane_toggle())

    # ------------------------------------------------------------------ loading
    def load(self, config: SceneConfig) -> None:
        """Show a configuration: static shapes, then the motion (analysed in the background)."""
        with self._lock:
            self.config = config
            self.ready.clear()
            if config.dim != self.state.dim:
                self.state.dim = config.dim
                self._make_views()
            a, b = config.shapes()
            self.state.shapes = {"A": a, "B": b}
            self.state.event = config.event
            self._sync_shape_fields()
            self._set_value(self.dim_choice, "3D ellipsoids" if config.dim == 3 else "2D ellipses")
            name = config.preset if config.motion is None else None
            if config.motion is not None or config.preset is not None:
                try:
                    self.model = load_motion(preset=name, motion=config.motion, dim=config.dim)
                except MotionError as e:
                    self.model = None
                    self._show_motion_error(e)
                    self._refresh_static()
                    self.ready.set()
                    return
                if self.model.dim != self.state.dim:
                    self.state.dim = self.model.dim
                    self._make_views()
                self._set_value(self.preset, name if name in list_presets() else STATIC)
                self._show_motion_fields()
                t = config.t if config.t is not None else self.model.default_t
                self._auto_t = config.t is None and config.event is None
                self.state.t = float(t)
                self._analyse()
            else:
                self.model = None
                self._set_value(self.preset, STATIC)
                self._refresh_static()
                self.ready.set()

    # ------------------------------------------------------------------ callbacks
    def _set_value(self, handle: Any, value: Any) -> None:
        """Assign a GUI value from Python without running our own callback logic."""
        if handle.value == value:
            return
        self._syncing = True
        try:
            handle.value = value
        finally:
            self._syncing = False

    def _batch(self) -> ContextManager[None]:
        """One websocket batch for an update (viser's ``atomic``): the client applies the poses,
        colours and panels of one step together, and the server wakes its sender once per step
        instead of once per message.
        """
        atomic = getattr(self.target, "atomic", None)
        return atomic() if atomic is not None else nullcontext()

    def _on_gizmo(self, name: str, ev: Any) -> None:
        if self._syncing:
            return
        tc = ev.target
        self.apply_drag(name, tuple(tc.position), tuple(tc.wxyz))

    def apply_drag(self, name: str, position: tuple[float, ...], wxyz: tuple[float, ...]) -> str | None:
        """A gizmo moved shape ``name`` to this pose: update, classify, recolour (hot path).

        Returns:
            The certified relation after the drag ("separate", "tangent", "overlap"), or None.
        """
        with self._lock, self._batch():
            if self.model is not None:
                self._leave_motion()
            sh = self.state.shapes[name]
            if self.state.dim == 2:
                import math

                angle = 2.0 * math.atan2(float(wxyz[3]), float(wxyz[0]))
                new = ShapeState((float(position[0]), float(position[1])), sh.semi_axes, (angle,))
            else:
                new = ShapeState(tuple(float(v) for v in position), sh.semi_axes, tuple(float(v) for v in wxyz))
            self.state.shapes[name] = new
            self._sync_shape_fields(only=name)
            return self._refresh_static(dragged=name)

    def _on_shape_text(self, name: str, key: str, ev: Any) -> None:
        if self._syncing:
            return
        with self._lock:
            sh = self.state.shapes[name]
            d = sh.to_dict()
            d[key] = self.shape_fields[name][key].value
            try:
                new = _drawable(ShapeState.from_dict(d, self.state.dim, name))
            except ValueError as e:
                self._field_error(self.shape_errors[name], str(e))
                return
            self._field_error(self.shape_errors[name], None)
            if self.model is not None:
                self._leave_motion()
            self.state.shapes[name] = new
            self._refresh_static()

    def set_shape(self, name: str, **fields: Any) -> str | None:
        """Set shape parameters from text/numbers (as the GUI fields do); returns the relation.

        Raises:
            ValueError: a bad value (the same message the GUI shows next to the field).
        """
        with self._lock:
            d = self.state.shapes[name].to_dict()
            d.update(fields)
            new = _drawable(ShapeState.from_dict(d, self.state.dim, name))
            if self.model is not None:
                self._leave_motion()
            self.state.shapes[name] = new
            self._sync_shape_fields(only=name)
            return self._refresh_static()

    def _field_error(self, md: Any, message: str | None) -> None:
        if message is None:
            md.visible = False
        else:
            # typed text comes back in messages: escape it (a shared scene shows it to every tab)
            md.content = f'<span style="color:#d62728">⚠ {html.escape(message)}</span>'
            md.visible = True

    def _sync_shape_fields(self, only: str | None = None) -> None:
        for name, sh in self.state.shapes.items():
            if only is not None and name != only:
                continue
            f = self.shape_fields[name]
            self._set_value(f["center"], ", ".join(format_number(v) for v in sh.center))
            self._set_value(f["semi_axes"], ", ".join(format_number(v) for v in sh.semi_axes))
            self._set_value(f["orientation"], ", ".join(format_number(v) for v in sh.orientation))

    def _on_dim(self, ev: Any) -> None:
        if self._syncing:
            return
        dim = 3 if self.dim_choice.value.startswith("3") else 2
        if dim != self.state.dim:
            cfg = SceneConfig(dim=dim, preset=None, gizmos=self.show_gizmos.value, show_plots=self.plots_on.value)
            self.load(cfg)
            self._frame_camera()

    def _on_plane_toggle(self) -> None:
        with self._lock:
            if self.model is not None:
                t = self.state.t if self.state.t_exact is None else self.state.t_exact
                self.set_t(t, event=self.state.event)
            else:
                self._refresh_static()

    def _update_gizmos(self) -> None:
        for v in self.views.values():
            v.set_gizmo(self.show_gizmos.value and self.model is None)

    # ------------------------------------------------------------------ static refresh
    def _refresh_static(self, dragged: str | None = None) -> str | None:
        """Classify the static shapes, recolour, update readout and contact point.

        A drag (``dragged`` names the shape) recolours from :func:`core.classify` at once
        (microseconds: the certified relation) and leaves the full readout (``explain``, the
        contact point, the plane) to the coalesced panel refresh, at most every PANEL_PERIOD.
        """
        shapes = self.state.shapes
        for name, sh in shapes.items():
            pos, wxyz, scale = sh.float_pose()
            self.views[name].set_pose(pos, wxyz, scale, from_drag=name == dragged)
        if dragged is not None:
            try:
                relation = str(classify(shapes["A"].quadric(), shapes["B"].quadric()))
            except ValueError as e:
                return self._show_static_error(e)
            self._set_relation(relation)
            self._static_due = True
            self._schedule_flush()
            return relation
        return self._static_panels()

    def _show_static_error(self, e: Exception) -> None:
        self.state.explanation = None
        self._set_relation(None)
        self._set_md(self.readout, readout_markdown(None, error=str(e)))
        return None

    def _static_panels(self) -> str | None:
        """The full static readout: explain, relation, contact point, plane (what a drag defers)."""
        self._static_due = False
        shapes = self.state.shapes
        try:
            A, B = shapes["A"].quadric(), shapes["B"].quadric()
            expl = explain(A, B).to_dict()
        except ValueError as e:
            return self._show_static_error(e)
        self.state.explanation = expl
        self._set_relation(expl["relation"])
        view = witness_view(A, B, expl["relation"])  # margin, sentence, certified plane / point
        self._set_md(self.readout, readout_markdown(expl, where="(static shapes)", witness=view and view.readout()))
        self._update_contact(A, B, expl, view)
        self._update_plane(A, B, expl["relation"], view)
        self._update_gizmos()
        return expl["relation"]

    def _set_md(self, handle: Any, text: str) -> None:
        if self._last_text.get(id(handle)) != text:
            self._last_text[id(handle)] = text
            handle.content = text

    def _set_relation(self, relation: str | None) -> None:
        self.state.relation = relation
        for v in self.views.values():
            v.set_relation(relation)

    def _update_contact(self, A: Any, B: Any, expl: dict[str, Any] | None, view: WitnessView | None = None) -> None:
        """Contact point: the certified witness when ``view`` has one, else a float estimate.

        The witness: where they touch, with the common normal (tangent), or a point inside both
        (overlap). Without one, at a timeline tangency: the float kernel of the pencil (display
        only: the float matrices at an algebraic event time are not tangent).
        """
        point, normal, label = None, None, "contact"
        if view is not None and view.point is not None:
            point, normal, label = view.point, view.normal, view.point_label
        elif expl is not None and expl["relation"] == str(Relation.TANGENT):
            point = contact_point(A, B, [q["approx"] for q in expl["coefficients"]])
        if point is None:
            if self._contact_on:
                self.contact.visible = False
                self.contact_label.visible = False
                self._contact_on = False
            self._show_normal(None)
            return
        p = tuple(float(v) for v in point) + ((0.0,) if len(point) == 2 else ())
        self.contact.position = p
        if self.contact_label.text != label:
            self.contact_label.text = label
        if not self._contact_on:
            self.contact.visible = True
            self.contact_label.visible = True
            self._contact_on = True
        self._show_normal(normal)

    def _show_normal(self, normal: Any) -> None:
        """The common normal at the contact point: a short segment (created on first use)."""
        line = getattr(self, "_normal_line", None)
        if normal is None:
            if line is not None and line.visible:
                line.visible = False
            return
        n = np.array([float(v) for v in normal] + ([0.0] if len(normal) == 2 else []))
        if line is None:
            segment = np.array([[[0.0, 0.0, 0.0], [0.0, 0.0, 0.6]]], dtype=np.float32)
            line = self._normal_line = self.scene.add_line_segments(
                "/contact/point/normal", segment, (20, 20, 20), thickness=0.015
            )
        axis = np.cross([0.0, 0.0, 1.0], n)
        w = 1.0 + float(n[2])
        q = np.array([w, *axis]) if w > 1e-9 else np.array([0.0, 1.0, 0.0, 0.0])
        line.wxyz = tuple(float(v) for v in q / np.linalg.norm(q))
        if not line.visible:
            line.visible = True

    def _update_plane(self, A: Any, B: Any, relation: str | None, view: WitnessView | None = None) -> None:
        """The certified separating plane (core.witness) when asked for and the shapes are separate."""
        found = None
        if self.show_plane.value and relation == str(Relation.SEPARATE):
            if view is None:  # timeline: the float matrices at t, certified by core.witness
                from core.witness import separating_plane_batch

                try:
                    pb = separating_plane_batch(np.asarray(A, dtype=float), np.asarray(B, dtype=float))
                    if bool(pb.certified):
                        found = (np.asarray(pb.normal, dtype=float), float(pb.offset))
                except (ValueError, ArithmeticError):
                    found = None
            else:
                found = view.plane
        if found is None:
            if self._plane_on:
                self.plane.visible = False
                self._plane_on = False
            return
        n, h = found
        Af = np.array([[float(v) for v in row] for row in A], dtype=float)
        Bf = np.array([[float(v) for v in row] for row in B], dtype=float)
        d = Af.shape[0] - 1
        cA = -np.linalg.solve(Af[:d, :d], Af[:d, d])
        cB = -np.linalg.solve(Bf[:d, :d], Bf[:d, d])
        mid = (cA + cB) / 2
        p = mid + (h - n @ mid) * n
        n3 = np.append(n, 0.0) if d == 2 else n
        p3 = np.append(p, 0.0) if d == 2 else p
        z = np.array([0.0, 0.0, 1.0])
        axis = np.cross(z, n3)
        w = 1.0 + float(z @ n3)
        q = np.array([w, *axis]) if w > 1e-9 else np.array([0.0, 1.0, 0.0, 0.0])
        q /= np.linalg.norm(q)
        size = 0.75 * float(np.linalg.norm(cB - cA)) + 1.0
        self.plane.position = tuple(float(v) for v in p3)
        self.plane.wxyz = tuple(float(v) for v in q)
        self.plane.scale = (size, size, 1.0)
        if not self._plane_on:
            self.plane.visible = True
            self._plane_on = True

    # ------------------------------------------------------------------ motion


    # ------------------------------------------------------------------ plots

    # ------------------------------------------------------------------ camera / lifecycle
    def _frame_camera(self) -> None:
        """Point the tab's camera at the shapes (2D: from above)."""
        cam = getattr(self.target, "camera", None)
        if cam is None:
            return
        pts = []
        for sh in self.state.shapes.values():
            pos, _, scale = sh.float_pose()
            r = max(scale[:2] if self.state.dim == 2 else scale)
            pts += [np.array(pos) + r, np.array(pos) - r]
        if self.model is not None:
            pts = self.model.extent_points(around=self.state.t)
        lo, hi = np.min(pts, axis=0), np.max(pts, axis=0)
        centre = (lo + hi) / 2
        radius = max(float(np.linalg.norm(hi - lo)) / 2, 1.0)
        try:
            fov, aspect = float(cam.fov), float(cam.aspect)
        except Exception:  # noqa: BLE001 - camera state not known yet: typical values
            fov, aspect = 1.3, 1.5
        # the GUI panel covers about the right 35 % of the page: fit the shapes in the left 62 %
        # and aim right of them by the matching offset
        free = 0.62
        half_h = math.tan(fov / 2)
        dist = 0.9 * radius / (half_h * min(1.0, free * aspect))
        shift = (0.5 - free / 2) * 2 * dist * half_h * aspect
        size = float(2 ** math.ceil(math.log2(4 * radius)))
        floor = 0.0 if self.state.dim == 2 else float(lo[2])
        self.grid = self.scene.add_grid(
            "/grid",
            width=size,
            height=size,
            plane="xy",
            cell_size=size / 16,
            section_size=size / 4,
            position=(float(centre[0]), float(centre[1]), floor - (0.02 if self.state.dim == 2 else 0.0)),
        )
        if self.state.dim == 2:
            cam.up_direction = (0.0, 1.0, 0.0)
            x = float(centre[0]) + shift
            cam.position = (x, float(centre[1]) - 1e-3, dist)
            cam.look_at = (x, float(centre[1]), 0.0)
        else:
            cam.up_direction = (0.0, 0.0, 1.0)
            view = np.array([0.3, -1.05, 0.6])
            view /= np.linalg.norm(view)
            right = np.cross(-view, np.array([0.0, 0.0, 1.0]))
            right /= np.linalg.norm(right)
            # viser keeps the orientation when the position is set: position first, then look_at
            cam.position = tuple(float(v) for v in centre + dist * view + shift * right)
            cam.look_at = tuple(float(v) for v in centre + shift * right)

    def close(self) -> None:
        """Stop playback and ignore pending analyses (the tab went away)."""
        self._closed = True


def _drawable(shape: ShapeState) -> ShapeState:
    """The shape if it is valid and inside the scene's drawing range, else ValueError.

    A typed centre of 1e300 is exact, but its matrix, its drawing and the readout's floats
    would overflow: the scene takes |centre| <= 1e12 and semi-axes in [1e-12, 1e12].
    """
    shape.quadric()
    big = to_fmpq(DRAWABLE)
    if any(abs(to_fmpq(v)) > big for v in shape.center):
        raise ValueError(f"centre too far for the scene (|x| <= {DRAWABLE:g})")
    if any(not 1 / big <= to_fmpq(v) <= big for v in shape.semi_axes):
        raise ValueError(f"semi-axes out of the scene's range [{1 / DRAWABLE:g}, {DRAWABLE:g}]")
    return shape


DRAWABLE = 10**12
"""Largest |coordinate| and semi-axis (and 1 / smallest semi-axis) of a shape typed in the
scene: entries of its matrix stay below 1e48 and the readout's floats finite."""
