"""Periodic boxes (orthogonal or tilted): the box, its lattice, its checks, and image pairs.

The box. HOOMD-blue's convention: ``(Lx, Ly, Lz)`` sides of an orthogonal box, or
``(Lx, Ly, Lz, xy, xz, yz)`` for a tilted (triclinic) one, whose box vectors are the columns
a1 = (Lx, 0, 0), a2 = (xy Ly, Ly, 0), a3 = (xz Lz, yz Lz, Lz) (xy, xz, yz are tilt *factors*);
in 2D ``(Lx, Ly)`` or ``(Lx, Ly, xy)`` (a1 = (Lx, 0), a2 = (xy Ly, Ly)), also accepted as the
six numbers a 2D HOOMD frame stores (Lz ignored, xz = yz = 0). :func:`read_box` returns the
d sides of an orthogonal box (a tilted box with every tilt 0 is one) and the six numbers
``(Lx, Ly, Lz, xy, xz, yz)`` of a tilted one (2D: ``(Lx, Ly, 0, xy, 0, 0)``): so a box array
is tilted exactly when it has 6 entries (:func:`is_tilted`).

The lattice vector of an image. Body j also stands at every c_j + v(k), k an integer vector
(its *image* k). v(k) is the float vector nearest (round to nearest, ties to even, per
component) to the exact lattice vector k1 a1 + k2 a2 [+ k3 a3] of the box's six float
numbers, the products xy Ly, xz Lz, yz Lz taken exactly (:func:`lattice_shifts`). For an
orthogonal box and k in {-1, 0, 1} that is k L itself (exact), as before; in a tilted box the
rounding is at most half an ulp per component and the same v(k) is used everywhere: by the
filter, by exact arithmetic, by ``Contacts.shifts()``, the pair details and the scene.

What is certified. The image of body j is the exact translate of j's matrix by v(k) (the same
float matrix the open search classifies; parameters are not rebuilt at a rounded centre). The
relation reported for (i, j) is the certified relation of body i and that image: the filter
classifies body i against body j moved by v(k) with the translated entries' rounding carried as
certified radii (:func:`core.fixed.filters.classify_translated`), and where it abstains, exact
rational arithmetic classifies the exactly translated matrix
(:func:`core.shapes.quadrics.origin_moved`). So every label is the true label of the input as
given: the body matrices, and their translates by the vectors v(k) of the box.

Only the nearest image can touch (the minimum image convention is exact) when r_i + r_j < h / 2
for every pair, r the certified bounding radii and h the cell's smallest *height* (the distance
between two opposite faces; the diameter of the largest sphere inside the cell): a nonzero
lattice vector k1 a1 + k2 a2 + k3 a3 with k_a != 0 has a component k_a h_a along the unit
normal of the faces a, so it is at least h long, and two images of j within r_i + r_j of body i
would need h <= 2 (r_i + r_j). For an orthogonal box h = min(L). :func:`check_box` refuses a
larger body (with room for the half-ulp roundings of v(k)), and centres that do not lie in one
box (fractional coordinates spanning more than 1 along a box vector): then the touching image
has k in {-1, 0, 1}^d.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from fractions import Fraction
from functools import lru_cache
from typing import Any

import numpy as np
from flint import fmpq

from ..fixed.classify import Certifier
from ..fixed.exact import classify_exact
from ..fixed.filters import classify_translated
from ..formulae.decision import RULE_RELATION
from ..relation import Relation
from ..shapes.quadrics import origin_moved, symmetric_part

__all__ = [
    "read_box",
    "is_tilted",
    "box_vectors",
    "lattice_shifts",
    "cell_heights",
    "fractional",
    "fractional_point",
    "box_vectors_exact",
    "shift_error",
    "check_box",
    "check_sizes",
    "classify_images",
]

_MARGIN = 1.0 - 2.0**-20
"""The size rule is checked with this margin (rounding of the radii sum and of h / 2)."""
_GAMMA = 2.0**-48
"""Relative error allowed per fractional coordinate step (a handful of roundings of 2^-53 each)."""
_TINY = 2.0**-1000
"""Absolute error floor (covers underflow in the error bounds)."""


def read_box(box: Any, d: int) -> np.ndarray | None:
    """The box as a float64 array: d sides (orthogonal), or 6 numbers (tilted); None for open space.

    Accepted: d sides; ``(Lx, Ly, Lz, xy, xz, yz)`` (3D); ``(Lx, Ly, xy)`` or the six numbers of
    a HOOMD 2D frame (2D; Lz is ignored, xz and yz must be 0). Sides positive, tilts finite.

    Raises:
        ValueError: anything else, saying what was expected.

    Examples:
        >>> read_box((10, 10, 5.5), 3).tolist()
        [10.0, 10.0, 5.5]
        >>> read_box((10, 10, 5.5, 0.5, 0, -0.25), 3).tolist()
        [10.0, 10.0, 5.5, 0.5, 0.0, -0.25]
        >>> read_box((10, 10, 5.5, 0, 0, 0), 3).tolist()      # no tilt: an orthogonal box
        [10.0, 10.0, 5.5]
        >>> read_box((10, 8, 0.5), 2).tolist()
        [10.0, 8.0, 0.0, 0.5, 0.0, 0.0]
        >>> read_box([10, 0], 2)
        Traceback (most recent call last):
        ...
        ValueError: box: expected 2 positive finite sides (Lx, Ly) or (Lx, Ly, xy) (a tilted box), got [10.0, 0.0]
    """
    if box is None:
        return None
    names = (
        "(Lx, Ly) or (Lx, Ly, xy) (a tilted box)"
        if d == 2
        else "(Lx, Ly, Lz) or (Lx, Ly, Lz, xy, xz, yz) (a tilted box, HOOMD's tilt factors)"
    )
    try:
        L = np.asarray(box, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"box: expected {d} positive finite sides {names}, got {box!r}") from None
    if d == 2 and L.size == 3:
        L = np.array([L[0], L[1], 0.0, L[2], 0.0, 0.0])
    elif d == 2 and L.size == 6:
        if L[4] != 0 or L[5] != 0:
            raise ValueError(f"box: a 2D box has no tilt factors xz, yz; got {L.tolist()}")
        L = np.array([L[0], L[1], 0.0, L[3], 0.0, 0.0])
    if L.size == 6:
        sides = L[:d]
        if not (np.isfinite(L).all() and (sides > 0).all()):
            raise ValueError(f"box: expected {d} positive finite sides {names}, got {L.tolist()}")
        if not L[3:].any():
            return L[:d].copy()
        with np.errstate(over="ignore"):
            products = L[3:] * L[[1, 2, 2]]
        if not np.isfinite(products).all() or not np.isfinite(cell_heights(L, d)).all() or not (cell_heights(L, d) > 0).all():
            raise ValueError(f"box: the tilt factors {L[3:].tolist()} are beyond the float range for these sides")
        return L
    if L.size != d or not (np.isfinite(L).all() and (L > 0).all()):
        raise ValueError(f"box: expected {d} positive finite sides {names}, got {L.tolist()}")
    return L


def is_tilted(box: Any) -> bool:
    """Whether a box from :func:`read_box` (or a :class:`core.Box`) is tilted: six numbers rather than d sides."""
    return box is not None and len(box) == 6


def box_vectors(box: np.ndarray, d: int) -> np.ndarray:
    """(d, d) float box vectors a1, a2[, a3] as columns, the tilt products rounded once.

    For estimates and drawing (fractional coordinates, the cell's edges); the images use the
    correctly rounded :func:`lattice_shifts`.

    Examples:
        >>> box_vectors(read_box((10, 8, 0.5), 2), 2).tolist()
        [[10.0, 4.0], [0.0, 8.0]]
    """
    if not is_tilted(box):
        return np.diag(box[:d])
    Lx, Ly, Lz, xy, xz, yz = (float(v) for v in box)
    if d == 2:
        return np.array([[Lx, xy * Ly], [0.0, Ly]])
    return np.array([[Lx, xy * Ly, xz * Lz], [0.0, Ly, yz * Lz], [0.0, 0.0, Lz]])


def lattice_shifts(box: np.ndarray, image: np.ndarray) -> np.ndarray:
    """The float lattice vectors v(k) of the images k (module docstring): (M, d) float64.

    Each component is the float nearest to the exact k1 a1 + k2 a2 [+ k3 a3] (products of the
    box's floats taken exactly). For an orthogonal box that is k L rounded once: exact for k in
    {-1, 0, 1}.

    Args:
        box: from :func:`read_box`.
        image: (M, d) integer images.

    Raises:
        ValueError: a lattice vector beyond the float range.

    Examples:
        >>> lattice_shifts(np.array([10.0, 8.0]), np.array([[1, -1], [0, 0]])).tolist()
        [[10.0, -8.0], [0.0, 0.0]]
        >>> b = read_box((10, 10, 10, 0.1, 0, 0), 3)     # a2 = (0.1 * 10, 10, 0): 0.1 * 10 exactly
        >>> lattice_shifts(b, np.array([[1, 1, 0]])).tolist()   # 11.000000000000000055511151231257827 rounded
        [[11.0, 10.0, 0.0]]
    """
    k = np.asarray(image)
    d = k.shape[-1]
    if not is_tilted(box):
        with np.errstate(over="ignore"):
            out = k.astype(np.float64) * box
    elif k.size and int(np.max(np.abs(k))) <= 1:
        table = _unit_shift_table(tuple(float(v) for v in box), d)
        code = np.zeros(k.shape[0], dtype=np.int64)
        for a in range(d):
            code = code * 3 + (k[:, a].astype(np.int64) + 1)
        out = table[code]
    else:
        rows, inverse = np.unique(k.reshape(-1, d), axis=0, return_inverse=True)
        vals = np.array([_exact_shift(tuple(float(v) for v in box), tuple(int(x) for x in r)) for r in rows])
        out = vals.reshape(-1, d)[inverse.reshape(-1)] if rows.size else np.zeros((0, d))
    if not np.isfinite(out).all():
        raise ValueError("box: a lattice vector k1 a1 + k2 a2 + k3 a3 is beyond the float range")
    return np.asarray(out, dtype=np.float64).reshape(k.shape[0], d)


@lru_cache(maxsize=64)
def _unit_shift_table(box: tuple[float, ...], d: int) -> np.ndarray:
    """v(k) for every k in {-1, 0, 1}^d, row sum_a (k_a + 1) 3^(d-1-a) (mixed radix, axis 0 first)."""
    table = np.array([_exact_shift(box, k) for k in itertools.product((-1, 0, 1), repeat=d)])
    table.setflags(write=False)
    return table


def _exact_shift(box: tuple[float, ...], k: tuple[int, ...]) -> list[float]:
    """One v(k): exact rationals, rounded once per component (float(Fraction) rounds to nearest)."""
    Lx, Ly, Lz, xy, xz, yz = (Fraction(v) for v in box)
    try:
        if len(k) == 2:
            return [float(k[0] * Lx + k[1] * xy * Ly), float(k[1] * Ly)]
        return [float(k[0] * Lx + k[1] * xy * Ly + k[2] * xz * Lz), float(k[1] * Ly + k[2] * yz * Lz), float(k[2] * Lz)]
    except OverflowError:
        return [math.inf] * len(k)


def shift_error(box: np.ndarray, d: int) -> float:
    """An upper bound of |v(k) - (k1 a1 + ...)| (Euclidean) for k in {-1, 0, 1}^d (0 if orthogonal)."""
    if not is_tilted(box):
        return 0.0
    return float(np.abs(box_vectors(box, d)).sum()) * 2.0**-51


def cell_heights(box: np.ndarray, d: int) -> np.ndarray:
    """Lower bounds of the cell's heights h_a (distance between the two faces crossed along a_a).

    Orthogonal: the sides. Tilted (3D): h_x = Lx / sqrt(1 + xy^2 + (xy yz - xz)^2),
    h_y = Ly / sqrt(1 + yz^2), h_z = Lz (2D: h_x = Lx / sqrt(1 + xy^2), h_y = Ly); computed in
    floats and lowered by 2^-40 relative (far more than their roundings).

    Examples:
        >>> cell_heights(read_box((10, 10, 10, 1, 0, 0), 3), 3).round(9).tolist()   # 10 / sqrt(2)
        [7.071067812, 10.0, 10.0]
    """
    if not is_tilted(box):
        return np.asarray(box[:d], dtype=np.float64)
    Lx, Ly, Lz, xy, xz, yz = (float(v) for v in box)
    with np.errstate(over="ignore", invalid="ignore"):
        if d == 2:
            h = np.array([Lx / math.sqrt(1.0 + xy * xy) if math.isfinite(xy * xy) else 0.0, Ly])
        else:
            t = 1.0 + xy * xy + (xy * yz - xz) ** 2 if abs(xy) < 1e150 and abs(yz) < 1e150 and abs(xz) < 1e150 else math.inf
            h = np.array([Lx / math.sqrt(t), Ly / math.sqrt(1.0 + yz * yz) if abs(yz) < 1e150 else 0.0, Lz])
    return h * (1.0 - 2.0**-40)


def fractional(centers: np.ndarray, box: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fractional coordinates f (c = f1 a1 + f2 a2 [+ f3 a3]) in floats, and a bound of their error.

    Args:
        centers: (N, d) float centres.
        box: from :func:`read_box`.

    Returns:
        (f (N, d), eps (d,)): |f_computed - f_exact| <= eps per axis, f_exact for the exact box
        vectors (a triangular solve; every step's rounding is bounded by _GAMMA relative).
    """
    c = np.asarray(centers, dtype=np.float64)
    N, d = c.shape
    if not N:
        return np.zeros((0, d)), np.zeros(d)
    with np.errstate(over="ignore", invalid="ignore"):
        f, e = _solve([c[:, a] for a in range(d)], _vectors(tuple(float(v) for v in box), d))
    return np.stack(f, axis=1), np.array([float(np.max(x)) for x in e])


def fractional_point(c: Sequence[float], box: np.ndarray | tuple[tuple[float, ...], ...]) -> tuple[list[float], list[float]]:
    """:func:`fractional` of one point, in Python floats (the same operations): (f, eps).

    ``box`` may also be :func:`box_vectors_exact` of the box (a caller asking for many points).
    """
    vectors = box if isinstance(box, tuple) else _vectors(tuple(float(v) for v in box), len(c))
    return _solve([float(v) for v in c], vectors)


def box_vectors_exact(box: np.ndarray, d: int) -> tuple[tuple[float, ...], ...]:
    """:func:`box_vectors` as nested tuples of Python floats (for :func:`fractional_point`)."""
    return _vectors(tuple(float(v) for v in box), d)


@lru_cache(maxsize=64)
def _vectors(box: tuple[float, ...], d: int) -> tuple[tuple[float, ...], ...]:
    """:func:`box_vectors` as nested tuples of Python floats (cached)."""
    return tuple(tuple(float(x) for x in row) for row in box_vectors(np.array(box), d))


def _solve(c: list[Any], B: tuple[tuple[float, ...], ...]) -> tuple[list[Any], list[Any]]:
    """The triangular solve B f = c and its error bound (numpy columns or Python floats alike)."""
    d = len(c)
    f: list[Any] = [0.0] * d
    e: list[Any] = [0.0] * d
    for a in range(d - 1, -1, -1):  # upper triangular: the last axis first
        acc = c[a]
        mag = abs(c[a])
        err: Any = 0.0
        for b in range(a + 1, d):
            if B[a][b]:
                acc = acc - B[a][b] * f[b]
                mag = mag + abs(B[a][b]) * abs(f[b])
                err = err + abs(B[a][b]) * e[b]
        f[a] = acc / B[a][a]
        e[a] = ((_GAMMA * mag + err) / B[a][a]) * (1 + _GAMMA) + _TINY
    return f, e


def check_box(centers: np.ndarray, radii: np.ndarray, box: np.ndarray) -> None:
    """Raise unless the minimum image convention is exact for these bodies in this box.

    Args:
        centers: (N, d) float centres of the bounding spheres (NaN rows: invalid, ignored).
        radii: (N,) certified bounding radii (NaN: invalid).
        box: from :func:`read_box` (sides, or the six numbers of a tilted box).

    Raises:
        ValueError: naming the body: its centre lies more than one box length from another's
            along a box vector (wrap the centres into the box first), or it is too large for the
            box (the two largest bounding radii must sum to less than half the smallest height
            of the cell: half the smallest side of an orthogonal box).

    Examples:
        >>> check_box(np.array([[0.0, 0.0], [9.0, 1.0]]), np.array([1.0, 1.0]), np.array([10.0, 10.0]))
        >>> check_box(np.array([[0.0, 0.0], [12.0, 1.0]]), np.array([1.0, 1.0]), np.array([10.0, 10.0]))
        Traceback (most recent call last):
        ...
        ValueError: body 1: centre x = 12 is more than one box side (Lx = 10) from body 0's (x = 0): the centres must lie in one box (wrap them into it first, e.g. x mod Lx)
        >>> check_box(np.array([[0.0, 0.0], [5.0, 5.0]]), np.array([1.6, 2.0]), read_box((10, 10, 1), 2))
        Traceback (most recent call last):
        ...
        ValueError: body 1 is too large for the periodic box: its bounding radius 2 plus the next largest, 1.6, must be less than half the smallest height of the cell (7.07107 / 2: the distance between opposite faces of the tilted cell, the diameter of the sphere inscribed in it), so that only the nearest image of a body can touch another
    """
    valid = np.flatnonzero(np.isfinite(radii))
    if not valid.size:
        return
    c = centers[valid]
    d = c.shape[1]
    axis_names = "xyz"
    if is_tilted(box):
        f, eps = fractional(c, box)
        for a in range(d):
            lo, hi = int(np.argmin(f[:, a])), int(np.argmax(f[:, a]))
            if not f[hi, a] - f[lo, a] <= 1.0:
                raise ValueError(
                    f"body {valid[hi]}: its centre is more than one box length from body {valid[lo]}'s along the box "
                    f"vector a{a + 1} (fractional coordinates {f[hi, a]:.12g} and {f[lo, a]:.12g}): the centres must "
                    "lie in one box (wrap them into it first)"
                )
            if not eps[a] < 2.0**-20:
                raise ValueError(f"box: the tilt factors {box[3:].tolist()} are too large to place the bodies in float64")
    else:
        for a in range(d):
            lo, hi = int(np.argmin(c[:, a])), int(np.argmax(c[:, a]))
            if c[hi, a] - c[lo, a] > box[a]:
                raise ValueError(
                    f"body {valid[hi]}: centre {axis_names[a]} = {c[hi, a] + 0.0:.12g} is more than one box side "
                    f"(L{axis_names[a]} = {box[a]:.12g}) from body {valid[lo]}'s ({axis_names[a]} = {c[lo, a] + 0.0:.12g}): "
                    f"the centres must lie in one box (wrap them into it first, e.g. {axis_names[a]} mod L{axis_names[a]})"
                )
    check_sizes(radii, box, d)


def check_sizes(radii: np.ndarray, box: np.ndarray, d: int) -> None:
    """The size rule of :func:`check_box` alone: the two largest radii sum to less than h / 2.

    Raises:
        ValueError: naming the largest body.
    """
    valid = np.flatnonzero(np.isfinite(radii))
    if not valid.size:
        return
    r = radii[valid]
    top = np.argsort(r)[::-1][:2]
    r1 = float(r[top[0]])
    r2 = float(r[top[1]]) if top.size > 1 else r1
    h = float(np.min(cell_heights(box, d)))
    half = h / 2 - shift_error(box, d)
    if not (r1 + r2 < half * _MARGIN):
        what = (
            "half the smallest side"
            if not is_tilted(box)
            else "half the smallest height of the cell"
        )
        detail = (
            f"({h:.6g} / 2)"
            if not is_tilted(box)
            else f"({h:.6g} / 2: the distance between opposite faces of the tilted cell, the diameter of the sphere inscribed in it)"
        )
        raise ValueError(
            f"body {valid[top[0]]} is too large for the periodic box: its bounding radius {r1:.6g} plus "
            f"the next largest, {r2:.6g}, must be less than {what} {detail}, "
            f"so that only the nearest image of a body can touch another"
        )


def classify_images(
    A: np.ndarray, B: np.ndarray, shift: np.ndarray, method: str
) -> tuple[np.ndarray, np.ndarray]:
    """Relations of A against B moved by ``shift`` (exactly), certified; and who certified them.

    Args:
        A: float64 stack (M, n, n) of valid bodies.
        B: the same shape; B[k] is moved by shift[k].
        shift: (M, n - 1) float lattice vectors v(k) (:func:`lattice_shifts`; B moves by exactly these).
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
