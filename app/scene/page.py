"""The scene's page: viser's client with a few lines of our own script.

viser's text inputs carry a ``<label for=ID>`` whose ID is not the input's id (Mantine gives
the input its own), so screen readers and ``get_by_label`` found no label for any field. The
script here ties each label to the input in its row (``aria-labelledby``, and the input takes
the label's ``for`` id when no element has it), and keeps doing so as the panel changes (a
``MutationObserver``). :class:`app.scene.links.Router` serves this page for every tab address.
"""

from __future__ import annotations

import gzip
import http
from functools import lru_cache
from pathlib import Path
from typing import Any

__all__ = ["LABELS_JS", "page_html", "page_response"]

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


@lru_cache(maxsize=1)
def page_html() -> bytes:
    """Viser's ``index.html`` with :data:`LABELS_JS` before ``</head>`` (read once)."""
    import viser

    page = (Path(viser.__file__).parent / "client" / "build" / "index.html").read_text(encoding="utf-8")
    script = f"<script>{LABELS_JS}</script>"
    return page.replace("</head>", script + "</head>", 1).encode("utf-8")


@lru_cache(maxsize=1)
def _gzipped() -> bytes:
    return gzip.compress(page_html())


def page_response(request: Any) -> Any:
    """A ``websockets`` HTTP response with the page (gzip when the browser takes it)."""
    from websockets.datastructures import Headers
    from websockets.http11 import Response

    use_gzip = "gzip" in request.headers.get("Accept-Encoding", "")
    body = _gzipped() if use_gzip else page_html()
    headers = Headers(
        **{
            "Content-Type": "text/html; charset=utf-8",
            "Content-Length": str(len(body)),
            "Content-Encoding": "gzip" if use_gzip else "identity",
            "Cache-Control": "no-store",
        }
    )
    return Response(http.HTTPStatus.OK, "OK", headers, body)
