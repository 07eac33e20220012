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

def spheres(n: int, m: Any, centres_out: Any, radii_out: Any, status_out: Any, /) -> int:
    """Certified bounding spheres of len(status_out) float64 n x n bodies (core/fixed/_spheres.h).

    centres_out (count, n - 1) and radii_out (count,) float64 (NaN where none), status_out int8:
    0 tight, 1 loose, 2 none here, 3 not exactly symmetric. Returns how many have a sphere.
    """

def query_one(
    geometry_i: Any, geometry_d: Any, table: Any, cr: Any, frac: Any, Q: Any, B: Any, rel: Any, out: Any, kout: Any, codes: Any,
    by: Any, exclude: int, /,
) -> tuple[int, int, int]:
    """One new body asked of a BodyIndex (core/fixed/_near.h), the separate pairs dropped.

    Its sphere, the bodies near it (sorted), their images, and (Q given) the relations of the pairs
    without an image (-3 for the others). Returns (candidates, kept, left to the caller), or
    (code, 0, 0): -1 an image beyond 127 boxes, -2 the general path, -4 a centre too far from the
    box, -10 - needed: the outputs must hold `needed` bodies.
    """

def query_many(
    geometry_i: Any, geometry_d: Any, table: Any, cr: Any, frac: Any, Q: Any, B: Any, rel: Any, spheres: Any, exclude: Any,
    qout: Any, out: Any, kout: Any, codes: Any, by: Any, start: int, /,
) -> tuple[int, int, int, int, int]:
    """query_one for new bodies B (M, n, n) with their spheres (M, n), from body start on, their pairs appended.

    Returns (bodies done, candidates, kept, left to the caller, status): status 0, or the code that
    stopped at body `bodies done` (-10 - needed: room for that body).
    """

def variant() -> str:
    """The SIMD variant in use."""

def variants() -> list[str]:
    """The variants of this build that this CPU runs, slowest first."""

def select(name: str, /) -> None:
    """Use this variant (ValueError if unknown or unsupported here)."""

def kernels_sha256() -> str:
    """First 16 hex digits of the SHA-256 of the _kernels.h this module was built from."""
