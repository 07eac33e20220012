"""The many-bodies view of one tab: all bodies as instanced meshes, and their contacts.

It is also the way in to the two-body view for any pair.

* Every body is one instance of a batched mesh (viser ``add_batched_meshes_simple``: one draw
  call for thousands), coloured by its worst certified relation (separate green, tangent amber,
  overlap red, invalid grey); separate bodies can be faded so the contacts stand out.
* The GUI lists the pairs (tangent first), opens a file (upload, CSV/NPZ) with an optional
  periodic box, and shows the selected body's pairs. Clicking a body selects it; clicking a body
  it touches (or picking a pair from the list) opens that pair in the existing two-body view
  (:class:`~app.scene.session.Session` on a :class:`~app.scene.state.SceneConfig` built from the
  two bodies' parameters), with a button back to all bodies.

The maths (contacts, picking, configurations) lives in :mod:`app.scene.bodies`.
"""

from __future__ import annotations

import html
import threading
from concurrent.futures import Executor
from functools import lru_cache
from typing import Any

import numpy as np

from core import Relation

from ..bodyfiles import read_bodies, read_bodies_bytes
from .bodies import BodiesModel
from .camera import Framing
from .lighting import light_scene
from .shapes import NEUTRAL, RELATION_COLORS, RELATION_HEX, unit_disc

__all__ = ["BodiesView", "load_model", "MESH_NODE", "FADED_OPACITY"]

MESH_NODE = "/bodies/meshes"
"""Scene name of the batched mesh of all bodies."""
FADED_OPACITY = 0.25
"""Opacity of separate bodies while "Fade separate bodies" is on."""
_DETAIL = ((2000, 2), (20000, 1), (None, 0))
"""Icosphere subdivisions by number of bodies (320, 80 or 20 triangles): thousands of bodies stay
interactive in a software renderer."""


def load_model(path: str, box: Any = None) -> BodiesModel:
    """Read a bodies file and search its contacts (``python -m app serve --bodies FILE``)."""
    bodies = read_bodies(path)
    return BodiesModel(bodies, box, name=str(path).rsplit("/", 1)[-1])


@lru_cache(maxsize=4)
def _sphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.uint32)


class BodiesView:
    """The scene and GUI of one tab showing many bodies (or, after a pick, one pair of them).

    Args:
        target: ``viser.ClientHandle`` of the tab (``.scene``, ``.gui``, ``.camera``).
        model: the bodies to show (None: an empty view with the upload button).
        cache: analysis cache handed to the two-body view.
        executor: where the two-body view runs analyses.
    """

    def __init__(self, target: Any, model: BodiesModel | None, *, cache: Any = None, executor: Executor | None = None) -> None:
        self.target = target
        self.scene = target.scene
        self.gui = target.gui
        self.model = model
        self.cache = cache
        self.executor = executor
        self.session: Any = None
        """The two-body :class:`~app.scene.session.Session` while a pair is open, else None."""
        self.pair: int | None = None
        """Index (in the contacts) of the open pair."""
        self.selected: int | None = None
        self.ready = threading.Event()
        """Set when the current view (all bodies, or a pair) is built."""
        self._lock = threading.RLock()
        self._closed = False
        self._choices: dict[str, int] = {}
        self._syncing = False
        self.show_bodies()

    # ------------------------------------------------------------------ all bodies
    def show_bodies(self) -> None:
        """Build (or rebuild, coming back from a pair) the view of all bodies."""
        with self._lock:
            self.ready.clear()
            if self.session is not None:
                self.session.close()
                self.session = None
            self.pair = None
            self.gui.reset()
            self.scene.reset()
            self._build_scene()
            self._build_gui()
            self._frame_camera()
            self.ready.set()

    def _build_scene(self) -> None:
        scene = self.scene
        light_scene(scene)
        self.mesh = None
        self.labels: list[Any] = []
        m = self.model
        if m is None or len(m.bodies) == 0:
            return
        N = len(m.bodies)
        if m.dim == 2:
            vertices, faces = unit_disc()
        else:
            vertices, faces = _sphere(next(s for n, s in _DETAIL if n is None or N <= n))
        self.mesh = scene.add_batched_meshes_simple(
            MESH_NODE,
            vertices,
            faces,
            batched_wxyzs=m.wxyz.astype(np.float32),
            batched_positions=m.positions.astype(np.float32),
            batched_scales=m.scales.astype(np.float32),
            batched_colors=self._colours(),
            batched_opacities=self._opacities(True),
            side="double" if m.dim == 2 else "front",
            cast_shadow=False,
            receive_shadow=False,
        )
        self.mesh.on_click(self._on_click)
        if m.box is not None:
            self._draw_box(m.box)

    def _colours(self) -> np.ndarray:
        """(N, 3) uint8: each body in the colour of its worst relation (grey: invalid)."""
        assert self.model is not None
        # rows for the codes INVALID (-2), UNDECIDED (-1), SEPARATE, TANGENT, OVERLAP
        table = np.array([NEUTRAL, NEUTRAL, *(RELATION_COLORS[k] for k in ("separate", "tangent", "overlap"))], dtype=np.uint8)
        return table[self.model.worst.astype(np.int64) + 2]

    def _opacities(self, fade: bool) -> np.ndarray:
        assert self.model is not None
        separate = self.model.worst == Relation.SEPARATE
        return np.where(separate & fade, FADED_OPACITY, 1.0).astype(np.float32)

    def _draw_box(self, box: tuple[float, ...]) -> None:
        assert self.model is not None
        from core.bodies.periodic import box_vectors, read_box

        d = self.model.dim
        lo = self.model.positions.min(axis=0)
        vectors = np.zeros((3, 3))
        L = read_box(box, d)
        assert L is not None
        vectors[:d, :d] = box_vectors(L, d)  # columns a1, a2[, a3]: a tilted box is a parallelepiped
        corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in ((0, 1) if d == 3 else (0,))], dtype=float)
        pts = lo + corners @ vectors.T
        segs = [
            (a, b)
            for a in range(len(pts))
            for b in range(a + 1, len(pts))
            if np.count_nonzero(corners[a] != corners[b]) == 1
        ]
        self.scene.add_line_segments(
            "/bodies/box", np.array([[pts[a], pts[b]] for a, b in segs], dtype=np.float32), (90, 90, 90),
            thickness=1.5, thickness_units="screen",
        )

    def _build_gui(self) -> None:
        gui = self.gui
        gui.configure_theme(control_width="large", show_share_button=False)
        gui.add_markdown("**Many bodies** — certified contacts")
        m = self.model
        self.summary = gui.add_markdown(m.summary() if m is not None else "Open a file of bodies (CSV or NPZ).")
        gui.add_html(_legend())
        with gui.add_folder("Contacts"):
            entries = m.listed() if m is not None else []
            self._set_choices(entries)
            self.pairs = gui.add_dropdown(
                "Pair", list(self._choices) or ["(no contacts)"], hint="pick a pair to open it in the two-body view"
            )
            self.open_button = gui.add_button("Open pair", disabled=not self._choices, icon=None)
            self.body_md = gui.add_markdown("Click a body to see its contacts; click one it touches to open the pair.")
            self.fade = gui.add_checkbox("Fade separate bodies", True)
        with gui.add_folder("File", expand_by_default=m is None):
            self.upload = gui.add_upload_button("Open a file of bodies", mime_type=".csv,.npz", hint="CSV (x,y,z,a,b,c,qw,qx,qy,qz or x,y,a,b,angle) or NPZ")
            self.box_text = gui.add_text("Periodic box", "" if m is None or m.box is None else ", ".join(f"{v:g}" for v in m.box), hint="Lx, Ly(, Lz), or Lx, Ly, Lz, xy, xz, yz (tilted); empty: open space")
            self.file_md = gui.add_markdown("")
        self.pairs.on_update(self._on_pick)
        self.open_button.on_click(lambda ev: self._open_current())
        self.fade.on_update(lambda ev: self._on_fade())
        self.upload.on_upload(self._on_upload)
        self.box_text.on_update(self._on_box)

    def _set_choices(self, entries: list[Any]) -> None:
        self._choices = {e.label: e.index for e in entries}

    # ------------------------------------------------------------------ callbacks
    def _on_pick(self, ev: Any) -> None:
        if self._syncing or getattr(ev, "client", None) is None:
            return
        self._open_current()

    def _open_current(self) -> None:
        k = self._choices.get(self.pairs.value)
        if k is not None:
            self.open_pair(k)

    def _on_fade(self) -> None:
        if self.mesh is not None and self.model is not None:
            self.mesh.batched_opacities = self._opacities(bool(self.fade.value))

    def _on_click(self, ev: Any) -> None:
        if self.model is None:
            return
        k = ev.instance_index
        if k is None:
            k = self.model.pick(ev.ray_origin, ev.ray_direction)
        if k is not None:
            self.select(int(k))

    def select(self, body: int) -> int | None:
        """Select a body (a click): show its pairs; open the pair if it touches the previous one.

        Returns:
            The index of the pair opened, or None.
        """
        with self._lock:
            m = self.model
            if m is None or self.session is not None:
                return None
            previous, self.selected = self.selected, body
            if previous is not None and previous != body:
                k = m.pair_between(previous, body)
                if k is not None:
                    self.open_pair(k)
                    return k
            entries = m.listed(body)
            self._set_choices(entries)
            self._syncing = True
            try:
                self.pairs.options = list(self._choices) or ["(no contacts)"]
            finally:
                self._syncing = False
            self.open_button.disabled = not self._choices
            partners = sorted({int(m.result.i[e.index]) if int(m.result.j[e.index]) == body else int(m.result.j[e.index]) for e in entries})
            why = m.invalid.get(body)
            if why:
                text = f"Body **{body}** is invalid: {html.escape(why)}"
            elif partners:
                shown = ", ".join(str(p) for p in partners[:12]) + (" …" if len(partners) > 12 else "")
                text = f"Body **{body}** touches or overlaps {len(partners)} bodies ({shown}): click one, or pick the pair above."
            else:
                text = f"Body **{body}** is separate from all others."
            self.body_md.content = text
            self._label(body)
            return None

    def _label(self, body: int) -> None:
        for h in self.labels:
            h.remove()
        assert self.model is not None
        pos = self.model.positions[body] + np.array([0.0, 0.0, self.model.scales[body].max() if self.model.dim == 3 else 0.0])
        self.labels = [
            self.scene.add_label(f"/bodies/selected/{body}", f"body {body}", position=tuple(float(v) for v in pos), anchor="bottom-center")
        ]

    def _on_upload(self, ev: Any) -> None:
        f = ev.target.value
        self.load_bytes(f.name, f.content)

    def load_bytes(self, name: str, content: bytes) -> str | None:
        """Show the bodies of an uploaded file; returns an error message (also shown) or None."""
        try:
            bodies = read_bodies_bytes(content, name)
            box = _parse_box(self.box_text.value, bodies.dim)
            model = BodiesModel(bodies, box, name=name)
        except ValueError as e:
            self.file_md.content = f'<span style="color:#d62728">⚠ {html.escape(str(e))}</span>'
            return str(e)
        with self._lock:
            self.model = model
            self.selected = None
            self.show_bodies()
        return None

    def _on_box(self, ev: Any) -> None:
        if self.model is None or getattr(ev, "client", None) is None:
            return
        try:
            box = _parse_box(self.box_text.value, self.model.dim)
            model = BodiesModel(self.model.bodies, box, name=self.model.name)
        except ValueError as e:
            self.file_md.content = f'<span style="color:#d62728">⚠ {html.escape(str(e))}</span>'
            return
        with self._lock:
            self.model = model
            self.show_bodies()

    # ------------------------------------------------------------------ one pair
    def open_pair(self, k: int) -> Any:
        """Open pair k (index in the contacts) in the two-body view of this tab."""
        from .session import Session

        with self._lock:
            assert self.model is not None
            cfg, note = self.model.pair_config(k)
            self.ready.clear()
            self.gui.reset()
            self.scene.reset()
            self.pair = k
            back = self.gui.add_button("← All bodies", order=-1000.0)
            self.gui.add_markdown(note, order=-999.0)
            back.on_click(lambda ev: self.show_bodies())
            self.session = Session(self.target, cfg, cache=self.cache, executor=self.executor)
            self.session.frame_camera()
            self.ready.set()
            return self.session

    # ------------------------------------------------------------------ camera, lifecycle
    def _frame_camera(self) -> None:
        cam = getattr(self.target, "camera", None)
        if cam is None or self.model is None or len(self.model.bodies) == 0:
            return
        lo, hi = self.model.extent()
        Framing(np.array([lo, hi]), self.model.dim).aim(cam, fill=1.35 if self.model.dim == 3 else 1.0, view=(0.55, -1.0, 0.7))

    def close(self) -> None:
        """The tab went away: stop the two-body view's work."""
        self._closed = True
        if self.session is not None:
            self.session.close()


def _parse_box(text: str, dim: int) -> tuple[float, ...] | None:
    """The periodic box typed in the GUI ("10, 10, 10"), or None when empty."""
    parts = [p for p in str(text).replace(",", " ").split() if p]
    if not parts:
        return None
    try:
        sides = tuple(float(p) for p in parts)
    except ValueError:
        raise ValueError(f"periodic box: expected {dim} numbers, got {text!r}") from None
    if len(sides) not in (dim, 6) and not (dim == 2 and len(sides) == 3):
        raise ValueError(f"periodic box: expected {dim} sides for {dim}D bodies (or a tilted box: Lx, Ly, Lz, xy, xz, yz), got {len(sides)}")
    return sides


def _legend() -> str:
    items = [("separate", RELATION_HEX["separate"]), ("tangent", RELATION_HEX["tangent"]), ("overlap", RELATION_HEX["overlap"]), ("invalid", "#969696")]
    spans = "".join(
        f'<span style="display:inline-block;margin-right:10px"><span style="display:inline-block;width:10px;height:10px;'
        f'border-radius:5px;background:{c};margin-right:4px"></span>{n}</span>'
        for n, c in items
    )
    return f'<div style="font-size:0.85em;padding:2px 0">{spans}</div>'
