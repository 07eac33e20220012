"""Periodic boxes: the box, its checks, and pairs whose second body is a lattice image.

What is certified. In a box of sides L = (L_x, L_y[, L_z]) body j also stands at every c_j + k L
(k integer): its *image* is the set {x : x - k L in body j}, the exact translate of body j's
matrix (the same float matrix the open search classifies; parameters are not rebuilt at a
rounded centre). The relation reported for (i, j) is the certified relation of body i and the
nearest image of j (minimum image convention). Since the centres span at most one box side per
axis, k is in {-1, 0, 1} and k L is an exact float; the filter classifies body i against body
j moved by k L with the translated entries' rounding carried as certified radii
(:func:`core.fixed.filters.classify_translated`), and where it abstains, exact rational
arithmetic classifies the exactly translated matrix (:func:`core.shapes.quadrics.origin_moved`).
So every label is the true label of the input as given: the body matrices and the box.

The minimum image is the only image that can touch when r_i + r_j < min(L) / 2 for every pair
(r the certified bounding radii): two images of j are at least min(L) apart, so both within
r_i + r_j of body i would need min(L) <= 2 (r_i + r_j). :func:`check_box` refuses a larger body.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from flint import fmpq

from ..fixed.classify import Certifier
from ..fixed.exact import classify_exact
from ..fixed.filters import classify_translated
from ..formulae.decision import RULE_RELATION
from ..relation import Relation
from ..shapes.quadrics import origin_moved, symmetric_part

__all__ = ["read_box", "check_box", "classify_images"]

_MARGIN = 1.0 - 2.0**-20
"""The size rule is checked with this margin (rounding of the radii sum and of L / 2)."""


def read_box(box: Any, d: int) -> np.ndarray | None:
    """The box sides as a float64 array (d,), or None for open space.

    Raises:
        ValueError: not d positive finite numbers.

    Examples:
        >>> read_box((10, 10, 5.5), 3).tolist()
        [10.0, 10.0, 5.5]
        >>> read_box([10, 0], 2)
        Traceback (most recent call last):
        ...
        ValueError: box: expected 2 positive finite sides (Lx, Ly), got [10.0, 0.0]
    """
    if box is None:
        return None
    names = "(Lx, Ly)" if d == 2 else "(Lx, Ly, Lz)"
    try:
        L = np.asarray(box, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"box: expected {d} positive finite sides {names}, got {box!r}") from None
    if L.size != d or not (np.isfinite(L).all() and (L > 0).all()):
        raise ValueError(f"box: expected {d} positive finite sides {names}, got {L.tolist()}")
    return L


def check_box(centers: np.ndarray, radii: np.ndarray, box: np.ndarray) -> None:
    """Raise unless the minimum image convention is exact for these bodies in this box.

    Args:
        centers: (N, d) float centres of the bounding spheres (NaN rows: invalid, ignored).
        radii: (N,) certified bounding radii (NaN: invalid).
        box: (d,) sides.

    Raises:
        ValueError: naming the body: its centre lies more than one box side from another's on
            some axis (wrap the centres into the box first), or it is too large for the box
            (the two largest bounding radii must sum to less than half the smallest side).

    Examples:
        >>> check_box(np.array([[0.0, 0.0], [9.0, 1.0]]), np.array([1.0, 1.0]), np.array([10.0, 10.0]))
        >>> check_box(np.array([[0.0, 0.0], [12.0, 1.0]]), np.array([1.0, 1.0]), np.array([10.0, 10.0]))
        Traceback (most recent call last):
        ...
        ValueError: body 1: centre x = 12 is more than one box side (Lx = 10) from body 0's (x = 0): the centres must lie in one box (wrap them into it first, e.g. x mod Lx)
    """
    valid = np.flatnonzero(np.isfinite(radii))
    if not valid.size:
        return
    c = centers[valid]
    axis_names = "xyz"
    for a in range(c.shape[1]):
        lo, hi = int(np.argmin(c[:, a])), int(np.argmax(c[:, a]))
        if c[hi, a] - c[lo, a] > box[a]:
            raise ValueError(
                f"body {valid[hi]}: centre {axis_names[a]} = {c[hi, a] + 0.0:.12g} is more than one box side "
                f"(L{axis_names[a]} = {box[a]:.12g}) from body {valid[lo]}'s ({axis_names[a]} = {c[lo, a] + 0.0:.12g}): "
                f"the centres must lie in one box (wrap them into it first, e.g. {axis_names[a]} mod L{axis_names[a]})"
            )
    r = radii[valid]
    top = np.argsort(r)[::-1][:2]
    r1 = float(r[top[0]])
    r2 = float(r[top[1]]) if top.size > 1 else r1
    half = float(np.min(box)) / 2
    if not (r1 + r2 < half * _MARGIN):
        raise ValueError(
            f"body {valid[top[0]]} is too large for the periodic box: its bounding radius {r1:.6g} plus "
            f"the next largest, {r2:.6g}, must be less than half the smallest side ({2 * half:.6g} / 2), "
            f"so that only the nearest image of a body can touch another"
        )


def classify_images(
    A: np.ndarray, B: np.ndarray, shift: np.ndarray, method: str
) -> tuple[np.ndarray, np.ndarray]:
    """Relations of A against B moved by ``shift`` (exactly), certified; and who certified them.

    Args:
        A: float64 stack (M, n, n) of valid bodies.
        B: the same shape; B[k] is moved by shift[k].
        shift: (M, n - 1) float lattice vectors k L (exact floats).
        method: "adaptive", "float" (UNDECIDED where the filter abstains) or "exact".

    Returns:
        (int8 Relation codes, int8 Certifier codes), shape (M,).
    """
    M = A.shape[0]
    codes = np.full(M, Relation.UNDECIDED, dtype=np.int8)
    by = np.zeros(M, dtype=np.int8)
    if method != "exact" and M:
        rules = classify_translated(A, B, shift)
        done = rules >= 0
        codes[done] = RULE_RELATION[rules[done]]
        by[done] = Certifier.FLOAT
    if method == "float":
        return codes, by
    for k in np.flatnonzero(codes == Relation.UNDECIDED).tolist():
        # the exact symmetric part (the shape B's matrix defines), moved by the exact lattice vector
        moved = origin_moved(symmetric_part(_exact(B[k]), "B"), [-_q(v) for v in shift[k]])
        codes[k] = classify_exact(_exact(A[k]), moved).relation
        by[k] = Certifier.EXACT
    return codes, by


def _q(v: float) -> fmpq:
    return fmpq(*float(v).as_integer_ratio())


def _exact(M: np.ndarray) -> list[list[fmpq]]:
    return [[_q(v) for v in row] for row in M]
