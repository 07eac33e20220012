"""The scene inside a Jupyter notebook, in one call.

``from app.notebook import show; show("example-29")`` starts the scene server in the notebook's
kernel (a free port on this machine, analyses in worker processes) and shows it in the cell as
an iframe; the object returned is the running scene (``.stop()`` ends it, ``.session`` is the
tab's state once the cell has been displayed). ``show(..., static=True)`` shows a self-contained
replay instead (:mod:`app.scene.replay`): no server, it stays in the saved notebook.
Jupyter displays the returned object through ``_repr_html_``: no IPython import is needed.
"""

from __future__ import annotations

import html
from typing import Any

from .scene.state import SceneConfig

__all__ = ["show", "NotebookScene", "NotebookReplay"]


def _config(config: SceneConfig | str | dict[str, Any] | None) -> SceneConfig:
    if config is None:
        return SceneConfig()
    if isinstance(config, SceneConfig):
        return config
    if isinstance(config, str):  # a preset name, or "none" for the default static shapes
        return SceneConfig(preset=None if config.lower() in ("none", "static") else config)
    return SceneConfig.from_dict(config)


class NotebookScene:
    """A running scene shown in a notebook cell (an iframe on its page).

    Args:
        config: what the scene opens on.
        height: height of the iframe in pixels.
        host: address the notebook's browser uses to reach this kernel's machine.
        port: scene port (0: a free one).
    """

    def __init__(self, config: SceneConfig, *, height: int = 600, host: str = "127.0.0.1", port: int = 0) -> None:
        from .scene.server import start_scene

        self.height = height
        self.scene = start_scene(host, port, config)
        self.url = f"http://{host}:{self.scene.port}/"

    @property
    def session(self) -> Any:
        """The newest tab's session (its state, its controllers), or None before one connects."""
        sessions = self.scene.sessions
        return sessions[max(sessions)] if sessions else None

    def _repr_html_(self) -> str:
        return (
            f'<iframe src="{html.escape(self.url, quote=True)}" width="100%" height="{self.height}" '
            'style="border:1px solid #ddd" allow="clipboard-write"></iframe>'
        )

    def stop(self) -> None:
        """Stop the server (the cell then shows a disconnected scene)."""
        self.scene.stop()


class NotebookReplay:
    """A self-contained replay shown in a notebook cell (kept in the saved notebook)."""

    def __init__(self, config: SceneConfig, *, height: int = 500, seconds: float = 12.0) -> None:
        from .scene.replay import replay_html

        self.height = height
        self.html = replay_html(config, seconds=seconds)

    def _repr_html_(self) -> str:
        return (
            f'<iframe srcdoc="{html.escape(self.html, quote=True)}" width="100%" height="{self.height}" '
            'style="border:1px solid #ddd"></iframe>'
        )


def show(
    config: SceneConfig | str | dict[str, Any] | None = None, *, height: int = 600, static: bool = False, **kwargs: Any
) -> NotebookScene | NotebookReplay:
    """Show the scene in the notebook: ``show("example-29")``, ``show({"dim": 2, ...})``, ``show(cfg)``.

    Args:
        config: a preset name, a configuration dict (the JSON of ``--config``) or a SceneConfig.
        height: height of the cell's view in pixels.
        static: a self-contained replay instead of the live scene.
        **kwargs: ``host``/``port`` of the live scene, or ``seconds`` of the replay.

    Returns:
        The object Jupyter displays (the live scene: call ``.stop()`` when done).
    """
    cfg = _config(config)
    if static:
        return NotebookReplay(cfg, height=height, **kwargs)
    return NotebookScene(cfg, height=height, **kwargs)
