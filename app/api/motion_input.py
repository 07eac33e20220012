"""The JSON form of a motion request, for core's reader.

The pydantic models of :mod:`app.api.motion_schemas` check the shape of a request; the text in
it (every expression, the interval) is read only in the analysis worker, by core's readers
(:func:`app.jobs.analyse_job`: :func:`core.moving.motions.read_motion` and
:func:`core.moving.motions.read_interval`, under the API's limits, each expression parsed once
and an error named by its place: ``a.translation[0]: ...``).
"""

from __future__ import annotations

from typing import Any

__all__ = ["motion_payload"]


def motion_payload(m: Any) -> Any:
    """The JSON form core.moving.motions reads, from the pydantic model (None fields dropped)."""
    if isinstance(m, list):
        return {"matrix": m}
    return m.model_dump(exclude_none=True)
