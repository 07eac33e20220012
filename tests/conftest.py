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


def _chromium() -> bool:
    return os.path.exists("/usr/bin/chromium")


@pytest.fixture(scope="session")
def headless_scene():
    """One scene server and one headless Chromium tab for the whole test session (browser tests).

    Tests open their own tab on their own configuration with a link (``hs.goto(link_path(cfg))``);
    starting a browser per module cost seconds each on the shared 2-core machines.
    """
    if not _chromium():
        pytest.skip("needs Debian chromium at /usr/bin/chromium")
    from app.scene.state import SceneConfig
    from app.screenshot import HeadlessScene

    with HeadlessScene(SceneConfig.from_dict({"preset": "example-29", "t": 0.3}), width=1300, height=950, timeout=90) as h:
        yield h
