"""The options every entry point shares (``method=``, ``on_invalid=``), checked in one place.

A wrong option is a ValueError that names the valid ones, whichever function was called.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

__all__ = ["Method", "METHODS", "SweepMethod", "SWEEP_METHODS", "OnInvalid", "ON_INVALID", "check_choice", "check_options"]

Method = Literal["adaptive", "float", "exact"]
METHODS: tuple[str, ...] = ("adaptive", "float", "exact")
"""Arithmetic of a certified answer: float filter then exact, float filter only, exact only."""
SweepMethod = Literal["adaptive", "exact"]
SWEEP_METHODS: tuple[str, ...] = ("adaptive", "exact")
"""Arithmetic of a sweep's first contacts (:func:`core.sweep_contacts`): no float-only answer, a time is certified or absent."""
OnInvalid = Literal["raise", "mark"]
ON_INVALID: tuple[str, ...] = ("raise", "mark")
"""What a batch does with an input that is not a shape: raise ValueError, or mark the row."""


def check_choice(value: object, options: Sequence[str], what: str) -> None:
    """ValueError listing the valid options unless ``value`` is one of them.

    Examples:
        >>> check_choice("fast", ("adaptive", "exact"), "method")
        Traceback (most recent call last):
        ...
        ValueError: unknown method 'fast'; valid options: adaptive, exact
    """
    if value not in options:
        raise ValueError(f"unknown {what} {value!r}; valid options: {', '.join(options)}")


def check_options(method: object, on_invalid: object, methods: Sequence[str] = METHODS) -> None:
    """Check ``method`` (one of ``methods``) and ``on_invalid`` (ValueError naming the valid options)."""
    check_choice(method, methods, "method")
    check_choice(on_invalid, ON_INVALID, "on_invalid")
