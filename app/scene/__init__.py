"""The viser visualiser: per-tab sessions, shapes, timeline, plots (see :mod:`app.scene.server`)."""

from .costs import measure_update_costs as measure_update_costs
from .server import SceneServer as SceneServer
from .server import start_scene as start_scene
from .session import Session as Session
from .state import SceneConfig as SceneConfig

__all__ = ["SceneConfig", "SceneServer", "Session", "measure_update_costs", "start_scene"]
