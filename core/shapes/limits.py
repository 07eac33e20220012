"""Size limits on user text: the one place they live (library defaults and the server's own).

Exact arithmetic on text a user typed can be made arbitrarily expensive by a short input
(``((1e1400)^64)^64``: gigabytes; ``sqrt(<100-digit semiprime>)``: a factorisation). The parser
of numbers (:mod:`core.shapes.numbers`) and of expressions in t (:mod:`core.moving.expressions`) check these
limits *before* each step, so such input is refused with a message that names the limit instead
of being computed.

* :data:`LIBRARY` (default everywhere in ``core``) is generous: it only stops work that no input
  of its size could justify (a 12-character ``"1e999999999"``, a billion-bit power).
* :data:`SERVER` is the policy of the HTTP API and the scene (``app``): their edges check text
  against it (number and expression lengths), and their worker processes parse under it.

A :class:`Limits` is passed explicitly (``parse_expression(text, limits=...)``,
``motion_from_dict(data, limits=...)``, ``parse_number(text, limits)``); inside one such call
the arithmetic operators read it from :func:`current` (a context variable set only for the
duration of the call, so threads and other calls never see it).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, replace

__all__ = ["Limits", "LimitExceeded", "LIBRARY", "SERVER", "current", "using", "check_bits", "check_degree", "log2_ceil"]


class LimitExceeded(ValueError):
    """Input over a size limit (a ValueError, so every caller already reports it as bad input)."""


@dataclass(frozen=True)
class Limits:
    """Sizes that user text may reach (``None``: no limit)."""

    number_chars: int | None
    """Longest number string ("3/7", "1.5e-3"). None in the library: a long number costs time
    in proportion to its length, which the caller chose; the server caps it at its edge."""
    decimal_exponent: int
    """Largest |e| written in "1.5e<e>": a 12-character "1e999999999" would otherwise ask for a
    3-billion-bit integer."""
    expression_chars: int | None
    """Longest expression text in t (None in the library: the size limits bound the work)."""
    coefficient_bits: int
    """Largest size of one exact coefficient while an expression or a motion matrix is built:
    bits of its numerator plus bits of its denominator. Checked before each operation from the
    sizes of the operands (an upper bound of the result), so the work is never started."""
    work_degree: int
    """Highest degree in t of an intermediate result (a polynomial in t is dense: its number of
    terms is its degree + 1, so this also bounds the terms)."""
    degree: int
    """Highest degree in t of numerator and denominator of one entry after simplification."""
    exponent: int
    """Largest integer n in ``x^n``."""
    depth: int
    """Deepest nesting of parentheses and unary signs (guards the recursion of the parser)."""
    sqrt_trial_primes: int
    """sqrt(n) is written k*sqrt(d) by trial division with this many primes (never a full
    factorisation: a 100-digit semiprime would take forever); a large cofactor that is not a
    perfect square stays inside d (same field, exact arithmetic unchanged)."""

    def __post_init__(self) -> None:
        """Reject non-positive limits (a ValueError naming the field)."""
        for name, value in self.__dict__.items():
            if value is None and name in ("number_chars", "expression_chars"):
                continue
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"Limits.{name} must be a positive integer, got {value!r}")


LIBRARY = Limits(
    number_chars=None,
    decimal_exponent=10_000,
    expression_chars=None,
    coefficient_bits=1_000_000,
    work_degree=256,
    degree=16,
    exponent=64,
    depth=60,
    sqrt_trial_primes=1000,
)
"""Defaults of the library: a 1-million-bit coefficient (300,000 digits) is the most any
arithmetic on text may build; a decimal exponent up to 10,000 (ten times the server's)."""

SERVER = replace(LIBRARY, number_chars=400, decimal_exponent=1000, expression_chars=2000, coefficient_bits=20_000)
"""The HTTP API's and the scene's limits: numbers up to 400 characters with |exponent| <= 1000
(beyond the float range by a margin), expressions up to 2,000 characters, coefficients up to
20,000 bits (~6,000 digits) while a motion is parsed and its matrix built; the rest as in the
library (whose texts have no length limit: their cost is bounded by the size limits)."""

_CURRENT: ContextVar[Limits] = ContextVar("core_limits", default=LIBRARY)


def current() -> Limits:
    """The limits in force in this call (:data:`LIBRARY` unless inside :func:`using`)."""
    return _CURRENT.get()


@contextmanager
def using(limits: Limits | None) -> Iterator[Limits]:
    """Make ``limits`` (None: keep the ones in force) current for the body of the ``with``."""
    if limits is None:
        yield _CURRENT.get()
        return
    token = _CURRENT.set(limits)
    try:
        yield limits
    finally:
        _CURRENT.reset(token)


def check_bits(bits: int, what: str = "constant") -> None:
    """Raise :class:`LimitExceeded` if a coefficient of ``bits`` bits is over the current limit.

    Examples:
        >>> check_bits(10)
        >>> with using(SERVER):
        ...     check_bits(297_664)
        Traceback (most recent call last):
        ...
        core.shapes.limits.LimitExceeded: constant too large: about 2^297664 (297664 bits), limit 20000 bits
    """
    limit = _CURRENT.get().coefficient_bits
    if bits > limit:
        raise LimitExceeded(f"{what} too large: about 2^{bits} ({bits} bits), limit {limit} bits")


def check_degree(degree: int) -> None:
    """Raise :class:`LimitExceeded` if an intermediate degree in t is over the current limit."""
    limit = _CURRENT.get().work_degree
    if degree > limit:
        raise LimitExceeded(f"degree in t too high: {degree} (limit {limit}) before simplification")


def log2_ceil(n: int) -> int:
    """ceil(log2(n)) for n >= 1 (bits added by summing n terms)."""
    return max(0, math.ceil(math.log2(n))) if n > 1 else 0
