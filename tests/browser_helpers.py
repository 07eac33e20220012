"""Waiting on a page's state and the test process's one Chromium: shared by the browser tests.

Every wait is on a state (a condition, a text on the page), never a fixed sleep; the timeouts are
upper bounds for a loaded machine, so a passing test never waits for them.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import subprocess
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from process_groups import end_group

from conftest import TEST_DPR, TEST_SETTLE_MS, TEST_SPHERE_SUBDIVISIONS

PLAYWRIGHT_SWITCHES = [
    "--disable-field-trial-config", "--disable-background-networking", "--disable-background-timer-throttling",
    "--disable-backgrounding-occluded-windows", "--disable-back-forward-cache", "--disable-breakpad",
    "--disable-component-extensions-with-background-pages", "--disable-component-update", "--no-default-browser-check",
    "--disable-default-apps", "--disable-dev-shm-usage", "--disable-extensions",
    "--disable-features=AvoidUnnecessaryBeforeUnloadCheckSync,DestroyProfileOnBrowserClose,HttpsUpgrades,"
    "HttpsFirstBalancedModeAutoEnable,LensOverlay,MediaRouter,PaintHolding,ThirdPartyStoragePartitioning,"
    "AvoidCorsURLLoaderRestartOnRedirect,OptimizationHints,NetworkTimeServiceQuerying,AimEnabled,PreconnectToSearch",
    "--enable-features=CDPScreenshotNewSurface", "--allow-pre-commit-input", "--disable-hang-monitor",
    "--disable-ipc-flooding-protection", "--disable-popup-blocking", "--disable-prompt-on-repost",
    "--disable-renderer-backgrounding", "--force-color-profile=srgb", "--metrics-recording-only", "--no-first-run",
    "--password-store=basic", "--use-mock-keychain", "--no-service-autorun", "--disable-search-engine-choice-screen",
    "--hide-scrollbars", "--mute-audio",
    "--blink-settings=primaryHoverType=2,availableHoverTypes=2,primaryPointerType=4,availablePointerTypes=4",
]
"""The switches Playwright 1.5x gives a headless Chromium it launches (playwright-core's
chromiumSwitches and headless arguments), for the one the tests start themselves: background tabs
not throttled, sRGB colours, no scrollbars, a mouse as the pointer."""


NOTEBOOK_HOST = "notebook.test"
"""A host name the test Chromium resolves to 127.0.0.1 (``--host-resolver-rules``): a page served
on loopback under a name, as a remote notebook server's page is (tests/test_replay_notebook.py)."""

DIE_WITH_PARENT = ["/usr/bin/setpriv", "--pdeathsig", "TERM"] if os.path.exists("/usr/bin/setpriv") else []
"""Run before Chromium so that it gets SIGTERM when the test process dies (a killed worker leaves no
browser): util-linux's setpriv (Debian: essential) sets the parent-death signal and execs."""


class SharedChromium:
    """The test process's one headless Chromium, started on first use and reached over DevTools.

    Every browser test of a pytest process (worker) opens its tabs in it (``HeadlessScene(cdp=...)``,
    :func:`connected`), instead of launching a browser of its own: a launch costs ~1.5 CPU-s
    more than a connection (the suite launched 14). Unlike a browser Playwright launched, it
    outlives each test's Playwright, which must stop before a test that runs asyncio (the sync
    API holds the thread's event loop). Stopped at the end of the session (tests/conftest.py).

    It runs in a session of its own (setsid), as Playwright starts a browser (node's ``detached``):
    with the kernel's autogroup scheduling a session is one scheduling group, so a browser in the
    test process's session shares that group's CPU with the tests. Measured with two CPU-bound
    busy loops on both cores: 420-431 s of tests in the test process's session, 334 s for the
    browsers Playwright launched.
    """

    def __init__(self) -> None:
        self._proc: subprocess.Popen[bytes] | None = None
        self._tmp: tempfile.TemporaryDirectory[str] | None = None
        self.url = ""

    def get(self, timeout: float = 120.0) -> str:
        """The DevTools address (``http://127.0.0.1:PORT``) of the running Chromium, started if need be."""
        if self._proc is not None and self._proc.poll() is None:
            return self.url
        self.stop()
        from app.screenshot import CHROMIUM, CHROMIUM_FLAGS

        self._tmp = tempfile.TemporaryDirectory(prefix="test-chromium-")
        root = Path(self._tmp.name)
        log = root / "stderr.log"
        with open(log, "wb") as err:
            self._proc = subprocess.Popen(
                [*DIE_WITH_PARENT, CHROMIUM, *CHROMIUM_FLAGS, *PLAYWRIGHT_SWITCHES, "--remote-debugging-port=0",
                 f"--host-resolver-rules=MAP {NOTEBOOK_HOST} 127.0.0.1",
                 f"--user-data-dir={root / 'profile'}", "about:blank"],
                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=err,
                start_new_session=True,  # its own session, as Playwright launches it (see below)
            )
        port_file = root / "profile" / "DevToolsActivePort"  # Chromium writes "PORT\n/devtools/browser/<id>"
        deadline = time.monotonic() + timeout
        while True:
            lines = port_file.read_text().splitlines() if port_file.exists() else []
            if len(lines) >= 2 and lines[0].isdigit():
                self.url = f"http://127.0.0.1:{lines[0]}"
                return self.url
            code = self._proc.poll()
            if code is not None or time.monotonic() > deadline:
                tail = log.read_text(errors="replace")[-2000:]
                self.stop()
                raise RuntimeError(f"Chromium gave no DevTools port in {timeout:g} s (exit code {code}): {tail}")
            time.sleep(0.05)

    def stop(self) -> None:
        """End the browser and every process it started (if it runs), then remove its profile.

        The helper processes (GPU, network, storage) can outlive the browser's main process by a
        moment and still write into the profile: removing it before they are gone failed with
        "Directory not empty" (2 stops of 30). They are in the browser's session (its process group).
        """
        proc, self._proc = self._proc, None
        if proc is not None:
            if proc.poll() is None:
                proc.terminate()
                try:
                    proc.wait(10)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
            end_group(proc.pid)
        if self._tmp is not None:
            self._tmp.cleanup()
            self._tmp = None


CHROMIUM_OF_THIS_PROCESS = SharedChromium()
atexit.register(CHROMIUM_OF_THIS_PROCESS.stop)


@contextlib.contextmanager
def connected() -> Iterator[Any]:
    """Playwright connected to this process's Chromium: yields its default context (``new_page()``);
    the tabs opened in it are closed on exit, the browser keeps running."""
    if not os.path.exists("/usr/bin/chromium"):
        pytest.skip("needs Debian chromium at /usr/bin/chromium")
    with connected_to(CHROMIUM_OF_THIS_PROCESS.get()) as context:
        yield context


@contextlib.contextmanager
def connected_to(cdp: str) -> Iterator[Any]:
    """Playwright connected to the Chromium at the DevTools address ``cdp``: see :func:`connected`."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        context = pw.chromium.connect_over_cdp(cdp).contexts[0]
        before = list(context.pages)
        try:
            yield context
        finally:
            for page in context.pages:
                if page not in before:
                    page.close()


def until(cond: Callable[[], object], timeout: float = 120.0, what: str = "") -> None:
    """Poll ``cond`` every 20 ms until it is true; fail naming ``what`` after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what or cond}")
        time.sleep(0.02)


def drawn_faces(page: Any, node: str) -> int | None:
    """Triangles of the first indexed mesh under the scene node ``node`` as three.js draws it (None: none)."""
    return page.evaluate(
        "(n) => { let f = null; window.__viserMutable?.nodeRefFromName?.[n]?.traverse(o => {"
        " if (f === null && o.geometry?.index) f = o.geometry.index.count / 3; }); return f; }",
        node,
    )


def text_shown(page: Any, fragment: str, timeout: float = 120.0) -> None:
    """Wait until the page's text contains ``fragment``."""
    page.wait_for_function("(f) => document.body.innerText.includes(f)", arg=fragment, timeout=timeout * 1000)


def tick(page: Any, label: str, is_on: Callable[[], object], timeout: float = 120.0, patience: float = 15.0) -> None:
    """Tick the checkbox labelled ``label`` until the server says so (``is_on``) and the page shows it.

    Not Playwright's ``check()``: viser ticks the box in the page when the click's update has gone
    round, which under load is later than ``check()`` looks. A click is repeated only when, ``patience``
    seconds after the last one, neither the server nor the page has it ticked (a click lost, never one
    in flight: it is undone only if slower than ``patience``).
    """
    box = page.get_by_label(label, exact=True)
    box.wait_for(state="visible")
    deadline = time.monotonic() + timeout
    last_click = -float("inf")
    while not (is_on() and box.is_checked()):
        now = time.monotonic()
        if now > deadline:
            raise AssertionError(f"timed out ticking {label!r} (server: {bool(is_on())}, page: {box.is_checked()})")
        if now - last_click > patience and not is_on() and not box.is_checked():
            box.click()
            last_click = time.monotonic()
        time.sleep(0.02)


def open_folder(page: Any, folder: str, label: str, timeout: float = 120.0, patience: float = 15.0) -> None:
    """Open the panel folder titled ``folder`` until the control labelled ``label`` in it is visible.

    A click on a folder's title can be lost when the panel re-renders under it (the server's answer
    to the previous action); it is repeated only when the control has not shown ``patience`` s after
    the last click (a second click on a folder that did open would close it).
    """
    control = page.get_by_label(label, exact=True)
    deadline = time.monotonic() + timeout
    last_click = -float("inf")
    while not control.is_visible():
        now = time.monotonic()
        if now > deadline:
            raise AssertionError(f"timed out opening the folder {folder!r} (no {label!r} shown)")
        if now - last_click > patience:
            page.get_by_text(folder, exact=True).click()
            last_click = time.monotonic()
        time.sleep(0.02)


def bodies_page(model: Any) -> Iterator[tuple[Any, Any]]:
    """A scene server on ``model`` (many bodies) and one headless tab on it, for a module fixture."""
    if not os.path.exists("/usr/bin/chromium"):
        pytest.skip("needs Debian chromium at /usr/bin/chromium")
    from app.scene.common.state import SceneConfig
    from app.screenshot import HeadlessScene

    with HeadlessScene(SceneConfig(), bodies=model, width=1000, height=720, timeout=120, dpr=TEST_DPR, settle_ms=TEST_SETTLE_MS,
                       sphere_subdivisions=TEST_SPHERE_SUBDIVISIONS,
                       cdp=CHROMIUM_OF_THIS_PROCESS.get()) as hs:
        yield hs, model


def field_input(page: Any, label: str, selector: str = "input") -> Any:
    """The visible input (``selector`` inside the row) of the field labelled ``label``."""
    idx = page.evaluate(
        """([l, sel]) => {
          const label = Array.from(document.querySelectorAll('label')).find(e => e.textContent === l && e.offsetParent !== null);
          const input = label?.closest('.mantine-Flex-root')?.querySelector(sel);
          return Array.from(document.querySelectorAll('input')).indexOf(input);
        }""", [label, selector])
    assert idx >= 0, f"no field labelled {label!r}"
    return page.locator("input").nth(idx)


def set_field(page: Any, label: str, text: str, handle: Any = None, patience: float = 15.0) -> None:
    """Type ``text`` into the text field labelled ``label`` and press Enter.

    With the server's ``handle`` of the field: until the server has the text, typing again when it
    has not arrived ``patience`` s after the last try (a panel re-rendered by the previous action's
    answer can drop the keys; the same text twice changes nothing).
    """
    deadline = time.monotonic() + 120
    while True:
        box = field_input(page, label, "input, textarea")
        box.fill(text)
        box.press("Enter")
        if handle is None:
            return
        tried = time.monotonic()
        while handle.value != text and time.monotonic() - tried < patience:
            time.sleep(0.02)
        if handle.value == text:
            return
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out setting {label} to {text!r} (the server has {handle.value!r})")
