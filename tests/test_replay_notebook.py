"""The HTML replay (``python -m app export``) and the notebook call, in a real browser.

The replay is one HTML file with viser's player and a recording; opened from disk with no server
it plays the motion: the caption names t and the certified relation, each event is held exactly
(tangent, amber), the shapes carry their relation as text.
"""

from __future__ import annotations

import json
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
    from app.scene.common.state import SceneConfig
    from app.scene.pair.replay import replay_html

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
    from browser_helpers import connected, drawn_faces

    from app.scene.common.state import SceneConfig
    from app.scene.pair.replay import replay_html
    from conftest import TEST_SPHERE_SUBDIVISIONS

    path = tmp_path / "ex29.html"
    path.write_text(replay_html(SceneConfig(preset="example-29"), seconds=4, frames=80, event_pause=1.0,
                                sphere_subdivisions=TEST_SPHERE_SUBDIVISIONS))
    colour = """() => { const r = window.__viserMutable?.nodeRefFromName?.['/shapes/A/mesh']; let h = null;
      r?.traverse(o => { if (h === null && o.material && o.material.color) h = '#' + o.material.color.getHexString(); }); return h; }"""
    seen: set[str] = set()
    with connected() as b:
        page = b.new_page()
        page.set_viewport_size({"width": 900, "height": 600})
        page.goto(path.as_uri())
        page.wait_for_function("() => window.__viserMutable?.nodeRefFromName?.['/shapes/A/mesh'] != null", timeout=60000)
        assert drawn_faces(page, "/shapes/A/mesh") == 20 * 4**TEST_SPHERE_SUBDIVISIONS  # the replay's detail
        for _ in range(160):  # the whole recording (6 s), sampled
            seen.add(page.evaluate(colour))
            if len(seen & {"#2ca02c", "#ffbf00", "#d62728"}) == 3:
                break
            page.wait_for_timeout(50)
    assert {"#2ca02c", "#ffbf00", "#d62728"} <= seen, seen


@pytest.mark.browser
@browser
def test_notebook_show_serves_the_scene_in_an_iframe():
    from browser_helpers import connected

    from app.notebook import show

    nb = show("circles-crossing", height=500)
    try:
        html = nb._repr_html_()
        assert html.startswith('<iframe src="http://127.0.0.1:') and 'height="500"' in html
        with connected() as b:
            page = b.new_page()
            page.set_content(html)  # what a notebook cell holds
            frame = page.frame_locator("iframe")
            frame.get_by_text("Jump to α1", exact=False).wait_for(timeout=60000)
            assert nb.session is not None and nb.session.state.motion.preset == "circles-crossing"
    finally:
        nb.stop()


class NotebookProxy:
    """A stand-in for a remote Jupyter server with jupyter-server-proxy, on its own origin.

    ``/lab/tree/nb.ipynb`` is a notebook page (JupyterLab's ``#jupyter-config-data`` with its
    ``baseUrl``) holding one cell's HTML; ``/proxy/<port>/<path>`` forwards HTTP and websockets
    to ``127.0.0.1:<port>/<path>`` with the prefix stripped and the request's headers (Origin,
    Host) passed on, as jupyter-server-proxy does (its ``LocalProxyHandler``).
    """

    def __init__(self, cell_html: str, base_url: str = "/") -> None:
        import asyncio
        import threading

        self.cell_html = cell_html
        self.base_url = base_url
        self.loop = asyncio.new_event_loop()
        self.port = 0
        ready = threading.Event()

        def run() -> None:
            asyncio.set_event_loop(self.loop)
            self.loop.run_until_complete(self._start(ready))
            self.loop.run_forever()

        threading.Thread(target=run, daemon=True).start()
        ready.wait(10)

    def page(self) -> str:
        cfg = json.dumps({"baseUrl": self.base_url})
        return (f'<!doctype html><html><head><script id="jupyter-config-data" type="application/json">{cfg}</script>'
                f"</head><body><div class=\"cell-output\">{self.cell_html}</div></body></html>")

    async def _start(self, ready) -> None:
        import http.client

        from websockets.asyncio.client import connect
        from websockets.asyncio.server import serve
        from websockets.datastructures import Headers
        from websockets.http11 import Response

        def upstream(path: str) -> tuple[int, str] | None:
            parts = path.split("/", 3)  # "", "proxy", port, rest
            if len(parts) < 3 or parts[1] != "proxy" or not parts[2].isdigit():
                return None
            return int(parts[2]), "/" + (parts[3] if len(parts) > 3 else "")

        def process_request(connection, request):
            if request.headers.get("Upgrade", "").lower() == "websocket":
                return None
            if request.path.startswith("/lab/tree/"):
                body = self.page().encode()
                return Response(200, "OK", Headers({"Content-Type": "text/html", "Content-Length": str(len(body))}), body)
            target = upstream(request.path)
            if target is None:
                return Response(404, "Not Found", Headers({"Content-Length": "0"}), b"")
            c = http.client.HTTPConnection("127.0.0.1", target[0], timeout=30)
            c.request("GET", target[1])
            r = c.getresponse()
            body = r.read()
            headers = Headers({k: v for k, v in r.getheaders() if k.lower() not in ("content-length", "transfer-encoding", "connection")})
            headers["Content-Length"] = str(len(body))
            return Response(r.status, r.reason, headers, body)

        async def handler(ws):
            import asyncio

            port, rest = upstream(ws.request.path)
            origin = ws.request.headers.get("Origin")
            async with connect(f"ws://127.0.0.1:{port}{rest}", subprotocols=[ws.subprotocol] if ws.subprotocol else None,
                               origin=origin, max_size=None, compression=None) as up:
                async def pump(src, dst):
                    async for message in src:
                        await dst.send(message)
                done, pending = await asyncio.wait([asyncio.ensure_future(pump(ws, up)), asyncio.ensure_future(pump(up, ws))],
                                                   return_when=asyncio.FIRST_COMPLETED)
                for task in pending:
                    task.cancel()

        self.server = await serve(handler, "127.0.0.1", 0, process_request=process_request, max_size=None, compression=None,
                                  select_subprotocol=lambda conn, offered: offered[0] if offered else None)
        self.port = self.server.sockets[0].getsockname()[1]
        ready.set()

    def stop(self) -> None:
        self.loop.call_soon_threadsafe(self.server.close)


@pytest.mark.browser
@browser
def test_notebook_scene_through_a_remote_notebooks_proxy():
    """A remote Jupyter (22.4): the browser reaches the kernel's scene only through the notebook
    server's proxy, on the notebook's own origin (a name, not loopback). The cell's iframe follows
    Jupyter's base URL (read from the page) to <base>proxy/PORT/s/<tab>/, the scene's redirects
    stay below that path, and the handshake is accepted for the cell's secret tab only: a tab of
    the same scene opened at the proxy's root is refused (the Origin is not the scene's)."""
    from browser_helpers import NOTEBOOK_HOST, connected

    from app.notebook import show

    nb = show("circles-crossing", height=500, proxy=True)
    proxy = NotebookProxy(nb._repr_html_(), base_url="/")
    try:
        assert nb.url == f"/proxy/{nb.scene.port}/s/{nb.tab}/"
        with connected() as b:  # the test Chromium resolves NOTEBOOK_HOST to 127.0.0.1
            page = b.new_page()
            page.goto(f"http://{NOTEBOOK_HOST}:{proxy.port}/lab/tree/nb.ipynb")
            frame = page.frame_locator("iframe")
            frame.get_by_text("Jump to α1", exact=False).wait_for(timeout=60000)
            assert nb.session is not None and nb.session.state.motion.preset == "circles-crossing"
            assert page.evaluate("() => document.querySelector('iframe').src") == \
                f"http://{NOTEBOOK_HOST}:{proxy.port}/proxy/{nb.scene.port}/s/{nb.tab}/"
            # the relative redirect of the scene's root stays below the proxy's path
            other = b.new_page()
            other.goto(f"http://{NOTEBOOK_HOST}:{proxy.port}/proxy/{nb.scene.port}/")
            assert other.url.startswith(f"http://{NOTEBOOK_HOST}:{proxy.port}/proxy/{nb.scene.port}/s/"), other.url
        # the notebook's Origin opens the cell's tab only: any other tab of the scene is refused
        origin = f"http://{NOTEBOOK_HOST}:{proxy.port}"
        assert handshake(nb.scene.port, f"/s/{nb.tab}/", origin) == 101
        assert handshake(nb.scene.port, "/s/AAAAAAAAAAAAAAAA/", origin) == 403
        assert handshake(nb.scene.port, "/", origin) == 403
    finally:
        proxy.stop()
        nb.stop()


def handshake(port: int, path: str, origin: str) -> int:
    """HTTP status of a websocket handshake to the scene (101: accepted)."""
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    try:
        with connect(f"ws://127.0.0.1:{port}{path}", origin=origin, subprotocols=["viser-v1.1.1"], open_timeout=30):
            return 101
    except InvalidStatus as e:
        return e.response.status_code
