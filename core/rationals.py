"""Exact conversion of user numbers to rationals (python-flint ``fmpq``).

A float is taken as the exact binary rational it is (``0.1`` is 3602879701896397/2**55); a
string is read as an exact decimal or fraction (``"0.1"`` is 1/10, ``"3/7"``). This is why
"exact" means exact for the caller's input, whatever form it came in.
"""

from __future__ import annotations

import math
import re
from fractions import Fraction
from numbers import Integral, Rational, Real
from typing import Any

import numpy as np
from flint import fmpq, fmpz

__all__ = ["to_fmpq", "MAX_NUMBER_CHARS", "MAX_DECIMAL_EXPONENT"]

MAX_NUMBER_CHARS = 400
"""Longest accepted number string (guards memory and time of a single conversion)."""

MAX_DECIMAL_EXPONENT = 1000
"""Largest |e| accepted in "1.5e-e": beyond the float range by a margin, far below a DoS."""

_NUMBER_RE = re.compile(
    r"^\s*(?P<sign>[+-]?)(?P<int>\d*)(?:\.(?P<frac>\d*))?(?:[eE](?P<exp>[+-]?\d+))?"
    r"(?:\s*/\s*(?P<den>\d+))?\s*$"
)


def _from_string(text: str) -> fmpq:
    if len(text) > MAX_NUMBER_CHARS:
        raise ValueError(f"number string too long ({len(text)} > {MAX_NUMBER_CHARS} characters)")
    m = _NUMBER_RE.match(text)
    if m is None or (not m.group("int") and not m.group("frac")):
        raise ValueError(f"not a number: {text!r} (expected e.g. '3', '-0.25', '1e-3' or '3/7')")
    digits = (m.group("int") or "") + (m.group("frac") or "")
    exp = int(m.group("exp") or 0) - len(m.group("frac") or "")
    if abs(exp) > MAX_DECIMAL_EXPONENT + MAX_NUMBER_CHARS:
        raise ValueError(f"exponent out of range in {text!r} (|e| <= {MAX_DECIMAL_EXPONENT})")
    num = fmpz(int(digits or "0"))
    if m.group("sign") == "-":
        num = -num
    den = fmpz(1)
    if m.group("den") is not None:
        den = fmpz(int(m.group("den")))
        if den == 0:
            raise ValueError(f"zero denominator in {text!r}")
    value = fmpq(num, den)
    if exp > 0:
        value *= fmpz(10) ** exp
    elif exp < 0:
        value /= fmpz(10) ** (-exp)
    return value


def to_fmpq(x: Any) -> fmpq:
    """Convert one number to an exact ``fmpq``.

    Args:
        x: int, float (exact binary value), ``Fraction``, ``fmpq``/``fmpz``, numpy scalar, or a
            string such as ``"3/7"``, ``"0.1"`` (exact decimal), ``"-2.5e-3"``.

    Returns:
        The exact rational value.

    Raises:
        ValueError: NaN, infinity, booleans, or a malformed string (the message says which).

    Examples:
        >>> to_fmpq("0.1"), to_fmpq(0.5), to_fmpq("3/7"), to_fmpq(-2)
        (1/10, 1/2, 3/7, -2)
        >>> to_fmpq(0.1) == to_fmpq("0.1")
        False
    """
    t = type(x)
    if t is float or t is np.float64:  # the common case first (hot in the exact path)
        f = float(x)
        if f - f != 0.0:  # inf or nan
            raise ValueError(f"not a finite number: {f!r}")
        return fmpq(*f.as_integer_ratio())
    if t is int:
        return fmpq(x)
    if t is fmpq:
        return x
    if isinstance(x, bool | np.bool_):
        raise ValueError(f"a boolean is not a number: {x!r}")
    if isinstance(x, fmpz):
        return fmpq(x)
    if isinstance(x, str):
        return _from_string(x)
    if isinstance(x, Integral):
        return fmpq(int(x))
    if isinstance(x, Fraction | Rational):
        return fmpq(int(x.numerator), int(x.denominator))
    if isinstance(x, float | np.floating | Real):
        f = float(x)
        if not math.isfinite(f):
            raise ValueError(f"not a finite number: {f!r}")
        p, q = f.as_integer_ratio()
        return fmpq(p, q)
    raise ValueError(f"cannot read {type(x).__name__} {x!r} as a number")
