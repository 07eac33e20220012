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

from .limits import LIBRARY, LimitExceeded, Limits

__all__ = ["to_fmpq", "to_float", "format_rational", "floor_log10", "sign", "parse_number", "MAX_DECIMAL_EXPONENT"]

MAX_DECIMAL_EXPONENT = LIBRARY.decimal_exponent
"""Largest |e| accepted in "1.5e<e>" by the library (:data:`core.shapes.limits.LIBRARY`): "1e999999999"
would ask for a 3-billion-bit integer. A number string has no length limit here (its cost grows
with its length, which the caller chose); the HTTP API and the scene cap it at their edge."""

_NUMBER_RE = re.compile(
    r"^\s*(?P<sign>[+-]?)(?P<int>[0-9]*)(?:\.(?P<frac>[0-9]*))?(?:[eE](?P<exp>[+-]?[0-9]+))?"
    r"(?:\s*/\s*(?P<den>[0-9]+))?\s*$",
    re.ASCII,  # only the digits 0-9: int() would also read fullwidth or Arabic-Indic digits
)
_EXP_DIGITS = 12
"""Longest exponent read as an integer (longer ones are out of range for any limit)."""


def parse_number(text: str, limits: Limits | None = None) -> fmpq:
    """Read an exact decimal or fraction ("3", "-0.25", "1e-3", "3/7", "2.5e3/7") as ``fmpq``.

    Args:
        text: the number string (ASCII digits only; surrounding spaces are ignored).
        limits: size limits (default :data:`core.shapes.limits.LIBRARY`): ``number_chars`` (None: any
            length) and ``decimal_exponent`` (the |e| written after "e").

    Raises:
        ValueError: not a number, a zero denominator, or over a limit (the message gives it).

    Examples:
        >>> parse_number("2.5e-3"), parse_number(" -3/7 ")
        (1/400, -3/7)
        >>> from core.shapes.limits import SERVER
        >>> parse_number("1e1001", SERVER)
        Traceback (most recent call last):
        ...
        core.shapes.limits.LimitExceeded: exponent out of range in '1e1001': |e| <= 1000 after 'e'
    """
    lim = limits or LIBRARY
    if lim.number_chars is not None and len(text) > lim.number_chars:
        raise LimitExceeded(f"number string too long ({len(text)} > {lim.number_chars} characters)")
    m = _NUMBER_RE.match(text)
    if m is None or (not m.group("int") and not m.group("frac")):
        raise ValueError(f"not a number: {_shown(text)} (expected e.g. '3', '-0.25', '1e-3' or '3/7')")
    exp_text = m.group("exp") or "0"
    written = int(exp_text) if len(exp_text.lstrip("+-").lstrip("0")) <= _EXP_DIGITS else None
    if written is None or abs(written) > lim.decimal_exponent:
        raise LimitExceeded(
            f"exponent out of range in {_shown(text)}: |e| <= {lim.decimal_exponent} after 'e'"
        )
    frac = m.group("frac") or ""
    digits = ((m.group("int") or "") + frac).lstrip("0")
    exp = written - len(frac)
    num = fmpz(digits) if digits else fmpz(0)
    if m.group("sign") == "-":
        num = -num
    den = fmpz(1)
    if m.group("den") is not None:
        den = fmpz(m.group("den"))
        if den == 0:
            raise ValueError(f"zero denominator in {_shown(text)}")
    value = fmpq(num, den)
    if num != 0:
        if exp > 0:
            value *= fmpz(10) ** exp
        elif exp < 0:
            value /= fmpz(10) ** (-exp)
    return value


def _shown(text: str, limit: int = 60) -> str:
    """The repr of the text, shortened in the middle when long (messages never echo a megabyte)."""
    if len(text) <= limit:
        return repr(text)
    return repr(text[: limit // 2]) + f" ... ({len(text)} characters) ... " + repr(text[-limit // 4 :])


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
        return parse_number(x)
    if isinstance(x, Integral):
        return fmpq(int(x))
    if isinstance(x, np.floating):  # float16/32/longdouble: exact, never through float64
        if not np.isfinite(x):
            raise ValueError(f"not a finite number: {x!r}")
        p, q = x.as_integer_ratio()
        return fmpq(int(p), int(q))
    if isinstance(x, Fraction | Rational):
        return fmpq(int(x.numerator), int(x.denominator))
    if isinstance(x, float | Real):
        f = float(x)
        if not math.isfinite(f):
            raise ValueError(f"not a finite number: {f!r}")
        if f != x:  # a Real type wider than a float (e.g. Decimal): refuse rather than round
            raise ValueError(f"cannot read {type(x).__name__} {x!r} exactly; pass a string or a Fraction")
        p, q = f.as_integer_ratio()
        return fmpq(p, q)
    if isinstance(x, np.ndarray) and x.ndim == 0:
        return to_fmpq(x[()])
    raise ValueError(f"cannot read {type(x).__name__} {x!r} as a number")


def sign(x: Any) -> int:
    """-1, 0 or 1: the sign of any ordered number (int, fmpz, fmpq, Fraction, float).

    Examples:
        >>> sign(fmpq(-1, 3)), sign(0), sign(2.5)
        (-1, 0, 1)
    """
    return (x > 0) - (x < 0)


def to_float(q: Any) -> float:
    """The float nearest to an exact rational (``fmpq``, ``fmpz``, int, Fraction); never raises.

    Correctly rounded (Python's int / int true division); ``inf``/``-inf`` when the value is
    beyond the float range and 0.0 (or a subnormal) below it. Display only: a float never
    decides anything in this project. The one rational-to-float conversion of the code base.

    Examples:
        >>> to_float(fmpq(1, 3)), to_float(fmpz(10) ** 400), to_float(-fmpq(1, fmpz(10) ** 400))
        (0.3333333333333333, inf, -0.0)
    """
    if isinstance(q, float):
        return q
    if not isinstance(q, fmpq):
        q = to_fmpq(q)
    p, d = int(q.p), int(q.q)
    try:
        return p / d
    except OverflowError:  # |p / d| beyond the largest float
        return math.inf if p > 0 else -math.inf


def floor_log10(q: Any) -> int:
    """floor(log10 |q|) of a nonzero rational, exactly, at any size.

    From the bit lengths (an estimate within one of the answer), corrected by exact comparisons
    with powers of ten. Never converts a big integer to decimal text, so it works far beyond
    Python's 4300-digit limit on ``str(int)``.

    Examples:
        >>> floor_log10(fmpq(1, 3)), floor_log10(fmpz(10) ** 5000), floor_log10(fmpq(-999, 10))
        (-1, 5000, 1)
    """
    if not isinstance(q, fmpq):
        q = to_fmpq(q)
    if q == 0:
        raise ValueError("floor_log10 of zero")
    p, d = abs(q.p), q.q
    # log10(p/d) lies in (bits(p) - 1 - bits(d), bits(p) - bits(d) + 1) * log10(2)
    e = math.floor((int(p.bit_length()) - int(d.bit_length())) * math.log10(2))
    while _ge_pow10(p, d, e + 1):
        e += 1
    while not _ge_pow10(p, d, e):
        e -= 1
    return e


def _ge_pow10(p: fmpz, d: fmpz, e: int) -> bool:
    """Whether p / d >= 10^e, exactly (p, d > 0)."""
    return bool(p >= d * fmpz(10) ** e) if e >= 0 else bool(p * fmpz(10) ** (-e) >= d)


def format_rational(q: Any, digits: int = 6) -> str:
    """Scientific text of an exact rational with ``digits`` significant digits, at any size.

    Mantissa and exponent are computed exactly in integers (no float, no decimal text of a big
    integer), so values far outside the float range (1e-400, 2^50000) still read as short
    numbers: ``-1.23457e+612``. The mantissa is rounded to nearest (ties away from zero).

    Examples:
        >>> format_rational(fmpq(-1, 3)), format_rational(fmpz(10) ** 400 * 7, 3), format_rational(0)
        ('-3.33333e-01', '7.00e+400', '0')
        >>> format_rational(fmpq(1, fmpz(3) ** 20000), 3)
        '3.76e-9543'
    """
    if not isinstance(q, fmpq):
        q = to_fmpq(q)
    if q == 0:
        return "0"
    if digits < 1:
        raise ValueError(f"digits must be >= 1, got {digits}")
    sign = "-" if q < 0 else ""
    p, d = abs(q.p), q.q
    e = floor_log10(q)  # 10^e <= p/d < 10^(e+1)
    k = digits - 1 - e  # mantissa digits = round(p/d * 10^k)
    num, den = (p * fmpz(10) ** k, d) if k >= 0 else (p, d * fmpz(10) ** (-k))
    m, r = divmod(num, den)
    if 2 * r >= den:
        m += 1
    if m >= fmpz(10) ** digits:  # rounding carried into a new digit (9.999 -> 10.00)
        m //= 10
        e += 1
    text = str(m)  # flint's decimal conversion: ``digits`` digits, no size limit
    mant = text[0] + ("." + text[1:] if digits > 1 else "")
    return f"{sign}{mant}e{'+' if e >= 0 else '-'}{abs(e):02d}"
