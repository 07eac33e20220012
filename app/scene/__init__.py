"""The viser visualiser: per-tab sessions of state, controllers and views (see :mod:`app.scene.pair.session`).

Three floors, each importing only those below it (tests/test_import_graph.py):
:mod:`app.scene.common` (what both scenes use), :mod:`app.scene.pair` (the two-shape scene; its
controllers see the session through :class:`~app.scene.pair.session_view.SessionView`),
:mod:`app.scene.bodies` (many bodies and the sweep; it opens a pair); :mod:`app.scene.server`
serves both.

State (what a tab shows; no viser): :mod:`~app.scene.common.state` (shapes, configuration, tab state),
:mod:`~app.scene.common.texts` (exact text of numbers, times and matrices), :mod:`~app.scene.pair.motion` (a
loaded motion, floats for drawing), :mod:`~app.scene.pair.analysis` (the analysis cache and core's ``MotionAnalysis`` prepared for
the timeline), :mod:`~app.scene.pair.readout` (the explanation at t), :mod:`~app.scene.pair.picture` (the
shapes and their certified relation, derived in one place), :mod:`~app.scene.pair.contact`
(witnesses), :mod:`~app.scene.pair.touch` (snap to contact), :mod:`~app.scene.pair.motion_form`,
:mod:`~app.scene.common.links` (tab addresses and shared links), :mod:`~app.scene.pair.export` (analysis
files); what worker processes run is :mod:`app.jobs`.

Controllers (callbacks change the state and call ``Session.refresh``):
:mod:`~app.scene.pair.control_shapes`, :mod:`~app.scene.pair.control_motion`,
:mod:`~app.scene.pair.control_timeline`, :mod:`~app.scene.pair.control_keys`, :mod:`~app.scene.pair.control_share`.

Views (viser handles, typed): :mod:`~app.scene.common.shapes` (how finely: :mod:`~app.scene.common.mesh_detail`), :mod:`~app.scene.common.markers`,
:mod:`~app.scene.common.camera`, :mod:`~app.scene.pair.gui` (the panel's handles),
:mod:`~app.scene.pair.panel_view` (fills the panel), :mod:`~app.scene.pair.plots`, text in
:mod:`~app.scene.pair.panels` and :mod:`~app.scene.pair.words`; :mod:`~app.scene.common.wire` is the only module
touching viser's private attributes. Around them: :mod:`~app.scene.pair.session` (one tab),
:mod:`~app.scene.server` (the server, tabs, presenter mode), :mod:`~app.scene.common.origin` (who may
connect), :mod:`~app.scene.pair.replay` (HTML replay), :mod:`~app.scene.pair.costs` (hot-path timer).

Exports load lazily: worker processes import :mod:`app.jobs` and :mod:`~app.scene.pair.motion` (``core`` only)
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
