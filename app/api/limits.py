"""Request-level guards: the contact search's per-request limits, validation errors.

Body sizes are limited where bodies arrive (:mod:`app.api.line`).

The library has no limits (``core.contacts`` answers any input it can hold); the server's
limits are applied here, at the edge, with messages that say what was asked, the limit and what
to do instead: :func:`contacts_limit_message` (the pairs the broad phase would examine, counted
before any is built: :class:`core.bodies.broadphase.TooManyPairs`) and
:func:`contacts_answer_message` (the pairs an answer would list, checked before it is built);
the same for ``/api/sweep`` (:func:`sweep_limit_message`, :func:`sweep_answer_message`) and its
exact times (:func:`sweep_times_message`).

FastAPI's default 422 handler echoes each offending input; a NaN there (Python's JSON reader
accepts the ``NaN`` token) cannot be written back as JSON and would turn the 422 into a 500,
and echoing a megabyte of input is waste. Our handler reports location, message and type only.
"""

from __future__ import annotations

from typing import Any

from fastapi import Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse

__all__ = [
    "validation_error_handler",
    "contacts_limit_message",
    "contacts_answer_message",
    "sweep_limit_message",
    "sweep_answer_message",
    "sweep_times_message",
]

_ELSEWHERE = "or search them with `python -m app contacts` or `core.contacts`, which have no such limit"
_SWEEP_ELSEWHERE = "or sweep them with `python -m app sweep` or `core.sweep_contacts`, which have no such limit"


def contacts_limit_message(bodies: int, pairs: int, limit: int) -> str:
    """422 detail: the broad phase would examine ``pairs`` pairs, over ``limit``.

    Examples:
        >>> contacts_limit_message(10_000, 49_995_000, 2_000_000)[:95]
        '10,000 bodies give 49,995,000 pairs to examine (bodies close enough that their bounding spheres'
    """
    return (
        f"{bodies:,} bodies give {pairs:,} pairs to examine (bodies close enough that their bounding spheres "
        f"may meet), over the limit of {limit:,} per request: send fewer or less crowded bodies, {_ELSEWHERE}"
    )


def contacts_answer_message(bodies: int, pairs: int, limit: int) -> str:
    """422 detail: the answer would list ``pairs`` pairs, over ``limit``."""
    return (
        f"the answer would list {pairs:,} pairs of the {bodies:,} bodies that touch or overlap, over the limit "
        f"of {limit:,} pairs per answer: send fewer bodies per request, {_ELSEWHERE}"
    )


def sweep_limit_message(bodies: int, pairs: int, limit: int) -> str:
    """422 detail of ``/api/sweep``: the swept broad phase would examine ``pairs`` pairs, over ``limit``.

    Examples:
        >>> sweep_limit_message(10_000, 49_995_000, 2_000_000)[:98]
        '10,000 moving bodies give 49,995,000 pairs to examine (bodies whose swept volumes may meet during '
    """
    return (
        f"{bodies:,} moving bodies give {pairs:,} pairs to examine (bodies whose swept volumes may meet during the "
        f"step), over the limit of {limit:,} per request: send fewer or less crowded bodies, {_SWEEP_ELSEWHERE}"
    )


def sweep_answer_message(bodies: int, pairs: int, limit: int) -> str:
    """422 detail of ``/api/sweep``: the answer would list ``pairs`` pairs, over ``limit``."""
    return (
        f"the answer would list {pairs:,} pairs of the {bodies:,} moving bodies that touch or overlap during the step, "
        f"over the limit of {limit:,} pairs per answer: send fewer bodies per request, {_SWEEP_ELSEWHERE}"
    )


def sweep_times_message(pairs: int, limit: int) -> str:
    """422 detail of ``/api/sweep``: ``exact_times`` for ``pairs`` pairs, over ``limit``."""
    return (
        f"exact_times: the answer lists {pairs:,} pairs, over the limit of {limit:,} exact times per answer (exact "
        "arithmetic per pair): ask without exact_times (t_lo, t_hi are certified brackets), send fewer bodies, or ask "
        "/api/analyse about one pair; `core.sweep_contacts(...).time(k)` has no such limit"
    )


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
