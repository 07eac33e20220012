"""Jobs run in the worker processes (module-level functions: picklable by reference)."""

from __future__ import annotations

from typing import Any

__all__ = ["analyse_job"]


def analyse_job(a: Any, b: Any, interval: list[Any], digits: int, polynomials: bool) -> dict[str, Any]:
    """:func:`core.parametric.analyse` as a JSON-ready dict (motions under ``a``/``b``)."""
    from core.parametric import analyse

    out = analyse(a, b, tuple(interval), digits=digits).to_dict(polynomials=polynomials)
    out["a"] = out.pop("A")
    out["b"] = out.pop("B")
    return out
