"""Display-only geometry: the contact point at a tangency (floats; never feeds a decision).

At an external tangency P(T) = det(T A + B) has a positive double root beta, and the contact
point X spans the kernel of beta A + B (then A X = -(1/beta) B X: the normals are opposite).
The relation itself is always certified by ``core``; this module only says *where* to draw.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.polynomial import polynomial as npoly

__all__ = ["contact_point"]


def contact_point(A: Any, B: Any, coefficients: Sequence[float]) -> np.ndarray | None:
    """Approximate contact point of two tangent shapes (floats, for drawing).

    Args:
        A, B: the two matrices (3x3 or 4x4; floats or exact numbers).
        coefficients: a_0..a_n of P(T) (floats, ascending).

    Returns:
        (d,) coordinates of the contact point, or None when no positive root is found.

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> contact_point(circle(0), circle(2), [-1, 1, 1, -1]).round(9).tolist()
        [1.0, 0.0]
    """
    a = np.asarray(coefficients, dtype=float)
    if not np.all(np.isfinite(a)) or a[-1] == 0:
        return None
    # the double root is a root of P'; pick the positive root of P' where |P| is smallest
    cands = npoly.polyroots(npoly.polyder(a))
    cands = cands[np.abs(cands.imag) <= 1e-6 * (1 + np.abs(cands.real))].real
    cands = cands[cands > 0]
    if cands.size == 0:
        return None
    beta = float(cands[np.argmin(np.abs(npoly.polyval(cands, a)))])
    Af = np.array([[float(v) for v in row] for row in A], dtype=float)
    Bf = np.array([[float(v) for v in row] for row in B], dtype=float)
    _, _, vt = np.linalg.svd(beta * Af + Bf)
    v = vt[-1]
    if v[-1] == 0:
        return None
    return v[:-1] / v[-1]
