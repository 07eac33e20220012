"""create_api(): the FastAPI application (routers, limits, worker pool, static files)."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from functools import lru_cache
from pathlib import Path
from typing import Any

from fastapi import FastAPI
from fastapi.exceptions import RequestValidationError
from fastapi.staticfiles import StaticFiles
from starlette.responses import PlainTextResponse
from starlette.types import Receive, Scope, Send

from core import InvalidInput, warm_up

from ..workers import WorkerPool
from .batching import PairBatcher
from .errors import invalid_input_handler, validation_error_handler
from .line import Line, RequestLine
from .routes import classify, contacts, health, landing, motion, presets, sweep, witness
from .settings import ApiSettings

__all__ = ["create_api", "DOCS_ASSETS", "GUIDE", "GUIDE_DIR", "GUIDE_BUILD"]

GUIDE = "/guide"
"""Where the documentation site is served (offline: classrooms without internet)."""

GUIDE_DIR = Path(__file__).resolve().parents[2] / "docs" / "_build" / "html"
"""The built documentation site of this checkout (docs/develop/docs.md builds it)."""

GUIDE_BUILD = "python -m sphinx -W --keep-going -b html docs docs/_build/html"
"""The command that builds it, named by the 404 of an unbuilt guide."""

DOCS_ASSETS = "/docs-assets"
"""Where Swagger UI's and ReDoc's scripts are served from (the ``fastapi-offline`` package's copies)."""

DESCRIPTION = """Certified interference of two ellipses or ellipsoids (Caravantes, Diaz-Toca,
Fioravanti, Gonzalez-Vega, *Solving the interference problem for ellipses and ellipsoids: new
formulae*). A relation is the true relation of the exact input: JSON numbers are the binary
floats they are, strings like "3/7" or "0.1" are exact. Matrices are symmetric 3x3 (ellipse) or
4x4 (ellipsoid), interior X^T A X < 0; P(T) = det(T A + B), coefficients ascending."""


def create_api(settings: ApiSettings | None = None, *, guide_dir: Path | None = GUIDE_DIR) -> FastAPI:
    """The HTTP API as an ASGI app (serve it with uvicorn; nothing starts at import).

    Args:
        settings: limits and the scene link; defaults to ``ApiSettings()``.
        guide_dir: the built documentation site served at ``/guide/`` (looked for at each
            request, so a site built after the start is served; None: no guide).

    Returns:
        A FastAPI app with /api/classify, /api/explain, /api/analyse, the witness routes,
        /api/contacts, /api/sweep, /api/presets, /healthz, the landing page at / and OpenAPI
        docs at /docs.
    """
    settings = settings or ApiSettings()
    workers = WorkerPool(
        settings.max_concurrent_analyses,
        memory_mb=settings.memory_limit_mb,
        max_waiting=settings.max_queued_analyses,
        max_wait_s=settings.queue_wait_s,
    )

    batcher = PairBatcher(settings.request_budget_s)
    line = Line(settings.max_large_bodies, settings.queue_wait_s, settings.body_stall_s, settings.body_read_s)

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        warm_up(wait=False)  # compile the float filter in the background; exact/numpy meanwhile
        workers.start()
        yield
        workers.shutdown()
        batcher.stop()

    app = FastAPI(
        title="Ellipse & ellipsoid interference",
        version="0.1.0",
        description=DESCRIPTION,
        lifespan=lifespan,
        docs_url=None,  # served below with local assets: the docs work without internet
        redoc_url=None,
    )
    _offline_docs(app)
    app.state.settings = settings
    app.state.workers = workers
    app.state.batcher = batcher
    app.state.line = line
    # ignored: starlette types every handler as taking any Exception; this one is registered for its class only
    app.add_exception_handler(RequestValidationError, validation_error_handler)  # type: ignore[arg-type]
    app.add_exception_handler(InvalidInput, invalid_input_handler)  # type: ignore[arg-type]  # bad input: 422, once
    app.add_middleware(
        RequestLine,
        line=line,
        max_bytes=settings.max_body_bytes,
        # /api/sweep: start and end rows, twice the bytes of the same bodies in /api/contacts
        per_path={"/api/contacts": settings.max_contacts_body_bytes, "/api/sweep": 2 * settings.max_contacts_body_bytes},
    )
    if settings.cors_origins:  # opt-in (--cors-origin): pages at these origins may call the API
        from fastapi.middleware.cors import CORSMiddleware

        app.add_middleware(
            CORSMiddleware,
            allow_origins=list(settings.cors_origins),
            allow_methods=["GET", "HEAD", "POST"],
            allow_headers=["content-type"],
            expose_headers=["retry-after"],
            max_age=600,
        )
    for module in (classify, contacts, sweep, motion, presets, witness, health, landing):
        app.include_router(module.router)
    if settings.static_dir is not None and settings.static_dir.is_dir():
        app.mount("/static", StaticFiles(directory=settings.static_dir), name="static")
    if settings.bench_dir is not None:  # may be written later by python -m bench.report
        app.mount("/bench/figures", StaticFiles(directory=settings.bench_dir, check_dir=False), name="bench")
    if guide_dir is not None:
        app.mount(GUIDE, _Guide(directory=guide_dir, html=True, check_dir=False), name="guide")
    return app


class _Guide(StaticFiles):
    """The documentation site's files, or a one-line 404 saying how to build it while it is not built."""

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Serve the file asked for; 404 with the build command when the site's folder is missing."""
        if self.directory is None or not (Path(self.directory) / "index.html").is_file():
            message = f"The guide is not built on this server: run `{GUIDE_BUILD}` in the repository.\n"
            await PlainTextResponse(message, status_code=404)(scope, receive, send)
            return
        await super().__call__(scope, receive, send)


REDOC_JS = "/redoc-assets/redoc.standalone.js"
"""ReDoc's script as served: the local copy with its one remaining internet address replaced."""

REDOC_LOGO_URL = "https://cdn.redoc.ly/redoc/logo-mini.svg"
"""The "API docs by Redocly" logo the standalone script loads from a CDN on every page view."""

REDOC_LOGO = (
    "data:image/svg+xml,%3Csvg xmlns='http://www.w3.org/2000/svg' viewBox='0 0 16 16'%3E"
    "%3Ccircle cx='8' cy='8' r='6' fill='%23c33'/%3E%3C/svg%3E"
)
"""A small local stand-in for that logo (a data URI: no request at all)."""


@lru_cache(maxsize=1)
def _redoc_js(path: Any) -> bytes:
    """The ReDoc script with the CDN logo replaced by :data:`REDOC_LOGO` (read once).

    Raises:
        RuntimeError: the script no longer holds the logo's address (a new ReDoc: check the
            page for other internet requests, then update :data:`REDOC_LOGO_URL`).
    """
    text = path.read_text(encoding="utf-8")
    if REDOC_LOGO_URL not in text:
        raise RuntimeError(f"{path} does not load {REDOC_LOGO_URL} any more: check /redoc for other CDN requests")
    script: bytes = text.replace(REDOC_LOGO_URL, REDOC_LOGO).encode("utf-8")
    return script


def _offline_docs(app: FastAPI) -> None:
    """/docs (Swagger UI) and /redoc from local copies of their assets, not a CDN.

    FastAPI's default pages load their scripts from a CDN, so without internet /docs was blank.
    The ``fastapi-offline`` package ships the same assets; they are mounted at :data:`DOCS_ASSETS`.
    """
    from pathlib import Path

    import fastapi_offline
    from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
    from fastapi.responses import HTMLResponse, Response

    static = Path(fastapi_offline.__file__).parent / "static"
    app.mount(DOCS_ASSETS, StaticFiles(directory=static), name="docs-assets")
    title = app.title

    @app.get("/docs", include_in_schema=False)
    def swagger() -> HTMLResponse:
        return get_swagger_ui_html(
            openapi_url=app.openapi_url or "/openapi.json",
            title=f"{title} - Swagger UI",
            swagger_js_url=f"{DOCS_ASSETS}/swagger-ui-bundle.js",
            swagger_css_url=f"{DOCS_ASSETS}/swagger-ui.css",
            swagger_favicon_url=f"{DOCS_ASSETS}/favicon.png",
        )

    @app.get(REDOC_JS, include_in_schema=False)
    def redoc_js() -> Response:
        return Response(_redoc_js(static / "redoc.standalone.js"), media_type="application/javascript",
                        headers={"Cache-Control": "public, max-age=86400"})

    @app.get("/redoc", include_in_schema=False)
    def redoc() -> HTMLResponse:
        return get_redoc_html(
            openapi_url=app.openapi_url or "/openapi.json",
            title=f"{title} - ReDoc",
            redoc_js_url=REDOC_JS,
            redoc_favicon_url=f"{DOCS_ASSETS}/favicon.png",
            with_google_fonts=False,
        )
