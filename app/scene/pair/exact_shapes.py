"""The exact static shapes of a motion at the time shown: what "leave the motion" keeps when it can.

A motion drawn at t shows float poses; leaving it (a drag, a typed field, "(static shapes)",
Touch then edit) used to make the shapes the 10-digit decimals shown, which turns the tangency
just reached (an event, a Touch) into separate or overlap by 1e-8. At a rational time (an event
such as 2/3, a typed 3/4, a float's binary value) the motion's matrices are exact rationals;
:func:`exact_shapes_at` turns each into a static shape whose fields show that exact value in a
short form:

* centre, semi-axes and orientation when the exact centre with the shown semi-axes and
  orientation gives exactly the motion's matrix (a Touch: B keeps its body and moves);
* otherwise the exact matrix itself (the Matrix field), when its entries are short;
* otherwise nothing (the caller falls back to the marked 10-digit decimals, as before).

An irrational time, or entries in Q(√d) with d > 1 (the shape fields read rationals only), has
no exact static form here: the fallback.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from flint import fmpq, fmpq_mat

from core.algebra.algebraic import RealAlgebraic
from core.shapes.numbers import to_fmpq

from ..common.state import ShapeState
from ..common.texts import exact_text

if TYPE_CHECKING:
    from .motion import MotionModel

__all__ = ["exact_shapes_at", "exact_time", "SHORT_CHARS"]

SHORT_CHARS = 24
"""Longest text of one exact entry kept (longer ones: the marked decimals, as a drag gives)."""


def exact_time(t: Any) -> fmpq | None:
    """The rational value of a time (an fmpq, a float's binary value, a rational RealAlgebraic), else None."""
    if isinstance(t, RealAlgebraic):
        return None if t.value is None else to_fmpq(t.value)
    try:
        return to_fmpq(t)
    except (TypeError, ValueError, OverflowError):
        return None


def _short(values: Any) -> bool:
    return all(len(exact_text(v)) <= SHORT_CHARS for v in values)


def _rows_at(model: MotionModel, name: str, t: fmpq) -> list[list[fmpq]] | None:
    """The exact matrix of shape ``name`` at the rational t, or None (an entry in Q(√d), d > 1)."""
    out = []
    for row in getattr(model, name).matrix():
        cells = []
        for e in row:
            den = e.den(t)
            a, b = e.num.at(t)
            if b != 0 or den == 0:
                return None
            cells.append(to_fmpq(a / den))
        out.append(cells)
    return out


def _proportional(m: Any, e: list[list[fmpq]]) -> bool:
    """True when the matrix ``m`` is a positive multiple of ``e`` (the same quadric, same inside)."""
    m = [[to_fmpq(v) for v in row] for row in m]
    ratio = None
    for rm, re_ in zip(m, e, strict=True):
        for a, b in zip(rm, re_, strict=True):
            if (a == 0) != (b == 0):
                return False
            if b != 0:
                r = a / b
                if ratio is None:
                    ratio = r
                elif r != ratio:
                    return False
    return ratio is not None and ratio > 0


def _shape(rows: list[list[fmpq]], drawn: ShapeState) -> ShapeState | None:
    """A short exact static form of the quadric ``rows`` (``drawn``: its float pose), or None."""
    d = len(rows) - 1
    Q = fmpq_mat([list(r[:d]) for r in rows[:d]])
    try:
        c = Q.solve(fmpq_mat([[-r[d]] for r in rows[:d]]))
    except ZeroDivisionError:
        return None
    centre = tuple(c[i, 0] for i in range(d))
    try:
        rounded = drawn.rationalised()
    except ValueError:
        rounded = drawn
    if _short(centre) and all(isinstance(v, fmpq) for v in (*rounded.semi_axes, *rounded.orientation)):
        candidate = ShapeState(centre, rounded.semi_axes, rounded.orientation)
        try:
            if _proportional(candidate.quadric(), rows):
                return candidate
        except (ValueError, ArithmeticError):
            pass
    if all(_short(r) for r in rows):
        try:
            return ShapeState.from_matrix(rows)
        except ValueError:
            return None
    return None


def exact_shapes_at(model: MotionModel, t: Any, drawn: dict[str, ShapeState]) -> dict[str, ShapeState]:
    """The shapes of ``model`` at the exact time ``t`` that have a short exact static form.

    Args:
        model: the motion.
        t: the time shown, exactly (an event's RealAlgebraic, a typed rational, a float).
        drawn: the shapes drawn at t (floats), by name: their semi-axes and orientation, rounded
            as the fields show them, are tried first.

    Returns:
        name -> exact static shape, for the shapes that have one (possibly none).

    Examples:
        >>> from app.scene.pair.motion import load_motion
        >>> m = load_motion(preset=None, motion={
        ...     "A": '{"shape": {"center": [0, 0], "semi_axes": [1, 1]}}',
        ...     "B": '{"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["3*t", "0"]}',
        ...     "interval": "0, 1"})
        >>> shapes = exact_shapes_at(m, fmpq(2, 3), dict(zip("AB", m.shapes_at(2 / 3))))
        >>> shapes["B"].center, shapes["B"].semi_axes
        ((2, 0), (1, 1))
    """
    tq = exact_time(t)
    if tq is None:
        return {}
    out = {}
    for name, sh in drawn.items():
        rows = _rows_at(model, name, tq)
        if rows is None:
            continue
        exact = _shape(rows, sh)
        if exact is not None:
            out[name] = exact
    return out
