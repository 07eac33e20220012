"""Display-only geometry: contact point at a tangency, separating plane (floats; never decide).

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
    return v[:-1] / v[-1] + 0.0  # + 0.0 turns -0.0 into 0.0


def _centre_and_inverse_shape(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d = M.shape[0] - 1
    Q, m = M[:d, :d], M[:d, d]
    if np.all(np.linalg.eigvalsh(Q) < 0):
        M, Q, m = -M, -Q, -m
    c = -np.linalg.solve(Q, m)
    k = float(c @ Q @ c - M[d, d])
    return c, k * np.linalg.inv(Q)  # shape (x-c)^T (Q/k) (x-c) <= 1, inverse shape matrix k Q^-1


def separating_plane(A: Any, B: Any, start: np.ndarray | None = None, iterations: int = 60) -> tuple[np.ndarray, float] | None:
    """A plane n.x = h with A on the side n.x < h and B on n.x > h (floats, display only).

    Maximises the support gap g(n) = n.(c_B - c_A) - |n|_A - |n|_B over unit n (|n|_E =
    sqrt(n^T S_E^-1 n) is the support width of ellipsoid E; g is concave) by projected gradient
    ascent from ``start`` (default: the direction between the centres). The plane sits halfway
    across the gap.

    Returns:
        (n, h) with unit normal n, or None when no positive gap was found (the certified
        relation is not "separate", or the gap is below what floats resolve).

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> n, h = separating_plane(circle(0), circle(3))
        >>> n.round(6).tolist(), round(h, 6)
        ([1.0, 0.0], 1.5)
    """
    Af = np.array([[float(v) for v in row] for row in A], dtype=float)
    Bf = np.array([[float(v) for v in row] for row in B], dtype=float)
    cA, SA = _centre_and_inverse_shape(Af)
    cB, SB = _centre_and_inverse_shape(Bf)
    dc = cB - cA
    n = np.array(start, dtype=float) if start is not None and np.linalg.norm(start) > 0 else dc.copy()
    if np.linalg.norm(n) == 0:
        return None
    n /= np.linalg.norm(n)
    scale = float(np.linalg.norm(dc)) + float(np.sqrt(np.trace(SA))) + float(np.sqrt(np.trace(SB)))
    step = 0.5
    best_n, best_g = n, -np.inf
    for _ in range(iterations):
        wa, wb = np.sqrt(n @ SA @ n), np.sqrt(n @ SB @ n)
        g = n @ dc - wa - wb
        if g > best_g:
            best_n, best_g = n, g
        grad = dc - SA @ n / wa - SB @ n / wb
        grad -= (grad @ n) * n  # tangent to the unit sphere
        gn = np.linalg.norm(grad)
        if gn < 1e-12 * scale:
            break
        n = n + step * grad / scale
        n /= np.linalg.norm(n)
        step *= 0.93
    if best_g <= 0:
        return None
    n = best_n
    h = 0.5 * ((n @ cA + np.sqrt(n @ SA @ n)) + (n @ cB - np.sqrt(n @ SB @ n)))
    return n, float(h)
