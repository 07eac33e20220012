"""The HTML replay (``python -m app export``) and the notebook call, in a real browser.

The replay is one HTML file with viser's player and a recording; opened from disk with no server
it plays the motion: the caption names t and the certified relation, each event is held exactly
(tangent, amber), the shapes carry their relation as text.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
browser = pytest.mark.skipif(not os.path.exists("/usr/bin/chromium"), reason="needs Debian chromium at /usr/bin/chromium")

def test_export_command_writes_a_standalone_replay(tmp_path):
    out = tmp_path / "ex29.html"
    r = subprocess.run([sys.executable, "-m", "app", "export", "--preset", "example-29", "--frames", "60", "--out", str(out)],
                       cwd=ROOT, capture_output=True, text=True, timeout=180, check=False)
    assert r.returncode == 0, r.stderr
    text = out.read_text()
    assert text.startswith("<!doctype html>") and "window.__VISER_EMBED_DATA__=" in text
    bad = subprocess.run([sys.executable, "-m", "app", "export", "--preset", "no-such", "--out", str(tmp_path / "x.html")],
                         cwd=ROOT, capture_output=True, text=True, timeout=180, check=False)
    assert bad.returncode == 2 and "unknown preset 'no-such'" in bad.stderr


def recorded_messages(html: str) -> list[dict]:
    """The messages of a replay's recording (base64 of zstd-compressed msgpack, viser's format)."""
    import base64

    import msgspec
    import zstandard

    b64 = html.split('window.__VISER_EMBED_DATA__="', 1)[1].split('"', 1)[0]
    raw = base64.b64decode(b64)
    inner = zstandard.ZstdDecompressor().decompress(raw[8:], max_output_size=int.from_bytes(raw[:8], "little"))
    n = int.from_bytes(inner[:8], "little")
    return msgspec.msgpack.decode(inner[8 : 8 + n])["messages"]


def test_replay_records_every_relation_and_each_event_exactly():
    from app.scene.replay import replay_html
    from app.scene.state import SceneConfig

    msgs = recorded_messages(replay_html(SceneConfig(preset="example-29"), seconds=4, frames=80))
    texts = [str(m) for _, m in msgs]
    captions = [t for t in texts if "/replay/caption" in t and "text" in t]
    joined = " ".join(captions)
    for word in ("SEPARATE", "OVERLAP", "α1 = (12 − 2√2)/17 · TANGENT (exact)", "α2 = (12 + 2√2)/17 · TANGENT (exact)"):
        assert word in joined, word
    times = [t for t, _ in msgs]
    assert times == sorted(times) and times[-1] >= 4  # the sweep, plus the held events
    assert any("B · tangent" in t for t in texts)


@pytest.mark.browser
@browser
def test_replay_plays_in_a_browser_without_a_server(tmp_path):
    """Opened from disk: the shapes take every relation's colour in turn (tangent at the events)."""
    from playwright.sync_api import sync_playwright

    from app.scene.replay import replay_html
    from app.scene.state import SceneConfig
    from app.screenshot import CHROMIUM, CHROMIUM_FLAGS

    path = tmp_path / "ex29.html"
    path.write_text(replay_html(SceneConfig(preset="example-29"), seconds=4, frames=80, event_pause=1.0))
    colour = """() => { const r = window.__viserMutable?.nodeRefFromName?.['/shapes/A/mesh']; let h = null;
      r?.traverse(o => { if (h === null && o.material && o.material.color) h = '#' + o.material.color.getHexString(); }); return h; }"""
    seen: set[str] = set()
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_FLAGS)
        page = b.new_page(viewport={"width": 900, "height": 600})
        page.goto(path.as_uri())
        page.wait_for_function("() => window.__viserMutable?.nodeRefFromName?.['/shapes/A/mesh'] != null", timeout=60000)
        for _ in range(160):  # the whole recording (6 s), sampled
            seen.add(page.evaluate(colour))
            if len(seen & {"#2ca02c", "#ffbf00", "#d62728"}) == 3:
                break
            page.wait_for_timeout(50)
        b.close()
    assert {"#2ca02c", "#ffbf00", "#d62728"} <= seen, seen


@pytest.mark.browser
@browser
def test_notebook_show_serves_the_scene_in_an_iframe():
    from playwright.sync_api import sync_playwright

    from app.notebook import show
    from app.screenshot import CHROMIUM, CHROMIUM_FLAGS

    nb = show("circles-crossing", height=500)
    try:
        html = nb._repr_html_()
        assert html.startswith('<iframe src="http://127.0.0.1:') and 'height="500"' in html
        with sync_playwright() as pw:
            b = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_FLAGS)
            page = b.new_page()
            page.set_content(html)  # what a notebook cell holds
            frame = page.frame_locator("iframe")
            frame.get_by_text("Jump to α1", exact=False).wait_for(timeout=60000)
            assert nb.session is not None and nb.session.state.motion.preset == "circles-crossing"
            b.close()
    finally:
        nb.stop()
