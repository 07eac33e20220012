"""The scene inside a Jupyter notebook, in one call, local or remote.

``from app.notebook import show; show("example-29")`` starts the scene server in the notebook's
kernel (a free port on the kernel's machine, analyses in worker processes) and shows it in the
cell as an iframe; the object returned is the running scene (``.stop()`` ends it, ``.session`` is
the tab's state once the cell has been displayed). ``show(..., static=True)`` shows a
self-contained replay instead (:mod:`app.scene.pair.replay`): no server, it stays in the saved notebook.

**Remote Jupyter** (JupyterHub, a server on another machine): the browser cannot reach the
kernel's ``127.0.0.1``. The cell then goes through the notebook server's own proxy,
`jupyter-server-proxy <https://jupyter-server-proxy.readthedocs.io>`_ (``pip install
jupyter-server-proxy`` where the Jupyter server runs): its ``<base_url>proxy/<port>/`` path
forwards HTTP and websockets to a port of the kernel's machine, behind the notebook's own login.
``proxy=None`` (the default) uses it when the package is importable in the kernel's environment
or the kernel runs under JupyterHub (``JUPYTERHUB_SERVICE_PREFIX``); ``proxy=True`` / ``False``
force the choice. The iframe's address is ``<base_url>proxy/<port>/s/<tab>/``; base_url is
``JUPYTERHUB_SERVICE_PREFIX`` when set, else read in the page from Jupyter's own page config
(JupyterLab / Notebook 7: ``#jupyter-config-data``; classic: ``body[data-base-url]``), "/" by
default. The scene's redirects and links are relative, so they stay under that path. The
page's Origin is the notebook server's, which the scene cannot vouch for (:mod:`app.scene.common.origin`):
the tab id in the address is a random secret that only this cell holds, and the scene trusts
handshakes to that tab (:meth:`app.scene.common.origin.OriginPolicy.trust_tab`).

Jupyter displays the returned object through ``_repr_html_``: no IPython import is needed.
"""

from __future__ import annotations

import html
import importlib.util
import os
from typing import Any

from .scene.common.state import SceneConfig

__all__ = ["show", "NotebookScene", "NotebookReplay"]


def _config(config: SceneConfig | str | dict[str, Any] | None) -> SceneConfig:
    if config is None:
        return SceneConfig()
    if isinstance(config, SceneConfig):
        return config
    if isinstance(config, str):  # a preset name, or "none" for the default static shapes
        return SceneConfig(preset=None if config.lower() in ("none", "static") else config)
    return SceneConfig.from_dict(config)


def _proxy_wanted() -> bool:
    """True when the notebook's proxy should carry the scene (see the module docstring)."""
    return bool(os.environ.get("JUPYTERHUB_SERVICE_PREFIX")) or importlib.util.find_spec("jupyter_server_proxy") is not None


_BASE_URL_JS = """(function (frame) {
  let base = null;
  const cfg = document.getElementById('jupyter-config-data');
  if (cfg) { try { base = JSON.parse(cfg.textContent).baseUrl || null; } catch (e) { base = null; } }
  if (!base && document.body && document.body.dataset.baseUrl) base = document.body.dataset.baseUrl;
  if (base) { if (!base.endsWith('/')) base += '/'; frame.src = base + frame.dataset.proxyPath; }
})(document.currentScript.previousElementSibling);"""
"""Re-points the iframe at Jupyter's own base URL, read from the notebook page."""


class NotebookScene:
    """A running scene shown in a notebook cell (an iframe on its page).

    Args:
        config: what the scene opens on.
        height: height of the iframe in pixels.
        host: interface the scene binds to and, without the proxy, the address the notebook's
            browser uses to reach it.
        port: scene port (0: a free one).
        proxy: reach the scene through the notebook server's jupyter-server-proxy (None: when
            it is installed or under JupyterHub; see the module docstring).
    """

    def __init__(
        self, config: SceneConfig, *, height: int = 600, host: str = "127.0.0.1", port: int = 0, proxy: bool | None = None
    ) -> None:
        from .scene.server import start_scene

        self.height = height
        self.scene = start_scene(host, port, config)
        self.tab = self.scene.store.new_id()
        """The cell's tab (``/s/<tab>/``): opens on ``config``; its id is the cell's secret."""
        self.scene.store.put(self.tab, config)
        self.proxy = _proxy_wanted() if proxy is None else proxy
        self.proxy_path = f"proxy/{self.scene.port}/s/{self.tab}/"
        """The scene's path below Jupyter's base URL, through jupyter-server-proxy."""
        if self.proxy:
            if self.scene.policy is not None:
                self.scene.policy.trust_tab(self.tab)
            prefix = os.environ.get("JUPYTERHUB_SERVICE_PREFIX") or "/"
            self.url = (prefix if prefix.endswith("/") else prefix + "/") + self.proxy_path
        else:
            self.url = f"http://{host}:{self.scene.port}/s/{self.tab}/"

    @property
    def session(self) -> Any:
        """The newest tab's session (its state, its controllers), or None before one connects."""
        sessions = self.scene.sessions
        return sessions[max(sessions)] if sessions else None

    def _repr_html_(self) -> str:
        frame = (
            f'<iframe src="{html.escape(self.url, quote=True)}" width="100%" height="{self.height}" '
            f'data-proxy-path="{html.escape(self.proxy_path, quote=True)}" '
            'style="border:1px solid #ddd" allow="clipboard-write"></iframe>'
        )
        if self.proxy and not os.environ.get("JUPYTERHUB_SERVICE_PREFIX"):
            frame += f"<script>{_BASE_URL_JS}</script>"
        return frame

    def stop(self) -> None:
        """Stop the server (the cell then shows a disconnected scene)."""
        self.scene.stop()


class NotebookReplay:
    """A self-contained replay shown in a notebook cell (kept in the saved notebook)."""

    def __init__(self, config: SceneConfig, *, height: int = 500, seconds: float = 12.0) -> None:
        from .scene.pair.replay import replay_html

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
        **kwargs: ``host``/``port``/``proxy`` of the live scene (see :class:`NotebookScene`), or
            ``seconds`` of the replay.

    Returns:
        The object Jupyter displays (the live scene: call ``.stop()`` when done).
    """
    cfg = _config(config)
    if static:
        return NotebookReplay(cfg, height=height, **kwargs)
    return NotebookScene(cfg, height=height, **kwargs)
