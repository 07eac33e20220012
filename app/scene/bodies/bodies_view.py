"""The many-bodies view of one tab: all bodies, their contacts, the way into the two-body view.

* Every body is drawn as a point, and the bodies largest on screen for the tab's camera as
  solids on top (:mod:`app.scene.bodies.bodies_layers`, :mod:`app.scene.bodies.bodies_lod`: 100,000 bodies
  stay interactive in software WebGL), each in the colour of its worst certified relation
  (separate green, tangent amber, overlap red, invalid grey). Separate bodies can be shown,
  faded or hidden; the contact network (a line per contact pair) can be shown.
* The GUI lists the pairs a page at a time ("showing 1–200 of 2,228 pairs"), filtered by
  relation and by body index; it opens a file (upload, CSV/NPZ) with an optional periodic box.
  Clicking a body selects it (its pairs are listed); clicking a body it touches, or picking a
  pair from the list, opens that pair in the existing two-body view
  (:class:`~app.scene.pair.session.Session` on a :class:`~app.scene.common.state.SceneConfig` built from
  the two bodies' parameters), with a button back to all bodies.

The maths (contacts, the list, picking, configurations) lives in :mod:`app.scene.bodies.model`.

Moving bodies (``serve --bodies START --to END``: a :class:`~app.scene.bodies.sweep_model.SweepModel`)
are the same view with a Timeline folder (:class:`~app.scene.bodies.sweep_view.SweepTimeline`): the
bodies at t coloured by their certified relation there, the list holds the contact events in
time order, and an event opens its pair in the two-body view on the pair's exact motion.
"""

from __future__ import annotations

import html
import threading
import time
from concurrent.futures import Executor
from typing import TYPE_CHECKING, Any

import numpy as np

from ...bodyfiles import BodySet, read_bodies
from ..common.camera import Framing
from ..common.lighting import light_scene
from ..common.mesh_detail import SPHERE_SUBDIVISIONS
from ..common.shapes import RELATION_HEX
from ..common.wire import Refusal, too_large
from .bodies_layers import SEPARATE_MODES, BodyLayers, relation_colour_rows
from .bodies_lod import ViewPose
from .model import UPLOAD_BYTES, UPLOAD_SECONDS, BodiesModel, PairPage, tab_bodies_job

if TYPE_CHECKING:
    from core import Box

    from ..pair.analysis import AnalysisCache

__all__ = ["BodiesView", "load_model", "NO_PAIRS"]

NO_PAIRS = "(no pairs)"
"""The pair list's only option when no pair passes the filter."""
CAMERA_QUIET = 0.12
"""Seconds without a camera message after which the solids are chosen anew."""
CAMERA_MAX_WAIT = 0.5
"""While the camera keeps moving, the solids are chosen anew at least this often (seconds)."""


def load_model(path: str, box: Any = None, *, frame: int | None = None, format: str | None = None) -> BodiesModel:
    """Read a bodies file and search its contacts (``python -m app serve --bodies FILE``).

    ``box`` (``--box``) overrides the file's own periodic box (a GSD/LAMMPS/extxyz box is used
    when none is given; any form of :meth:`core.Box.from_any`: :func:`app.bodies_cli.command_box`).
    """
    from ...bodies_cli import command_box

    bodies = read_bodies(path, frame=frame, format=format)
    return BodiesModel(bodies, command_box(box, bodies), name=str(path).rsplit("/", 1)[-1])


class BodiesView:
    """The scene and GUI of one tab showing many bodies (or, after a pick, one pair of them).

    Args:
        target: ``viser.ClientHandle`` of the tab (``.scene``, ``.gui``, ``.camera``), or a
            ``viser.ViserServer`` (no camera: no solids until :meth:`set_pose`).
        model: the bodies to show (None: an empty view with the upload button).
        cache: analysis cache handed to the two-body view.
        executor: where the two-body view runs analyses.
        sphere_subdivisions: of the two-body view's solids (:class:`app.scene.pair.session.Session`).
        uploads: the server's :class:`~app.scene.common.wire.UploadGuard`: a file over
            :data:`~app.scene.bodies.model.UPLOAD_BYTES` is refused before the server keeps it, and the
            panel says so (None: checked once received).
    """

    def __init__(
        self, target: Any, model: BodiesModel | None, *, cache: Any = None, executor: Executor | None = None,
        sphere_subdivisions: int = SPHERE_SUBDIVISIONS, uploads: Any = None,
    ) -> None:
        self.sphere_subdivisions = sphere_subdivisions
        self.uploads = uploads
        self.target = target
        self.scene = target.scene
        self.gui = target.gui
        if getattr(model, "moving", False):  # moving bodies: this tab's own time (the sweep is shared)
            model = model.for_view()  # type: ignore[union-attr]
        self.model = model
        self.cache: AnalysisCache | None = cache
        self.executor = executor
        self.session: Any = None
        """The two-body :class:`~app.scene.pair.session.Session` (built at the first "Open pair", then
        kept, hidden, while all bodies are shown: a pair opens like a preset, with no shader to
        compile), or None."""
        self.pair: int | None = None
        """Index (in the contacts) of the open pair, or None when all bodies are shown."""
        self.selected: int | None = None
        self.layers: BodyLayers | None = None
        """The bodies' scene nodes (None: no bodies, or a pair is open)."""
        self.ready = threading.Event()
        """Set when the current view (all bodies, or a pair) is built."""
        self.relation = "all"
        self.body: int | None = None
        """The body the list is filtered by (None: all)."""
        self.page_no = 0
        self.separate = "faded"
        self.network = False
        self.listing: PairPage | None = None
        """The page of pairs the list shows."""
        self._lock = threading.RLock()
        self._closed = False
        self._from_tab = False
        """The bodies shown came from this tab's upload (else the server's file): their work is budgeted."""
        self._choices: dict[str, int] = {}
        self._syncing = False
        self._timer: threading.Timer | None = None
        self._last_pose = 0.0
        self.labels: list[Any] = []
        self._bodies_gui: list[Any] = []
        self._pair_gui: list[Any] = []
        self._session_nodes: dict[str, bool] = {}
        self._bodies_camera: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.timeline: Any = None
        """The :class:`~app.scene.bodies.sweep_view.SweepTimeline` of moving bodies, or None."""
        self.scene.on_click()(self._on_scene_click)
        cam = getattr(target, "camera", None)
        if cam is not None:
            cam.on_update(self._on_camera)
        self._build_all()

    # ------------------------------------------------------------------ all bodies
    def show_bodies(self) -> None:
        """Show all bodies: back from a pair (nothing is rebuilt), or build the view anew."""
        with self._lock:
            if self.pair is not None and self.session is not None:
                return self._back_from_pair()
            self._build_all()

    def _build_all(self) -> None:
        """Build the view of all bodies (a new file or box: the two-body view goes too)."""
        with self._lock:
            if self._closed:
                return
            self.ready.clear()
            if self.session is not None:
                self.session.close()
                self.session = None
            self.pair = None
            self._session_nodes = {}
            if self.timeline is not None:
                self.timeline.close()
                self.timeline = None
            self.gui.reset()
            self.scene.reset()
            self.labels = []
            light_scene(self.scene)
            self.layers = self._build_layers()
            self._build_gui()
            self._frame_camera()
            if self.selected is not None and self.model is not None:
                self._label(self.selected)
            self.set_pose(ViewPose.of_camera(getattr(self.target, "camera", None)))
            self.ready.set()

    def _build_layers(self) -> BodyLayers | None:
        m = self.model
        if m is None or len(m.bodies) == 0:
            return None
        layers = BodyLayers(self.scene, m.dim, m.positions, m.wxyz, m.scales, m.colours(), m.worst, separate=self.separate)
        if m.box is not None:
            layers.add_box(m.box_corner(), m.box)
        if self.network:
            layers.set_network(True, m.contact_segments(), relation_colour_rows(m.result.relation))
        return layers

    def set_pose(self, pose: ViewPose | None) -> None:
        """Choose the solids for this camera pose (the tab's camera calls it when it stops)."""
        with self._lock:
            if self._closed or self.layers is None or self.pair is not None or pose is None:
                return  # closed: a camera timer that fired as the tab went away draws nothing
            self.layers.set_pose(pose)
            self._last_pose = time.monotonic()
            self._show_drawn()

    def _show_drawn(self) -> None:
        if self.layers is None or not hasattr(self, "drawn_md"):
            return
        d = self.layers.drawn()
        self.drawn_md.content = (
            f"Drawn: {d['fine'] + d['coarse']:,} bodies as solids (the largest on screen; they follow the camera), "
            f"{d['points']:,} as points."
        )

    def _build_gui(self) -> None:
        gui = self.gui
        gui.configure_theme(control_width="large", show_share_button=False)
        self.back_button = gui.add_button("← All bodies", order=-1000.0, visible=False)
        self.pair_note = gui.add_markdown("", order=-999.0, visible=False)
        self._pair_gui = [self.back_button, self.pair_note]
        self.back_button.on_click(lambda ev: self.show_bodies())
        m = self.model
        moving = self.moving
        title = gui.add_markdown(getattr(m, "title", "**Many bodies** — certified contacts"))
        self.summary = gui.add_markdown(m.summary() if m is not None else "Open a file of bodies (CSV or NPZ).")
        legend = gui.add_html(_legend(moving))
        self._bodies_gui = [title, self.summary, legend]
        if moving:
            from .sweep_view import SweepTimeline

            self.timeline = SweepTimeline(self)
            self._bodies_gui.append(self.timeline.folder)
        contacts_folder = gui.add_folder("Contact events" if moving else "Contacts")
        self._bodies_gui.append(contacts_folder)
        what = "event" if moving else "pair"
        with contacts_folder:
            filters = list(m.relation_filters()) if m is not None else ["all"]
            self.relation_box = gui.add_dropdown("Relation", filters, initial_value=self.relation if self.relation in filters else "all",
                                                 hint="list only the pairs of this relation")
            self.body_text = gui.add_text("Body", "" if self.body is None else str(self.body),
                                          hint="a body's index: list only its pairs (empty: all bodies)")
            self.list_md = gui.add_markdown("")
            self.pairs = gui.add_dropdown(what.capitalize(), [NO_PAIRS], hint=f"pick a{'n' if moving else ''} {what} to open its pair in the two-body view"
                                          + (" at t*, with its exact motion" if moving else ""))
            self.prev_button = gui.add_button("◀ Previous page", disabled=True)
            self.next_button = gui.add_button("Next page ▶", disabled=True)
            self.open_button = gui.add_button(f"Open {what}", disabled=True)
            self.body_md = gui.add_markdown(
                "Click a body to list its events; click one it meets to open the pair at its first contact." if moving
                else "Click a body to list its contacts; click one it touches to open the pair."
            )
        view_folder = gui.add_folder("View")
        with view_folder:
            self.separate_box = gui.add_dropdown("Separate bodies", list(SEPARATE_MODES), initial_value=self.separate,
                                                 hint="faded: pale; hidden: only bodies in contact are drawn")
            self.network_box = gui.add_checkbox("Contact network", self.network and not moving, visible=not moving,
                                                hint="a line between the centres of each contact pair")
            self.drawn_md = gui.add_markdown("")
        file_folder = gui.add_folder("File", expand_by_default=m is None)
        self._bodies_gui += [view_folder, file_folder]
        with file_folder:
            self.upload = gui.add_upload_button("Open a file of bodies", mime_type=".csv,.npz", hint="CSV (x,y,z,a,b,c,qw,qx,qy,qz or x,y,a,b,angle) or NPZ")
            if self.uploads is not None:  # at once: a larger file is refused before the server keeps it
                self.uploads.limit(self.upload, UPLOAD_BYTES, self._on_refused)
            self.box_text = gui.add_text("Periodic box", _box_text(m.box if m is not None else None), hint="Lx, Ly(, Lz), or Lx, Ly, Lz, xy, xz, yz (tilted); empty: open space")
            self.file_md = gui.add_markdown("")
        self._refresh_list()
        self._show_drawn()
        self.relation_box.on_update(lambda ev: self._from_client(ev, self._on_relation))
        self.body_text.on_update(lambda ev: self._from_client(ev, self._on_body_text))
        self.pairs.on_update(lambda ev: self._from_client(ev, self._open_current))
        self.prev_button.on_click(lambda ev: self.turn_page(-1))
        self.next_button.on_click(lambda ev: self.turn_page(+1))
        self.open_button.on_click(lambda ev: self._open_current())
        self.separate_box.on_update(lambda ev: self._from_client(ev, lambda: self.set_separate(str(self.separate_box.value))))
        self.network_box.on_update(lambda ev: self._from_client(ev, lambda: self.set_network(bool(self.network_box.value))))
        self.upload.on_upload(self._on_upload)
        self.box_text.on_update(self._on_box)

    def _from_client(self, ev: Any, action: Any) -> None:
        """Run ``action`` for a change the user made (not for the view's own updates of the GUI)."""
        if self._syncing or getattr(ev, "client", None) is None:
            return
        action()

    # ------------------------------------------------------------------ the list of pairs
    def _refresh_list(self) -> None:
        """Show the current page of the filtered pair list."""
        m = self.model
        if m is None:
            self.list_md.content = ""
            return
        try:
            self.listing = m.page(self.relation, self.body, self.page_no)
        except ValueError as e:
            self.listing = None
            self.list_md.content = _warning(str(e))
            self._set_pair_options([])
            return
        pg = self.listing
        self.page_no = pg.page
        noun = "events" if self.moving else "pairs"
        what = (noun if self.relation == "all" else f"{self.relation} {noun}") + ("" if self.body is None else f" of body {self.body}")
        text = pg.caption(what)
        if pg.pages > 1:
            text += f" (page {pg.page + 1:,} of {pg.pages:,})"
        self.list_md.content = text[0].upper() + text[1:]
        self._set_pair_options(pg.entries)
        self.prev_button.disabled = pg.page == 0
        self.next_button.disabled = pg.page >= pg.pages - 1
        if self.timeline is not None:  # the events' exact times, for their labels (in the background)
            self.timeline.want_labels([e.index for e in pg.entries])

    def _set_pair_options(self, entries: list[Any]) -> None:
        self._choices = {e.label: e.index for e in entries}
        self._syncing = True
        try:
            self.pairs.options = list(self._choices) or [NO_PAIRS]
        finally:
            self._syncing = False
        self.open_button.disabled = not self._choices

    def filter_pairs(self, relation: str | None = None, body: int | None | str = "keep", page: int = 0) -> PairPage | None:
        """Filter the list (a relation, a body or None for all, "keep" to keep it) and show a page."""
        with self._lock:
            if relation is not None:
                self.relation = relation
            if body != "keep":
                self.body = body if body is None else int(body)
            self.page_no = page
            self._refresh_list()
            return self.listing

    def turn_page(self, step: int) -> PairPage | None:
        """Show the next (+1) or previous (-1) page of the list."""
        with self._lock:
            self.page_no += step
            self._refresh_list()
            return self.listing

    def _on_relation(self) -> None:
        self.filter_pairs(relation=str(self.relation_box.value))

    def _on_body_text(self) -> None:
        text = str(self.body_text.value).strip()
        if not text:
            self.filter_pairs(body=None)
            return
        try:
            body = int(text)
        except ValueError:
            self.list_md.content = _warning(f"body: expected a whole number, got {text}")
            return
        self.filter_pairs(body=body)
        if self.listing is not None and self.model is not None:
            self._describe(body)

    # ------------------------------------------------------------------ options
    def set_separate(self, mode: str) -> None:
        """Draw separate bodies "shown", "faded" or "hidden"."""
        with self._lock:
            self.separate = mode
            if self.layers is not None:
                self.layers.set_separate(mode)
                self._show_drawn()

    def set_network(self, shown: bool) -> None:
        """Show or hide the contact network (built the first time it is shown)."""
        with self._lock:
            self.network = shown
            m = self.model
            if self.layers is None or m is None or self.moving:
                return
            if shown and self.layers.network is None:
                self.layers.set_network(True, m.contact_segments(), relation_colour_rows(m.result.relation))
            else:
                self.layers.set_network(shown)

    # ------------------------------------------------------------------ callbacks
    def _open_current(self) -> None:
        k = self._choices.get(self.pairs.value)
        if k is not None:
            self.open_pair(k)

    def _on_camera(self, cam: Any) -> None:
        """A camera message: choose the solids when the camera stops (or every CAMERA_MAX_WAIT s)."""
        if self._closed or self.pair is not None or self.layers is None:
            return
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
            if time.monotonic() - self._last_pose >= CAMERA_MAX_WAIT:
                self._timer = None
                self.set_pose(ViewPose.of_camera(cam))
                return
            self._timer = threading.Timer(CAMERA_QUIET, lambda: self.set_pose(ViewPose.of_camera(cam)))
            self._timer.daemon = True
            self._timer.start()

    def settling(self) -> bool:
        """True while a camera move waits for its solids (a timer is pending), or moving bodies' colours are decided."""
        t = self._timer
        return (t is not None and t.is_alive()) or (self.timeline is not None and self.pair is None and self.timeline.busy())

    def _on_scene_click(self, ev: Any) -> None:
        if self.model is None or self.pair is not None:
            return
        k = self.model.pick(ev.ray_origin, ev.ray_direction)
        if k is not None:
            self.select(int(k))

    def select(self, body: int) -> int | None:
        """Select a body (a click): list its pairs; open the pair if it touches the previous one.

        Returns:
            The index of the pair opened, or None.
        """
        with self._lock:
            m = self.model
            if m is None or self.pair is not None:
                return None
            previous, self.selected = self.selected, body
            if previous is not None and previous != body:
                k = m.pair_between(previous, body)
                if k is not None and self.open_pair(k) is not None:
                    return k  # else not opened (a body not drawn): the body is selected, and says why
            self._syncing = True
            try:
                self.body_text.value = str(body)
            finally:
                self._syncing = False
            self.filter_pairs(body=body)
            self._describe(body)
            return None

    def _describe(self, body: int) -> None:
        m = self.model
        assert m is not None
        if not 0 <= body < len(m.bodies):
            return
        self.selected = body
        partners = m.partners(body)
        why = m.invalid.get(body)
        undrawn = getattr(m, "undrawn", {}).get(body)
        if why:
            text = f"Body **{body}** is invalid: {html.escape(why)}"
        elif undrawn:
            text = (f"Body **{body}** is not drawn: {html.escape(undrawn)}. It touches or overlaps {len(partners)} bodies"
                    + (f" ({', '.join(str(p) for p in partners[:12])}{' …' if len(partners) > 12 else ''})" if partners else "")
                    + "; its pairs are listed, not opened in the two-body view.")
        elif partners:
            shown = ", ".join(str(p) for p in partners[:12]) + (" …" if len(partners) > 12 else "")
            if self.moving:
                text = f"Body **{body}** meets {len(partners)} bodies during the step ({shown}): click one, or pick its event above."
            else:
                text = f"Body **{body}** touches or overlaps {len(partners)} bodies ({shown}): click one, or pick the pair above."
        else:
            text = f"Body **{body}** is separate from all others" + (" during the whole step." if self.moving else ".")
        self.body_md.content = text
        self._label(body)

    def _label(self, body: int) -> None:
        for h in self.labels:
            h.remove()
        assert self.model is not None
        if body in getattr(self.model, "undrawn", {}):  # no label on its speck at the origin
            self.labels = []
            return
        pos = self.model.positions[body] + np.array([0.0, 0.0, self.model.scales[body].max() if self.model.dim == 3 else 0.0])
        self.labels = [
            self.scene.add_label("/selected", f"body {body}", position=tuple(float(v) for v in pos), anchor="bottom-center")
        ]

    def _on_upload(self, ev: Any) -> None:
        f = ev.target.value
        self.load_bytes(f.name, f.content)

    def _on_refused(self, refusal: Refusal) -> None:
        """An upload refused before it was kept (too large, stalled, ...): the panel says why."""
        text = refusal.message() + (_TOO_LARGE_HINT if refusal.reason == "too large" else "")
        with self._lock:
            if not self._closed:
                self.file_md.content = _warning(text)

    def load_bytes(self, name: str, content: bytes) -> str | None:
        """Show the bodies of an uploaded file; returns an error message (also shown) or None.

        The file is the tab's: it is read and its contacts found in a worker process, under
        :data:`~app.scene.bodies.model.UPLOAD_SECONDS`, :data:`~app.scene.bodies.model.UPLOAD_PAIRS` and
        :data:`~app.scene.bodies.model.UPLOAD_BYTES` (:func:`~app.scene.bodies.model.tab_bodies_job`).
        """
        try:
            if len(content) > UPLOAD_BYTES:
                raise ValueError(too_large(name, len(content), UPLOAD_BYTES) + _TOO_LARGE_HINT)
            self.file_md.content = f"Reading {html.escape(name)} and finding its contacts…"
            model = self._tab_bodies(content, name)
            if model.bodies.box is not None:  # the file's own box (GSD, LAMMPS, extxyz) wins, and is shown
                self.box_text.value = _box_text(model.box)
        except ValueError as e:
            self.file_md.content = _warning(str(e))
            return str(e)
        with self._lock:
            self.model = model
            self._from_tab = True
            self.selected = self.body = None
            self.relation, self.page_no = "all", 0
            self._build_all()
        return None

    def _tab_bodies(self, source: bytes | BodySet, name: str) -> BodiesModel:
        """:func:`~app.scene.bodies.model.tab_bodies_job` with the typed box.

        In a worker process for a tab's file; here, without limits, for the server's own bodies
        (``--bodies``: a presenter's million, which a worker's memory cap could refuse).
        """
        box = str(self.box_text.value)
        if isinstance(source, BodySet) and not self._from_tab:
            return tab_bodies_job(source, name, box, None)
        return self.analysis_cache().run(tab_bodies_job, source, name, box, timeout=UPLOAD_SECONDS, what=f"finding the contacts of {name}")

    def _on_box(self, ev: Any) -> None:
        if self.model is None or getattr(ev, "client", None) is None:
            return
        if self.moving:
            self.file_md.content = "The box of moving bodies is the one they were swept in (`--box`, or START's)."
            return
        try:
            model = self._tab_bodies(self.model.bodies, self.model.name)
        except ValueError as e:
            self.file_md.content = _warning(str(e))
            return
        with self._lock:
            self.model = model
            self.page_no = 0
            self._build_all()

    # ------------------------------------------------------------------ one pair
    @property
    def moving(self) -> bool:
        """True when the view shows moving bodies (a timeline, events)."""
        return bool(getattr(self.model, "moving", False))

    def analysis_cache(self) -> AnalysisCache:
        """The analysis cache the two-body view shares (created here when the server gave none)."""
        if self.cache is None:
            from ..pair.analysis import AnalysisCache

            self.cache = AnalysisCache(self.executor)
        return self.cache

    def open_pair(self, k: int) -> Any:
        """Open pair k (index in the contacts) in the two-body view of this tab.

        The bodies, their GUI and the two-body view's nodes are hidden or shown, never rebuilt:
        the first pair builds the two-body :class:`~app.scene.pair.session.Session`, later pairs are
        loaded into it (no shader to compile in the browser: that was most of a second).
        Moving bodies: the timeline jumps to the pair's first contact t* and the pair opens on
        its exact motion at t* (:meth:`app.scene.bodies.sweep_view.SweepTimeline.open_event`).
        """
        if self.timeline is not None:
            return self.timeline.open_event(k)
        m = self.model
        assert m is not None
        i, j = int(m.result.i[k]), int(m.result.j[k])
        gone = next((b for b in (i, j) if b in m.undrawn), None)
        if gone is not None:  # its floats would overflow the two-body view's drawing and camera
            self.body_md.content = (f"Pair {i} – {j} is not opened: body **{gone}** is not drawn "
                                    f"({html.escape(m.undrawn[gone])}).")
            return None
        cfg, note = m.pair_config(k)
        return self._open_two_body(k, cfg, note)

    def _open_two_body(self, k: int, cfg: Any, note: str, *, motion: Any = None, target: dict[str, Any] | None = None) -> Any:
        """Show the two-body view on ``cfg`` (and then on ``motion``, at ``target``: event or t)."""
        from ..pair.session import Session

        with self._lock:
            if self._closed:  # the tab went away: a session built now would never be closed
                return None
            assert self.model is not None
            if self._timer is not None:
                self._timer.cancel()
            self.ready.clear()
            self._bodies_camera = _camera_of(getattr(self.target, "camera", None)) if self.pair is None else self._bodies_camera
            self.pair = k
            for h in self._bodies_gui + self.labels:
                h.visible = False
            if self.layers is not None:
                self.layers.frame.visible = False
            self.pair_note.content = note
            for h in self._pair_gui:
                h.visible = True
            if self.session is None:
                self.pair_folder = self.gui.add_folder("Two-body view", order=-998.0)
                with self.pair_folder:
                    self.session = Session(self.target, cfg, cache=self.analysis_cache(), executor=self.executor,
                                           sphere_subdivisions=self.sphere_subdivisions, uploads=self.uploads)
            else:
                self.pair_folder.visible = True
                self._show_session_nodes(True)
                self.session.load(cfg)
            if motion is not None:
                self.session.show_motion(motion, **(target or {}))
            else:
                self.session.frame_camera()
            self.ready.set()
            return self.session

    def _back_from_pair(self) -> None:
        with self._lock:
            self.ready.clear()
            self._show_session_nodes(False)
            self.pair_folder.visible = False
            for h in self._pair_gui:
                h.visible = False
            self.pair = None
            for h in self._bodies_gui + self.labels:
                h.visible = True
            if self.layers is not None:
                self.layers.frame.visible = True
            cam = getattr(self.target, "camera", None)
            if cam is not None and self._bodies_camera is not None:  # the bodies as the user left them
                position, look_at, up = self._bodies_camera
                cam.up_direction, cam.position, cam.look_at = up, position, look_at
            self.ready.set()

    def _show_session_nodes(self, shown: bool) -> None:
        """Hide the two-body view's scene nodes (remembering which were visible), or show them again.

        Its nodes are found in viser's registry of the tab's scene (viser 1.1.1 has no public
        listing): every node outside ``/bodies`` whose parent is not itself a node.
        """
        registry: dict[str, Any] = getattr(self.scene, "_handle_from_node_name", {})
        if not shown:
            self._session_nodes = {}
            for name, h in list(registry.items()):
                parent = name.rsplit("/", 1)[0]
                if name.startswith(("/bodies", "/selected")) or name == "/WorldAxes" or parent in registry:
                    continue
                self._session_nodes[name] = bool(h.visible)
                h.visible = False
        else:
            for name, was in self._session_nodes.items():
                h = registry.get(name)
                if h is not None:
                    h.visible = was

    # ------------------------------------------------------------------ camera, lifecycle
    def _frame_camera(self) -> None:
        cam = getattr(self.target, "camera", None)
        if cam is None or self.model is None or len(self.model.bodies) == 0:
            return
        lo, hi = self.model.extent()
        Framing(np.array([lo, hi]), self.model.dim).aim(cam, fill=1.35 if self.model.dim == 3 else 1.0, view=(0.55, -1.0, 0.7), whole=False)

    def close(self) -> None:
        """The tab went away: stop the two-body view's work, the timeline and the camera timer.

        Under the view's lock: a pair being opened meanwhile (its two-body session being built)
        finishes first and its session is closed here; after this nothing opens or builds.
        """
        with self._lock:
            self._closed = True
            if self._timer is not None:
                self._timer.cancel()
            if self.timeline is not None:
                self.timeline.close()
            if self.session is not None:
                self.session.close()


_TOO_LARGE_HINT = ": find its contacts with `python -m app contacts`, or start the scene on it (--bodies)"


def _warning(text: str) -> str:
    """A message of the panel in the warning colour (HTML-escaped)."""
    return f'<span style="color:#d62728">⚠ {html.escape(text)}</span>'


def _camera_of(cam: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Position, look-at point and up direction of a tab's camera (None if it never reported)."""
    try:
        return np.array(cam.position), np.array(cam.look_at), np.array(cam.up_direction)
    except Exception:  # noqa: BLE001 - no camera, or no camera message yet
        return None


def _box_text(box: Box | None) -> str:
    """The box as the field shows it: every number in its shortest exact decimal (:func:`parse_box` reads it back the same)."""
    return "" if box is None else ", ".join(repr(v) for v in box.to_tuple())


def _legend(moving: bool = False) -> str:
    items = [("separate", RELATION_HEX["separate"]), ("tangent", RELATION_HEX["tangent"]), ("overlap", RELATION_HEX["overlap"]), ("invalid", "#969696")]
    if moving:
        from .sweep_model import PENDING_COLOUR

        items.append(("deciding", "#{:02x}{:02x}{:02x}".format(*PENDING_COLOUR)))
    spans = "".join(
        f'<span style="display:inline-block;margin-right:10px"><span style="display:inline-block;width:10px;height:10px;'
        f'border-radius:5px;background:{c};margin-right:4px"></span>{n}</span>'
        for n, c in items
    )
    return f'<div style="font-size:0.85em;padding:2px 0">{spans}</div>'
