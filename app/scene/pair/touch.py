"""Snap to contact: the motion that slides B along the line of centres until it touches A.

A drag in floats never lands exactly on a tangency; the exact contact is an event of a motion.
:func:`touch_motion` builds it from the static shapes, exactly: B keeps its body and moves by
``t * (c_B - c_A)`` relative to A's centre, so B's centre is ``c_A + t (c_B - c_A)`` (t = 1: where
B is now, t = 0: on A's centre). The direction is the exact rational difference of the centres
as typed (floats are their binary values). On ``I = [0, T]`` with T beyond the sum of the largest
semi-axes the relation is overlap near 0 and separate at T; the last event after which the
shapes are separate is the external tangency, an exact algebraic t that the scene shows with
its certified relation (:meth:`app.scene.pair.control_motion.MotionControl.analyse_pending`).
"""

from __future__ import annotations

import json
import math
from typing import Any

from core.moving.result import Event
from core.relation import Relation
from core.shapes.numbers import to_fmpq

from ..common.state import ShapeState

__all__ = ["touch_motion", "touch_event"]


def _exact(values: Any) -> list[str]:
    return [str(to_fmpq(v)) for v in values]


def touch_motion(a: ShapeState, b: ShapeState) -> dict[str, str]:
    """The editor texts {"A", "B", "interval"} of the touch motion of two static shapes.

    Raises:
        ValueError: the centres coincide (no line of centres).

    Examples:
        >>> from flint import fmpq
        >>> one = (fmpq(1), fmpq(1))
        >>> m = touch_motion(ShapeState((fmpq(0), fmpq(0)), one, (0.0,)), ShapeState((fmpq(3), fmpq(0)), one, (0.0,)))
        >>> json.loads(m["B"])["translation"], m["interval"]
        (['(0) + (3)*t', '(0) + (0)*t'], '0, 2')
    """
    ca, cb = [to_fmpq(v) for v in a.center], [to_fmpq(v) for v in b.center]
    d = [y - x for x, y in zip(ca, cb, strict=True)]
    if all(v == 0 for v in d):
        raise ValueError("Touch: the centres coincide, so there is no line of centres to slide along")
    norm = math.sqrt(sum(float(v) ** 2 for v in d))
    reach = max(float(v) for v in a.semi_axes) + max(float(v) for v in b.semi_axes)
    end = max(2, math.ceil(reach / norm) + 1)  # beyond it the centres are farther apart than any two points
    body_b: dict[str, object] = {"center": [0] * len(cb), "semi_axes": _exact(b.semi_axes)}
    body_a: dict[str, object] = {"center": _exact(a.center), "semi_axes": _exact(a.semi_axes)}
    for body, sh in ((body_a, a), (body_b, b)):
        o = sh.orientation
        if len(o) == 1:
            if o[0] != 0:
                body["orientation"] = float(o[0]) if isinstance(o[0], float) else float(to_fmpq(o[0]))
        else:
            body["orientation"] = _exact(o)
    # B's centre: c_A + t (c_B - c_A), exact rationals per axis
    translation = [f"({ci}) + ({di})*t" for di, ci in zip(d, ca, strict=True)]
    return {
        "A": json.dumps({"shape": body_a}),
        "B": json.dumps({"shape": body_b, "translation": translation}),
        "interval": f"0, {end}",
    }


def touch_event(events: list[Event]) -> int | None:
    """1-based index of the external tangency: the last event after which the shapes are separate."""
    for k in range(len(events), 0, -1):
        if events[k - 1].relation == Relation.TANGENT and events[k - 1].after == Relation.SEPARATE:
            return k
    return None
