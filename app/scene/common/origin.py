"""Who may open a scene session: the websocket handshake is refused (403) for a foreign Origin.

Browsers let any web page open a websocket to ``localhost``; the page's address travels in the
``Origin`` header of the handshake. Without a check, a page the user visits could drive the
scene on their machine (and send it expensive input). Accepted:

* no ``Origin`` header (scripts, tests, non-browser clients: a browser always sends one);
* the scene's own pages: ``http(s)://HOST:PORT`` with the scene's PORT and a HOST that is a
  loopback name (``localhost``, ``127.x.y.z``, ``[::1]``), the host the scene is bound to or this
  machine's host name; or, for such a HOST or an IP address, HOST:PORT is the address the
  handshake itself was sent to (its ``Host`` header: a page served through a port mapping,
  ``docker run -p 9090:8080``, or on the machine's LAN address). Other names are never taken
  from the ``Host`` header: DNS rebinding can point any name at this machine;
* origins listed with ``python -m app serve --allow-origin URL`` (repeatable), e.g. a reverse
  proxy's public address.

viser 1.1.1 runs its own ``websockets`` server and takes no hook for this; :func:`start_viser`
installs the check as that server's ``process_request`` (the handshake hook of ``websockets``),
by wrapping ``websockets.asyncio.server.serve`` only while viser starts its server thread.

:func:`stop_viser` stops such a server without waiting for a browser's spare connections: a
browser opens TCP connections it may never send a request on (more than one tab on a host), and
``websockets`` waits for each one's handshake for up to its ``open_timeout`` (10 s) when it
closes. viser's ``stop()`` gives up after 6 s and leaves its thread running, so every scene a
browser had two tabs on took 6 s to stop.
"""

from __future__ import annotations

import http
import ipaddress
import socket
import threading
import weakref
from collections.abc import Callable, Iterable
from typing import Any
from urllib.parse import urlsplit

__all__ = ["OriginPolicy", "normalise_origin", "start_viser", "stop_viser"]

_DEFAULT_PORTS = {"http": 80, "https": 443}
_PATCH_LOCK = threading.Lock()
_WEBSOCKETS: weakref.WeakKeyDictionary[Any, Any] = weakref.WeakKeyDictionary()
"""The ``websockets`` server under each viser server :func:`start_viser` started (for :func:`stop_viser`)."""


def normalise_origin(url: str) -> str:
    """``scheme://host[:port]`` in lower case, the default port dropped (how browsers send it).

    Raises:
        ValueError: not an http(s) origin (a path, query or user part is not an origin).

    Examples:
        >>> normalise_origin("HTTPS://Example.org:443/")
        'https://example.org'
        >>> normalise_origin("http://10.0.0.5:8080")
        'http://10.0.0.5:8080'
    """
    parts = urlsplit(url.strip())
    if parts.scheme.lower() not in _DEFAULT_PORTS or not parts.hostname:
        raise ValueError(f"not an origin: {url!r} (expected e.g. http://host:8080 or https://example.org)")
    if parts.path not in ("", "/") or parts.query or parts.fragment or parts.username or parts.password:
        raise ValueError(f"not an origin: {url!r} (scheme, host and port only)")
    scheme, host = parts.scheme.lower(), parts.hostname.lower()
    try:
        port = parts.port
    except ValueError:
        raise ValueError(f"not an origin: {url!r} (bad port)") from None
    if ":" in host:
        host = f"[{host}]"
    if port is None or port == _DEFAULT_PORTS[scheme]:
        return f"{scheme}://{host}"
    return f"{scheme}://{host}:{port}"


def _split(origin: str) -> tuple[str, str, int] | None:
    """(scheme, host without brackets, port) of an origin, or None if it is not http(s)."""
    try:
        parts = urlsplit(origin)
        port = parts.port
    except ValueError:
        return None
    scheme = parts.scheme.lower()
    if scheme not in _DEFAULT_PORTS or not parts.hostname:
        return None
    return scheme, parts.hostname.lower(), port if port is not None else _DEFAULT_PORTS[scheme]


def _address_of(host_header: str | None, scheme: str) -> tuple[str, int] | None:
    """(host, port) of a ``Host`` header (no brackets, lower case; the scheme's default port)."""
    if not host_header:
        return None
    try:
        parts = urlsplit(f"//{host_header.strip()}")
        port = parts.port
    except ValueError:
        return None
    if not parts.hostname:
        return None
    return parts.hostname.lower(), port if port is not None else _DEFAULT_PORTS[scheme]


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _is_ip(host: str) -> bool:
    try:
        ipaddress.ip_address(host)
    except ValueError:
        return False
    return True


class OriginPolicy:
    """The rule above for a scene bound to ``host`` (its port is set once the server runs).

    Examples:
        >>> p = OriginPolicy("127.0.0.1", ["https://example.org"], port=8080)
        >>> [p.allows(o, "127.0.0.1:8080") for o in (None, "http://localhost:8080", "https://example.org")]
        [True, True, True]
        >>> [p.allows(o, "127.0.0.1:8080") for o in ("http://evil.example", "http://localhost:9999", "null")]
        [False, False, False]
        >>> p.allows("http://localhost:9090", "localhost:9090")   # served through a port mapping
        True
        >>> p.allows("http://192.168.1.99:8080", "localhost:8080")  # another machine's page
        False
    """

    def __init__(self, host: str, allowed: Iterable[str] = (), *, port: int | None = None) -> None:
        self.host = (host or "").strip("[]").lower()
        self.allowed = frozenset(normalise_origin(a) for a in allowed)
        self.port = port
        names = {socket.gethostname().lower()}
        try:
            names.add(socket.getfqdn().lower())
        except OSError:  # pragma: no cover - resolver trouble
            pass
        self.machine_names = frozenset(n for n in names if n)
        self.trusted_tabs: set[str] = set()
        """Tab ids handed out as capabilities (a notebook cell's scene): a handshake to
        ``/s/<id>/`` of such a tab opens whatever its Origin (see :meth:`trust_tab`)."""

    def trust_tab(self, tab: str) -> None:
        """Accept handshakes to the tab ``/s/<tab>/`` from any page.

        For a scene shown in a notebook cell through the notebook's proxy
        (jupyter-server-proxy: ``<notebook>/proxy/PORT/s/<tab>/``): the page's Origin is the
        notebook server's, a name this scene cannot vouch for. The tab id is a random 96-bit
        secret that only the cell's output holds, so knowing it is the permission.
        """
        self.trusted_tabs.add(tab)

    def allows(self, origin: str | None, host_header: str | None = None) -> bool:
        """True if a websocket handshake with this ``Origin`` (and ``Host``) may open a session."""
        if origin is None:
            return True
        try:
            if normalise_origin(origin) in self.allowed:
                return True
        except ValueError:
            return False
        parsed = _split(origin)
        if parsed is None:
            return False
        scheme, host, port = parsed
        ours = _is_loopback(host) or host == self.host or host in self.machine_names
        if ours and port == self.port:
            return True
        # the page's address is the one this handshake was sent to (port mapping, proxy on an IP)
        return (ours or _is_ip(host)) and (host, port) == _address_of(host_header, scheme)

    def process_request(self, inner: Callable[..., Any] | None) -> Callable[..., Any]:
        """A ``websockets`` ``process_request`` hook: 403 for a refused handshake, else ``inner``."""

        def check(connection: Any, request: Any) -> Any:
            if request.headers.get("Upgrade", "").lower() == "websocket":
                origins = request.headers.get_all("Origin")
                origin = origins[0] if len(origins) == 1 else None
                if self.trusted_tabs:
                    from .links import tab_id_of

                    if tab_id_of(request.path) in self.trusted_tabs:
                        return inner(connection, request) if inner is not None else None
                if len(origins) > 1 or not self.allows(origin, request.headers.get("Host")):
                    return connection.respond(
                        http.HTTPStatus.FORBIDDEN,
                        f"This scene does not accept sessions from pages at {', '.join(origins)!s}. "
                        "Open the scene's own address, or start it with --allow-origin URL.\n",
                    )
            return inner(connection, request) if inner is not None else None

        return check


def start_viser(policy: OriginPolicy, router: Any = None, *, max_message: int | None = None, **kwargs: Any) -> Any:
    """``viser.ViserServer(**kwargs)`` whose websocket handshake applies ``policy``.

    ``router`` (an :class:`app.scene.common.links.Router`) also routes the HTTP requests (tab addresses);
    ``max_message`` replaces viser's largest websocket message a client may send (50 MB).

    Raises:
        RuntimeError: viser started its server some other way, so the check is not in place
            (the server is stopped: a scene without the check is never left running).
    """
    import viser
    import websockets.asyncio.server as ws_server

    original = ws_server.serve
    installed: list[bool] = []
    if policy.port is None and kwargs.get("port"):
        policy.port = int(kwargs["port"])

    started: list[Any] = []

    def serve(*args: Any, process_request: Callable[..., Any] | None = None, **kw: Any) -> Any:
        installed.append(True)
        if router is not None:
            process_request = router.process_request(process_request)
        if max_message is not None:
            kw["max_size"] = max_message
        started.append(original(*args, process_request=policy.process_request(process_request), **kw))
        return started[-1]

    with _PATCH_LOCK:  # viser calls serve() from its thread before ViserServer() returns
        ws_server.serve = serve  # type: ignore[assignment,misc]  # patched on purpose: serve is a class in websockets
        try:
            server = viser.ViserServer(**kwargs)
        finally:
            ws_server.serve = original  # type: ignore[misc]
    if not installed:
        server.stop()
        raise RuntimeError("viser did not start its websocket server through websockets.asyncio.server.serve: "
                           "the Origin check of the scene could not be installed")
    policy.port = int(server.get_port())
    websockets_server = getattr(started[-1], "server", None)  # websockets' Server (handlers, loop)
    if websockets_server is not None:
        _WEBSOCKETS[server] = websockets_server
    return server


def stop_viser(server: Any) -> None:
    """``server.stop()``, first dropping the connections that have not sent a request yet.

    Such a connection is a browser's spare socket (or a client that never spoke): closing the
    server would wait for its handshake (module docstring). Dropped on the server's event loop,
    now and again just after the stop has closed the listening socket.
    """
    ws = _WEBSOCKETS.get(server)
    loop = getattr(ws, "loop", None)
    if loop is not None:
        def drop_unopened() -> None:
            from websockets.protocol import State

            for connection in list(getattr(ws, "handlers", {})):
                if connection.protocol.state is State.CONNECTING:
                    connection.transport.abort()

        try:
            loop.call_soon_threadsafe(drop_unopened)
            for delay in (0.05, 0.5):  # accepted between this call and the listener's close
                loop.call_soon_threadsafe(loop.call_later, delay, drop_unopened)
        except RuntimeError:  # the loop is already closed: nothing waits on it
            pass
    server.stop()
