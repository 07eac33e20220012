"""Reading a motion request inside the analysis worker: every string parsed under the limits.

Runs in the worker process (:func:`app.api.jobs.analyse_job`), never in the server process: a
hostile expression costs at most the worker's time and memory budget. Every expression string
is parsed once under the API's limits (:meth:`app.api.settings.ApiSettings.text_limits`), so a
typo or an oversized constant is reported with its place in the request
(``a.translation[0]: ...``) and its position in the text; then core.moving.motions builds each motion
(structure, symmetry, square roots) under the same limits.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from core.moving.expressions import parse_expression
from core.moving.motions import Motion, motion_from_dict
from core.shapes.limits import Limits
from core.shapes.numbers import parse_number

__all__ = ["motion_payload", "check_motion", "check_interval"]

_INFINITE = ("inf", "+inf", "-inf", "infinity", "-infinity", "+infinity")


def motion_payload(m: Any) -> Any:
    """The JSON form core.moving.motions reads, from the pydantic model (None fields dropped)."""
    if isinstance(m, list):
        return {"matrix": m}
    return m.model_dump(exclude_none=True)


def _strings(x: Any, path: str) -> Iterator[tuple[str, str]]:
    if isinstance(x, str):
        yield path, x
    elif isinstance(x, dict):
        for k, v in x.items():
            yield from _strings(v, f"{path}.{k}")
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from _strings(v, f"{path}[{i}]")


def check_motion(payload: Any, name: str, limits: Limits) -> Motion:
    """The motion, built under ``limits``; ValueError naming the place (``a.translation[0]: ...``)."""
    for path, text in _strings(payload, name):
        try:
            parse_expression(text, limits=limits)
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from None
    try:
        m = motion_from_dict(payload, limits=limits)
        m.matrix()
    except ValueError as e:
        raise ValueError(f"{name}: {e}") from None
    return m


def check_interval(interval: list[Any], limits: Limits) -> None:
    """Number strings of the interval ends under ``limits`` (ValueError naming the end)."""
    for which, end in zip(("lo", "hi"), interval, strict=True):
        if isinstance(end, str) and end.strip().lower() not in _INFINITE:
            try:
                parse_number(end, limits)
            except ValueError as e:
                raise ValueError(f"interval {which}: {e}") from None
