"""Headless screenshots of the scene: Debian Chromium driven by Playwright, no display needed.

``python -m app screenshot --preset example-29 --t 0.7 --out shot.png`` starts a scene server on
a free loopback port in this process, opens it in headless Chromium (SwiftShader WebGL), waits
until the tab shows exactly its state (the session has loaded and analysed it, the browser
draws both shapes at their poses in their relation colour and the readout names the relation),
then saves the page (scene and GUI, as a user sees it).

Many images cost one browser and one server: :class:`HeadlessScene` keeps the tab open and
:meth:`HeadlessScene.show` loads the next configuration into the same session (or moves t), so
each further image costs the redraw, not a browser start. :func:`screenshots` renders a list of
shots into a folder. The same machinery drives the browser tests.
"""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .output import Output
from .scene.common.mesh_detail import SPHERE_SUBDIVISIONS, check_sphere_subdivisions
from .scene.common.page import SETTLE_FLAG, SETTLE_MAX_MS
from .scene.common.shapes import NEUTRAL, PALETTES, RELATION_HEX
from .scene.common.state import SceneConfig

__all__ = ["CHROMIUM", "CHROMIUM_FLAGS", "HeadlessScene", "Shot", "screenshot", "screenshots", "SCREENSHOT_EXTRA"]

SCREENSHOT_EXTRA = (
    "screenshots need Playwright, an optional part: pip install 'ellipsoid-interference[screenshot]' "
    "(and Debian's chromium: apt-get install chromium; never 'playwright install')"
)
"""What to do when Playwright is missing (it is the ``screenshot`` extra, not a core dependency)."""

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

_TWO_FRAMES_JS = (
    "() => new Promise((r) => { requestAnimationFrame(() => requestAnimationFrame(r)); setTimeout(r, 5000); })"
)
"""Two painted animation frames, or 5 s (page.evaluate has no timeout: a tab that stops
rendering must not hang the caller)."""

_HIDE_TOAST = ".mantine-Notifications-root{display:none!important}"

_MESH_COLOR_JS = """(n) => {
  const root = window.__viserMutable?.nodeRefFromName?.[n];
  if (!root) return null;
  let hex = null;
  root.traverse((o) => { if (hex === null && o.material && o.material.color) hex = '#' + o.material.color.getHexString(); });
  return hex;
}"""

_POSE_JS = """(n) => {
  const r = window.__viserMutable?.nodeRefFromName?.[n];
  if (!r) return null;
  return [r.position.x, r.position.y, r.position.z, r.quaternion.w, r.quaternion.x, r.quaternion.y, r.quaternion.z];
}"""

_BODIES_DRAWN_JS = """(want) => {
  const m = window.__viserMutable?.nodeRefFromName;
  if (!m) return false;
  for (const [name, count] of Object.entries(want)) {
    const r = m[name];
    if (!r) return false;
    let n = null;
    r.traverse((o) => { if (n === null && o.isInstancedMesh2) n = o.instancesCount; if (n === null && o.isPoints) n = o.geometry.attributes.position?.count ?? null; });
    if (n !== count) return false;
  }
  return true;
}"""
"""Every node of the bodies view is in the browser with its number of instances / points."""

_FRAME_JS = "() => window.__viserTestpoints?.rendererInfo?.render?.frame ?? 0"

_MARK_PANEL_JS = "() => { window.__fieldsBeforeRenewal = Array.from(document.querySelectorAll('input')); }"
_RENEWED_JS = "() => (window.__fieldsBeforeRenewal ?? []).some((e) => !e.isConnected)"
"""Mark the page's fields, then: some have left it. viser keys panel elements by id, so a renewed
tab's old panel leaves whole (only the client's own settings fields stay); the server clears the
scene before the panel, and the page applies messages in order: the old scene is gone too."""

_DRAWN_JS = """([poses, colours, word]) => {
  const m = window.__viserMutable?.nodeRefFromName;
  if (!m) return false;
  for (const [name, p] of Object.entries(poses)) {
    const r = m[name];
    if (!r) return false;
    const q = [r.position.x, r.position.y, r.position.z, r.quaternion.w, r.quaternion.x, r.quaternion.y, r.quaternion.z];
    for (let i = 0; i < 7; i++) if (Math.abs(q[i] - p[i]) > 1e-6 * (1 + Math.abs(p[i]))) return false;
  }
  for (const [name, want] of Object.entries(colours)) {
    const r = m[name];
    let hex = null;
    r.traverse((o) => { if (hex === null && o.material && o.material.color) hex = '#' + o.material.color.getHexString(); });
    if (hex !== want) return false;
  }
  return word === null || document.body.innerText.includes(word);
}"""


@dataclass
class Shot:
    """One image: a configuration, optionally a time or an event of its motion, and the file."""

    config: SceneConfig
    out: Path
    t: float | str | None = None
    event: int | None = None


class HeadlessScene:
    """A scene server plus one headless Chromium tab looking at it (context manager).

    Args:
        config: what the tab opens on.
        width: viewport width in CSS pixels (device pixel ratio fixed to 1).
        height: viewport height.
        timeout: seconds to wait for the browser, the analysis and the final picture.
        shared: presenter mode (one scene for every tab).
        prefetch: analyse every preset when the server starts, as ``serve`` does (off: only
            what is shown is analysed, the right thing for screenshots).
        dpr: device pixel ratio the canvas renders at (viser's ``fixedDpr``): 1 for pictures;
            the browser tests take 0.5 (a quarter of the pixels: software WebGL draws a frame in
            about half the CPU time, and they read colours and three.js state, not detail).
        cdp: DevTools address (``http://127.0.0.1:PORT``) of a Chromium that is already running:
            the tab opens in its default profile (its cache is kept) and is closed on exit, with
            every other tab opened since, while the browser keeps running. None: launch one (a
            browser start costs ~1.5 CPU-s more than a connection; the test suite shares one).
        settle_ms: how long the client keeps drawing after each change (the page's
            ``renderSettleMs``, :data:`app.scene.common.page.SETTLE_FLAG`); None: viser's 250 ms, right
            for pictures (a change's asynchronous tails, such as a label's glyphs, are drawn
            before the picture is taken). The browser tests, which read three.js state and the
            panel, take 0: one frame per change (in software WebGL the window is 3 frames), 14 %
            less CPU in tests/test_browser_scene.py.
        sphere_subdivisions: of the icosphere the solids are drawn with
            (:data:`app.scene.common.mesh_detail.SPHERE_SUBDIVISIONS_RANGE`): the default for pictures; the
            browser tests, which read colours, poses and the panel, take 3 (a frame in software
            WebGL ~23 instead of ~60 ms of CPU).
        start_path: the page the tab opens first: ``/`` (``config``), or a lesson step's link.
    """

    def __init__(
        self,
        config: SceneConfig,
        *,
        width: int = 1400,
        height: int = 900,
        timeout: float = 120.0,
        shared: bool = False,
        bodies: Any = None,
        prefetch: bool = False,
        dpr: float = 1.0,
        cdp: str | None = None,
        settle_ms: float | None = None,
        sphere_subdivisions: int = SPHERE_SUBDIVISIONS,
        start_path: str = "/",
    ) -> None:
        self.sphere_subdivisions = check_sphere_subdivisions(sphere_subdivisions)
        self.start_path = start_path
        """The page the tab opens first (``/``, or a lesson step's ``/?lesson=paper&step=3``)."""
        if not 0.1 <= dpr <= 4:
            raise ValueError(f"dpr must be in [0.1, 4], not {dpr}")
        if settle_ms is not None and not 0 <= settle_ms <= SETTLE_MAX_MS:
            raise ValueError(f"settle_ms must be in [0, {SETTLE_MAX_MS}], not {settle_ms}")
        self.settle_ms = settle_ms
        self.config = config
        self.dpr = dpr
        self.prefetch = prefetch
        self.bodies = bodies
        """Many bodies to show instead of ``config`` (:mod:`app.scene.bodies.bodies_view`), or None."""
        self.width = width
        self.height = height
        self.timeout = timeout
        self.shared = shared
        self.cdp = cdp
        self.scene: Any = None
        self.session: Any = None
        self.page: Any = None
        self._pw: Any = None
        self._browser: Any = None
        self._tabs_before: list[Any] = []
        self._tmp: tempfile.TemporaryDirectory[str] | None = None

    def __enter__(self) -> HeadlessScene:
        if self.cdp is None and not os.path.exists(CHROMIUM):
            raise RuntimeError(f"{CHROMIUM} not found: install Debian's chromium (apt-get install chromium)")
        try:
            from playwright.sync_api import sync_playwright
        except ImportError:
            raise RuntimeError(SCREENSHOT_EXTRA) from None

        from .scene.server import start_scene

        self.scene = start_scene(
            "127.0.0.1", 0, self.config, shared=self.shared, bodies=self.bodies, prefetch=self.prefetch,
            sphere_subdivisions=self.sphere_subdivisions,
        )
        try:
            self._pw = sync_playwright().start()
            if self.cdp is not None:
                try:
                    self._browser = self._pw.chromium.connect_over_cdp(self.cdp, timeout=self.timeout * 1000).contexts[0]
                except Exception as e:  # Playwright's Error: a one-line reason, not its call log
                    reason = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
                    raise RuntimeError(f"no Chromium answers at {self.cdp}: {reason}") from None
                self._tabs_before = list(self._browser.pages)
                self.page = self._browser.new_page()
                self.page.set_viewport_size({"width": self.width, "height": self.height})
            else:
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
            self.session = self.goto(self.start_path)
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc: Any) -> None:
        for closer in (
            self._close_browser,
            lambda: self._pw and self._pw.stop(),
            lambda: self.scene and self.scene.stop(),
            lambda: None if self._tmp is None else self._tmp.cleanup(),
        ):
            try:
                closer()
            except Exception:  # noqa: BLE001 - best-effort teardown
                pass

    def _close_browser(self) -> None:
        """Close the browser this scene launched, or only the tabs it opened in a running one (``cdp``)."""
        if self._browser is None:
            return
        if self.cdp is None:
            self._browser.close()
            return
        for page in self._browser.pages:
            if page not in self._tabs_before:
                page.close()

    @property
    def url(self) -> str:
        """The scene's root URL (with the flags a headless capture needs)."""
        return f"http://127.0.0.1:{self.scene.port}/?{self._flags}"

    @property
    def _flags(self) -> str:
        """The page's query flags for a headless capture: the pixel ratio, no viser logo, the settle window."""
        settle = "" if self.settle_ms is None else f"&{SETTLE_FLAG}={self.settle_ms:g}"
        return f"fixedDpr={self.dpr:g}&hideViserLogo{settle}"

    def goto(self, path: str, page: Any = None) -> Any:
        """Open ``path`` of the scene in ``page`` (default: the tab); return the new tab's session.

        ``path`` is ``/``, a ``/c/<config>/`` link or a ``/s/<tab>/`` address; the tab's session
        is returned once the browser shows its state.
        """
        page = page or self.page
        before = max(self.scene.sessions, default=-1)
        page.goto(f"http://127.0.0.1:{self.scene.port}{path}{'&' if '?' in path else '?'}{self._flags}")
        page.add_style_tag(content=_HIDE_TOAST)
        session = self.scene.wait_for_session(self.timeout, after=before) if not self.shared else self.scene.shared
        if page is self.page:
            self.session = session
            self.wait_settled()
        return session

    def open(self, config: SceneConfig | dict[str, Any]) -> Any:
        """Start the tab again on ``config``, as a new tab on its link starts, without a page load.

        Unlike :meth:`show`, which loads ``config`` into the tab's session (the panel as the
        previous configuration left it), the tab gets a new session and a new panel
        (:meth:`SceneServer.renew <app.scene.server.SceneServer.renew>`); ``config`` is read as
        a link's (user input). Returns the new session once the browser shows its state: the
        old panel's elements have left the page, then :meth:`wait_settled`.
        """
        data = config.to_dict() if isinstance(config, SceneConfig) else config
        client_id = next((k for k, v in list(self.scene.sessions.items()) if v is self.session), None)
        if client_id is None:
            raise RuntimeError("the tab has no session on the server (closed or reloading): open a page with goto()")
        self.page.evaluate(_MARK_PANEL_JS)
        self.session = self.scene.renew(client_id, data)
        self.page.wait_for_function(_RENEWED_JS)
        self.wait_settled()
        return self.session

    def server_clients(self) -> list[Any]:
        """The connected tabs' ``viser.ClientHandle`` objects."""
        return list(self.scene.server.get_clients().values())

    # -------------------------------------------------------------- what is shown
    def show(self, config: SceneConfig | None = None, *, t: float | str | None = None, event: int | None = None) -> None:
        """Show ``config`` in the same tab (no reload), then t or an event of its motion; wait for it."""
        s = self.session
        if hasattr(s, "show_bodies"):  # many bodies: moving ones have a time and events
            return self._show_bodies_at(t, event)
        if config is not None:
            s.load_untrusted(config.to_dict())
            if not s.ready.wait(self.timeout):
                raise TimeoutError("the scene did not finish loading/analysing its configuration")
        if (event is not None or t is not None) and s.state.motion is not None and s.state.analysis is None:
            # the tab's own message (e.g. the analysis failed), not the t box's "being analysed"
            why = "; ".join(s.state.errors.values()) or s.state.status or "no analysis"
            raise RuntimeError(f"the motion has no analysis to take t or an event from: {why}")
        if event is not None:
            if s.jump_to_event(event) is None:
                raise ValueError(f"this motion has no event {event}")
        elif t is not None:
            error = s.timeline_ctl.apply_text(str(t))
            if error is not None:
                raise ValueError(error)
        self.wait_settled()

    def _show_bodies_at(self, t: float | str | None, event: int | None) -> None:
        """Moving bodies (``--to``): the bodies at t, or the K-th contact event opened; wait for it.

        Raises:
            ValueError: t or an event for bodies that do not move, t outside [0, 1], no event K.
        """
        view = self.session
        if t is None and event is None:
            return self.wait_settled()
        if view.timeline is None:
            raise ValueError("--t and --event show moving bodies: give the bodies at t = 1 with --to END")
        if view.pair is not None:
            view.show_bodies()
        if event is not None:
            n = len(view.model.order)
            if not 1 <= event <= n:
                raise ValueError(f"--event {event}: the step has {n} contact event{'s' if n != 1 else ''} (1..{n})")
            view.open_pair(int(view.model.order[event - 1]))
        else:
            tf = float(t)  # type: ignore[arg-type]
            if not 0.0 <= tf <= 1.0:
                raise ValueError(f"--t {t}: moving bodies are shown over the step t in [0, 1]")
            view.timeline.set_time(tf)
        self.wait_settled()

    # -------------------------------------------------------------- waiting and reading
    def frame(self) -> int:
        """Frames rendered so far by the tab's WebGL renderer."""
        return int(self.page.evaluate(_FRAME_JS))

    def mesh_color(self, name: str) -> str | None:
        """Material colour "#rrggbb" of a mesh node as three.js has it, or None if absent."""
        colour: str | None = self.page.evaluate(_MESH_COLOR_JS, f"/shapes/{name}/mesh")
        return colour

    def drawn_pose(self, name: str) -> list[float] | None:
        """[x, y, z, w, qx, qy, qz] of node ``/shapes/<name>`` as three.js has it (None if absent)."""
        pose: list[float] | None = self.page.evaluate(_POSE_JS, f"/shapes/{name}")
        return pose

    def expected(self, session: Any = None) -> tuple[dict[str, list[float]], dict[str, str], str | None]:
        """What the browser must show for a two-body session (default: the tab's): poses, colours, word."""
        s = session if session is not None else self.session
        with s.lock:
            poses = {}
            for name, view in s.views.items():
                p = view.control.position
                q = view.control.wxyz
                poses[f"/shapes/{name}"] = [float(v) for v in (*p, *q)]
            relation = s.state.relation
            palette = PALETTES.get(s.state.palette, RELATION_HEX)
            hidden = s.state.answer_hidden
        if hidden:  # a lesson's open question: grey shapes, "press Reveal" for the relation
            grey = "#{:02x}{:02x}{:02x}".format(*NEUTRAL)
            return poses, {f"/shapes/{n}/mesh": grey for n in ("A", "B")}, "press Reveal"
        colours = {f"/shapes/{n}/mesh": palette[relation] for n in ("A", "B")} if relation else {}
        return poses, colours, relation.upper() if relation else None

    def wait_settled(self, frames: int = 2) -> None:
        """Wait until the tab shows the session's state: loaded, poses, colours, readout, frames."""
        deadline = time.monotonic() + self.timeout
        s = self.session
        if hasattr(s, "show_bodies"):  # many bodies: the view of all bodies, or its open pair
            if s.pair is None:
                return self._wait_bodies(frames)
            s = s.session
        if not s.ready.wait(self.timeout):
            raise TimeoutError("the scene did not finish loading/analysing its configuration")
        while s.pending() and time.monotonic() < deadline:  # the coalesced panel refresh
            time.sleep(0.01)
        self.page.wait_for_function("() => (window.__viserTestpoints?.rendererInfo?.render?.frame ?? 0) > 2")
        self._wait_drawn(s, deadline)
        # two animation frames: the browser has rendered and painted the state just applied
        # (viser renders on demand: a frame counter may not move when nothing changes)
        for _ in range(frames):
            self.page.evaluate(_TWO_FRAMES_JS)

    def _wait_drawn(self, s: Any, deadline: float, patience: float = 10.0) -> None:
        """Wait until the browser draws what the session ``s`` holds (:meth:`expected`).

        The expectation is read again every ``patience`` s: a session that changed once more after
        it was read (a late update of the same load) is then waited for as it is now, never as it was.
        """
        from playwright.sync_api import TimeoutError as PlaywrightTimeout

        while True:
            poses, colours, word = self.expected(s)
            left = deadline - time.monotonic()
            try:
                self.page.wait_for_function(_DRAWN_JS, arg=[poses, colours, word], timeout=max(1.0, min(left, patience)) * 1000)
                return
            except PlaywrightTimeout:
                if time.monotonic() >= deadline:
                    drawn = {name: self.page.evaluate(_POSE_JS, name) for name in poses}
                    shown = {name: self.page.evaluate(_MESH_COLOR_JS, name) for name in colours}
                    raise TimeoutError(
                        f"the tab did not draw the session's state within {self.timeout} s: wanted {poses}, {colours}, {word}, "
                        f"drawn poses {drawn}, colours {shown}"
                    ) from None

    def _wait_bodies(self, frames: int) -> None:
        """Many bodies: the view built and drawn as it is for the tab's camera.

        The tab's camera reported, its solids chosen for that camera and in the browser with
        every instance (a newer choice restarts the wait), then a few painted frames.
        """
        view = self.session
        deadline = time.monotonic() + self.timeout
        if not view.ready.wait(self.timeout):
            raise TimeoutError("the bodies view was not built")
        self.page.wait_for_function("() => (window.__viserTestpoints?.rendererInfo?.render?.frame ?? 0) > 2")
        layers = view.layers
        while layers is not None:  # the camera settles, the solids follow; the browser draws them
            version = layers.version
            if layers.pose is None or view.settling():
                if time.monotonic() > deadline:
                    raise TimeoutError("the tab never reported its camera")
                time.sleep(0.02)
                continue
            try:
                self.page.wait_for_function(_BODIES_DRAWN_JS, arg=layers.expected_in_browser(),
                                            timeout=max(0.1, min(5.0, deadline - time.monotonic())) * 1000)
            except Exception:  # noqa: BLE001 - a newer choice of solids replaced the one waited for
                if time.monotonic() > deadline:
                    raise TimeoutError("the browser never drew the bodies") from None
                continue
            if layers.version == version and not view.settling():
                break
        for _ in range(frames):  # painted (see wait_settled)
            self.page.evaluate(_TWO_FRAMES_JS)

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

    def save(self, out: str | Path | Output) -> Path:
        """Screenshot of the page (scene + GUI) to a PNG file, written whole (:mod:`app.output`)."""
        target = out if isinstance(out, Output) else _output(Path(out))
        with target as f:
            f.write(self.page.screenshot())
        return target.path

    def check_event(self, event: int | None) -> None:
        """Refuse an event the shown motion does not have (the tab would show another t)."""
        s = self.session
        if event is None or s is None or not hasattr(s, "state"):
            return
        an = s.state.analysis
        if s.state.motion is None:
            raise ValueError(_no_event(event, None))
        if an is not None and not 1 <= event <= len(an.events):
            raise ValueError(_no_event(event, len(an.events)))


def _no_event(event: int, count: int | None) -> str:
    """The message for an --event the motion does not have (``count`` events; None: no motion)."""
    if count is None:
        return f"--event {event}: the scene has no motion (choose a preset or a configuration with a motion)"
    return f"--event {event}: this motion has {count} event{'s' if count != 1 else ''} (1..{count})"


def _check_events(shots: Sequence[Shot]) -> None:
    """Refuse, before a browser starts, an --event that a shot's motion does not have.

    The motion is read and analysed as the scene does (:func:`app.jobs.analyse_job`); a motion
    that cannot be read or analysed is left to the scene, which says why next to its field.
    """
    from core.shapes.limits import SERVER

    from .jobs import analyse_job
    from .scene.pair.motion import MotionError, load_motion

    counts: dict[int, int | None] = {}
    for shot in shots:
        event = shot.event if shot.event is not None else shot.config.event
        if event is None:
            continue
        cfg = shot.config
        if id(cfg) not in counts:
            if cfg.motion is None and cfg.preset is None:
                counts[id(cfg)] = None
            else:
                try:
                    model = load_motion(preset=cfg.preset, motion=cfg.motion, limits=SERVER)
                    counts[id(cfg)] = len(analyse_job(model.A, model.B, model.interval).events)
                except (MotionError, ValueError):
                    continue  # the scene shows the reason; HeadlessScene.check_event stays the guard
        n = counts[id(cfg)]
        if n is None or not 1 <= event <= n:
            raise ValueError(_no_event(event, n))


def screenshot(
    config: SceneConfig, out: str | Path, *, width: int = 1400, height: int = 900, timeout: float = 120.0, bodies: Any = None,
    cdp: str | None = None,
) -> Path:
    """Render ``config`` to a PNG as a user sees it (shapes in their relation colours).

    Args:
        config: the scene to show (preset, t or event, shapes, dimension).
        out: PNG path (parent directories are created).
        width: viewport width in pixels.
        height: viewport height in pixels.
        timeout: seconds to wait for rendering (the analysis of a preset included).
        bodies: many bodies to show instead (``--bodies FILE``: :mod:`app.scene.bodies.bodies_view`).
        cdp: DevTools address of a running Chromium to draw in (a tab of it), or None: launch one.

    Returns:
        The path written.

    Raises:
        RuntimeError: chromium missing. TimeoutError: the scene never finished rendering.
    """
    return screenshots([Shot(config, Path(out))], width=width, height=height, timeout=timeout, bodies=bodies, cdp=cdp)[0]


def screenshots(
    shots: Iterable[Shot],
    *,
    width: int = 1400,
    height: int = 900,
    timeout: float = 120.0,
    timings: list[float] | None = None,
    bodies: Any = None,
    cdp: str | None = None,
) -> list[Path]:
    """Render many shots with one browser and one server (one tab, reloaded for nothing).

    Args:
        shots: what to render, in order (consecutive shots of one configuration only move t).
        width: viewport width in pixels.
        height: viewport height in pixels.
        timeout: seconds to wait for each image.
        timings: if given, receives the seconds each image took (the first includes the start).
        bodies: many bodies to show instead of the shots' configurations (``--bodies FILE``).
        cdp: DevTools address of a running Chromium (``python -m app screenshot --browser URL``): the shots
            are drawn in a tab of it, closed afterwards; None: a browser is launched and closed.

    Returns:
        The paths written, in order.
    """
    shots = list(shots)
    if not shots:
        return []
    targets = [_output(Path(shot.out)) for shot in shots]  # every path checked before the browser starts
    if bodies is None:
        _check_events(shots)  # and every event (seconds of browser start saved on a typo)
    out: list[Path] = []
    t0 = time.perf_counter()
    with HeadlessScene(shots[0].config, width=width, height=height, timeout=timeout, bodies=bodies, cdp=cdp) as hs:
        shown: SceneConfig | None = shots[0].config
        for shot, target in zip(shots, targets, strict=True):
            if shot.config is not shown:
                hs.show(shot.config)
                shown = shot.config
            if bodies is None:
                hs.check_event(shot.event if shot.event is not None else shot.config.event)
            if shot.t is not None or shot.event is not None:
                hs.show(t=shot.t, event=shot.event)
            out.append(hs.save(target))
            if timings is not None:
                now = time.perf_counter()
                timings.append(now - t0)
                t0 = now
    return out


def _output(path: Path) -> Output:
    """The PNG's :class:`~app.output.Output` (its folders created, as documented)."""
    if not path.is_dir():
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise ValueError(f"--out {path}: cannot create the folder {path.parent}: {e.strerror}") from None
    return Output(path, binary=True)


def shots_for(config: SceneConfig, out: str | Path, ts: Sequence[float | str], events: Sequence[int]) -> list[Shot]:
    """The shots of ``python -m app screenshot``: one image, or one per --t/--event in a folder.

    Args:
        config: the scene.
        out: a PNG path (one image), or a folder (several: ``t-<value>.png``, ``event-<k>.png``).
        ts: times (each an image).
        events: events (each an image).
    """
    out = Path(out)
    if len(ts) + len(events) <= 1 and out.suffix.lower() == ".png":
        return [Shot(config, out, ts[0] if ts else None, events[0] if events else None)]
    shots = [Shot(config, out / f"t-{_safe(t)}.png", t=t) for t in ts]
    shots += [Shot(config, out / f"event-{k}.png", event=k) for k in events]
    return shots or [Shot(config, out / "scene.png")]


def _safe(t: float | str) -> str:
    return "".join(c if c.isalnum() or c in ".-" else "_" for c in str(t))
