"""The viser scene server: one :class:`~app.scene.session.Session` per browser tab.

``start_scene(host, port)`` returns a running ``viser.ViserServer`` (its own thread). Every tab
that connects gets a private scene and GUI (``client.scene``/``client.gui``) built from the
server's configuration, so a classroom of students never fights over one scene; analyses are
shared through one cache and run in worker processes, so a slow analysis never blocks other tabs.
``shared=True`` (``python -m app serve --shared``) is the presenter mode: one scene for all tabs.
Only the scene's own pages (and clients without an Origin header) may connect
(:mod:`app.scene.origin`).
"""

from __future__ import annotations

import threading
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from .analysis import AnalysisCache
from .session import Session
from .state import SceneConfig

__all__ = ["SceneServer", "start_scene"]


class SceneServer:
    """A running scene: the ``ViserServer`` plus the live sessions (one per connected tab)."""

    def __init__(self, server: Any, config: SceneConfig, *, processes: bool = True, shared: bool = False) -> None:
        self.server = server
        self.config = config
        """Configuration new tabs open on (change it to change what the next tab sees)."""
        self.executor = ThreadPoolExecutor(max_workers=2, thread_name_prefix="analysis")
        self.cache = AnalysisCache(self.executor, processes=processes)
        self.sessions: dict[int, Session] = {}
        self._lock = threading.Lock()
        self.new_session = threading.Condition(self._lock)
        self.shared: Session | None = None
        """The one session every tab sees (presenter mode), or None (one session per tab)."""
        self.cache.warm()
        if shared:
            self.shared = Session(
                server, config, cache=self.cache, executor=self.executor,
                cameras=lambda: [c.camera for c in server.get_clients().values()],
            )

        @server.on_client_connect
        def _(client: Any) -> None:
            if self.shared is not None:
                session = self.shared  # the scene is shared; every tab's camera is framed
            else:
                session = Session(client, self.config, cache=self.cache, executor=self.executor)
            session.frame_camera()
            with self._lock:
                self.sessions[client.client_id] = session
                self.new_session.notify_all()

        @server.on_client_disconnect
        def _(client: Any) -> None:
            with self._lock:
                s = self.sessions.pop(client.client_id, None)
            if s is not None and s is not self.shared:
                s.close()

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

    def wait_for_session(self, timeout: float = 30.0) -> Session:
        """Block until a tab has connected; return its session (the newest one)."""
        with self._lock:
            ok = self.new_session.wait_for(lambda: bool(self.sessions), timeout=timeout)
            if not ok:
                raise TimeoutError("no browser tab connected to the scene")
            return list(self.sessions.values())[-1]

    def stop(self) -> None:
        """Stop the server and the analysis workers."""
        for s in list(self.sessions.values()):
            s.close()
        self.server.stop()
        self.cache.shutdown()
        self.executor.shutdown(wait=False, cancel_futures=True)


def start_scene(
    host: str = "127.0.0.1",
    port: int = 8080,
    config: SceneConfig | None = None,
    *,
    verbose: bool = False,
    processes: bool = True,
    shared: bool = False,
    allow_origins: Iterable[str] = (),
) -> SceneServer:
    """Start the scene server (returns at once; viser serves from its own thread).

    Args:
        host: interface to bind ("127.0.0.1" loopback by default; "0.0.0.0" to share).
        port: TCP port; 0 picks a free one (read it from ``.port``). A busy port makes viser
            move to the next free one.
        config: what each new tab opens on (default: :class:`SceneConfig` defaults).
        verbose: let viser print its own banner.
        processes: run analyses in child processes (a long analysis never holds the GIL of
            the process serving the tabs); False runs them in worker threads.
        shared: presenter mode: every tab sees and drives one scene (default: each tab has
            its own).
        allow_origins: web origins (``https://host:port``) besides the scene's own whose pages
            may open sessions (:mod:`app.scene.origin`; ``--allow-origin`` on the command line).
    """
    from core import warm_up

    from .origin import OriginPolicy, start_viser

    warm_up(wait=False)  # compile the float filter in the background; drags use exact meanwhile
    server = start_viser(OriginPolicy(host, allow_origins), host=host, port=port, verbose=verbose)
    server.gui.configure_theme(control_width="large", show_share_button=False)
    return SceneServer(server, config or SceneConfig(), processes=processes, shared=shared)
