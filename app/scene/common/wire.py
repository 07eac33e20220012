"""Hot-path property updates for viser handles, without viser's per-assignment introspection.

viser 1.1.1's public setters re-derive type hints for every element of a tuple of arrays
(~25 us per uPlot series) and compare poses with ``np.allclose`` (~20 us per vector), which
made the scene's full t-step miss its 1 ms budget. These helpers store the value on the
handle and queue the same websocket message the public setter would, through the handle's own
``_queue_update`` / scene queue (viser is pinned to 1.1.1; ``tests/test_scene.py`` checks that
the values read back and the messages match the public path). If the private attributes ever
move, they fall back to the public setters: slower, never wrong.

This is the only module of the scene that touches viser's private attributes: also
:func:`force_pose` (a node re-added under a name the browser has seen keeps the browser's old
pose unless the new one is sent explicitly, even when it equals the new handle's default) and
:class:`MessageCounter` (the benchmark's count of queued websocket messages) and
:func:`handshake_path` (the page path a tab connected from: its tab address) and
:func:`client_records` (viser's records of connected clients) and :class:`UploadGuard` (every
byte a client uploads is counted before viser keeps it).
"""

from __future__ import annotations

import asyncio
import threading
import time
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["set_uplot_data", "set_position", "set_wxyz", "force_pose", "MessageCounter", "handshake_path", "client_records",
           "UploadGuard", "Refusal", "too_large", "MAX_MESSAGE_BYTES", "MIN_PART_BYTES"]


def set_uplot_data(handle: Any, data: Sequence[np.ndarray]) -> None:
    """``handle.data = data`` for a uPlot handle: float64 copies (the queued message owns them)."""
    arrays = tuple(np.array(a, dtype=np.float64) for a in data)
    try:
        impl = handle._impl
        if impl.removed:
            raise RuntimeError("Cannot assign to 'data' on a removed uPlot handle.")
        impl.props.data = arrays
        queue = handle._queue_update
    except AttributeError:  # viser internals moved: public path
        handle.data = arrays
        return
    queue("data", arrays)


def _set_vector(handle: Any, attr: str, value: Sequence[float], message: str, *, force: bool = False) -> None:
    vec = tuple(float(v) for v in value)
    try:
        from viser import _messages

        impl = handle._impl
        current = getattr(impl, attr)
        make = getattr(_messages, message)
        queue = impl.api._queue_scene_message
        removed = impl.removed
    except (AttributeError, ImportError):
        if force:  # public path: move away and back so that the value is sent
            setattr(handle, attr, tuple(v + 1.0 for v in vec))
        setattr(handle, attr, vec)
        return
    if removed:
        raise RuntimeError(f"Cannot assign to {attr!r} on a removed scene node.")
    if not force and tuple(current.tolist()) == vec:  # exactly unchanged: nothing to send
        return
    current[:] = vec
    queue(make(impl.name, vec))


def set_position(handle: Any, position: Sequence[float]) -> None:
    """``handle.position = position`` (sent unless exactly unchanged)."""
    _set_vector(handle, "position", position, "SetPositionMessage")


def set_wxyz(handle: Any, wxyz: Sequence[float]) -> None:
    """``handle.wxyz = wxyz`` (sent unless exactly unchanged)."""
    _set_vector(handle, "wxyz", wxyz, "SetOrientationMessage")


def force_pose(handle: Any, position: Sequence[float], wxyz: Sequence[float]) -> None:
    """Send a node's position and orientation even if they equal what the server holds.

    After a node is removed and re-added under the same name (a 3D <-> 2D switch rebuilds the
    shapes) the browser keeps the old node's pose while the new handle holds viser's defaults:
    a setter that skips "unchanged" values would leave the picture at the old pose.
    """
    _set_vector(handle, "position", position, "SetPositionMessage", force=True)
    _set_vector(handle, "wxyz", wxyz, "SetOrientationMessage", force=True)


class MessageCounter:
    """Counts the websocket messages queued through one scene API.

    ``client.scene`` or ``server.scene``: the benchmark's measure of what an update sends.
    """

    def __init__(self, scene: Any) -> None:
        self.count = 0
        iface = scene._websock_interface
        orig = iface.queue_message

        def counting(message: Any) -> None:
            self.count += 1
            orig(message)

        iface.queue_message = counting


def client_records(server: Any) -> dict[str, int]:
    """Sizes of viser's records of connected clients (all 0 once every tab has left).

    Its clients, their message states and connections, and the broadcast buffer's cursors (one
    per client reading it); -1 for a record this viser does not have.
    """
    ws = getattr(server, "_websock_server", None)
    buffer = getattr(ws, "_broadcast_buffer", None)
    found = {
        "viser clients": getattr(server, "_connected_clients", None),
        "viser client states": getattr(ws, "_client_state_from_id", None),
        "viser connections": getattr(ws, "_live_connections", None),
        "viser broadcast cursors": getattr(buffer, "generator_cursors", None),
    }
    return {k: -1 if v is None else len(v) for k, v in found.items()}


def handshake_path(server: Any, client: Any) -> str | None:
    """The path of the websocket handshake of ``client`` (the page's path, e.g. ``/s/<tab id>``).

    viser keeps each client's ``websockets`` connection, whose ``request`` is the handshake;
    None if that is not available (an older or newer viser: tabs then open the default).
    """
    try:
        connection = server._websock_server._live_connections[client.client_id]
        return str(connection.request.path)
    except (AttributeError, KeyError, TypeError):
        return None


# ---------------------------------------------------------------------------------------- uploads
MAX_MESSAGE_BYTES = 1 << 20
"""Largest websocket message the scene reads from a client (viser's own server reads 50 MB).

viser's browser client sends a file in parts of 512 KiB and the longest text the scene reads is
:data:`app.scene.pair.motion.MAX_MOTION_TEXT` characters; a larger message closes the connection (code
1009) before it is read whole. ``websockets`` reads ahead at most 16 messages of a connection
(its ``max_queue``), so a client holds at most ~16 MiB of the server in messages not yet handled.
"""

MIN_PART_BYTES = 4096
"""Smallest mean part of an upload a client may declare (viser's client sends 512 KiB parts).

Each part costs the server a slot besides its bytes: a file declared in more than
``size // MIN_PART_BYTES + 1`` parts is refused at its start."""

UPLOAD_IDLE_SECONDS = 30.0
"""An upload whose next part does not arrive within this time is dropped (its parts freed)."""

MAX_TRANSFERS = 8
"""Uploads one client may have under way at once (a tab has one or two upload buttons)."""

REFUSAL_ACKS = (8, 1.0)
"""Refusals acknowledged to one client: a burst of 8, then one a second (each is a message queued
to it: a client that sends refusable uploads without reading would grow its queue)."""


@dataclass(frozen=True)
class Refusal:
    """An upload the scene refused, and why (what the tab's panel says: :meth:`message`)."""

    client_id: int
    filename: str
    size: int
    """Bytes the client declared."""
    limit: int
    """The button's limit (bytes)."""
    reason: str
    """"too large", "busy" (the tab's or the server's other uploads), "stalled" or "malformed"."""
    detail: str = ""

    def message(self) -> str:
        """One line for the tab: what is wrong, with the limit.

        Examples:
            >>> Refusal(1, "big.csv", 10**8, 64 << 20, "too large").message()
            'big.csv is too large (100,000,000 bytes; the limit is 67,108,864 bytes, 64 MiB)'
        """
        name = self.filename or "the file"
        if self.reason == "too large":
            return too_large(name, self.size, self.limit)
        if self.reason == "stalled":
            return f"{name}: the upload stopped ({self.detail}); open the file again"
        if self.reason == "busy":
            return f"{name} was refused: {self.detail}; try again once the other uploads are done"
        return f"{name} was refused: {self.detail}"


def too_large(name: str, size: int, limit: int) -> str:
    """What a tab is told of a file over its upload limit (refused before it is sent, or after).

    Examples:
        >>> too_large("scene.json", 300_000, 256 * 1024)
        'scene.json is too large (300,000 bytes; the limit is 262,144 bytes)'
    """
    return f"{name} is too large ({size:,} bytes; the limit is {_size(limit)})"


def _size(n: int) -> str:
    """'67,108,864 bytes, 64 MiB' (the MiB when the number is a whole number of them)."""
    return f"{n:,} bytes" + (f", {n >> 20} MiB" if n >= 1 << 20 and n % (1 << 20) == 0 else "")


@dataclass
class _Rule:
    max_bytes: int
    on_refused: Callable[[Refusal], None] | None
    pending: Refusal | None = None
    """The newest refusal not yet told (refusals in a burst are told once, the last)."""


@dataclass
class _Transfer:
    gui: Any
    client_id: int
    button: str
    filename: str
    size: int
    count: int
    limit: int
    loop: asyncio.AbstractEventLoop
    last: float
    received: int = 0
    indices: set[int] = field(default_factory=set)
    timer: asyncio.TimerHandle | None = None


class UploadGuard:
    """Counts every byte a client uploads before viser keeps it (viser 1.1.1 keeps whatever it is sent).

    viser buffers the parts of an upload in the server process with no limit on the size or the
    part count a client declares, until the last part arrives. This guard replaces viser's two
    upload handlers on the server's GUI and on every tab's own (installed as the tab connects,
    before its panel exists). A transfer is refused at its start, before anything is buffered,
    when its declared size exceeds its button's limit (:meth:`limit`; default ``per_client``),
    its part count is out of proportion (:data:`MIN_PART_BYTES`), or the client's uploads under
    way (``per_client`` bytes, :data:`MAX_TRANSFERS`) or the server's (``total``) would exceed
    their budget with it. A part beyond the declared size drops its transfer; a transfer with no
    part for ``idle`` seconds is dropped; a tab that leaves loses its transfers. A refused or
    dropped transfer is acknowledged as finished (the browser's progress ends and its button
    works again) and the button's ``on_refused`` is told (:class:`Refusal`, on a worker thread).

    Args:
        server: the ``viser.ViserServer`` (the guard is installed on its GUI and its tabs').
        per_client: most bytes one client may have under way, all its uploads together.
        total: most bytes under way for all clients together (None: no such limit).
        idle: seconds a transfer may wait for its next part.

    Raises:
        RuntimeError: viser's upload handlers are not where this module expects them (a scene
            without the guard is never started).
    """

    def __init__(self, server: Any, *, per_client: int, total: int | None = None, idle: float = UPLOAD_IDLE_SECONDS) -> None:
        from concurrent.futures import ThreadPoolExecutor

        self.per_client, self.total, self.idle = int(per_client), total, float(idle)
        self._lock = threading.Lock()
        self._transfers: dict[tuple[int, str], _Transfer] = {}
        self._rules: dict[int, dict[str, _Rule]] = {}
        self._acks: dict[int, tuple[float, float]] = {}
        """Per client: refusal acknowledgements it may still get, and when that was counted."""
        self._tell = ThreadPoolExecutor(max_workers=1, thread_name_prefix="upload-refused")
        self._installed: weakref.WeakSet[Any] = weakref.WeakSet()
        self.install(server.gui)
        server.on_client_connect(self._on_connect)
        server.on_client_disconnect(self._on_disconnect)

    # ---------------------------------------------------------------- set-up
    def install(self, gui: Any) -> None:
        """Replace viser's upload handlers of ``gui`` (a server's or a tab's GUI) by the guard's (once)."""
        from functools import partial

        from viser import _messages

        if gui in self._installed:
            return
        try:
            iface = gui._websock_interface
            start, part = gui._handle_file_transfer_start, gui._handle_file_transfer_part
            gui._current_file_upload_states  # noqa: B018 - checked: the guard drops entries of it
            gui._gui_input_handle_from_uuid  # noqa: B018
            iface.unregister_handler(_messages.FileTransferStartUpload, start)
            iface.unregister_handler(_messages.FileTransferPart, part)
        except (AttributeError, AssertionError, ValueError) as e:
            raise RuntimeError(f"viser's upload handlers moved ({e!r}): the scene's upload limits cannot be installed") from None
        iface.register_handler(_messages.FileTransferStartUpload, partial(self._start, gui, start))
        iface.register_handler(_messages.FileTransferPart, partial(self._part, gui, part))
        self._installed.add(gui)

    async def _on_connect(self, client: Any) -> None:  # async: on the event loop, before the tab's panel exists
        self.install(client.gui)

    async def _on_disconnect(self, client: Any) -> None:
        self.forget(client.client_id)
        with self._lock:
            self._rules.pop(id(client.gui), None)

    def limit(self, button: Any, max_bytes: int, on_refused: Callable[[Refusal], None] | None = None) -> None:
        """Refuse uploads to ``button`` larger than ``max_bytes`` (capped at ``per_client``); tell ``on_refused``."""
        gui, uuid = button._impl.gui_api, button._impl.uuid
        with self._lock:
            rules = self._rules.setdefault(id(gui), {})
            live = gui._gui_input_handle_from_uuid
            for gone in [u for u in rules if u not in live]:  # buttons removed since (a panel rebuilt)
                del rules[gone]
            rules[uuid] = _Rule(int(max_bytes), on_refused)

    def close(self) -> None:
        """Stop telling refusals (the server stops)."""
        self._tell.shutdown(wait=False, cancel_futures=True)

    # ---------------------------------------------------------------- state
    def buffered(self, client_id: int | None = None) -> int:
        """Bytes reserved by uploads under way (of one client, or of all)."""
        with self._lock:
            return sum(t.size for t in self._transfers.values() if client_id is None or t.client_id == client_id)

    def transfers(self) -> int:
        """Uploads under way."""
        with self._lock:
            return len(self._transfers)

    def registries(self) -> dict[str, int]:
        """Sizes of the guard's per-tab records (all 0 once every tab has left: nothing is kept per tab)."""
        with self._lock:
            return {"transfers": len(self._transfers), "rules": sum(len(r) for r in self._rules.values()),
                    "ack budgets": len(self._acks)}

    def forget(self, client_id: int) -> None:
        """Drop the uploads of a client that left (nothing is told: there is no one to tell)."""
        with self._lock:
            for k in [k for k, t in self._transfers.items() if t.client_id == client_id]:
                self._drop_locked(k)
            self._acks.pop(client_id, None)

    # ---------------------------------------------------------------- viser's messages (event loop)
    def _start(self, gui: Any, original: Callable[[Any, Any], None], client_id: Any, msg: Any) -> None:
        button = msg.source_component_uuid
        if button not in gui._gui_input_handle_from_uuid:
            return  # not this GUI's button (the server's GUI sees every tab's messages); viser ignores it too
        size, count, key = msg.size_bytes, msg.part_count, (id(gui), msg.transfer_uuid)
        with self._lock:
            rule = self._rules.get(id(gui), {}).get(button)
            limit = min(rule.max_bytes, self.per_client) if rule is not None else self.per_client
            mine = [t for t in self._transfers.values() if t.client_id == client_id]
            reason, detail = "", ""
            if not (isinstance(size, int) and isinstance(count, int)) or size < 0 or count < 0 or (count == 0) != (size == 0):
                reason, detail = "malformed", "its declared size and part count do not agree"
            elif size > limit:
                reason = "too large"
            elif count > size // MIN_PART_BYTES + 1:
                reason, detail = "malformed", f"{count:,} parts declared for {size:,} bytes"
            elif key in self._transfers:
                reason, detail = "malformed", "a transfer of that id is under way"
            elif len(mine) >= MAX_TRANSFERS or sum(t.size for t in mine) + size > self.per_client:
                reason, detail = "busy", f"this tab's uploads under way would exceed {MAX_TRANSFERS} files or {_size(self.per_client)}"
            elif self.total is not None and sum(t.size for t in self._transfers.values()) + size > self.total:
                reason, detail = "busy", "the server is receiving too many files at once"
            if not reason:
                loop = asyncio.get_running_loop()
                t = _Transfer(gui, client_id, button, str(msg.filename), size, count, limit, loop, time.monotonic())
                t.timer = loop.call_later(self.idle, self._expire, key)
                self._transfers[key] = t
        if reason:
            shown = size if isinstance(size, int) else 0
            self._refuse(gui, button, msg.transfer_uuid, Refusal(client_id, str(msg.filename), shown, limit, reason, detail))
            return
        original(client_id, msg)
        self._release_if_done(gui, key)

    def _part(self, gui: Any, original: Callable[[Any, Any], None], client_id: Any, msg: Any) -> None:
        key = (id(gui), msg.transfer_uuid)
        refusal: Refusal | None = None
        with self._lock:
            t = self._transfers.get(key)
            if t is None or t.client_id != client_id:
                return  # refused, dropped, finished or another GUI's: discarded, nothing kept
            k, n = msg.part_index, len(msg.content)
            if not isinstance(k, int) or not 0 <= k < t.count or k in t.indices:
                return  # a repeated or out-of-range part: viser drops it too
            if t.received + n > t.size:
                self._drop_locked(key)
                refusal = Refusal(t.client_id, t.filename, t.size, t.limit, "malformed", f"more bytes sent than the {t.size:,} declared")
            else:
                t.received += n
                t.indices.add(k)
                t.last = time.monotonic()
        if refusal is not None:
            self._refuse(gui, t.button, msg.transfer_uuid, refusal)
            return
        original(client_id, msg)
        self._release_if_done(gui, key)

    def _expire(self, key: tuple[int, str]) -> None:
        """The idle timer of a transfer (event loop): drop it if no part came for ``idle`` seconds."""
        with self._lock:
            t = self._transfers.get(key)
            if t is None:
                return
            left = t.last + self.idle - time.monotonic()
            if left > 0:
                t.timer = t.loop.call_later(left, self._expire, key)
                return
            self._drop_locked(key)
        self._refuse(t.gui, t.button, key[1], Refusal(t.client_id, t.filename, t.size, t.limit, "stalled",
                                                       f"no part arrived for {self.idle:g} s"))

    # ---------------------------------------------------------------- helpers
    def _release_if_done(self, gui: Any, key: tuple[int, str]) -> None:
        """Forget a transfer viser has finished (its file handed to the button's callbacks)."""
        if key[1] not in gui._current_file_upload_states:
            with self._lock:
                t = self._transfers.pop(key, None)
                if t is not None and t.timer is not None:
                    t.timer.cancel()

    def _drop_locked(self, key: tuple[int, str]) -> None:
        t = self._transfers.pop(key, None)
        if t is None:
            return
        if t.timer is not None:
            t.timer.cancel()
        t.gui._current_file_upload_states.pop(key[1], None)  # its parts go with it

    def _refuse(self, gui: Any, button: str, transfer: str, refusal: Refusal) -> None:
        """End the browser's progress on the transfer (its button works again) and tell the button's owner.

        Both are rationed: a client is acknowledged :data:`REFUSAL_ACKS` refusals (burst, then per
        second), and a button's owner is told the newest of a burst of refusals once.
        """
        from viser import _messages

        burst, per_second = REFUSAL_ACKS
        now = time.monotonic()
        with self._lock:
            tokens, then = self._acks.get(refusal.client_id, (float(burst), now))
            tokens = min(float(burst), tokens + (now - then) * per_second)
            ack = tokens >= 1.0
            self._acks[refusal.client_id] = (tokens - 1.0 if ack else tokens, now)
            rule = self._rules.get(id(gui), {}).get(button)
            tell = rule is not None and rule.on_refused is not None and rule.pending is None
            if rule is not None:
                rule.pending = refusal
        if ack:
            total = max(refusal.size, 0)
            gui._websock_interface.queue_message(_messages.FileTransferPartAck(
                source_component_uuid=button, transfer_uuid=transfer, transferred_bytes=total, total_bytes=total))
        if tell:
            assert rule is not None
            try:
                self._tell.submit(self._told, rule)
            except RuntimeError:  # stopping
                pass

    def _told(self, rule: _Rule) -> None:
        with self._lock:
            refusal, rule.pending = rule.pending, None
        if refusal is not None and rule.on_refused is not None:
            rule.on_refused(refusal)
