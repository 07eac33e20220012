"""The viser visualiser: per-tab sessions of state, controllers and views (see :mod:`app.scene.session`).

State (what a tab shows; no viser): :mod:`~app.scene.state` (shapes, configuration, tab state),
:mod:`~app.scene.texts` (exact text of numbers, times and matrices), :mod:`~app.scene.motion` (a
loaded motion, floats for drawing), :mod:`~app.scene.analysis` (the analysis cache and core's ``MotionAnalysis`` prepared for
the timeline), :mod:`~app.scene.readout` (the explanation at t), :mod:`~app.scene.picture` (the
shapes and their certified relation, derived in one place), :mod:`~app.scene.contact`
(witnesses), :mod:`~app.scene.touch` (snap to contact), :mod:`~app.scene.motion_form`,
:mod:`~app.scene.links` (tab addresses and shared links), :mod:`~app.scene.export` (analysis
files); what worker processes run is :mod:`app.jobs`.

Controllers (callbacks change the state and call ``Session.refresh``):
:mod:`~app.scene.control_shapes`, :mod:`~app.scene.control_motion`,
:mod:`~app.scene.control_timeline`, :mod:`~app.scene.control_keys`, :mod:`~app.scene.control_share`.

Views (viser handles, typed): :mod:`~app.scene.shapes` (how finely: :mod:`~app.scene.mesh_detail`), :mod:`~app.scene.markers`,
:mod:`~app.scene.camera`, :mod:`~app.scene.gui` (the panel's handles),
:mod:`~app.scene.panel_view` (fills the panel), :mod:`~app.scene.plots`, text in
:mod:`~app.scene.panels` and :mod:`~app.scene.words`; :mod:`~app.scene.wire` is the only module
touching viser's private attributes. Around them: :mod:`~app.scene.session` (one tab),
:mod:`~app.scene.server` (the server, tabs, presenter mode), :mod:`~app.scene.origin` (who may
connect), :mod:`~app.scene.replay` (HTML replay), :mod:`~app.scene.costs` (hot-path timer).

Exports load lazily: worker processes import :mod:`app.jobs` and :mod:`~app.scene.motion` (``core`` only)
without paying for viser.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .common.state import SceneConfig as SceneConfig
    from .pair.costs import measure_update_costs as measure_update_costs
    from .pair.session import Session as Session
    from .server import SceneServer as SceneServer
    from .server import start_scene as start_scene

__all__ = ["SceneConfig", "SceneServer", "Session", "measure_update_costs", "start_scene"]

_HOME = {
    "SceneConfig": "common.state",
    "SceneServer": "server",
    "Session": "pair.session",
    "measure_update_costs": "pair.costs",
    "start_scene": "server",
}


def __getattr__(name: str) -> Any:
    if name in _HOME:
        return getattr(import_module(f".{_HOME[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
