"""The motion editor's form: a moving shape as fields (shape, translation per axis, rotation, scale).

The JSON box of the motion editor takes any motion of :mod:`core.moving.motions`; the form is
the same "shape" form field by field, easier to type in a classroom: each field is a list of
expressions in t separated by commas (``11 - 12*t, 0, 0``), the rotation a quaternion whose
components are expressions (``1, t`` turns an ellipse about z; ``1, 0, 0, t`` an ellipsoid).
:func:`source_from_form` writes the JSON form (read and checked in a worker process, like typed
JSON); :func:`form_from_source` fills the form from a motion when it has that form.
"""

from __future__ import annotations

import json
from typing import Any

__all__ = ["FORM_FIELDS", "form_from_source", "source_from_form", "form_text"]

FORM_FIELDS = ("center", "semi_axes", "orientation", "translation", "rotation", "scale")
"""Fields of one shape in the form (labels in :mod:`app.scene.pair.gui`)."""


def _join(values: Any) -> str:
    return ", ".join(str(v) for v in values)


def _split(text: str) -> list[str]:
    return [p.strip() for p in text.split(",") if p.strip()]


def form_from_source(source: Any) -> dict[str, str] | None:
    """The form's texts for a motion in the "shape" form.

    None for a "matrix" motion or a rotation given as a matrix: those are edited as JSON.

    Examples:
        >>> form_from_source({"shape": {"center": [0, 0], "semi_axes": [2, 1]}, "rotation": {"quaternion": ["1", "t"]}})
        {'center': '0, 0', 'semi_axes': '2, 1', 'orientation': '', 'translation': '', 'rotation': '1, t', 'scale': ''}
    """
    if not isinstance(source, dict) or "shape" not in source:
        return None
    rot = source.get("rotation")
    if rot is not None and "quaternion" not in rot:
        return None
    shape = source["shape"]
    ori = shape.get("orientation")
    return {
        "center": _join(shape.get("center", [])),
        "semi_axes": _join(shape.get("semi_axes", [])),
        "orientation": "" if ori is None else (str(ori) if isinstance(ori, int | float) else _join(ori)),
        "translation": _join(source.get("translation", [])),
        "rotation": "" if rot is None else _join(rot["quaternion"]),
        "scale": _join(source.get("scale", [])),
    }


def source_from_form(fields: dict[str, str]) -> dict[str, Any]:
    """The JSON form of a motion from the form's texts (empty fields are left out).

    Raises:
        ValueError: the centre or the semi-axes are missing.

    Examples:
        >>> source_from_form({"center": "0, 0, 0", "semi_axes": "2, 1, 1", "translation": "11 - 12*t, 0, 0"})
        {'shape': {'center': ['0', '0', '0'], 'semi_axes': ['2', '1', '1']}, 'translation': ['11 - 12*t', '0', '0']}
    """
    center, axes = _split(fields.get("center", "")), _split(fields.get("semi_axes", ""))
    if not center or not axes:
        raise ValueError("the form needs the centre and the semi-axes of the shape")
    shape: dict[str, Any] = {"center": center, "semi_axes": axes}
    ori = _split(fields.get("orientation", ""))
    if ori:
        shape["orientation"] = ori
    out: dict[str, Any] = {"shape": shape}
    for key in ("translation", "scale"):
        parts = _split(fields.get(key, ""))
        if parts:
            out[key] = parts
    rot = _split(fields.get("rotation", ""))
    if rot:
        out["rotation"] = {"quaternion": rot}
    return out


def form_text(fields: dict[str, str]) -> str:
    """The JSON text of :func:`source_from_form` (what the JSON box then shows)."""
    return json.dumps(source_from_form(fields))
