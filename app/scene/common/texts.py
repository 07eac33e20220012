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
from core.shapes.numbers import decimal_exponent, floor_log10, parse_number, to_fmpq

__all__ = [
    "Number", "parse_vector", "parse_matrix", "read_time", "time_float", "SHOWN_DIGITS",
    "exact_text", "decimal_text", "round_decimal", "APPROX",
]

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



SHOWN_DIGITS = 10
"""Significant digits of a computed number shown in a field (a pose drawn at t, a drag).

A drag or leaving a motion makes the shape *exactly* the decimals shown with these digits
(:meth:`app.scene.common.state.ShapeState.rationalised`): the fields then hold what is certified."""

APPROX = "≈ "
"""Prefix of a field that shows a rounded, computed value (never a number that looks exact)."""


def decimal_text(q: fmpq, max_chars: int = 40) -> str | None:
    """The exact decimal text of a rational with a terminating decimal expansion, else None.

    Examples:
        >>> decimal_text(fmpq(3, 8)), decimal_text(fmpq(-12, 1)), decimal_text(fmpq(1, 3))
        ('0.375', '-12', None)
        >>> decimal_text(fmpq(1, 10**30)), decimal_text(fmpq(1, 2**20000)), decimal_text(fmpq(10**5000))
        ('1e-30', None, '1e5000')
    """
    k = decimal_exponent(q)
    if k is None:
        return None
    if k > 0 and floor_log10(q) + k + 1 > max_chars:
        return None  # every one of its digits is significant: too long however it is written
    m = (q * fmpq(10) ** k).p  # an fmpz: its text has no 4300-digit limit
    sign, digits = ("-" if m < 0 else ""), str(abs(m))
    if k == 0:
        text = sign + digits
    else:
        digits = digits.rjust(k + 1, "0")
        text = sign + digits[:-k] + "." + digits[-k:]
    if len(text) > max_chars or (k > 8 and len(digits.lstrip("0")) <= 6):  # 1e-30, not 0.000…0001
        zeros = len(digits) - len(digits.lstrip("0"))
        mant = digits.rstrip("0").lstrip("0")
        exp = (len(digits) - zeros - 1) - k  # value = m.mmm × 10^exp
        body = mant[0] + ("." + mant[1:] if len(mant) > 1 else "")
        text = f"{sign}{body}e{exp}"
        if len(text) > max_chars:
            return None
    return text


def exact_text(q: Any) -> str:
    """Exact text of a rational: its decimal when it terminates (shortly), else "p/q".

    Examples:
        >>> exact_text(fmpq(1, 10)), exact_text(fmpq(3, 7)), exact_text(fmpq(5))
        ('0.1', '3/7', '5')
    """
    q = to_fmpq(q)
    return decimal_text(q) or str(q)


def _floor_log10(x: fmpq) -> int:
    """floor(log10(|x|)) of a nonzero rational, exactly."""
    x = abs(x)
    k = len(str(int(x.p))) - len(str(int(x.q)))
    while fmpq(10) ** k > x if k >= 0 else fmpq(1, 10**-k) > x:
        k -= 1
    while (fmpq(10) ** (k + 1) if k + 1 >= 0 else fmpq(1, 10 ** -(k + 1))) <= x:
        k += 1
    return k


def round_decimal(x: Any, scale: Any = None, digits: int = SHOWN_DIGITS) -> fmpq:
    """``x`` rounded to ``digits`` significant digits of ``scale`` (default: of x itself), exactly.

    The quantum is 10^(floor(log10 scale) - digits + 1); float noise far below the scale of a
    shape (a centre of 1e-17 beside semi-axes of 1) rounds to 0.

    Examples:
        >>> round_decimal(0.1), round_decimal(2.0000000000000004), round_decimal(-2.7e-17, 3.0)
        (1/10, 2, 0)
        >>> round_decimal(1 / 3, digits=3)
        333/1000
    """
    xq = to_fmpq(x)
    s = to_fmpq(x if scale is None else scale)
    if s == 0:
        return xq
    e = _floor_log10(s) - digits + 1
    quantum = fmpq(10) ** e if e >= 0 else fmpq(1, 10**-e)
    r = xq / quantum
    n = int(r.p) // int(r.q)  # floor
    frac = r - n
    if frac > fmpq(1, 2) or (frac == fmpq(1, 2) and n % 2 == 1):
        n += 1
    return n * quantum
