"""Landing page (static/index.html served at /): links, presets, figures, and curl examples that work.

The curl examples are run for real (bash + curl against a uvicorn server on a free port) and their
output is compared with the output printed under them on the page.
"""

from __future__ import annotations

import html
import json
import re
import shutil
import socket
import subprocess
import threading
import time
from pathlib import Path

import pytest
import uvicorn
from fastapi.testclient import TestClient

from app.api import ApiSettings, create_api
from app.api.settings import default_static_dir

STATIC = default_static_dir()
EXAMPLE = re.compile(r'<pre class="curl"><code>(.*?)</code></pre>\s*(?:<pre class="out"><code>(.*?)</code></pre>)?', re.S)
PNG_1x1 = bytes.fromhex(
    "89504e470d0a1a0a0000000d4948445200000001000000010806000000"
    "1f15c4890000000d49444154789c6360000002000154a24f5d0000000049454e44ae426082"
)


def test_static_folder_is_found():
    assert STATIC is not None and (STATIC / "index.html").is_file() and (STATIC / "style.css").is_file()


def test_page_links_scene_docs_and_explains():
    with TestClient(create_api(ApiSettings(scene_url="http://127.0.0.1:8080"))) as c:
        r = c.get("/")
        assert r.status_code == 200 and r.headers["content-type"].startswith("text/html")
        page = r.text
    assert '<a id="scene-link" class="button" href="http://127.0.0.1:8080">Open the 3D scene</a>' in page
    assert 'href="/docs"' in page
    assert "API=http://testserver" in page  # the examples are filled in with this server's URL
    for phrase in ("interior is X<sup>T</sup> A X &lt; 0", "P(T) = det(T A + B)", "ascending", "certified"):
        assert phrase in page
    assert "<!--" not in page  # every marker was replaced


def test_api_only_page_and_escaping():
    with TestClient(create_api(ApiSettings(scene_url=None))) as c:
        assert "The 3D scene is not running on this server (API only)." in c.get("/").text
    with TestClient(create_api(ApiSettings(scene_url='http://x/"><script>alert(1)</script>'))) as c:
        page = c.get("/").text
    assert "<script>" not in page and 'href="http://x/&quot;&gt;&lt;script&gt;' in page


def test_presets_screenshots_and_bench_figures(tmp_path):
    static = tmp_path / "static"
    shutil.copytree(STATIC, static, ignore=shutil.ignore_patterns("img"))
    (static / "img" / "bench").mkdir(parents=True)
    (static / "img" / "example-29.png").write_bytes(PNG_1x1)
    (static / "img" / "bench" / "throughput.png").write_bytes(PNG_1x1)
    bench = tmp_path / "figures"
    bench.mkdir()
    (bench / "near_tangent.png").write_bytes(PNG_1x1)
    with TestClient(create_api(ApiSettings(static_dir=static, bench_dir=bench))) as c:
        page = c.get("/").text
        assert c.get("/bench/figures/near_tangent.png").content == PNG_1x1
        names = [p["name"] for p in c.get("/api/presets").json()]
        assert c.get("/static/img/example-29.png").content == PNG_1x1
        assert c.get("/static/style.css").status_code == 200
    assert len(names) >= 5
    for name in names:
        assert f'id="preset-{name}"' in page and f'href="/api/presets/{name}"' in page
    assert '<img src="/static/img/example-29.png" alt="example-29"' in page
    assert page.count('<img src="/static/img/') == 2  # only the screenshot that exists, and the figure
    assert '<img src="/static/img/bench/throughput.png" alt="throughput">' in page
    assert '<img src="/bench/figures/near_tangent.png" alt="near_tangent">' in page
    with TestClient(create_api(ApiSettings(static_dir=static, bench_dir=tmp_path / "missing"))) as c:
        shutil.rmtree(static / "img" / "bench")
        assert "Benchmark figures will appear here" in c.get("/").text


def test_no_static_folder_is_404(tmp_path):
    with TestClient(create_api(ApiSettings(static_dir=tmp_path))) as c:
        r = c.get("/")
    assert (r.status_code, r.json()) == (404, {"detail": "no landing page: static/index.html not found"})


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def live_server():
    port = _free_port()
    server = uvicorn.Server(uvicorn.Config(create_api(ApiSettings(scene_url=None)), host="127.0.0.1", port=port, log_level="warning"))
    th = threading.Thread(target=server.run, daemon=True)
    th.start()
    deadline = time.monotonic() + 20
    while not server.started and time.monotonic() < deadline:
        time.sleep(0.05)
    assert server.started, "uvicorn did not start"
    yield f"http://127.0.0.1:{port}"
    server.should_exit = True
    th.join(timeout=10)


def _examples(page: str) -> list[tuple[str, str | None]]:
    return [(html.unescape(cmd), html.unescape(out) if out else None) for cmd, out in EXAMPLE.findall(page)]


@pytest.mark.skipif(shutil.which("curl") is None or shutil.which("bash") is None, reason="needs curl and bash")
def test_curl_examples_work_against_a_running_server(live_server):
    page = subprocess.run(["curl", "-s", live_server + "/"], capture_output=True, text=True, timeout=30, check=True).stdout
    examples = _examples(page)
    assert len(examples) >= 6
    for cmd, expected in examples:
        res = subprocess.run(["bash", "-c", f"set -o pipefail; API={live_server}; {cmd}"], capture_output=True, text=True, timeout=120, check=False)
        assert res.returncode == 0, (cmd, res.stderr)
        got = res.stdout.strip()
        assert got, cmd
        if expected is None:
            assert json.loads(got)["relation"] == "tangent"  # the explain example
            continue
        try:
            assert json.loads(got) == json.loads(expected), cmd
        except json.JSONDecodeError:
            assert got == expected.strip(), cmd


def test_examples_are_found_on_the_page():
    page = (STATIC / "index.html").read_text()
    cmds = [cmd for cmd, _ in _examples(page)]
    assert any("/api/classify" in c for c in cmds) and any("/api/explain" in c for c in cmds)
    assert any("/api/analyse" in c for c in cmds)
    assert all(c.startswith("curl ") for c in cmds)


# --- Dockerfile (no Docker engine here: checked by reading) --------------------------------

def _dockerfile() -> dict[str, list[str]]:
    text = (Path(__file__).resolve().parents[1] / "Dockerfile").read_text()
    text = text.replace("\\\n", " ")
    out: dict[str, list[str]] = {}
    for raw in text.splitlines():
        line = raw.strip()
        if line and not line.startswith("#"):
            key, _, rest = line.partition(" ")
            out.setdefault(key.upper(), []).append(rest.strip())
    return out


def _stages() -> dict[str, str]:
    """Instructions of each stage of the Dockerfile by its name (comments dropped)."""
    text = (Path(__file__).resolve().parents[1] / "Dockerfile").read_text()
    out: dict[str, str] = {}
    name = ""
    for raw in text.splitlines():
        line = raw.strip()
        if line.startswith("FROM "):
            name = line.split(" AS ")[-1].strip()
            out[name] = ""
        elif name and line and not line.startswith("#"):
            out[name] += line + "\n"
    return out


def test_dockerfile_serves_scene_and_api_as_documented():
    from app.cli import build_parser

    d = _dockerfile()
    assert all(f.startswith("python:3.11-slim AS ") for f in d["FROM"])  # multi-stage, one base
    assert d["FROM"][-1] == "python:3.11-slim AS runtime"
    assert any(u not in ("root", "0") for u in d["USER"])  # non-root
    stages = _stages()
    runtime = stages["runtime"]
    assert "gcc" not in runtime and "playwright" not in runtime.lower()  # no compiler, no browser at run time
    assert "gcc" in stages["build"] and "pip wheel" in stages["build"]  # the compiled filter goes into the wheel
    deps = stages["deps"]
    assert "COPY pyproject.toml ./" in deps and "COPY core" not in deps and "playwright" in deps  # deps before the code; Playwright left out
    assert "pip install --no-deps /wheels/*.whl" in runtime  # the package, without re-resolving dependencies
    cmd = json.loads(d["CMD"][-1])
    assert cmd[:4] == ["python", "-m", "app", "serve"]
    args = build_parser().parse_args(cmd[3:])  # the CLI accepts exactly this command
    assert (args.host, args.port, args.api_port, args.api_only) == ("0.0.0.0", 8080, 8000, False)
    assert set(d["EXPOSE"][0].split()) == {"8080", "8000"}
    assert "/healthz" in d["HEALTHCHECK"][0] and "8000" in d["HEALTHCHECK"][0]
    copied = " ".join(d["COPY"])
    for part in ("pyproject.toml", "README.md", "core", "app", "static"):
        assert part in copied


def test_preset_cards_open_the_preset_in_the_scene(tmp_path):
    """Issue 22.4: each preset card links to the scene on that preset (a /c/<configuration>/ link
    whose configuration is the preset), when the scene runs; API only: no such link."""
    from app.scene.common.links import decode_config

    static = tmp_path / "static"
    shutil.copytree(STATIC, static, ignore=shutil.ignore_patterns("img"))
    (static / "img").mkdir()
    (static / "img" / "example-30.png").write_bytes(PNG_1x1)
    with TestClient(create_api(ApiSettings(static_dir=static, scene_url="http://127.0.0.1:8080/"))) as c:
        page = c.get("/").text
        names = [p["name"] for p in c.get("/api/presets").json()]
    links = re.findall(r'<a class="open-scene" href="http://127\.0\.0\.1:8080/c/([A-Za-z0-9_=-]+)/">Open in the scene</a>', page)
    assert [decode_config(t)["preset"] for t in links] == names
    card = page[page.index('id="preset-example-30"'):]
    assert card.index('<a href="http://127.0.0.1:8080/c/') < card.index('<img src="/static/img/example-30.png"')
    with TestClient(create_api(ApiSettings(static_dir=static, scene_url=None))) as c:
        assert "Open in the scene" not in c.get("/").text
