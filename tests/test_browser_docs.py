"""The API's documentation pages in a real browser with no internet (issue 16, defect 6).

Every request that leaves the machine is refused, as on a classroom network without internet
access: /docs (Swagger UI) and /redoc must still render the endpoints from local assets.
"""

from __future__ import annotations

import os
import socket
import threading
import time

import pytest
import uvicorn

from app.api import ApiSettings, create_api

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists("/usr/bin/chromium"), reason="needs Debian chromium at /usr/bin/chromium"),
]


@pytest.fixture(scope="module")
def api_url():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = uvicorn.Server(uvicorn.Config(create_api(ApiSettings(scene_url=None)), host="127.0.0.1", port=port, log_level="warning"))
    th = threading.Thread(target=server.run, daemon=True)
    th.start()
    deadline = time.monotonic() + 30
    while not server.started and time.monotonic() < deadline:
        time.sleep(0.05)
    yield f"http://127.0.0.1:{port}"
    server.should_exit = True
    th.join(timeout=10)


@pytest.mark.parametrize("path, ready", [
    ("/docs", "document.querySelectorAll('.swagger-ui .opblock-summary-path').length"),
    ("/redoc", "document.querySelectorAll('[data-section-id^=\"operation\"], [id^=\"operation/\"]').length"),
])
def test_docs_render_without_internet(api_url, path, ready):
    from browser_helpers import connected

    refused: list[str] = []
    with connected() as browser:
        page = browser.new_page()

        def offline(route):  # the machine's own server only
            if route.request.url.startswith(api_url):
                route.continue_()
            else:  # not even ReDoc's "powered by" logo (issue 22.4): nothing leaves the machine
                refused.append(route.request.url)
                route.abort()

        page.route("**/*", offline)
        page.goto(api_url + path)
        page.wait_for_function(f"() => ({ready}) >= 8", timeout=60000)
        text = page.evaluate("() => document.body.innerText")
    assert "/api/classify" in text and "/api/analyse" in text
    assert refused == [], refused  # no script, style or font was asked of the internet
