"""Jobs run in the worker processes (module-level functions: picklable by reference)."""

from __future__ import annotations

from typing import Any

from core.shapes.limits import Limits

__all__ = ["analyse_job"]


def analyse_job(a: Any, b: Any, interval: list[Any], digits: int, polynomials: bool, limits: Limits) -> dict[str, Any]:
    """Read both motions under ``limits``, then :func:`core.moving.analysis.analyse` as a JSON-ready dict.

    The request's text is parsed here, in the worker, never in the server process.
    """
    from core.moving.analysis import analyse

    from .motion_input import check_interval, check_motion

    ma, mb = check_motion(a, "a", limits), check_motion(b, "b", limits)
    check_interval(interval, limits)
    out = analyse(ma, mb, tuple(interval), digits=digits).to_dict(polynomials=polynomials)
    out["a"] = out.pop("A")
    out["b"] = out.pop("B")
    return out
