"""Exact text a user types in the scene: numbers, vectors, matrices, times; and numbers shown back.

Typed text stays exact: "3/7" is the rational 3/7, "0.1" is 1/10, "(12-2*sqrt(2))/17" an algebraic
number; a float (a drag, a motion drawn at t) is the exact binary rational it is. Every reader
applies the scene's edge limits (:data:`core.shapes.limits.SERVER`) and names the field in its
message.
"""

from __future__ import annotations

import math
from typing import Any

from flint import fmpq

from core.algebra.algebraic import RealAlgebraic
from core.algebra.closedform import algebraic_from_quadratic
from core.moving.expressions import parse_expression
from core.shapes.limits import SERVER
from core.shapes.numbers import format_rational, parse_number, to_float, to_fmpq

__all__ = ["Number", "parse_vector", "parse_matrix", "read_time", "time_float", "format_number"]

Number = float | fmpq
"""A shape parameter: a float (its exact binary value) or an exact rational (typed text)."""


def parse_vector(text: Any, count: int | tuple[int, ...], what: str) -> tuple[Number, ...]:
    """Read ``count`` numbers from "1, 2/3, 0.5" (or a JSON list); exact for typed text.

    Args:
        text: a string of comma/space separated numbers, or a sequence of numbers/strings.
        count: accepted number(s) of components.
        what: field name for the error message.

    Returns:
        A tuple of floats (for float input) or ``fmpq`` (for strings and ints).

    Raises:
        ValueError: wrong count or an unreadable component (the message names the field).

    Examples:
        >>> parse_vector("1, 3/7  0.5", 3, "centre")
        (1, 3/7, 1/2)
        >>> parse_vector([1.5, "2"], 2, "centre")
        (1.5, 2)
        >>> parse_vector("1, x", 2, "centre")
        Traceback (most recent call last):
        ...
        ValueError: centre: component 2: not a number: 'x' (expected e.g. '3', '-0.25', '1e-3' or '3/7')
    """
    counts = (count,) if isinstance(count, int) else count
    if isinstance(text, str):
        parts: list[Any] = [p for p in text.replace(",", " ").replace(";", " ").split() if p]
    elif isinstance(text, int | float):
        parts = [text]
    else:
        try:
            parts = list(text)
        except TypeError:
            raise ValueError(f"{what}: expected numbers, got {text!r}") from None
    if len(parts) not in counts:
        want = " or ".join(str(c) for c in counts)
        raise ValueError(f"{what}: expected {want} numbers, got {len(parts)}")
    out: list[Number] = []
    for i, p in enumerate(parts, start=1):
        try:
            if isinstance(p, float):
                if not math.isfinite(p):
                    raise ValueError(f"not finite: {p}")
                out.append(p)
            elif isinstance(p, str):  # typed text: the scene's edge limits (core.shapes.limits.SERVER)
                out.append(parse_number(p, SERVER))
            else:
                out.append(to_fmpq(p))
        except ValueError as e:
            raise ValueError(f"{what}: component {i}: {e}") from None
    return tuple(out)


def read_time(text: str) -> fmpq | RealAlgebraic:
    """An exact time from text: a number, a fraction, or an expression with sqrt of constants.

    Parsed by the bounded expression parser (:mod:`core.moving.expressions`, the scene's limits);
    the value must not depend on t.

    Raises:
        ValueError: unreadable, or not a constant.

    Examples:
        >>> read_time("2/3"), read_time("1e-3")
        (2/3, 1/1000)
        >>> read_time("(12-2*sqrt(2))/17").decimal(10)
        '0.5395042868'
        >>> read_time("t + 1")
        Traceback (most recent call last):
        ...
        ValueError: t must be a number, not an expression in t
    """
    rf = parse_expression(text.strip(), limits=SERVER)
    if rf.den.degree() > 0 or rf.num.p.degree() > 0 or rf.num.q.degree() > 0:
        raise ValueError("t must be a number, not an expression in t")
    a = rf.num.p[0] if rf.num.p.degree() == 0 else fmpq(0)
    b = rf.num.q[0] if rf.num.q.degree() == 0 else fmpq(0)
    if b == 0:
        return fmpq(a)
    return algebraic_from_quadratic(fmpq(a), fmpq(b), int(rf.num.d))


def parse_matrix(text: Any, dim: int, what: str) -> list[list[Number]]:
    """Read a (dim+1) x (dim+1) matrix: rows separated by ";" or new lines, or a JSON-like list.

    Raises:
        ValueError: wrong size or an unreadable entry (the message names the field).

    Examples:
        >>> parse_matrix("1, 0, -2; 0, 1, 0; -2, 0, 3", 2, "A.matrix")[2]
        [-2, 0, 3]
        >>> parse_matrix("1 0; 0 1", 2, "A.matrix")
        Traceback (most recent call last):
        ...
        ValueError: A.matrix: expected 3 rows (a 3x3 matrix for an ellipse), got 2
    """
    n = dim + 1
    kind = "an ellipse" if dim == 2 else "an ellipsoid"
    if isinstance(text, str):
        cleaned = text.strip().replace("[[", "").replace("]]", "").replace("],", ";").replace("[", "").replace("]", "")
        rows: list[Any] = [r for r in cleaned.replace("\n", ";").split(";") if r.strip()]
    elif isinstance(text, list | tuple):
        rows = list(text)
    else:
        raise ValueError(f"{what}: expected rows of numbers")
    if len(rows) != n:
        raise ValueError(f"{what}: expected {n} rows (a {n}x{n} matrix for {kind}), got {len(rows)}")
    return [list(parse_vector(r, n, f"{what} row {i + 1}")) for i, r in enumerate(rows)]


def time_float(t: Any) -> float:
    """A time as a float for drawing (+-inf beyond the float range).

    Examples:
        >>> time_float(fmpq(1, 4)), time_float(fmpq(10) ** 400)
        (0.25, inf)
    """
    try:
        return float(t)
    except OverflowError:
        return math.inf if t > 0 else -math.inf


def format_number(v: Number, digits: int = 6) -> str:
    """Short text of a number: exact "p/q" for small rationals, else a rounded decimal.

    Examples:
        >>> format_number(fmpq(3, 7)), format_number(0.25), format_number(1 / 3), format_number(-0.0)
        ('3/7', '0.25', '0.333333', '0')
    """
    if isinstance(v, fmpq):
        if len(str(v)) <= 24:
            return str(v)
        f = to_float(v)
        if not math.isfinite(f) or (f == 0 and v != 0):  # beyond the float range: exact digits
            return format_rational(v, digits)
        v = f
    return f"{float(v) + 0.0:.{digits}g}"  # + 0.0: a float -0.0 (from a motion) shows as 0
