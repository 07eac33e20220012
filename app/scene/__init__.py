"""The viser visualiser: per-tab sessions of state, controllers and views (see :mod:`app.scene.session`).

Exports load lazily: worker processes import :mod:`app.scene.jobs` (``core`` only) without
paying for viser.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .costs import measure_update_costs as measure_update_costs
    from .server import SceneServer as SceneServer
    from .server import start_scene as start_scene
    from .session import Session as Session
    from .state import SceneConfig as SceneConfig

__all__ = ["SceneConfig", "SceneServer", "Session", "measure_update_costs", "start_scene"]

_HOME = {
    "SceneConfig": "state",
    "SceneServer": "server",
    "Session": "session",
    "measure_update_costs": "costs",
    "start_scene": "server",
}


def __getattr__(name: str) -> Any:
    if name in _HOME:
        return getattr(import_module(f".{_HOME[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
