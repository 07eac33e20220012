"""Between the pydantic models and core: build matrices, call the classifier, map errors.

No mathematics here: shapes go to :func:`core.quadric_from_axes`, matrices to
:func:`core.validate_quadric` (so every bad matrix is named "a" or "b", as in the JSON), and the
relation comes from :func:`core.classify`. A core ``ValueError`` becomes a 422 whose detail is
the core message, prefixed with where in the request the culprit is.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
from fastapi import HTTPException

from core import Relation, classify, quadric_from_axes, validate_quadric
from core.rationals import to_fmpq

from .schemas import ClassifyOut, PairItem, ShapeIn

__all__ = ["bad_input", "quadric_input", "checked_pair", "classify_pair"]


@contextmanager
def bad_input(where: str = "") -> Iterator[None]:
    """Turn a core ``ValueError`` into HTTP 422 with its message (prefixed by ``where``)."""
    try:
        yield
    except (ValueError, ArithmeticError) as e:  # ArithmeticError: e.g. a number too big for a float
        raise HTTPException(status_code=422, detail=f"{where}{e}") from None


def _is_exact(v: Any) -> bool:
    return not isinstance(v, float)


def quadric_input(q: list[list[Any]] | ShapeIn) -> Any:
    """Core input for a matrix or a shape.

    A shape is built **exactly** (rational matrix) when no number in it is a JSON float and the
    orientation is absent or a quaternion; otherwise in float64 (number strings are rounded to
    the nearest double and a 2D angle is radians), and that float matrix is then taken as the
    exact binary rationals it holds, like any float input.
    """
    if not isinstance(q, ShapeIn):
        return q
    orientation = q.orientation
    if len(q.center) == 3 and orientation is not None and not isinstance(orientation, list):
        raise ValueError("a 3D orientation is a quaternion [w, x, y, z], not an angle")
    values = [*q.center, *q.semi_axes]
    if isinstance(orientation, list):
        values += orientation
    exact = all(_is_exact(v) for v in values) and (orientation is None or isinstance(orientation, list))
    if exact:
        return quadric_from_axes(q.center, q.semi_axes, orientation, exact=True)

    def fl(v: Any) -> float:
        try:
            return v if isinstance(v, float) else float(to_fmpq(v))
        except OverflowError:
            raise ValueError(f"{v!r} is too large for a float (this shape is built in floats)") from None

    if isinstance(orientation, list):
        orientation = [fl(v) for v in orientation]
    elif orientation is not None:
        orientation = fl(orientation)
    return quadric_from_axes([fl(v) for v in q.center], [fl(v) for v in q.semi_axes], orientation)


_EXACT_FLOAT_INT = 2**53
"""Integers below this are exactly representable as float64."""


def _as_float64_if_exact(m: Any) -> Any:
    """A float64 array when every entry is a JSON float or a float-exact integer (same values,
    so the float filter can run on e.g. ``[[1, 0, -3.5], ...]``); otherwise unchanged.
    """
    if isinstance(m, np.ndarray):
        return m
    flat = [v for row in m for v in row]
    if all(isinstance(v, float) or (type(v) is int and abs(v) < _EXACT_FLOAT_INT) for v in flat):
        return np.array(m, dtype=np.float64)
    return m


def checked_pair(pair: PairItem, where: str = "") -> tuple[Any, Any]:
    """Both shapes as core input, validated (422 naming "a" or "b" otherwise)."""
    out = []
    for name, q in (("a", pair.a), ("b", pair.b)):
        with bad_input(f"{where}{name}: "):
            m = quadric_input(q)
        with bad_input(where):
            validate_quadric(m, name=name)
        out.append(_as_float64_if_exact(m))
    a, b = out
    if len(a) != len(b):
        raise HTTPException(
            status_code=422,
            detail=f"{where}a is {len(a)}x{len(a)} and b is {len(b)}x{len(b)}: both must be ellipses (3x3) or both ellipsoids (4x4)",
        )
    return a, b


def classify_pair(pair: PairItem, method: str, where: str = "") -> ClassifyOut:
    """Certified relation of one pair, with the arithmetic that certified it.

    ``adaptive`` asks the float filter first and exact rationals only when it abstains, so the
    answer says which of the two decided (per pair, without shared counters).
    """
    a, b = checked_pair(pair, where)
    with bad_input(where):
        if method == "exact":
            rel, by = classify(a, b, method="exact"), "exact"
        else:
            rel, by = classify(a, b, method="float"), "float"
            if rel == Relation.UNDECIDED and method == "adaptive":
                rel, by = classify(a, b, method="exact"), "exact"
    return ClassifyOut(
        relation=str(rel),
        certified_by=None if rel == Relation.UNDECIDED else by,
        kind="ellipse" if len(a) == 3 else "ellipsoid",
        method=method,
    )
