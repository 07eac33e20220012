"""Dependencies of the routes: the settings, the worker pool, the pair batcher and the line of this app.

They live on ``app.state`` (set by :func:`app.api.create_api`), are reached through ``Depends``
and can be swapped in tests with ``app.dependency_overrides[get_settings] = ...``.

The getters are ``async`` so that FastAPI calls them on the event loop: a plain function
dependency runs in a thread of anyio's pool (40 threads, shared with the work that waits there
for a worker process), so ``/healthz`` (three dependencies) waited for a free thread when the
pool was taken, and made three thread round trips on a loaded machine.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from ..workers import WorkerPool
from .batching import PairBatcher
from .line import Line
from .settings import ApiSettings

__all__ = ["get_settings", "get_workers", "get_batcher", "get_line", "SettingsDep", "WorkersDep", "BatcherDep", "LineDep"]


async def get_settings(request: Request) -> ApiSettings:
    """Settings of the app serving this request."""
    settings: ApiSettings = request.app.state.settings
    return settings


async def get_workers(request: Request) -> WorkerPool:
    """Process pool for motion analyses of the app serving this request."""
    workers: WorkerPool = request.app.state.workers
    return workers


async def get_batcher(request: Request) -> PairBatcher:
    """The thread that classifies single pairs of JSON numbers together, off the event loop."""
    batcher: PairBatcher = request.app.state.batcher
    return batcher


async def get_line(request: Request) -> Line:
    """The places of large request bodies and their reader (:mod:`app.api.line`)."""
    line: Line = request.app.state.line
    return line


SettingsDep = Annotated[ApiSettings, Depends(get_settings)]
WorkersDep = Annotated[WorkerPool, Depends(get_workers)]
BatcherDep = Annotated[PairBatcher, Depends(get_batcher)]
LineDep = Annotated[Line, Depends(get_line)]
