"""Headless screenshots of the scene: Debian Chromium driven by Playwright, no display needed.

``python -m app screenshot --preset example-29 --t 0.7 --out shot.png`` starts a scene server on
a free loopback port in this process, opens it in headless Chromium (SwiftShader WebGL), waits
until the tab's session has loaded and analysed its configuration *and* the browser shows the
shapes in their relation colour, then saves the page (scene and GUI, as a user sees it).
The same machinery (:class:`HeadlessScene`) drives the browser tests.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Any

from .scene.shapes import RELATION_HEX
from .scene.state import SceneConfig

__all__ = ["CHROMIUM", "CHROMIUM_FLAGS", "HeadlessScene", "screenshot"]

CHROMIUM = "/usr/bin/chromium"
"""Debian's chromium (installed by apt; never a Playwright browser download)."""

CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-unsafe-swiftshader",
]
"""Flags verified to give WebGL2 on SwiftShader on a machine with no GPU and no display."""

_HIDE_TOAST = ".mantine-Notifications-root{display:none!important}"

_MESH_COLOR_JS = """(n) => {
  const root = window.__viserMutable?.nodeRefFromName?.[n];
  if (!root) return null;
  let hex = null;
  root.traverse((o) => { if (hex === null && o.material && o.material.color) hex = '#' + o.material.color.getHexString(); });
  return hex;
}"""

_FRAME_JS = "() => window.__viserTestpoints?.rendererInfo?.render?.frame ?? 0"


class HeadlessScene:
    """A scene server plus one headless Chromium tab looking at it (context manager).

    Args:
        config: what the tab opens on.
        width, height: viewport in CSS pixels (device pixel ratio fixed to 1).
        timeout: seconds to wait for the browser, the analysis and the final colours.
    """

    def __init__(self, config: SceneConfig, *, width: int = 1400, height: int = 900, timeout: float = 120.0) -> None:
        self.config = config
        self.width = width
        self.height = height
        self.timeout = timeout
        self.scene: Any = None
        self.session: Any = None
        self.page: Any = None
        self._pw: Any = None
        self._browser: Any = None
        self._tmp: tempfile.TemporaryDirectory[str] | None = None

    def __enter__(self) -> HeadlessScene:
        if not os.path.exists(CHROMIUM):
            raise RuntimeError(f"{CHROMIUM} not found: install Debian's chromium (apt-get install chromium)")
        from playwright.sync_api import sync_playwright

        from .scene.server import start_scene

        self.scene = start_scene("127.0.0.1", 0, self.config)
        try:
            self._pw = sync_playwright().start()
            self._tmp = tempfile.TemporaryDirectory(prefix="app-chromium-")
            self._browser = self._pw.chromium.launch_persistent_context(
                self._tmp.name,
                executable_path=CHROMIUM,
                headless=True,
                args=CHROMIUM_FLAGS,
                viewport={"width": self.width, "height": self.height},
                device_scale_factor=1,
            )
            self.page = self._browser.pages[0] if self._browser.pages else self._browser.new_page()
            self.page.set_default_timeout(self.timeout * 1000)
            self.page.goto(f"http://127.0.0.1:{self.scene.port}/?fixedDpr=1&hideViserLogo")
            self.page.add_style_tag(content=_HIDE_TOAST)
            self.session = self.scene.wait_for_session(self.timeout)
            self.wait_settled()
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc: Any) -> None:
        for closer in (
            lambda: self._browser and self._browser.close(),
            lambda: self._pw and self._pw.stop(),
            lambda: self.scene and self.scene.stop(),
            lambda: self._tmp and self._tmp.cleanup(),
        ):
            try:
                closer()
            except Exception:  # noqa: BLE001 - best-effort teardown
                pass

    # -------------------------------------------------------------- waiting and reading
    def frame(self) -> int:
        """Frames rendered so far by the tab's WebGL renderer."""
        return int(self.page.evaluate(_FRAME_JS))

    def mesh_color(self, name: str) -> str | None:
        """Material colour "#rrggbb" of a mesh node as three.js has it, or None if absent."""
        return self.page.evaluate(_MESH_COLOR_JS, f"/shapes/{name}/mesh")

    def wait_settled(self, frames: int = 2) -> None:
        """Wait for the session to be ready, the shapes in the expected colour, then frames."""
        deadline = time.monotonic() + self.timeout
        if not self.session.ready.wait(self.timeout):
            raise TimeoutError("the scene did not finish loading/analysing its configuration")
        self.page.wait_for_function("() => (window.__viserTestpoints?.rendererInfo?.render?.frame ?? 0) > 2")
        for name in ("A", "B"):
            self.page.wait_for_function("(n) => window.__viserMutable?.nodeRefFromName?.[n] != null", arg=f"/shapes/{name}/mesh")
        want = RELATION_HEX.get(self.session.state.relation or "")
        if want is not None:
            self.page.wait_for_function(
                f"(n) => ({_MESH_COLOR_JS})(n) === {want!r}",
                arg="/shapes/B/mesh",
                timeout=max(1.0, deadline - time.monotonic()) * 1000,
            )
        # a few more frames so the final state is on the canvas; viser renders on demand, so
        # when nothing changes no frame may come: that is fine (the colour is already applied)
        f0 = self.frame()
        try:
            self.page.wait_for_function(f"() => ({_FRAME_JS})() >= {f0 + frames}", timeout=3000)
        except Exception:  # noqa: BLE001 - playwright TimeoutError: scene idle, already drawn
            pass

    def canvas_pixels(self, every: int = 6) -> Any:
        """RGBA samples of the WebGL canvas on a grid of every ``every``-th pixel: (N, 4) uint8.

        Read in the page (nearest-neighbour downsampling onto a 2D canvas), so no image library
        is needed. The background is transparent (alpha 0); shapes are the (semi-)opaque pixels.
        """
        import base64

        import numpy as np

        b64 = self.page.evaluate(
            """(every) => {
  const src = document.querySelector('canvas[data-engine]');
  const c = document.createElement('canvas');
  c.width = Math.max(1, Math.floor(src.width / every));
  c.height = Math.max(1, Math.floor(src.height / every));
  const ctx = c.getContext('2d');
  ctx.imageSmoothingEnabled = false;
  ctx.drawImage(src, 0, 0, c.width, c.height);
  const d = ctx.getImageData(0, 0, c.width, c.height).data;
  let s = '';
  for (let i = 0; i < d.length; i += 8192) s += String.fromCharCode.apply(null, d.subarray(i, i + 8192));
  return btoa(s);
}""",
            every,
        )
        return np.frombuffer(base64.b64decode(b64), dtype=np.uint8).reshape(-1, 4)

    def save(self, out: str | Path) -> Path:
        """Screenshot of the page (scene + GUI) to a PNG file."""
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        self.page.screenshot(path=str(out))
        return out


def screenshot(config: SceneConfig, out: str | Path, *, width: int = 1400, height: int = 900, timeout: float = 120.0) -> Path:
    """Render ``config`` to a PNG as a user sees it (shapes in their relation colours).

    Args:
        config: the scene to show (preset, t or event, shapes, dimension).
        out: PNG path (parent directories are created).
        width: viewport width in pixels.
        height: viewport height in pixels.
        timeout: seconds to wait for rendering (the analysis of a preset included).

    Returns:
        The path written.

    Raises:
        RuntimeError: chromium missing. TimeoutError: the scene never finished rendering.
    """
    with HeadlessScene(config, width=width, height=height, timeout=timeout) as hs:
        return hs.save(out)
