"""The scene's page: viser's client with a few lines of our own script, its code cacheable.

viser's text inputs carry a ``<label for=ID>`` whose ID is not the input's id (Mantine gives
the input its own), so screen readers and ``get_by_label`` found no label for any field. The
script here ties each label to the input in its row (``aria-labelledby``, and the input takes
the label's ``for`` id when no element has it), and keeps doing so as the panel changes (a
``MutationObserver``). :class:`app.scene.common.links.Router` serves this page for every tab address.

viser 1.1 ships its client as one ``index.html`` holding the code (2.5 MB of JavaScript and
150 KB of CSS) zstd-compressed and base-88 encoded, which the page decodes with a WebAssembly
inflater and runs as an inline module on every load: nothing of it can be cached, so each tab
(and each reload) downloads 670 KB and compiles the whole client again (~1 s of CPU on the
2-core test machines). The page served here is viser's loader without the payload; the code
and the style are files named by their content hash (``_client/<hash>.js`` / ``.css``, served
with ``Cache-Control: immutable``), so a browser fetches them once and reuses its compiled
code. Pages of an unknown layout are served as viser ships them.

The client keeps drawing for 250 ms after each change it is asked to show (viser's settle window,
for changes with asynchronous tails); a page address with ``renderSettleMs=N`` (0..10000) sets
that window, e.g. 0 for one frame per change: in software WebGL a frame takes ~80 ms, so the
window is 3 frames of CPU per change that headless tests reading state need not pay (the
client's one frame a second when idle still draws a late tail). See :data:`SETTLE_FLAG`.
"""

from __future__ import annotations

import gzip
import hashlib
import http
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

__all__ = [
    "CLIENT_PREFIX", "LABELS_JS", "SETTLE_FLAG", "SETTLE_MAX_MS", "SHARED_CLIENT_DIR", "TAB_CLIENT_DIR", "client_asset_response",
    "page_html", "page_response", "settle_flag_supported", "warm",
]

LABELS_JS = """
(() => {
  const tie = () => {
    for (const label of document.querySelectorAll('label[for]')) {
      const row = label.closest('.mantine-Flex-root');
      const input = row && row.querySelector('input:not([type=file]), textarea, [role=slider]');
      if (!input) continue;
      if (!label.id) label.id = 'label-' + label.htmlFor;
      if (input.getAttribute('aria-labelledby') !== label.id) input.setAttribute('aria-labelledby', label.id);
      if (input.id !== label.htmlFor && !document.getElementById(label.htmlFor)) input.id = label.htmlFor;
    }
  };
  let queued = false;
  const later = () => { if (!queued) { queued = true; requestAnimationFrame(() => { queued = false; tie(); }); } };
  const start = () => { tie(); new MutationObserver(later).observe(document.body, {childList: true, subtree: true}); };
  if (document.body) start(); else document.addEventListener('DOMContentLoaded', start);
})();
"""
"""Ties every field's label to its input (accessibility), on load and on every panel change."""


CLIENT_PREFIX = "/_client/"
"""Where the client's code and style are served (``<prefix><sha256 prefix>.js`` / ``.css``)."""
TAB_CLIENT_DIR = "../.." + CLIENT_PREFIX
"""The files as a tab's page (``/s/<id>/``) names them: relative, so a proxy's prefix is kept."""
SHARED_CLIENT_DIR = CLIENT_PREFIX.lstrip("/")
"""The files as the presenter-mode page (``/``) names them."""

_PAYLOAD = re.compile(r'<script data-p="([^"]*)" data-ss="(\d+)" data-cs="(\d+)">')
_DECODE_AND_RUN = re.compile(r"const a=de\(d\.p\);.*inst\.exports\.free\(up\);", re.S)
_DIR = "__CLIENT_DIR__"
_BASE88 = (
    "!#$%()*+,-./0123456789:;=?@ABCDEFGHIJKLMNOPQRSTUVWXYZ[\\]^_abcdefghijklmnopqrstuvwxyz{|}~"
)


SETTLE_FLAG = "renderSettleMs"
"""The page address's flag setting the client's settle window in ms (see the module's docstring)."""
SETTLE_MAX_MS = 10_000
"""The largest settle window the flag sets; a larger value means viser's own."""

_SETTLE = re.compile(
    r"var (\w+)=(\d+),(\w+)=1e3;(function \w+\(\)\{.{0,600}?requestRender=\(\)=>\{\w+\.current=performance\.now\(\)\+\1,)",
    re.S,
)
"""viser 1.1.1's render scheduler (minified): ``var <settle>=250,<heartbeat>=1e3;function ...
requestRender=()=>{<ref>.current=performance.now()+<settle>, ...``.

This one regex cannot be replaced by something independent of the minified code: viser has no
option for its settle window, so the only handle is its code. It names no minified identifier
(any word, with back-references), anchors on what minifying keeps (the literals ``250`` and ``1e3``,
``requestRender``, ``performance.now()``), must match exactly once, and fails safe: no match
serves viser's code unchanged and :func:`settle_flag_supported` says so (a test fails on a new
viser)."""


def settle_reader_js(own: str) -> str:
    """The expression put in place of viser's settle window ``own`` (ms): it reads :data:`SETTLE_FLAG`.

    Examples:
        >>> settle_reader_js("250").startswith("(()=>{const v=new URLSearchParams(location.search)")
        True
    """
    return (
        f'(()=>{{const v=new URLSearchParams(location.search).get("{SETTLE_FLAG}"),n=v===null||v===""?NaN:Number(v);'
        f"return globalThis.__renderSettleMs=n>=0&&n<={SETTLE_MAX_MS}?n:{own}}})()"
    )


def _with_settle_flag(js: str) -> str | None:
    """The client's code with its settle window read from the page's :data:`SETTLE_FLAG`.

    Its own value when the flag is absent or not a number in 0..:data:`SETTLE_MAX_MS`; None when the scheduler is
    not found (another viser: the code is served unchanged, the flag ignored). The window in effect
    is ``window.__renderSettleMs``.
    """
    if len(_SETTLE.findall(js)) != 1:
        return None

    def settle(m: re.Match[str]) -> str:
        return f"var {m.group(1)}={settle_reader_js(m.group(2))},{m.group(3)}=1e3;{m.group(4)}"

    return _SETTLE.sub(settle, js, count=1)


@dataclass(frozen=True)
class _Client:
    """viser's page split into a small loader page and the two files it loads."""

    loader: str
    """index.html with the payload removed; :data:`_DIR` marks where the files' folder goes."""
    js: bytes
    css: bytes
    name: str
    """The files' name: a prefix of the SHA-256 of both."""
    settle_flag: bool = False
    """The code reads the page's :data:`SETTLE_FLAG`."""


def _base88(text: str) -> bytes:
    """Decode viser's base-88 (five characters -> four bytes, a short tail -> one fewer)."""
    value = {c: i for i, c in enumerate(_BASE88)}
    out = bytearray()
    full = len(text) - len(text) % 5
    for i in range(0, full, 5):
        v = 0
        for ch in text[i : i + 5]:
            v = v * 88 + value[ch]
        out += v.to_bytes(4, "big")
    if len(text) > full:
        v = 0
        for ch in text[full:]:
            v = v * 88 + value[ch]
        out += v.to_bytes(len(text) - full - 1, "big")
    return bytes(out)


@lru_cache(maxsize=1)
def _viser_page() -> str:
    """The ``index.html`` viser ships (read once)."""
    import viser

    return (Path(viser.__file__).parent / "client" / "build" / "index.html").read_text(encoding="utf-8")


@lru_cache(maxsize=1)
def _client() -> _Client | None:
    """Split viser's client into loader, code and style.

    None when the page is not laid out as viser 1.1.1 lays it out (the payload, one decode-and-run
    block, one ``<title>`` before which the style is linked): then it is served whole.
    """
    page = _viser_page()
    m = _PAYLOAD.search(page)
    if m is None or len(_DECODE_AND_RUN.findall(page)) != 1 or page.count("<title>") != 1:
        return None
    try:
        import zstandard  # a dependency of viser

        ss, cs = int(m.group(2)), int(m.group(3))
        raw = zstandard.ZstdDecompressor().decompress(_base88(m.group(1)), max_output_size=ss + cs)
    except Exception:  # noqa: BLE001 - any surprise: serve viser's page unchanged
        return None
    if len(raw) != ss + cs:
        return None
    css, js = raw[:ss], raw[ss:]
    flagged = _with_settle_flag(js.decode("utf-8"))
    if flagged is not None:
        js = flagged.encode("utf-8")
    name = hashlib.sha256(css + js).hexdigest()[:20]
    # the loader still builds the zstd module the client uses (globalThis.__viserZstdWasm), then
    # runs the client from its file instead of decoding it; the style is linked in the head
    run = (
        'const e=document.createElement("script");e.type="module";'
        f'e.src="{_DIR}{name}.js";document.head.appendChild(e);'
    )
    loader = page[: m.start()] + '<script data-p="" data-ss="0" data-cs="0">' + page[m.end() :]
    loader = _DECODE_AND_RUN.sub(lambda _: run, loader, count=1)
    links = f'<link rel="stylesheet" href="{_DIR}{name}.css"><link rel="modulepreload" href="{_DIR}{name}.js">'
    loader = loader.replace("<title>", links + "<title>", 1)
    return _Client(loader=loader, js=js, css=css, name=name, settle_flag=flagged is not None)


def settle_flag_supported() -> bool:
    """Whether the client served reads :data:`SETTLE_FLAG` (viser's code as 1.1.1 lays it out)."""
    client = _client()
    return client is not None and client.settle_flag


@lru_cache(maxsize=4)
def page_html(client_dir: str = CLIENT_PREFIX) -> bytes:
    """The page: viser's loader running the client from ``client_dir``, :data:`LABELS_JS` added.

    ``client_dir`` is a URL path, relative to the page or absolute; viser's whole page (with
    :data:`LABELS_JS`) when its layout is unknown.
    """
    client = _client()
    page = client.loader.replace(_DIR, client_dir) if client is not None else _viser_page()
    script = f"<script>{LABELS_JS}</script>"
    return page.replace("</head>", script + "</head>", 1).encode("utf-8")


@lru_cache(maxsize=8)
def _gzipped(client_dir: str) -> bytes:
    return gzip.compress(page_html(client_dir))


@lru_cache(maxsize=1)
def _assets() -> dict[str, tuple[bytes, bytes, str]]:
    """``<hash>.js`` and ``<hash>.css`` -> (body, gzipped body, content type).

    Empty when the page is served whole. Built once: a request for another name is a lookup.
    """
    client = _client()
    if client is None:
        return {}
    return {
        client.name + ".js": (client.js, gzip.compress(client.js), "text/javascript; charset=utf-8"),
        client.name + ".css": (client.css, gzip.compress(client.css), "text/css; charset=utf-8"),
    }


def warm() -> None:
    """Build the page and the client's files now, not in the first request (once per process).

    The scene server calls it in a thread when it starts.
    """
    for client_dir in (TAB_CLIENT_DIR, SHARED_CLIENT_DIR):
        _gzipped(client_dir)
    _assets()


def _response(
    request: Any, body: bytes, gzipped: bytes, content_type: str, cache: str, status: http.HTTPStatus = http.HTTPStatus.OK
) -> Any:
    from websockets.datastructures import Headers
    from websockets.http11 import Response

    use_gzip = "gzip" in request.headers.get("Accept-Encoding", "")
    data = gzipped if use_gzip else body
    headers = Headers(
        **{
            "Content-Type": content_type,
            "Content-Length": str(len(data)),
            "Content-Encoding": "gzip" if use_gzip else "identity",
            "Cache-Control": cache,
            "Connection": "close",  # the websockets server closes after an HTTP answer: say so
        }
    )
    return Response(status, status.phrase, headers, data)


def page_response(request: Any, client_dir: str = CLIENT_PREFIX) -> Any:
    """A ``websockets`` HTTP response with the page (gzip when the browser takes it), never cached.

    The client's files it names are cached (see :func:`client_asset_response`).
    """
    return _response(
        request, page_html(client_dir), _gzipped(client_dir), "text/html; charset=utf-8", "no-store"
    )


def client_asset_response(request: Any, name: str) -> Any:
    """The client's code or style ``name`` (``<hash>.js`` / ``.css``), or 404.

    Cacheable for good: the name changes with the content.
    """
    asset = _assets().get(name)
    if asset is None:
        body = b"no such client file\n"
        return _response(request, body, gzip.compress(body), "text/plain", "no-store", http.HTTPStatus.NOT_FOUND)
    body, gzipped, content_type = asset
    return _response(request, body, gzipped, content_type, "public, max-age=31536000, immutable")
