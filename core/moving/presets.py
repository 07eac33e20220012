"""Built-in moving pairs: the paper's Examples 29-33 and 2D cases whose answer is known by hand.

Each preset is a plain dict in the JSON motion format of :mod:`core.moving.motions` (the HTTP API and the
scene use the same format)::

    {"name": ..., "description": ..., "A": <motion>, "B": <motion>,
     "interval": [lo, hi]}            # strings (exact) or None for an infinite end

Motion convention (NOTES.md): x_world = R(t) x_body + c(t). ``analyse(**preset_arguments(name))``
runs a preset.
"""

from __future__ import annotations

import copy
from typing import Any

__all__ = ["PRESETS", "preset", "preset_names", "preset_arguments"]

_D30A = "(8*t^2 - 8*t + 3)"
_D30B = "(-6*t^2 + 6*t - 2)"

PRESETS: dict[str, dict[str, Any]] = {
    "example-29": {
        "description": "Paper Ex. 29: two ellipsoids on lines, s0 = 0 identically; tangent at (12 -+ 2 sqrt 2)/17, overlap between, t in [0, 1]",
        "A": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 1, 1]}, "translation": ["11 - 12*t", "0", "0"]},
        "B": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 1, 1]}, "translation": ["3", "4*t - 2", "4*t - 4"]},
        "interval": ["0", "1"],
    },
    "example-30": {
        "description": "Paper Ex. 30: degree-2 rational rotations (one with sqrt 2) and cubic translations; s0 of degree 84, tangent at four instants",
        "A": {
            "shape": {"center": [0, 0, 0], "semi_axes": [2, 4, 2]},
            "rotation": {"matrix": [
                [f"(-8*t^2 + 8*t - 1)/{_D30A}", f"(-4*t + 2)/{_D30A}", f"(4*t - 2)/{_D30A}"],
                [f"(4*t - 2)/{_D30A}", f"1/{_D30A}", f"2*(2*t - 1)^2/{_D30A}"],
                [f"(-4*t + 2)/{_D30A}", f"2*(2*t - 1)^2/{_D30A}", f"1/{_D30A}"],
            ]},
            "translation": ["-8*t^3 + 24*t^2 - 6*t - 2", "-24*t^3 + 24*t^2 + 6*t - 6", "-32*t^3 + 48*t^2 - 12*t - 2"],
        },
        "B": {
            "shape": {"center": [0, 0, 0], "semi_axes": [1, 3, 4]},
            "rotation": {"matrix": [
                [f"sqrt(2)*(t - 1)*(3*t - 1)/{_D30B}", f"2*t*(2*t - 1)/{_D30B}", f"sqrt(2)*(t - 1)^2/{_D30B}"],
                [f"sqrt(2)*(2*t - 1)/{_D30B}", f"-2*t*(t - 1)/{_D30B}", f"sqrt(2)*(2*t - 1)^2/{_D30B}"],
                [f"-sqrt(2)*t*(3*t - 2)/{_D30B}", f"2*(2*t - 1)*(t - 1)/{_D30B}", f"sqrt(2)*t^2/{_D30B}"],
            ]},
            "translation": [
                "(72 - 24*sqrt(2))*t^3 + (-156 + 72*sqrt(2))*t^2 + (114 - 72*sqrt(2))*t - 27 + 24*sqrt(2)",
                "12*t - 6",
                "(88 - 24*sqrt(2))*t^3 + (-168 + 72*sqrt(2))*t^2 + (114 - 72*sqrt(2))*t - 26 + 24*sqrt(2)",
            ],
        },
        "interval": [None, None],
    },
    "example-31": {
        "description": "Paper Ex. 31: touch and leave; tangent only at t = 4, separate elsewhere",
        "A": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 3, 4]}, "translation": ["0", "7", "0"]},
        "B": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 4, 2]}, "translation": ["0", "0", "(t - 4)/2"]},
        "interval": [None, None],
    },
    "example-32": {
        "description": "Paper Ex. 32: rational translations; tangent at -+ sqrt(5)/2, separate between, overlap outside",
        "A": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 3, 4]}, "translation": ["2*(t^2 - 1)/(t^2 + 1)", "-6*t/(t^2 + 1)", "0"]},
        "B": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 3, 2]}, "translation": ["-2*(t^2 - 2)/(t^2 + 1)", "6*t/(t^2 + 1)", "0"]},
        "interval": [None, None],
    },
    "example-33": {
        "description": "Paper Ex. 33: externally tangent for every t (s0 = 0 identically, s1 < 0, s1,0 > 0)",
        "A": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 3, 4]}, "translation": ["2*(t^2 - 1)/(t^2 + 1)", "-6*t/(t^2 + 1)", "0"]},
        "B": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 3, 2]}, "translation": ["-2*(t^2 - 1)/(t^2 + 1)", "6*t/(t^2 + 1)", "0"]},
        "interval": [None, None],
    },
    "circles-crossing": {
        "description": "2D: unit circles at (t, 0) and (-t, 0), centre distance 2|t|: overlap for |t| < 1, tangent at t = -+1",
        "A": {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["t", "0"]},
        "B": {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["-t", "0"]},
        "interval": ["-2", "2"],
    },
    "circles-graze": {
        "description": "2D: unit circle at (t, 2) passes over the unit circle at the origin: touch and leave at t = 0",
        "A": {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["t", "2"]},
        "B": {"shape": {"center": [0, 0], "semi_axes": [1, 1]}},
        "interval": ["-3", "3"],
    },
    "ellipse-spin": {
        "description": "2D: ellipse (2, 1) spinning at the origin (quaternion [1, t]) next to a unit circle at (3, 0): tangent only when the long axis points at it (t = 0)",
        "A": {"shape": {"center": [0, 0], "semi_axes": [2, 1]}, "rotation": {"quaternion": ["1", "t"]}},
        "B": {"shape": {"center": [3, 0], "semi_axes": [1, 1]}},
        "interval": ["-1", "1"],
    },
    "circles-sqrt2": {
        "description": "2D with sqrt(2) in the input: unit circles at (sqrt(2) t, 0) and the origin: tangent at t = -+sqrt(2), overlap between",
        "A": {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["sqrt(2)*t", "0"]},
        "B": {"shape": {"center": [0, 0], "semi_axes": [1, 1]}},
        "interval": [None, None],
    },
    "circles-endpoint": {
        "description": "2D: circles 2t apart on [1, 2]: tangent at the left end t = 1, separate after",
        "A": {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["t", "0"]},
        "B": {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["-t", "0"]},
        "interval": ["1", "2"],
    },
}
"""Presets by name (treat as read-only; :func:`preset` returns a deep copy)."""


def preset_names() -> list[str]:
    """Names of the built-in presets, paper examples first."""
    return list(PRESETS)


def preset(name: str) -> dict[str, Any]:
    """A deep copy of one preset (with its ``name``); ValueError listing the names if unknown.

    Examples:
        >>> preset("example-31")["interval"]
        [None, None]
    """
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; available: {', '.join(PRESETS)}")
    out = copy.deepcopy(PRESETS[name])
    out["name"] = name
    return out


def preset_arguments(name: str) -> dict[str, Any]:
    """Keyword arguments for :func:`core.moving.analysis.analyse`: ``A_t``, ``B_t``, ``interval``."""
    p = preset(name)
    return {"A_t": p["A"], "B_t": p["B"], "interval": tuple(p["interval"])}
