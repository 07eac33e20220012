"""Reading request bodies as JSON without silent changes: the route class of every API router.

Python's JSON reader turns ``1e-400`` into 0.0 and ``1e400`` into inf, reads a 5,000-digit
integer in quadratic time (or refuses it with a bare error), and reports a deeply nested body as
a generic parse error. :class:`JsonRoute` reads bodies with hooks instead: a number that a float
cannot hold, or an integer over the edge limit, becomes an :class:`OutOfRange` marker that the
number validator (:func:`app.api.schemas.checked_number`) refuses with a message naming the
field; a body nested too deeply is a 400 that says so. A large body is read and validated as
the route's model in a worker thread, one at a time and in its turn (:meth:`app.api.line.Line.parse`:
its wait is bounded, 503 beyond), so a burst of them leaves the event loop (and ``/healthz``)
answering.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Coroutine
from typing import Any

from fastapi import HTTPException, Request, Response
from fastapi.routing import APIRoute
from pydantic import BaseModel, ValidationError

from core.shapes.limits import SERVER

from .line import INLINE_BYTES, Line
from .schemas import OutOfRange

__all__ = ["INLINE_BYTES", "JsonRoute", "OutOfRange", "read_json"]

_NONZERO = frozenset("123456789")


def _shown(text: str) -> str:
    return text if len(text) <= 40 else f"{text[:20]}...({len(text)} characters)"


def _float(text: str) -> float | OutOfRange:
    value = float(text)
    if value - value != 0.0:  # inf: the literal overflows a double
        return OutOfRange(text, f"JSON number {_shown(text)} overflows a float (|x| > 1.8e308); "
                                f'send it as a string ("{_shown(text)}") for its exact value')
    if value == 0.0 and _NONZERO.intersection(text.split("e")[0].split("E")[0]):
        return OutOfRange(text, f"JSON number {_shown(text)} underflows to 0 as a float; "
                                f'send it as a string ("{_shown(text)}") for its exact value')
    return value


def _int(text: str) -> int | OutOfRange:
    digits = len(text.lstrip("-"))
    limit = SERVER.number_chars or 0
    if limit and digits > limit:
        return OutOfRange(text, f"integer too large (more than {limit} digits); send it as a string fraction")
    return int(text)


def read_json(body: bytes | str) -> Any:
    """Parse a request body like ``json.loads``, with the markers above.

    Raises:
        json.JSONDecodeError: malformed JSON (FastAPI answers 422 with the position).
        HTTPException: 400 when the body is nested too deeply for the reader.

    Examples:
        >>> read_json('[1.5, 1e-400, 2]')
        [1.5, OutOfRange('1e-400'), 2]
    """
    try:
        return json.loads(body, parse_float=_float, parse_int=_int)
    except RecursionError:
        raise HTTPException(
            400,
            "JSON nested too deeply: the body has more levels of [ and { than the JSON reader allows "
            "(about 1000); the inputs of this API need at most 5",
        ) from None


def _read_checked(body: bytes, model: type[BaseModel] | None) -> Any:
    """The body read, and validated as ``model`` when it can be: the model instance, else the data.

    FastAPI validates what :meth:`Request.json` returns: a model instance passes as it is
    (microseconds), while invalid data is validated again by FastAPI, on the loop, so that every
    422 has the one format of the API.
    """
    data = read_json(body)
    if model is None:
        return data
    try:
        return model.model_validate(data)
    except ValidationError:
        return data


class _JsonRequest(Request):
    model: type[BaseModel] | None = None
    """The route's body model (a single, not embedded, pydantic model), else None."""

    async def json(self) -> Any:
        if not hasattr(self, "_json"):
            body = await self.body()
            if len(body) <= INLINE_BYTES:
                self._json = read_json(body)
            else:
                line: Line = self.app.state.line
                self._json = await line.parse(self, _read_checked, body, self.model)
        return self._json


class JsonRoute(APIRoute):
    """APIRoute whose handler reads JSON with :func:`read_json` (FastAPI's custom-route hook).

    A large body is read and validated in a worker thread, one body at a time, in its turn
    (:meth:`app.api.line.Line.parse`).
    """

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        """The default handler, given a request that parses its body with :func:`read_json`."""
        handler = super().get_route_handler()
        model = _body_model(self)

        async def route_handler(request: Request) -> Response:
            wrapped = _JsonRequest(request.scope, request.receive)
            wrapped.model = model
            return await handler(wrapped)

        return route_handler


def _body_model(route: APIRoute) -> type[BaseModel] | None:
    """The pydantic model of a route's whole body (one body parameter, not embedded), else None."""
    field = route.body_field
    if field is None or getattr(route, "_embed_body_fields", True):
        return None
    annotation = field.field_info.annotation
    return annotation if isinstance(annotation, type) and issubclass(annotation, BaseModel) else None
