"""Types of the compiled extension core.fixed._filter (core/fixed/_filter.c, built by setup.py)."""

from typing import Any

def classify(n: int, a: Any, b: Any, out: Any, table: Any = ..., /) -> int:
    """Rule ids of len(out) pairs of n x n float64 or float32 matrices into the int8 buffer out.

    With a 256-byte table, table[rule id as a byte] instead. Returns how many pairs are undecided.
    """

def balance(n: int, a: Any, b: Any, a_out: Any, b_out: Any, e_out: Any, shift: Any = ..., shift_out: Any = ..., /) -> int:
    """The second stage's change of units (core.fixed.filters._balanced) of len(e_out) float64 pairs.

    a_out, b_out (and shift_out) get the pairs with space scaled by 2^e, e_out the int64 e (0 where
    the scaling is not exact or not needed). Returns how many pairs moved.
    """

def variant() -> str:
    """The SIMD variant in use."""

def variants() -> list[str]:
    """The variants of this build that this CPU runs, slowest first."""

def select(name: str, /) -> None:
    """Use this variant (ValueError if unknown or unsupported here)."""

def kernels_sha256() -> str:
    """First 16 hex digits of the SHA-256 of the _kernels.h this module was built from."""
