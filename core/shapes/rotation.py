"""Quaternion -> rotation matrix: the one formula of the project, for any ring of numbers.

A quaternion q = (w, x, y, z) of any non-zero length is the rotation R = R~(q) / |q|^2, with R~
the quadratic numerator below (exactly orthogonal once divided: R~ R~^T = |q|^4 I). In 2D the
quaternion (w, 0, 0, z) turns about z; it is written (w, z) and gives the 2 x 2 block.

:func:`rotation_numerator` performs the same operations, in the same order, on whatever it is
given: Python floats (one shape), numpy float arrays (N shapes at once, elementwise: bit for bit
the floats of one shape), ``fmpq`` (an exactly orthogonal rational matrix), polynomials or
rational functions of time (a rotating body). The caller divides by the norm its own way (and
refuses a zero norm with its own message).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TypeVar

__all__ = ["rotation_numerator"]

T = TypeVar("T")


def rotation_numerator(q: Sequence[T]) -> tuple[list[list[T]], T]:
    """(R~, |q|^2): the rotation of quaternion q is R~ / |q|^2, entry by entry.

    Args:
        q: (w, x, y, z) (3D: a 3 x 3 R~), or (w, z) (2D: the rotation about z of the quaternion
            (w, 0, 0, z), a 2 x 2 R~). Entries of one ring: floats, numpy arrays, ``fmpq``,
            polynomials, rational functions.

    Returns:
        The numerator rows and the squared norm; neither is divided, nothing is checked.

    Examples:
        >>> from flint import fmpq
        >>> R, n = rotation_numerator([fmpq(1), fmpq(0), fmpq(0), fmpq(1)])   # 90 degrees about z
        >>> [[v / n for v in row] for row in R]
        [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
        >>> rotation_numerator([1.0, 1.0])                                  # 2D, the same turn
        ([[0.0, -2.0], [2.0, 0.0]], 2.0)
    """
    v: list[Any] = list(q)
    if len(v) == 2:
        w, z = v
        c = w * w - z * z
        s = (w * z) * 2
        return [[c, -s], [s, c]], w * w + z * z
    if len(v) != 4:
        raise ValueError(f"a quaternion has 4 components (w, x, y, z), or 2 (w, z) in 2D; got {len(v)}")
    w, x, y, z = v
    rows = [
        [w * w + x * x - y * y - z * z, (x * y - w * z) * 2, (x * z + w * y) * 2],
        [(x * y + w * z) * 2, w * w - x * x + y * y - z * z, (y * z - w * x) * 2],
        [(x * z - w * y) * 2, (y * z + w * x) * 2, w * w - x * x - y * y + z * z],
    ]
    return rows, w * w + x * x + y * y + z * z
