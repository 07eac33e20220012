"""Checks of a motion request before it is sent to a worker (fast 422s, limits from settings).

Every expression string is checked against ``max_expression_chars`` and parsed once with
``max_degree`` (core.expressions), so a typo is reported with its place in the request and its
position in the text; then core.motions reads the whole motion (structure, symmetry, square
roots). The worker parses again: parsing is cheap next to the analysis.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from core.expressions import parse_expression
from core.motions import motion_from_dict

from .settings import ApiSettings

__all__ = ["motion_payload", "check_motion"]


def motion_payload(m: Any) -> Any:
    """The JSON form core.motions reads, from the pydantic model (None fields dropped)."""
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


def check_motion(payload: Any, name: str, settings: ApiSettings) -> None:
    """Raise ValueError naming the place (``a.translation[0]: ...``) of the first problem."""
    for path, text in _strings(payload, name):
        if len(text) > settings.max_expression_chars:
            raise ValueError(f"{path}: expression too long ({len(text)} > {settings.max_expression_chars} characters)")
        try:
            parse_expression(text, max_degree=settings.max_degree)
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from None
    try:
        motion_from_dict(payload).matrix()
    except ValueError as e:
        raise ValueError(f"{name}: {e}") from None
