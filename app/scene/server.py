"""The viser scene server: one :class:`~app.scene.pair.session.Session` per browser tab.

``start_scene(host, port)`` returns a running :class:`SceneServer` (viser serves from its own
thread). Every tab that connects gets a private scene and GUI (``client.scene``/``client.gui``),
so a classroom of students never fights over one scene; analyses are shared through one cache
and run in warm worker processes, so a slow analysis never blocks other tabs. Each tab has its
own address (``/s/<tab id>/``, :mod:`app.scene.common.links`): a reload reopens it as it was, and a
link ``/c/<configuration>/`` opens a new tab on a shared configuration. ``shared=True``
(``python -m app serve --shared``) is the presenter mode: one scene for all tabs, every tab's
camera framed. Only the scene's own pages (and clients without an Origin header) may connect
(:mod:`app.scene.common.origin`). What a client sends is budgeted: one websocket message at most
:data:`app.scene.common.wire.MAX_MESSAGE_BYTES`, uploads counted before they are kept
(:class:`app.scene.common.wire.UploadGuard`: :data:`app.scene.bodies.model.UPLOAD_BYTES` per client under way,
:data:`UPLOADS_TOTAL_BYTES` for all).
"""

from __future__ import annotations

import ctypes
import gc
import socket
import threading
import time
from collections.abc import Callable, Collection, Iterable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import viser

from .bodies.model import UPLOAD_BYTES
from .common import page, wire
from .common.links import Router, TabStore, tab_id_of
from .common.mesh_detail import SPHERE_SUBDIVISIONS, check_sphere_subdivisions
from .common.state import SceneConfig
from .pair.analysis import AnalysisCache
from .pair.session import Session

__all__ = ["SceneServer", "start_scene", "PortBusy", "UPLOADS_TOTAL_BYTES"]

RECLAIM_SECONDS = 2.0
"""A closed tab's memory is reclaimed this long after it closes, once for all the tabs closed meanwhile."""

UPLOADS_TOTAL_BYTES = 4 * UPLOAD_BYTES
"""Most bytes of uploads under way in the scene for all tabs together (each tab: ``UPLOAD_BYTES``,
the largest upload button's limit)."""


class PortBusy(RuntimeError):
    """The scene's port is taken by another program."""


class SceneServer:
    """A running scene: the ``ViserServer`` plus the live sessions (one per connected tab).

    Args:
        server: the running viser server.
        config: what a new tab opens on.
        processes: run analyses in worker processes (else threads).
        shared: presenter mode (one scene for every tab).
        store: the tabs' configurations (reloads, links).
        bodies: many bodies (an :class:`app.scene.bodies.model.BodiesModel`, ``--bodies FILE``): each
            tab opens on them (:mod:`app.scene.bodies.bodies_view`) instead of ``config``.
        prefetch: analyse every preset at start, so a pick in the dropdown shows at once (an
            interactive server); off for one-shot uses (screenshots) that show one motion.
        sphere_subdivisions: of the icosphere every tab draws the solids with
            (:data:`app.scene.common.mesh_detail.SPHERE_SUBDIVISIONS_RANGE`).
    """

    def __init__(
        self,
        server: viser.ViserServer,
        config: SceneConfig,
        *,
        processes: bool = True,
        shared: bool = False,
        store: TabStore | None = None,
        bodies: Any = None,
        prefetch: bool = True,
        policy: Any = None,
        sphere_subdivisions: int = SPHERE_SUBDIVISIONS,
    ) -> None:
        self.server = server
        self.sphere_subdivisions = check_sphere_subdivisions(sphere_subdivisions)
        """Icosphere subdivisions of the solids of every session."""
        self.policy = policy
        """The :class:`~app.scene.common.origin.OriginPolicy` of the handshakes (None: not checked here)."""
        self.config = config
        """Configuration new tabs open on (change it to change what the next tab sees)."""
        self.bodies = bodies
        """Many bodies each new tab shows, or None."""
        self.store = store or TabStore()
        self.executor = ThreadPoolExecutor(max_workers=2, thread_name_prefix="analysis")
        self.cache = AnalysisCache(self.executor, processes=processes)
        self.sessions: dict[int, Session] = {}
        self._tabs: dict[int, str] = {}
        self._building: set[int] = set()
        """Clients whose session is being built."""
        self._left: set[int] = set()
        """Of those, the ones that disconnected meanwhile (see :meth:`_register`)."""
        self._framed: dict[int, list[Any]] = {}
        """Per tab: the shape of its view last seen and until when a change frames again (:meth:`_frame_on_resize`)."""
        self._resize_hooked: set[int] = set()
        """Tabs whose camera calls :meth:`_frame_on_resize`'s callback."""
        self._lock = threading.Lock()
        self.new_session = threading.Condition(self._lock)
        self.reclaim = Reclaimer(RECLAIM_SECONDS)
        """Gives a closed tab's memory back (see :class:`Reclaimer`)."""
        self.uploads = wire.UploadGuard(server, per_client=UPLOAD_BYTES, total=UPLOADS_TOTAL_BYTES)
        """Counts what tabs upload before viser keeps it (installed before any tab's panel exists)."""
        self.shared: Session | None = None
        """The one session every tab sees (presenter mode), or None (one session per tab)."""
        self.lesson: str | None = None
        """The lesson a new tab opens on (``serve --lesson``; :mod:`app.scene.common.lesson`), or None."""
        self.guide: str | None = None
        """The documentation site's address (``http://host:port/guide/``, served by the API) that a tab's
        panel links to ("What am I seeing?", a lesson's tutorial), or None: no link (no API beside the scene)."""
        self.cache.warm()
        self.prefetched = self.cache.prefetch(_preset_models) if prefetch else None
        """The thread analysing the presets at start (joined: every preset is in the cache), or None."""
        if shared:
            self.shared = Session(
                server, config, cache=self.cache, executor=self.executor, sphere_subdivisions=self.sphere_subdivisions,
                cameras=lambda: [c.camera for c in server.get_clients().values()], uploads=self.uploads,
            )
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)

    def _connect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            self._building.add(client.client_id)
        try:
            self._open(client)
        finally:
            with self._lock:
                self._building.discard(client.client_id)
                self._left.discard(client.client_id)

    def _open(self, client: viser.ClientHandle) -> None:
        if self.bodies is not None and self.shared is None:  # many bodies (issue 14): one view per tab
            from .bodies.bodies_view import BodiesView

            view = BodiesView(client, self.bodies, cache=self.cache, executor=self.executor,
                              sphere_subdivisions=self.sphere_subdivisions, uploads=self.uploads)
            self._register(client.client_id, view, None)
            return
        tab = None
        if self.shared is not None:
            session = self.shared  # the scene is shared; every tab's camera is framed
        else:
            tab = tab_id_of(wire.handshake_path(self.server, client))
            from .pair.lesson_view import lesson_session

            session = lesson_session(self, client, tab) or self._session(client, self.store.get(tab) if tab is not None else None)
        session.frame_camera()
        self._frame_on_resize(client)
        self._register(client.client_id, session, tab)

    FRAME_ON_RESIZE = 10.0
    """Seconds after a tab opens (or starts again) during which a change of its view's shape frames the shapes again."""

    def _frame_on_resize(self, client: viser.ClientHandle) -> None:
        """Frame the tab's shapes again when its view first reports, or changes shape, soon after it opens.

        A tab's first framing runs before its page says what it sees (field of view and shape of
        the view guessed), and a window docked beside the scene (the roots of P(T)) narrows the
        view after the shapes were framed: a camera keeps its vertical field of view, so a wide
        pair came out cut at the sides (issue 55: framed 3.99 from a pair that needs 5.12). Only
        within :attr:`FRAME_ON_RESIZE` s of the tab's (re)start: later, a resize keeps the user's camera.
        """
        with self._lock:
            self._framed[client.client_id] = [None, time.monotonic() + self.FRAME_ON_RESIZE]

        def seen(cam: viser.CameraHandle) -> None:
            try:
                aspect = float(cam.aspect)
            except AssertionError:
                return
            with self._lock:
                record = self._framed.get(client.client_id)
                session = self.sessions.get(client.client_id)
                if record is None:
                    return
                old, until = record
                record[0] = aspect
            if session is None or session.camera_chosen or time.monotonic() > until or (old is not None and abs(aspect - old) <= 1e-3):
                return
            session.frame_camera(grid=False)

        if client.client_id not in self._resize_hooked:
            self._resize_hooked.add(client.client_id)
            client.camera.on_update(seen)

    def _session(
        self, client: viser.ClientHandle, saved: SceneConfig | dict[str, Any] | None, open_folders: Collection[str] | None = None,
        *, answer_hidden: bool = False,
    ) -> Session:
        """A new session of ``client`` on a tab's stored configuration, a link's (a dict) or the default (None).

        ``open_folders``: the panel's folders shown open (a lesson step's); None: the usual ones.
        ``answer_hidden``: the relation kept back from the first picture on (a lesson step's open question).
        """
        session = Session(client, self.config if isinstance(saved, dict) or saved is None else saved,
                          cache=self.cache, executor=self.executor, defer_load=isinstance(saved, dict),
                          sphere_subdivisions=self.sphere_subdivisions, uploads=self.uploads, open_folders=open_folders,
                          answer_hidden=answer_hidden, guide=self.guide)
        if isinstance(saved, dict):  # a link: user input, read like an uploaded file
            session.load_untrusted(saved)
        return session

    def renew(
        self, client_id: int, link: dict[str, Any], *, open_folders: Collection[str] | None = None,
        then: Callable[[Session], object] | None = None, answer_hidden: bool = False,
    ) -> Session:
        """Start the tab ``client_id`` again on ``link`` (a link's configuration), without a page load.

        The tab gets what a new tab opened on the link gets: its session is closed, its panel and
        scene are cleared (viser's ``gui.reset()`` and ``scene.reset()``: the page's state of the
        old panel, such as open folders and lists, goes with its elements) and a new session is
        built on ``link``, read as user input. The page keeps its loaded client and WebGL context:
        a renewal costs the browser ~0.4 CPU-s, a page load ~1.5 (software WebGL). The tab keeps
        its address, and a reload then reopens the new state. ``open_folders``: the new panel's
        open folders (a lesson step's); ``then(session)`` runs in the same batch (a lesson's folder);
        ``answer_hidden``: the new scene keeps the relation back (a lesson step's open question).

        Raises:
            KeyError: no tab ``client_id`` has a session (closed, or still being built).
            ValueError: a presenter scene (one session for all tabs) or many bodies.
        """
        if self.shared is not None or self.bodies is not None:
            raise ValueError("only a tab of its own (not presenter mode, not many bodies) is started again")
        client = self.server.get_clients().get(client_id)
        with self._lock:
            old = self.sessions.pop(client_id, None) if client is not None else None
            if client is None or old is None:
                raise KeyError(f"no tab {client_id} has a session")
            # built again like a tab that connects: a disconnect meanwhile closes the new session (_register)
            self._building.add(client_id)
            tab = self._tabs.get(client_id)
        try:
            old.close()
            self.reclaim.soon()
            # one batch from the reset to the new panel: the page never shows the tab empty (viser then
            # unfolds its own settings in the panel, and a page read in the fold's 200 ms showed them)
            with client.atomic():
                client.scene.reset()  # before the panel: a page that shows the old panel gone has no old scene
                client.gui.reset()
                session = self._session(client, link, open_folders, answer_hidden=answer_hidden)
                if then is not None:
                    then(session)
                session.frame_camera()
            self._register(client_id, session, tab)
            self._frame_on_resize(client)
        finally:
            with self._lock:
                self._building.discard(client_id)
                self._left.discard(client_id)
        return session

    def _register(self, client_id: int, session: Any, tab: str | None) -> None:
        """Make ``session`` the tab's, unless the tab left while it was being built: then close it.

        viser runs the connect and disconnect callbacks of a client on a thread pool, so a tab
        closed (or reloaded) while its session is built is seen leaving before it has a session.
        Was: the session was registered afterwards and never closed (its analyses and timers ran on
        for a tab that was gone, and a scene's newest session could be a dead one).
        """
        with self._lock:
            left = client_id in self._left
            if not left:
                self.sessions[client_id] = session
                if tab is not None:
                    self._tabs[client_id] = tab
                self.new_session.notify_all()
        if left and session is not self.shared:
            session.close()  # the tab's stored configuration stays what it opened (a reload reopens it)
            self.reclaim.soon()

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            s = self.sessions.pop(client.client_id, None)
            tab = self._tabs.pop(client.client_id, None)
            self._framed.pop(client.client_id, None)
            self._resize_hooked.discard(client.client_id)
            if s is None and client.client_id in self._building:  # _register closes it when built
                self._left.add(client.client_id)
        if s is not None and s is not self.shared:
            if tab is not None:
                self.store.put(tab, s.snapshot())  # a reload of this tab reopens it as it is
            s.close()
            self.reclaim.soon()

    def registries(self) -> dict[str, int]:
        """Sizes of every record the server keeps per connected tab: all 0 once every tab has left.

        The sessions and tab addresses, tabs being built or left meanwhile, the upload guard's
        records and viser's own (:func:`app.scene.common.wire.client_records`). The tabs' stored
        configurations (a reload reopens them) are not per connection: :class:`TabStore` keeps
        the newest ``size``.
        """
        with self._lock:
            own = {"sessions": len(self.sessions), "tab addresses": len(self._tabs), "building": len(self._building),
                   "left while building": len(self._left), "framings": len(self._framed) + len(self._resize_hooked)}
        return {**own, **{f"uploads: {k}": v for k, v in self.uploads.registries().items()}, **wire.client_records(self.server)}

    @property
    def port(self) -> int:
        """The port the scene listens on."""
        return int(self.server.get_port())

    @property
    def url(self) -> str:
        """URL to open in a browser."""
        host = self.server.get_host()
        shown = "127.0.0.1" if host in ("0.0.0.0", "::", "") else host
        return f"http://{shown}:{self.port}/"

    def wait_for_session(self, timeout: float = 30.0, *, after: int = -1) -> Session:
        """Block until a tab has connected; return its session (the newest one).

        Args:
            timeout: seconds to wait.
            after: only a session of a client id above this (a tab that connects after a given one).
        """
        with self._lock:
            ok = self.new_session.wait_for(lambda: any(k > after for k in self.sessions), timeout=timeout)
            if not ok:
                raise TimeoutError("no browser tab connected to the scene")
            return self.sessions[max(self.sessions)]

    def stop(self) -> None:
        """Stop the server and the analysis workers."""
        from .common.origin import stop_viser

        for s in list(self.sessions.values()):
            s.close()
        stop_viser(self.server)
        self.uploads.close()
        self.reclaim.close()
        self.cache.shutdown()
        self.executor.shutdown(wait=False, cancel_futures=True)


class Reclaimer:
    """Gives the memory of closed tabs back to the system, ``delay`` seconds after a tab closes.

    A session is a web of objects that refer to each other (controllers, views, viser's handles
    and their callbacks): it is freed by Python's cycle collector, whose full passes are rare,
    and the C library keeps freed heap pages for reuse. Measured with browser tabs opened and
    closed one after another: the scene's resident memory grew ~0.4 MB per closed tab with no
    session left alive (``bench/scene_memory.py``). One pass per ``delay`` (a full collection,
    ~0.1 s with the scene's ~10^5 objects, then glibc's ``malloc_trim``) serves all the tabs
    that closed meanwhile.
    """

    def __init__(self, delay: float) -> None:
        self.delay = delay
        self.passes = 0
        """Passes run so far."""
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None
        self._closed = False
        self._trim = _malloc_trim()

    def soon(self) -> None:
        """A tab closed: reclaim within ``delay`` (once for every tab closed meanwhile)."""
        with self._lock:
            if self._timer is None and not self._closed:
                self._timer = threading.Timer(self.delay, self.now)
                self._timer.daemon = True
                self._timer.start()

    def now(self) -> None:
        """Collect the garbage of closed tabs and return free heap pages to the system."""
        with self._lock:
            self._timer = None
        gc.collect()
        if self._trim is not None:
            self._trim(0)
        self.passes += 1

    def close(self) -> None:
        """No more passes (the server stops)."""
        with self._lock:
            self._closed = True
            if self._timer is not None:
                self._timer.cancel()


def _malloc_trim() -> Any:
    """The C library's ``malloc_trim`` (glibc: returns free heap pages to the system), or None if it has none."""
    try:
        trim = ctypes.CDLL(None).malloc_trim
    except (AttributeError, OSError):
        return None
    trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    return trim


def _port_free(host: str, port: int) -> bool:
    """True if nothing listens on (host, port) (viser would otherwise move to the next port)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host if host not in ("", "0.0.0.0", "::") else host or "0.0.0.0", port))
        except OSError:
            return False
    return True


def start_scene(
    host: str = "127.0.0.1",
    port: int = 8080,
    config: SceneConfig | None = None,
    *,
    verbose: bool = False,
    processes: bool = True,
    shared: bool = False,
    allow_origins: Iterable[str] = (),
    bodies: Any = None,
    prefetch: bool = True,
    sphere_subdivisions: int = SPHERE_SUBDIVISIONS,
) -> SceneServer:
    """Start the scene server (returns at once; viser serves from its own thread).

    Args:
        host: interface to bind ("127.0.0.1" loopback by default; "0.0.0.0" to share).
        port: TCP port; 0 picks a free one (read it from ``.port``).
        config: what each new tab opens on (default: :class:`SceneConfig` defaults).
        verbose: let viser print its own banner.
        processes: run analyses in child processes (a long analysis never holds the GIL of
            the process serving the tabs); False runs them in worker threads.
        shared: presenter mode: every tab sees and drives one scene (default: each tab has
            its own).
        allow_origins: web origins (``https://host:port``) besides the scene's own whose pages
            may open sessions (:mod:`app.scene.common.origin`; ``--allow-origin`` on the command line).
        bodies: many bodies (:class:`app.scene.bodies.model.BodiesModel`, ``--bodies FILE``): each tab
            opens on them (:mod:`app.scene.bodies.bodies_view`) instead of ``config``.
        prefetch: analyse every preset at start (see :class:`SceneServer`).
        sphere_subdivisions: of the icosphere the solids are drawn with (see :class:`SceneServer`;
            ``--sphere-subdivisions`` on the command line).

    Raises:
        PortBusy: ``port`` is taken (viser would silently take the next port, perhaps the API's).
    """
    from core import warm_up

    from .common.origin import OriginPolicy, start_viser, stop_viser

    check_sphere_subdivisions(sphere_subdivisions)  # before a port is taken
    if port and not _port_free(host, port):
        raise PortBusy(f"the scene's port {port} on {host} is already in use: stop the program using it or choose another with --port")
    warm_up(wait=False)  # compile the float filter in the background; drags use exact meanwhile
    # the page and the client's files (~0.5 s to build): ready before the first tab asks for them
    threading.Thread(target=page.warm, name="scene-page", daemon=True).start()
    store = TabStore()
    router = Router(store, enabled=not shared)
    policy = OriginPolicy(host, allow_origins)
    server = start_viser(policy, router, max_message=wire.MAX_MESSAGE_BYTES, host=host, port=port, verbose=verbose)
    if port and server.get_port() != port:  # taken between the check and the start
        stop_viser(server)
        raise PortBusy(f"the scene's port {port} on {host} is already in use: choose another with --port")
    server.gui.configure_theme(control_width="large", show_share_button=False)
    return SceneServer(
        server, config or SceneConfig(), processes=processes, shared=shared, store=store, bodies=bodies, prefetch=prefetch,
        policy=policy, sphere_subdivisions=sphere_subdivisions,
    )


def _preset_models() -> list[Any]:
    """The motions of the presets (fixed inputs): analysed once at start, so a pick shows at once."""
    from .pair.motion import list_presets, load_motion

    return [load_motion(preset=name, motion=None) for name in list_presets()]
