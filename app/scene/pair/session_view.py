"""What a controller may touch of its tab: :class:`SessionView`, the narrow face of :class:`~app.scene.pair.session.Session`.

The controllers (``control_*.py``) change the tab's state from GUI callbacks and ask the session
to draw it. They are typed against this protocol, not the whole Session, so mypy holds each of
them to these members (and they no longer import the session module: no circle between it and
them). The sibling controllers a controller calls are narrowed too (:class:`TimelineSteps`,
:class:`MotionFreezer`). Every member is read-only here: a controller never rebinds one.
"""

from __future__ import annotations

import threading
from concurrent.futures import Executor
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    import viser

    from ..common.state import AppState, SceneConfig
    from ..common.wire import UploadGuard
    from .analysis import AnalysisCache
    from .gui import Gui
    from .panel_view import Syncing

__all__ = ["SessionView", "TimelineSteps", "MotionFreezer", "FieldReader"]


class TimelineSteps(Protocol):
    """What other controllers ask of the timeline's controller."""

    def set_t(self, t: Any, *, event: int | None = None, defer_panels: bool = False, text: str | None = None) -> str | None:
        """Move to time ``t`` (or to event ``event``) and draw it."""

    def jump_to_event(self, k: int) -> str | None:
        """Move to event ``k`` (1-based) exactly."""

    def apply_text(self, text: str) -> str | None:
        """Move to the time the t box says."""

    def stop_playing(self) -> None:
        """Uncheck Play."""


class MotionFreezer(Protocol):
    """What the shapes' controller asks of the motion's: leave the motion, keeping the shapes drawn."""

    def freeze(self) -> None:
        """Turn the scene static with the shapes as drawn at t."""


class FieldReader(Protocol):
    """The panel's reading of a field the user typed into."""

    def take(self, handle: Any) -> Any:
        """The field's value as its handler reads it."""


class SessionView(Protocol):
    """The members of a tab's session that its controllers use, and no others."""

    @property
    def PICTURE_FIRST(self) -> float:  # noqa: N802  (the session's class constant)
        """Seconds the panel waits after a new motion's picture."""

    @property
    def target(self) -> viser.ClientHandle | viser.ViserServer:
        """The tab (or the shared scene's server)."""

    @property
    def gui_api(self) -> viser.GuiApi:
        """The tab's GUI."""

    @property
    def ui(self) -> Gui:
        """The panel's handles."""

    @property
    def state(self) -> AppState:
        """What the tab shows."""

    @property
    def lock(self) -> threading.RLock:
        """Held while the state changes and is drawn."""

    @property
    def syncing(self) -> Syncing:
        """Raised while Python assigns GUI values (controllers ignore those callbacks)."""

    @property
    def closed(self) -> bool:
        """True once the tab is closed."""

    @property
    def ready(self) -> threading.Event:
        """Set when the configuration is loaded, analysed and drawn."""

    @property
    def cache(self) -> AnalysisCache:
        """The analyses shared by the tabs."""

    @property
    def executor(self) -> Executor | None:
        """Where analyses run off the GUI's thread (None: in the caller)."""

    @property
    def uploads(self) -> UploadGuard | None:
        """The server's guard of uploaded bytes."""

    @property
    def views(self) -> dict[str, Any]:
        """The drawn shapes by name ("A", "B")."""

    @property
    def panel(self) -> FieldReader:
        """The panel's view (a controller only reads fields through it)."""

    @property
    def timeline_ctl(self) -> TimelineSteps:
        """The timeline's controller."""

    @property
    def motion_ctl(self) -> MotionFreezer:
        """The motion's controller."""

    def refresh(self, *, dragged: str | None = None, defer: bool = False, panel_delay: float | None = None) -> str | None:
        """Draw the state; the relation drawn."""

    def load(self, config: SceneConfig) -> None:
        """Show ``config``."""

    def load_untrusted(self, data: dict[str, Any]) -> None:
        """Show a configuration a user brought (checked first)."""

    def snapshot(self) -> SceneConfig:
        """The configuration of what the tab shows."""

    def set_dimension(self, dim: int) -> None:
        """Switch between ellipses (2) and ellipsoids (3)."""

    def field_error(self, field: str, message: str) -> None:
        """Show ``message`` under a field of the panel."""

    def frame_camera(self, *, grid: bool = True, around_shapes: bool = False) -> None:
        """Frame the shapes (and the grid)."""
