"""Shared pytest configuration: hypothesis profiles (HYPOTHESIS_PROFILE=ci|dev), import path."""

import os
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

ROOT = Path(__file__).resolve().parent.parent
for p in (ROOT, ROOT / "tests"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

settings.register_profile(
    "ci", max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
settings.register_profile("dev", max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


TEST_DPR = 0.5
"""Device pixel ratio of the test tabs' canvas: a quarter of the pixels of a picture, so that
software WebGL draws each frame in about half the CPU time (measured 0.15 -> 0.08 CPU-s per frame
at 1000 x 720); the tests read colours, three.js state and the panel, not detail. Pictures
(``app.screenshot``, the screenshot tests) keep 1."""

TEST_SETTLE_MS = 0
"""The test tabs' settle window (``HeadlessScene(settle_ms=...)``): one frame per change instead of
viser's 250 ms of frames (3 frames in software WebGL). The tests wait on what is drawn (poses,
colours, three.js state), never on a number of frames; the client's one frame a second when
idle still draws a change's late tail. tests/test_browser_scene.py: 60 -> 51 CPU-s. Pictures keep
viser's window."""


TEST_SPHERE_SUBDIVISIONS = 3
"""Icosphere subdivisions of the solids in the test tabs' scenes (``HeadlessScene`` and
``start_scene(sphere_subdivisions=...)``): 1,280 faces instead of 20,480, so that software WebGL
draws a frame of two ellipsoids in ~23 instead of ~60 ms of CPU (the browser test files: 146 ->
132 CPU-s). The tests read colours, poses, three.js state and the panel; the default mesh and its
gap bound are tested without a browser (tests/test_scene.py), and pictures keep it."""


def _chromium() -> bool:
    return os.path.exists("/usr/bin/chromium")


class _SharedScene:
    """One scene server and one headless Chromium tab, shared by the tests that ask for them.

    Opened by the first test that uses the ``headless_scene`` fixture and kept for the next ones
    (a server, a Playwright and a page load cost seconds on the shared 2-core machines); closed
    before a test that does not use it, because Playwright's sync API (and ``asyncio.run``)
    cannot run while another sync Playwright holds this thread's event loop. The tab is in the
    process's one Chromium (``browser_helpers.SharedChromium``), which keeps running.
    """

    def __init__(self) -> None:
        self.scene = None

    def get(self):
        if self.scene is None:
            from browser_helpers import CHROMIUM_OF_THIS_PROCESS

            from app.scene.common.state import SceneConfig
            from app.screenshot import HeadlessScene

            scene = HeadlessScene(SceneConfig.from_dict({"preset": "example-29", "t": 0.3}), width=1000, height=720,
                                  timeout=90, dpr=TEST_DPR, settle_ms=TEST_SETTLE_MS,
                                  sphere_subdivisions=TEST_SPHERE_SUBDIVISIONS,
                                  cdp=CHROMIUM_OF_THIS_PROCESS.get())
            self.scene = scene.__enter__()
        return self.scene

    def close(self) -> None:
        if self.scene is not None:
            scene, self.scene = self.scene, None
            scene.__exit__(None, None, None)


_SHARED = _SharedScene()


def pytest_collection_modifyitems(session, config, items):
    """Files with browser tests first (each takes 20-90 s; the rest mostly under 10 s).

    pytest-xdist (``--dist loadfile --no-loadscope-reorder``, pyproject.toml) hands out whole files
    in collection order: starting the long files first leaves short ones to fill the end, so no
    worker waits alone for a long file at the end of the run. Without the option xdist 3.8 sends
    the files with the most tests first, and this sort did nothing. The order inside a file is
    kept; the sort is the same in every worker.
    """
    browser_files = {item.nodeid.split("::")[0] for item in items if item.get_closest_marker("browser")}
    items.sort(key=lambda item: item.nodeid.split("::")[0] not in browser_files)


def pytest_runtest_setup(item):
    """Close the shared browser before a test that does not use it (it may start its own)."""
    if "headless_scene" not in getattr(item, "fixturenames", ()):
        _SHARED.close()


def pytest_sessionfinish(session, exitstatus):
    _SHARED.close()
    if "browser_helpers" in sys.modules:  # the process's one Chromium, if a test started it
        sys.modules["browser_helpers"].CHROMIUM_OF_THIS_PROCESS.stop()


@pytest.fixture
def headless_scene():
    """The shared scene server and headless Chromium tab (see :class:`_SharedScene`).

    Tests start the tab on their own configuration as its link would (``hs.open(cfg)``: a new session
    and panel without a page load); tests of page loads and links load the link (``hs.goto(link_path(cfg))``).
    """
    if not _chromium():
        pytest.skip("needs Debian chromium at /usr/bin/chromium")
    return _SHARED.get()
