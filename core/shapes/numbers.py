"""Exact conversion of user numbers to rationals (python-flint ``fmpq``).

A float is taken as the exact binary rational it is (``0.1`` is 3602879701896397/2**55); a
string is read as an exact decimal or fraction (``"0.1"`` is 1/10, ``"3/7"``). This is why
"exact" means exact for the caller's input, whatever form it came in.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from fractions import Fraction
from numbers import Integral, Rational, Real
from typing import Any, cast

import numpy as np
from flint import fmpq, fmpz

from .limits import LIBRARY, LimitExceeded, Limits

__all__ = [
    "to_fmpq",
    "to_float",
    "binary64",
    "binary64_array",
    "format_rational",
    "floor_log10",
    "sign",
    "sign_variations",
    "parse_number",
    "MAX_DECIMAL_EXPONENT",
    "EXACT_INT",
]

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
        return cast(fmpq, x)
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


EXACT_INT = 2**53
"""Integers of smaller magnitude are all float64 values (beyond it, only some are)."""


def binary64(v: Any, *, typed: bool = False) -> float | None:
    """V as a float if its exact value is a binary64 value, else None (never rounds).

    Python floats and float64 scalars are taken as they are (NaN and infinities included); any
    other number (int, Fraction, fmpq, a numpy scalar of another width, a string such as "0.5")
    only when it is finite and exactly a float64. Booleans are not numbers (None). ``typed``:
    only floats and integers count (a Fraction, fmpq or string that happens to be a binary64
    value gives None: the caller chose exact numbers, and gets the exact path).

    Examples:
        >>> binary64("0.5"), binary64("0.1"), binary64(2**53 + 1), binary64(2**60), binary64(True)
        (0.5, None, None, 1.152921504606847e+18, None)
    """
    if type(v) is float or type(v) is np.float64:
        return float(v)
    if isinstance(v, bool | np.bool_):
        return None
    if isinstance(v, np.floating):  # float16/32/longdouble: NaN and inf are binary64 values too
        f = float(v)
        return f if f != f or f == v else None
    if typed and not isinstance(v, int | np.integer):
        return None
    try:
        q = to_fmpq(v)
    except (ValueError, TypeError):
        return None
    if q.q & (q.q - 1) or q.q > 2**1074:  # not a dyadic rational a float64 can hold
        return None
    try:
        f = int(q.p) / int(q.q)  # correctly rounded
    except OverflowError:
        return None
    return f if math.isfinite(f) and to_fmpq(f) == q else None


def binary64_array(x: Any, *, typed: bool = False) -> np.ndarray | None:
    """X as a float64 array if every entry is exactly a binary64 value, else None (never rounds).

    The one test of "plain floats" of the project: float arrays of any width whose values a
    float64 holds (float16/32 always; a long double only when widening back gives it again),
    integer arrays below 2^53 in magnitude, and other arrays (lists, object arrays) entry by
    entry (:func:`binary64`, with ``typed`` passed on). Booleans, complex numbers and ragged
    input give None.

    Examples:
        >>> binary64_array([[0.5, 1], ["0.25", 3]])
        array([[0.5 , 1.  ],
               [0.25, 3.  ]])
        >>> binary64_array([0.1, "0.1"]) is None
        True
    """
    if isinstance(x, np.ndarray):
        arr = x
    else:
        try:  # object: a big int next to a float must not be rounded by numpy's own conversion
            arr = np.asarray(x, dtype=object)
        except ValueError:  # ragged
            return None
    kind = arr.dtype.kind
    if kind == "f":
        wide = arr.astype(np.float64)
        if arr.dtype.itemsize > 8 and not ((wide.astype(arr.dtype) == arr) | np.isnan(arr)).all():
            return None
        return wide
    if kind in "iu":
        wide = arr.astype(np.float64)
        if arr.size and (int(arr.max()) >= EXACT_INT or int(arr.min()) <= -EXACT_INT):
            # beyond 2^53 only some integers are float64 values (2^60 is, 2^53 + 1 is not)
            if any(int(f) != v for f, v in zip(wide.reshape(-1).tolist(), arr.reshape(-1).tolist(), strict=True)):
                return None
        return wide
    if kind not in "OU":
        return None  # booleans, complex, bytes, dates
    flat = arr.reshape(-1).tolist()
    if all(type(v) is float for v in flat):
        return np.array(flat, dtype=np.float64).reshape(arr.shape)
    out = np.empty(len(flat), dtype=np.float64)
    for k, v in enumerate(flat):
        f = binary64(v, typed=typed)
        if f is None:
            return None
        out[k] = f
    return out.reshape(arr.shape)


def sign(x: Any) -> int:
    """-1, 0 or 1: the sign of any ordered number (int, fmpz, fmpq, Fraction, float).

    Examples:
        >>> sign(fmpq(-1, 3)), sign(0), sign(2.5)
        (-1, 0, 1)
    """
    return int((x > 0) - (x < 0))


def sign_variations(values: Iterable[Any]) -> int:
    """Number of sign changes after dropping zeros (Descartes' Var), of sign codes or numbers.

    The one Var of the project: the decision trees (:mod:`core.formulae.decision`) read it on
    sign codes, root isolation (:mod:`core.algebra.realroots`) on integer coefficients.

    Examples:
        >>> sign_variations([-1, 1, 0, -1])
        2
        >>> sign_variations([0, 0])
        0
        >>> from flint import fmpz
        >>> sign_variations([fmpz(3), fmpz(-7), fmpz(0), fmpz(2)])
        2
    """
    last = 0
    count = 0
    for v in values:
        s = sign(v)
        if s == 0:
            continue
        if last != 0 and s != last:
            count += 1
        last = s
    return count


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


def decimal_exponent(q: fmpq) -> int | None:
    """The least k >= 0 with q 10^k an integer (q's decimal expansion ends k digits after the point), else None.

    Examples:
        >>> decimal_exponent(fmpq(3, 8)), decimal_exponent(fmpq(-12)), decimal_exponent(fmpq(1, 3))
        (3, 0, None)
    """
    d = int(q.q)
    twos = (d & -d).bit_length() - 1  # the power of 2 in d
    d >>= twos
    fives = 0
    while d % 5 == 0:
        d //= 5
        fives += 1
    return max(twos, fives) if d == 1 else None


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
