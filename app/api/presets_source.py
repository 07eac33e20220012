"""The presets shared with the scene (:mod:`core.moving.presets`), in the input format of /api/analyse.

core.moving.presets stores ``{"description", "A", "B", "interval"}``; the API speaks ``a``/``b``
(lower case, as in /api/classify), so a preset fetched from GET /api/presets/NAME can be posted
to /api/analyse unchanged. If core.moving.presets is missing the API serves no presets rather than
failing to start.
"""

from __future__ import annotations

from typing import Any

__all__ = ["preset_summaries", "api_presets", "api_preset"]


def _table() -> dict[str, dict[str, Any]]:
    try:
        from core.moving.presets import PRESETS
    except ImportError:
        return {}
    return PRESETS


def _api_form(name: str, p: dict[str, Any]) -> dict[str, Any]:
    return {
        "name": name,
        "description": p.get("description", ""),
        "a": p["A"],
        "b": p["B"],
        "interval": list(p.get("interval") or [None, None]),
    }


def api_presets() -> list[dict[str, Any]]:
    """Every preset in API form, catalogue order."""
    return [_api_form(name, p) for name, p in _table().items()]


def api_preset(name: str) -> dict[str, Any]:
    """One preset in API form.

    Raises:
        KeyError: unknown name (the message lists the available ones).
    """
    table = _table()
    if name not in table:
        raise KeyError(f"unknown preset {name!r}; available: {', '.join(table) or 'none'}")
    return _api_form(name, table[name])


def preset_summaries() -> list[tuple[str, str]]:
    """(name, one-line description) of every preset, in catalogue order."""
    return [(name, str(p.get("description", ""))) for name, p in _table().items()]
