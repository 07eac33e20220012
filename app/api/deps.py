"""Dependencies of the routes: the settings and the worker pool of this app instance.

Both live on ``app.state`` (set by :func:`app.api.create_api`), are reached through ``Depends``
and can be swapped in tests with ``app.dependency_overrides[get_settings] = ...``.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from ..workers import WorkerPool
from .settings import ApiSettings

__all__ = ["get_settings", "get_workers", "SettingsDep", "WorkersDep"]


def get_settings(request: Request) -> ApiSettings:
    """Settings of the app serving this request."""
    return request.app.state.settings


def get_workers(request: Request) -> WorkerPool:
    """Process pool for motion analyses of the app serving this request."""
    return request.app.state.workers


SettingsDep = Annotated[ApiSettings, Depends(get_settings)]
WorkersDep = Annotated[WorkerPool, Depends(get_workers)]
