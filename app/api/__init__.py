"""HTTP API (FastAPI) over the certified classifier and the motion analyser.

Public API::

    from app.api import create_api, ApiSettings
    app = create_api(ApiSettings(scene_url="http://127.0.0.1:8080"))   # serve with uvicorn

Exports load lazily: the worker processes import the API's jobs (:mod:`app.api.jobs`) and models
without FastAPI, which only :mod:`app.api.factory` and the routes load.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .factory import create_api as create_api
    from .settings import ApiSettings as ApiSettings

__all__ = ["ApiSettings", "create_api"]

_HOME = {"ApiSettings": "settings", "create_api": "factory"}


def __getattr__(name: str) -> Any:
    if name in _HOME:
        return getattr(import_module(f".{_HOME[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
