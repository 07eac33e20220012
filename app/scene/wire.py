"""Hot-path property updates for viser handles, without viser's per-assignment introspection.

viser 1.1.1's public setters re-derive type hints for every element of a tuple of arrays
(~25 us per uPlot series) and compare poses with ``np.allclose`` (~20 us per vector), which
made the scene's full t-step miss its 1 ms budget. These helpers store the value on the
handle and queue the same websocket message the public setter would, through the handle's own
``_queue_update`` / scene queue (viser is pinned to 1.1.1; ``tests/test_scene.py`` checks that
the values read back and the messages match the public path). If the private attributes ever
move, they fall back to the public setters: slower, never wrong.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["set_uplot_data", "set_position", "set_wxyz"]


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


def _set_vector(handle: Any, attr: str, value: Sequence[float], message: str) -> None:
    vec = tuple(float(v) for v in value)
    try:
        from viser import _messages

        impl = handle._impl
        current = getattr(impl, attr)
        make = getattr(_messages, message)
        queue = impl.api._queue_scene_message
        removed = impl.removed
    except (AttributeError, ImportError):
        setattr(handle, attr, vec)
        return
    if removed:
        raise RuntimeError(f"Cannot assign to {attr!r} on a removed scene node.")
    if tuple(current.tolist()) == vec:  # exactly unchanged: nothing to send
        return
    current[:] = vec
    queue(make(impl.name, vec))


def set_position(handle: Any, position: Sequence[float]) -> None:
    """``handle.position = position`` (sent unless exactly unchanged)."""
    _set_vector(handle, "position", position, "SetPositionMessage")


def set_wxyz(handle: Any, wxyz: Sequence[float]) -> None:
    """``handle.wxyz = wxyz`` (sent unless exactly unchanged)."""
    _set_vector(handle, "wxyz", wxyz, "SetOrientationMessage")
