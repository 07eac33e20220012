"""Configurations in URLs, and tabs that keep their state across a reload.

Every tab has an address of its own, ``/s/<tab id>/``: opening the scene's root ``/`` redirects
to a fresh one, and the server keeps each tab's last configuration (a snapshot taken when the
tab disconnects), so a reload reopens the tab as it was. A shared link,
``/c/<configuration>/``, carries a whole :class:`~app.scene.common.state.SceneConfig` (JSON, zlib,
base64url); opening it starts a new tab on that configuration (redirected to its own ``/s/``
address). The viser client connects its websocket to the page's path, so the handshake names
the tab; :func:`tab_id_of` reads it back (:mod:`app.scene.common.wire` holds the one private access).

Text from a URL is user input: it is size-checked here and read like an uploaded file
(a typed motion in it is parsed and analysed in a worker process, as if typed in the editor).
"""

from __future__ import annotations

import base64
import binascii
import dataclasses
import http
import json
import re
import secrets
import threading
import zlib
from collections import OrderedDict
from collections.abc import Callable
from typing import Any
from urllib.parse import urlsplit

from .lesson import LessonMarks
from .page import (
    CLIENT_PREFIX,
    SHARED_CLIENT_DIR,
    TAB_CLIENT_DIR,
    client_asset_response,
    page_response,
)
from .state import SceneConfig

__all__ = ["encode_config", "decode_config", "TabStore", "Router", "MAX_LINK_CHARS", "link_path"]

MAX_LINK_CHARS = 16384
"""Longest configuration token accepted in a URL (compressed; about 60 kB of JSON)."""

_TAB = re.compile(r"^/s/([A-Za-z0-9_-]{8,64})/?")
_LINK = re.compile(rf"^/c/([A-Za-z0-9_=-]{{1,{MAX_LINK_CHARS}}})/?")


def encode_config(config: SceneConfig | dict[str, Any]) -> str:
    """URL-safe token of a configuration: base64url of zlib-compressed JSON (no padding).

    Examples:
        >>> token = encode_config({"dim": 2, "preset": "circles-crossing", "t": 0.5})
        >>> decode_config(token)
        {'dim': 2, 'preset': 'circles-crossing', 't': 0.5}
    """
    data = config.to_dict() if isinstance(config, SceneConfig) else config
    raw = json.dumps(data, separators=(",", ":"), sort_keys=False).encode()
    return base64.urlsafe_b64encode(zlib.compress(raw, 9)).decode().rstrip("=")


def decode_config(token: str) -> dict[str, Any]:
    """The JSON object of a token (not yet checked as a configuration: :meth:`SceneConfig.from_dict`).

    Raises:
        ValueError: too long, not base64url, not zlib, too large once inflated, or not a JSON object.

    Examples:
        >>> decode_config("not a token!")
        Traceback (most recent call last):
        ...
        ValueError: link: the configuration is not readable (not base64url)
    """
    if len(token) > MAX_LINK_CHARS:
        raise ValueError(f"link: the configuration is too long ({len(token)} > {MAX_LINK_CHARS} characters)")
    try:
        packed = base64.urlsafe_b64decode(token + "=" * (-len(token) % 4))
    except (binascii.Error, ValueError):
        raise ValueError("link: the configuration is not readable (not base64url)") from None
    d = zlib.decompressobj()
    try:
        raw = d.decompress(packed, 64 * MAX_LINK_CHARS)
    except zlib.error:
        raise ValueError("link: the configuration is not readable (not compressed JSON)") from None
    if d.unconsumed_tail:
        raise ValueError("link: the configuration is too large once unpacked")
    try:
        data = json.loads(raw)
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError):
        raise ValueError("link: the configuration is not valid JSON") from None
    if not isinstance(data, dict):
        raise ValueError("link: the configuration must be a JSON object")
    return data


def link_path(config: SceneConfig | dict[str, Any]) -> str:
    """The path of a link that opens a new tab on ``config`` (``/c/<token>/``)."""
    return f"/c/{encode_config(config)}/"


class TabStore:
    """Each tab's last configuration by tab id (in memory, the most recent ``size`` tabs).

    A value is a :class:`SceneConfig`, or the JSON object of a link (read and checked when the
    tab opens it, so that a bad link shows its error in that tab).
    """

    def __init__(self, size: int = 2000) -> None:
        self._items: OrderedDict[str, SceneConfig | dict[str, Any]] = OrderedDict()
        self._lock = threading.Lock()
        self.size = size
        self.lessons = LessonMarks(size)
        """The lesson and step of each tab in one (:mod:`app.scene.common.lesson`)."""

    def new_id(self) -> str:
        """A fresh tab id (random, unguessable)."""
        return secrets.token_urlsafe(12)

    def put(self, tab: str, config: SceneConfig | dict[str, Any]) -> None:
        """Remember the configuration of a tab."""
        with self._lock:
            self._items[tab] = config
            self._items.move_to_end(tab)
            while len(self._items) > self.size:
                self._items.popitem(last=False)

    def get(self, tab: str) -> SceneConfig | dict[str, Any] | None:
        """The last configuration of a tab, or None."""
        with self._lock:
            return self._items.get(tab)


def tab_id_of(path: str | None) -> str | None:
    """The tab id of a handshake or page path ``/s/<id>``, or None.

    Examples:
        >>> tab_id_of("/s/AbCdEfGh1234/"), tab_id_of("/"), tab_id_of(None)
        ('AbCdEfGh1234', None, None)
    """
    if not path:
        return None
    m = _TAB.match(urlsplit(path).path)
    return m.group(1) if m else None


class Router:
    """The HTTP side of tab addresses, as a ``websockets`` ``process_request`` hook around viser's.

    * ``GET /`` (the page, not the websocket) -> 302 to ``/s/<new id>/`` (the query kept);
    * ``GET /c/<token>/`` -> the token is stored for a new tab id, 302 to ``/s/<id>/``;
    * ``GET /s/<id>/...`` -> viser's page (:mod:`app.scene.common.page`);
    * ``GET /_client/<hash>.js`` / ``.css`` -> the client's code and style (cached by browsers).

    Args:
        store: where tabs keep their configurations.
        enabled: False in presenter mode (one shared scene: no per-tab addresses).
    """

    def __init__(self, store: TabStore, *, enabled: bool = True) -> None:
        self.store = store
        self.enabled = enabled

    def process_request(self, inner: Callable[..., Any] | None) -> Callable[..., Any]:
        """Wrap viser's HTTP hook ``inner`` (websocket handshakes pass through unchanged)."""

        def route(connection: Any, request: Any) -> Any:
            if request.headers.get("Upgrade", "").lower() == "websocket":
                return inner(connection, request) if inner is not None else None
            parts = urlsplit(request.path)
            if parts.path.startswith(CLIENT_PREFIX):  # the client's code and style, one for every tab
                return client_asset_response(request, parts.path[len(CLIENT_PREFIX) :])
            if not self.enabled:  # presenter mode: one page, still with its labels tied to inputs
                if parts.path in ("", "/", "/index.html"):
                    return page_response(request, SHARED_CLIENT_DIR)
                return inner(connection, request) if inner is not None else None
            query = f"?{parts.query}" if parts.query else ""
            # relative redirects: the same request works behind a proxy that serves the scene
            # under a path of its own (jupyter-server-proxy's <notebook>/proxy/PORT/)
            if parts.path in ("", "/", "/index.html"):
                return _redirect(connection, f"s/{self.store.new_id()}/{query}")
            m = _LINK.match(parts.path)
            if m is not None:
                try:
                    data: dict[str, Any] = decode_config(m.group(1))
                except ValueError as e:
                    data = {"error": str(e)}
                tab = self.store.new_id()
                self.store.put(tab, data)
                up = "../../" if parts.path.endswith("/") else "../"  # from /c/<token>/ (or /c/<token>)
                return _redirect(connection, f"{up}s/{tab}/{query}")
            m = _TAB.match(parts.path)
            if m is not None:  # the page itself, or a file next to it
                rest = parts.path[m.end():]
                if rest in ("", "index.html") and parts.query:  # ?lesson=paper&step=3: the tab's lesson
                    self.store.lessons.note_query(m.group(1), parts.query)
                if rest in ("", "index.html"):  # viser's page with labels tied to inputs; the
                    return page_response(request, TAB_CLIENT_DIR)  # client relative: proxies
                request = dataclasses.replace(request, path="/" + rest + query)
            return inner(connection, request) if inner is not None else None

        return route


def _redirect(connection: Any, location: str) -> Any:
    response = connection.respond(http.HTTPStatus.FOUND, f"See {location}\n")
    response.headers["Location"] = location
    response.headers["Cache-Control"] = "no-store"
    return response
