"""The presets shared with the scene (core.presets), read defensively.

core.presets is written in parallel with the API; until it exists the API serves no presets
(GET /api/presets returns an empty list) instead of failing to start.
"""

from __future__ import annotations

from typing import Any

__all__ = ["preset_summaries"]


def _presets() -> dict[str, Any]:
    try:
        from core import presets  # noqa: PLC0415
    except ImportError:
        return {}
    table = getattr(presets, "PRESETS", None)
    return dict(table) if isinstance(table, dict) else {}


def preset_summaries() -> list[tuple[str, str]]:
    """(name, one-line description) of every preset, in catalogue order."""
    out = []
    for name, p in _presets().items():
        desc = p.get("description", "") if isinstance(p, dict) else getattr(p, "description", "")
        out.append((str(name), str(desc)))
    return out
