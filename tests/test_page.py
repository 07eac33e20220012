"""The scene's page over HTTP: a small page, the client's code and style as cacheable files.

viser ships its client inside index.html (compressed, decoded in the browser on every load);
app.scene.common.page serves the loader alone and the code and style as files named by their hash.
What a browser does with them is checked in tests/test_browser_scene.py; here the bytes: the
files are exactly what viser's page holds, named by their content, cached for good, and the
page of every mode names them by a path that reaches them.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import httpx
import pytest
import viser
import zstandard

from app.scene.common import page
from app.scene.common.state import SceneConfig
from app.scene.server import start_scene

VISER_PAGE = (Path(viser.__file__).parent / "client" / "build" / "index.html").read_text(
    encoding="utf-8"
)
ALPHABET = (
    "!#$%()*+,-./0123456789:;=?@ABCDEFGHIJKLMNOPQRSTUVWXYZ[\\]^_abcdefghijklmnopqrstuvwxyz{|}~"
)


def encode88(data: bytes) -> str:
    """The encoder matching viser's base-88 decoder (the loader's ``de``), written from its
    description: four bytes -> five digits, a tail of k bytes -> k + 1 digits."""
    out = []
    full = len(data) - len(data) % 4
    for i in range(0, full, 4):
        v = int.from_bytes(data[i : i + 4], "big")
        out.append("".join(ALPHABET[v // 88**j % 88] for j in range(4, -1, -1)))
    if len(data) > full:
        tail = data[full:]
        v = int.from_bytes(tail, "big")
        out.append("".join(ALPHABET[v // 88**j % 88] for j in range(len(tail), -1, -1)))
    return "".join(out)


@pytest.mark.parametrize(
    "data", [b"", b"a", b"ab", b"abc", b"abcd", bytes(range(256)), b"\xff" * 7, b"\x00" * 9]
)
def test_base88_decodes_what_the_loader_encoding_makes(data):
    assert page._base88(encode88(data)) == data


def test_the_files_are_viser_client_named_by_their_hash():
    client = page._client()
    assert client is not None, "viser's page is no longer laid out as 1.1.1 lays it out"
    m = re.search(r'data-p="([^"]*)" data-ss="(\d+)" data-cs="(\d+)"', VISER_PAGE)
    ss, cs = int(m.group(2)), int(m.group(3))
    raw = zstandard.ZstdDecompressor().decompress(page._base88(m.group(1)), max_output_size=ss + cs)
    assert client.css == raw[:ss]
    # the code is viser's with one change: the settle window read from the page's address
    js = client.js.decode("utf-8")
    reader = re.compile(r"\(\(\)=>\{const v=new URLSearchParams\(location\.search\)\.get\(\"renderSettleMs\"\).*?:250\}\)\(\)")
    assert len(reader.findall(js)) == 1 and client.settle_flag
    assert reader.sub("250", js).encode("utf-8") == raw[ss:]
    assert client.name == hashlib.sha256(client.css + client.js).hexdigest()[:20]
    assert "__viserZstdWasm" in js and "__viserMutable" in js  # the client's code, not garbage
    assert client.css.decode("utf-8").lstrip().startswith(":root")
    # the loader keeps the WebAssembly module the client needs and no longer carries the payload
    assert "globalThis.__viserZstdWasm=m.module" in client.loader
    assert len(client.loader) < len(VISER_PAGE) / 10


@pytest.fixture(scope="module")
def scenes():
    """A scene server with a tab per browser and one in presenter mode (no analysis processes)."""
    cfg = SceneConfig.from_dict({"preset": "example-29", "t": 0.3})
    tabs = start_scene("127.0.0.1", 0, cfg, processes=False, prefetch=False)
    shared = start_scene("127.0.0.1", 0, cfg, processes=False, prefetch=False, shared=True)
    try:
        yield tabs, shared
    finally:
        tabs.stop()
        shared.stop()


def _client_links(html: str) -> list[str]:
    return re.findall(r'(?:href|src)="([^"]*_client/[^"]+)"', html)


@pytest.mark.parametrize("mode", ["tabs", "shared"])
def test_every_page_names_client_files_that_are_served_and_cached_for_good(scenes, mode):
    server = scenes[0] if mode == "tabs" else scenes[1]
    base = f"http://127.0.0.1:{server.port}"
    with httpx.Client(timeout=30) as http:
        r = http.get(base + "/", follow_redirects=True)
        assert r.status_code == 200 and r.headers["cache-control"] == "no-store"
        assert len(r.content) < 200_000  # was ~820 KB (viser's whole client in the page)
        links = _client_links(r.text)
        client = page._client()
        assert sorted({link.rsplit("/", 1)[1] for link in links}) == [
            client.name + ".css",
            client.name + ".js",
        ]
        for link in set(links):
            url = httpx.URL(str(r.url)).join(link)  # relative, as the browser resolves it
            assert url.path.startswith("/_client/")  # one address for every tab: cached once
            f = http.get(url, headers={"Accept-Encoding": "gzip"})
            assert f.status_code == 200
            assert f.headers["cache-control"] == "public, max-age=31536000, immutable"
            assert f.headers["content-encoding"] == "gzip"
            want = client.js if link.endswith(".js") else client.css
            assert f.content == want  # httpx undoes the gzip
            assert f.headers["content-type"].startswith(
                "text/javascript" if link.endswith(".js") else "text/css"
            )


def test_unknown_client_files_are_404_never_the_page(scenes):
    base = f"http://127.0.0.1:{scenes[0].port}"
    with httpx.Client(timeout=30) as http:
        for name in [
            "nope.js",
            page._client().name + ".map",
            "sub/" + page._client().name + ".js",
            "",
        ]:
            r = http.get(base + "/_client/" + name)
            assert r.status_code == 404, name
            assert r.headers["cache-control"] == "no-store"


def _clear_caches() -> None:
    for cached in (page._client, page.page_html, page._gzipped, page._assets):
        cached.cache_clear()


def test_a_client_without_the_known_scheduler_is_served_unchanged(monkeypatch):
    """Another viser whose render scheduler is not found: its code as it ships, the flag ignored."""
    _clear_caches()
    try:
        monkeypatch.setattr(page, "_SETTLE", re.compile("no such scheduler"))
        client = page._client()
        assert client is not None and not client.settle_flag and not page.settle_flag_supported()
        assert b"renderSettleMs" not in client.js and len(client.js) == int(re.search(r'data-cs="(\d+)"', VISER_PAGE).group(1))
    finally:
        monkeypatch.undo()
        _clear_caches()


def test_a_page_of_another_layout_is_served_whole(monkeypatch):
    """A viser whose page is not laid out as 1.1.1's: the page as it ships (no split), not an error."""
    _clear_caches()
    try:
        monkeypatch.setattr(page, "_PAYLOAD", re.compile("no such payload"))
        html = page.page_html("../../_client/").decode("utf-8")
        assert page._client() is None
        assert 'data-p="' in html and len(html) > len(VISER_PAGE) and "_client/" not in html
        assert page.LABELS_JS in html
        assert page._assets() == {}  # no client files to serve: every name is 404
    finally:
        monkeypatch.undo()
        _clear_caches()
