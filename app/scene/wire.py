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
:func:`handshake_path` (the page path a tab connected from: its tab address).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["set_uplot_data", "set_position", "set_wxyz", "force_pose", "MessageCounter", "handshake_path"]


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
