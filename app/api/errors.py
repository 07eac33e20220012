"""The app's answers to errors: one place maps each kind of error to its HTTP answer.

* :func:`invalid_input_handler`: bad input, :class:`core.InvalidInput` (raised by core, by
  :mod:`app.api.convert` and the jobs of :mod:`app.api.jobs`, in a server thread or carried back
  from a worker process), answers 422 ``{"detail": message}``, with ``"pair"`` (its index in the
  request's batch) and ``"matrix"`` ("a", "b") when known. Nothing below the routes knows HTTP.
* :func:`validation_error_handler`: a request that does not fit its schema. FastAPI's default 422
  handler echoes each offending input; a NaN there (Python's JSON reader accepts the ``NaN``
  token) cannot be written back as JSON and would turn the 422 into a 500, and echoing a megabyte
  of input is waste. Ours reports location, message and type only.
"""

from __future__ import annotations

from typing import Any

from fastapi import Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse

from core import InvalidInput

__all__ = ["invalid_input_handler", "validation_error_handler"]


async def invalid_input_handler(request: Request, exc: InvalidInput) -> JSONResponse:
    """422 with ``{"detail": message}`` plus ``"pair"`` and ``"matrix"`` where the error says them."""
    content: dict[str, Any] = {"detail": str(exc)}
    if exc.pair is not None:
        content["pair"] = exc.pair
    if exc.matrix is not None:
        content["matrix"] = exc.matrix
    return JSONResponse(status_code=422, content=content)


def _clean(error: dict[str, Any]) -> dict[str, Any]:
    msg = str(error.get("msg", ""))
    ctx = error.get("ctx") or {}
    if error.get("type") == "json_invalid" and "error" in ctx:
        msg = f"{msg}: {ctx['error']}"
    return {"loc": [p if isinstance(p, int) else str(p) for p in error.get("loc", ())], "msg": msg,
            "type": str(error.get("type", ""))}


def _is_json(content_type: str) -> bool:
    media = content_type.split(";", 1)[0].strip().lower()
    return media == "application/json" or (media.startswith("application/") and media.endswith("+json"))


async def validation_error_handler(request: Request, exc: RequestValidationError) -> JSONResponse:
    """422 with ``{"detail": [{"loc", "msg", "type"}, ...]}`` (no echo of the input).

    As the OpenAPI schema declares: 400 when there is no JSON to validate (malformed JSON, or
    an empty body), 422 when the JSON does not fit the schema or a value is invalid.

    A body sent without a JSON content type (``curl -d`` sends a form type) is not read as JSON
    by FastAPI; say so (415) instead of reporting a missing object.
    """
    errors = exc.errors()
    content_type = request.headers.get("content-type", "")
    if any(tuple(e.get("loc", ()))[:1] == ("body",) for e in errors) and not _is_json(content_type):
        got = f"got {content_type!r}" if content_type else "no content-type header"
        return JSONResponse(
            status_code=415,
            content={"detail": f"send the body as JSON with the header 'content-type: application/json' ({got})"},
        )
    unreadable = [e for e in errors if e.get("type") == "json_invalid" or (tuple(e.get("loc", ())) == ("body",) and e.get("type") == "missing")]
    if unreadable:  # the schema's 400: no JSON to validate (malformed, or no body at all)
        return JSONResponse(status_code=400, content={"detail": [_clean(e) for e in unreadable]})
    return JSONResponse(status_code=422, content={"detail": [_clean(e) for e in errors]})
