"""What the user does to the shapes and the view: drag a gizmo, type a centre, switch 2D/3D, toggles.

Each callback changes the tab's :class:`~app.scene.common.state.AppState` and calls the session's one
``refresh()``; a bad value is stored as the error of its field (shown next to it) and changes
nothing else. A drag or a typed shape during a motion leaves the motion: the shapes stay where
they were drawn and become static.
"""

from __future__ import annotations

import math
from functools import partial
from typing import TYPE_CHECKING, Any

import viser

from core.shapes.numbers import to_fmpq

from ..common.mesh_detail import DRAWABLE
from ..common.state import SceneConfig, ShapeState
from .gui import DIM_LABELS, ignoring_event

if TYPE_CHECKING:
    from .session_view import SessionView

__all__ = ["ShapeControl", "drawable", "DRAWABLE"]


def drawable(shape: ShapeState) -> ShapeState:
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


class ShapeControl:
    """Callbacks of the shape folders, the gizmos and the View folder of one session."""

    def __init__(self, session: SessionView) -> None:
        self.s = session
        ui = session.ui
        for name, sg in ui.shapes.items():
            for key, handle in sg.fields.items():
                handle.on_update(ignoring_event(partial(self.on_shape_text, name, key)))
        ui.view.dimension.on_update(lambda _ev: self.on_dimension())
        ui.view.gizmos.on_update(lambda _ev: self.on_option("gizmos", bool(ui.view.gizmos.value)))
        ui.view.plane.on_update(lambda _ev: self.on_option("separating_plane", bool(ui.view.plane.value)))
        ui.view.palette.on_update(lambda _ev: self.on_option("palette", str(ui.view.palette.value)))
        ui.plots.live.on_update(lambda _ev: self.on_option("show_plots", bool(ui.plots.live.value)))
        ui.plots.scale.on_update(lambda _ev: self.on_option("plot_scale", str(ui.plots.scale.value)))
        ui.roots.show_roots.on_update(lambda _ev: self.on_roots())
        ui.roots.axes.on_update(lambda _ev: self.on_roots())

    def attach_gizmos(self) -> None:
        """Listen to the gizmos of the current shape views (after they are (re)built)."""
        for name, view in self.s.views.items():
            view.control.on_update(partial(self.on_gizmo, name))

    # ------------------------------------------------------------------ callbacks
    def on_gizmo(self, name: str, ev: viser.TransformControlsEvent) -> None:
        """A gizmo moved: the drag path (recolour now, readout within the panel period)."""
        if self.s.syncing.active:
            return
        tc = ev.target
        self.drag(name, tuple(tc.position), tuple(tc.wxyz))
        if getattr(ev, "phase", None) == "end":  # the drag is over: draw the shape certified (the
            with self.s.lock:                   # decimals its fields show), not the pointer's float pose
                self.s.views[name].resend_pose()

    def drag(self, name: str, position: tuple[float, ...], wxyz: tuple[float, ...]) -> str | None:
        """Shape ``name`` now has this pose (floats): classify, recolour (the hot path)."""
        s = self.s
        with s.lock:
            st = s.state
            if st.motion is not None:
                s.motion_ctl.freeze()
            sh = st.shapes[name]
            axes = sh.semi_axes
            if st.dim == 2:
                angle = 2.0 * math.atan2(float(wxyz[3]), float(wxyz[0]))
                new = ShapeState((float(position[0]), float(position[1])), axes, (angle,))
            else:
                new = ShapeState(tuple(float(v) for v in position), axes, tuple(float(v) for v in wxyz))
            try:  # the shape becomes exactly the decimals its fields show (SHOWN_DIGITS)
                new = new.rationalised()
                if sh.matrix is None and "semi_axes" in sh.typed:  # unchanged by a drag: still as typed
                    new.typed = {"semi_axes": sh.typed["semi_axes"]}
            except ValueError as e:
                s.field_error(f"shape {name}", str(e))
                return st.relation
            st.shapes[name] = new
            st.errors.pop(f"shape {name}", None)
            return s.refresh(dragged=name)

    def on_shape_text(self, name: str, key: str) -> None:
        """A Shape field was edited: read it exactly; an error stays next to the field."""
        if self.s.syncing.active:
            return
        value = self.s.panel.take(self.s.ui.shapes[name].fields[key])
        try:
            self.set_shape(name, **{key: value})
        except ValueError as e:
            self.s.field_error(f"shape {name}", str(e))

    def set_shape(self, name: str, **fields: Any) -> str | None:
        """Set shape parameters from text/numbers (as the GUI fields do); returns the relation.

        Raises:
            ValueError: a bad value (the same message the GUI shows next to the field).
        """
        s = self.s
        with s.lock:
            st = s.state
            if st.motion is not None:  # the shapes drawn at t become the decimals shown, exactly
                s.motion_ctl.freeze()
            old = st.shapes[name]
            # a new matrix replaces the shape; a new centre (etc.) edits the shape's parameters,
            # the others as their fields show them (a computed float: the decimals shown)
            typed: dict[str, str] = {}
            if "matrix" in fields:
                d: dict[str, Any] = {}
            else:
                base = old if old.matrix is None else ShapeState(old.center, old.semi_axes, old.orientation)
                base = base.rationalised()
                d = base.params_dict()
                typed = {k: v for k, v in old.typed.items() if k != "matrix"} if old.matrix is None else {}
            d.update(fields)
            new = drawable(ShapeState.from_dict(d, st.dim, name))
            for key, value in fields.items():
                if isinstance(value, str):
                    typed[key] = value.strip()
            new.typed = typed
            st.shapes[name] = new
            st.errors.pop(f"shape {name}", None)
            return s.refresh()

    def on_dimension(self) -> None:
        """View -> Dimension: the other dimension's default static shapes."""
        s = self.s
        if s.syncing.active:
            return
        dim = 3 if str(s.ui.view.dimension.value) == DIM_LABELS[3] else 2
        if dim != s.state.dim:
            st = s.state
            s.load(SceneConfig(dim=dim, preset=None, gizmos=st.gizmos, show_plots=st.show_plots,
                               separating_plane=st.separating_plane, palette=st.palette))
            s.frame_camera()

    def on_roots(self) -> None:
        """"Show the roots of P(T)" switched: the panel draws (or removes) the roots' plots."""
        s = self.s
        if s.syncing.active:
            return
        with s.lock:
            s.refresh()

    def on_option(self, key: str, value: Any) -> None:
        """A display option (gizmos, plane, palette, plots): stored and drawn."""
        s = self.s
        if s.syncing.active:
            return
        with s.lock:
            setattr(s.state, key, value)
            s.refresh()
