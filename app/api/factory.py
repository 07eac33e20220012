"""create_api(): the FastAPI application (routers, limits, worker pool, static files)."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from fastapi import FastAPI
from fastapi.exceptions import RequestValidationError
from fastapi.staticfiles import StaticFiles

from core import warm_up

from ..workers import WorkerPool
from .limits import BodySizeLimit, validation_error_handler
from .routes import classify, health, landing, motion, presets, witness
from .settings import ApiSettings

__all__ = ["create_api"]

DESCRIPTION = """Certified interference of two ellipses or ellipsoids (Caravantes, Diaz-Toca,
Fioravanti, Gonzalez-Vega, *Solving the interference problem for ellipses and ellipsoids: new
formulae*). A relation is the true relation of the exact input: JSON numbers are the binary
floats they are, strings like "3/7" or "0.1" are exact. Matrices are symmetric 3x3 (ellipse) or
4x4 (ellipsoid), interior X^T A X < 0; P(T) = det(T A + B), coefficients ascending."""


def create_api(settings: ApiSettings | None = None) -> FastAPI:
    """The HTTP API as an ASGI app (serve it with uvicorn; nothing starts at import).

    Args:
        settings: limits and the scene link; defaults to ``ApiSettings()``.

    Returns:
        A FastAPI app with /api/classify, /api/explain, /api/analyse, /api/presets, /healthz,
        the landing page at / and OpenAPI docs at /docs.
    """
    settings = settings or ApiSettings()
    workers = WorkerPool(
        settings.max_concurrent_analyses,
        memory_mb=settings.memory_limit_mb,
        preload=("core", "core.moving.analysis", "app.api.jobs"),
    )

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        warm_up(wait=False)  # compile the float filter in the background; exact/numpy meanwhile
        workers.start()
        yield
        workers.shutdown()

    app = FastAPI(
        title="Ellipse & ellipsoid interference",
        version="0.1.0",
        description=DESCRIPTION,
        lifespan=lifespan,
    )
    app.state.settings = settings
    app.state.workers = workers
    app.add_exception_handler(RequestValidationError, validation_error_handler)
    app.add_middleware(BodySizeLimit, max_bytes=settings.max_body_bytes)
    for module in (classify, motion, presets, witness, health, landing):
        app.include_router(module.router)
    if settings.static_dir is not None and settings.static_dir.is_dir():
        app.mount("/static", StaticFiles(directory=settings.static_dir), name="static")
    if settings.bench_dir is not None:  # may be written later by python -m bench.report
        app.mount("/bench/figures", StaticFiles(directory=settings.bench_dir, check_dir=False), name="bench")
    return app
