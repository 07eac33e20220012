"""Ellipses and ellipsoids as homogeneous quadric matrices: THE conventions of this project.

Conventions (written once here and in the README):

* An ellipse is a symmetric 3x3 matrix A on homogeneous coordinates X = (x, y, 1); an ellipsoid a
  symmetric 4x4 matrix on (x, y, z, 1). The interior is X^T A X < 0, the boundary X^T A X = 0.
  Valid iff the quadratic block is positive definite and det A < 0. A matrix with all signs
  flipped (positive interior) is normalised to this form, not rejected.
* P(T) = det(T A + B), coefficients always in ascending order [a_0, ..., a_n]; a_n = det A < 0,
  a_0 = det B < 0. T is the pencil variable; t is time, always.
* A shape is centre c, semi-axes r and orientation R (2D: angle in radians, counter-clockwise;
  3D: unit quaternion wxyz, viser's convention). Its matrix is
  [[Q, -Q c], [-c^T Q, c^T Q c - 1]] with Q = R diag(1/r^2) R^T (body axes -> world).
* Inputs may be floats of any width (float16/32/64, long double: the exact binary rationals they
  are), ints, Fractions, fmpq, or strings ("3/7", "0.1" exact decimal). See
  :func:`core.shapes.numbers.to_fmpq`.
* The shape {X : X^T A X <= 0} depends only on the quadratic form, that is on the exact symmetric
  part (A + A^T)/2: that is what is classified, so a matrix built in floating point
  (``R @ D @ R.T``), symmetric only up to rounding, is certified for its own quadratic form. A
  matrix whose asymmetry is far beyond rounding is refused as a likely mistake: entry pair (i, j)
  may differ by at most :data:`SYMMETRY_TOLERANCE` times sqrt(m_i m_j), m_i the largest |entry|
  in row or column i (about 1e-6 relative: ten billion float64 roundings, a few float32 ones).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Literal, TypeAlias, overload

import numpy as np
from flint import fmpq, fmpz

from ..errors import InvalidInput
from ..formulae.pencil import determinant
from .numbers import sign, to_fmpq
from .rotation import rotation_numerator

__all__ = [
    "SYMMETRY_TOLERANCE",
    "Entry",
    "Matrix",
    "Stack",
    "ExactMatrix",
    "ShapeParams",
    "quadric_from_axes",
    "quadrics_from_axes",
    "axes_row_errors",
    "rotations_from_orientations",
    "origin_moved",
    "axes_from_quadric",
    "rotation_from_quaternion",
    "validate_quadric",
]

ExactMatrix = list[list[fmpq]]
"""A matrix of exact rationals, as nested lists."""
Entry: TypeAlias = int | float | Fraction | fmpq | fmpz | np.floating[Any] | np.integer[Any]
"""One number of a user's matrix, read exactly (strings such as "3/7" are read too, typed as ``object``)."""
Matrix: TypeAlias = Sequence[Sequence[Entry]]
"""One matrix as nested sequences of numbers (a type checker then knows: one pair, one result)."""
Stack: TypeAlias = Sequence[Matrix] | Sequence[Sequence[Matrix]]
"""A stack of matrices as nested sequences (then: an array of results)."""

SYMMETRY_TOLERANCE = Fraction(1, 2**20)
"""Largest accepted asymmetry |a_ij - a_ji| / sqrt(m_i m_j) (see the module docstring); the
float filter applies the same rule, conservatively, and leaves borderline pairs to this one."""


@dataclass(frozen=True)
class ShapeParams:
    """Centre, semi-axes and orientation of an ellipse (angle) or ellipsoid (wxyz), as floats."""

    center: tuple[float, ...]
    """(x, y) or (x, y, z)."""
    semi_axes: tuple[float, ...]
    """Semi-axis lengths along the body axes."""
    orientation: tuple[float, ...]
    """2D: (angle,) in radians; 3D: unit quaternion (w, x, y, z)."""


@overload
def rotation_from_quaternion(wxyz: Sequence[Any] | np.ndarray, *, exact: Literal[False] = False) -> np.ndarray: ...
@overload
def rotation_from_quaternion(wxyz: Sequence[Any] | np.ndarray, *, exact: Literal[True]) -> ExactMatrix: ...
@overload
def rotation_from_quaternion(wxyz: Sequence[Any] | np.ndarray, *, exact: bool) -> np.ndarray | ExactMatrix: ...
def rotation_from_quaternion(wxyz: Sequence[Any] | np.ndarray, *, exact: bool = False) -> np.ndarray | ExactMatrix:
    """3x3 rotation matrix of quaternion (w, x, y, z); need not be unit (divided by |q|^2).

    With ``exact=True`` a rational quaternion gives an exactly orthogonal rational matrix.

    Examples:
        >>> rotation_from_quaternion([1, 0, 0, 1], exact=True)[0]   # 90 degrees about z
        [0, -1, 0]
    """
    if len(wxyz) != 4:
        raise ValueError(f"a quaternion has 4 components (w, x, y, z), got {len(wxyz)}")
    v: list[Any] = [to_fmpq(a) for a in wxyz] if exact else [float(a) for a in wxyz]
    R, n = rotation_numerator(v)
    if n == 0:
        raise ValueError("orientation quaternion is zero")
    rows = [[a / n for a in r] for r in R]
    return rows if exact else np.array(rows, dtype=float)


@overload
def quadric_from_axes(center: Sequence[Any] | np.ndarray, semi_axes: Sequence[Any] | np.ndarray, orientation: Any = ..., *, exact: Literal[False] = ...) -> np.ndarray: ...
@overload
def quadric_from_axes(center: Sequence[Any] | np.ndarray, semi_axes: Sequence[Any] | np.ndarray, orientation: Any = ..., *, exact: Literal[True]) -> ExactMatrix: ...
@overload
def quadric_from_axes(center: Sequence[Any] | np.ndarray, semi_axes: Sequence[Any] | np.ndarray, orientation: Any = ..., *, exact: bool) -> np.ndarray | ExactMatrix: ...
def quadric_from_axes(
    center: Sequence[Any] | np.ndarray,
    semi_axes: Sequence[Any] | np.ndarray,
    orientation: Any = None,
    *,
    exact: bool = False,
) -> np.ndarray | ExactMatrix:
    """Matrix of the ellipse/ellipsoid with this centre, semi-axes and orientation.

    Args:
        center: (x, y) or (x, y, z).
        semi_axes: positive lengths, same count as ``center``.
        orientation: 2D: angle in radians (float), or a quaternion (w, 0, 0, z) for an exact
            rotation about z; 3D: quaternion wxyz (need not be unit). None = axis-aligned.
        exact: return nested lists of ``fmpq`` (then the angle must be a quaternion or None).

    Returns:
        (n+1, n+1) float ndarray, or nested lists of ``fmpq`` when ``exact``.

    Examples:
        >>> quadric_from_axes([0, 0], [1, 1], exact=True)     # unit circle
        [[1, 0, 0], [0, 1, 0], [0, 0, -1]]
    """
    d = len(center)
    if d not in (2, 3) or len(semi_axes) != d:
        raise ValueError(f"need 2 or 3 centre coordinates and as many semi-axes, got {d} and {len(semi_axes)}")
    c: list[Any]
    r: list[Any]
    if exact:
        c = [to_fmpq(v) for v in center]
        r = [to_fmpq(v) for v in semi_axes]
    else:
        c = [float(v) for v in center]
        r = [float(v) for v in semi_axes]
        if not all(math.isfinite(v) for v in (*c, *r)):
            raise ValueError("centre and semi-axes must be finite numbers")
    if any(v <= 0 for v in r):
        raise ValueError(f"semi-axes must be positive, got {[str(v) for v in r]}")
    if not exact:  # the many-shape builder's checks, e.g. a centre too far for its float matrix (FAR_FROM_ORIGIN)
        for reason in axes_row_errors(np.array([c]), np.array([r]), first=True).values():
            raise ValueError(reason)
    R = _orientation_matrix(d, orientation, exact)
    if not exact:  # the float matrix is built by the one vectorised routine (bit for bit)
        out: np.ndarray = _assemble_float(np.array([c]), np.array([r]), np.asarray(R, dtype=float)[None])[0]
        if np.isnan(out).any():
            raise ValueError(unrepresentable(c, r))
        return out
    inv_r2 = [1 / (v * v) for v in r]
    Q = [[sum(R[min(i, j)][k] * inv_r2[k] * R[max(i, j)][k] for k in range(d)) for j in range(d)] for i in range(d)]
    Qc = [sum(Q[i][j] * c[j] for j in range(d)) for i in range(d)]
    cQc = sum(c[i] * Qc[i] for i in range(d))
    M = [[Q[i][j] for j in range(d)] + [-Qc[i]] for i in range(d)]
    M.append([-v for v in Qc] + [cQc - 1])
    return M


def unrepresentable(c: Any, r: Any) -> str:
    """Why a shape has no float64 matrix (the message of :func:`quadric_from_axes` and the builders)."""
    return (f"centre {list(map(float, c))} and semi-axes {list(map(float, r))}: no float64 matrix holds this shape "
            "(at any scale its entries would span more than 2^2040, the shape being tiny or huge beside its distance "
            "from the origin); place the origin nearer the bodies, or give exact parameters (exact=True)")


def quadrics_from_axes(
    centers: Any, semi_axes: Any, orientations: Any = None, *, unrepresentable_rows: Literal["raise", "nan"] = "raise",
    checked: bool = False,
) -> np.ndarray:
    """Float matrices of N shapes: :func:`quadric_from_axes` vectorised, bit for bit.

    Row k of the result is exactly (every bit) ``quadric_from_axes(centers[k], semi_axes[k],
    orientations[k])``: the same float operations in the same order, so a body of a packing and
    the same shape opened alone (the scene's two-body view, the API) are one matrix and get one
    certified label.

    Args:
        centers: (N, d) floats, d = 2 or 3.
        semi_axes: (N, d) positive floats.
        orientations: 3D: (N, 4) quaternions wxyz (need not be unit); 2D: (N,) or (N, 1) angles
            in radians, or (N, 4) quaternions (w, 0, 0, z); None = axis-aligned.
        unrepresentable_rows: "raise" a ValueError for a row no float64 matrix holds, or "nan":
            such a row is NaN (:func:`core.bodies.bodies_from_axes` marks it invalid).
        checked: the caller already found every row a shape (:func:`axes_row_errors` empty):
            the check is not run twice (:func:`core.bodies.build.matrices_and_errors`).

    Returns:
        float64 array (N, d + 1, d + 1).

    Raises:
        ValueError: wrong shapes, or a row with a non-finite number, a semi-axis <= 0 or a zero
            quaternion (the message names the first such row: :func:`axes_row_errors`), or a row
            no float64 matrix holds (:func:`unrepresentable`; with ``unrepresentable_rows="nan"``
            such a row is NaN instead).

    Examples:
        >>> M = quadrics_from_axes([[0, 0, 0], [3, 0, 0]], [[1, 1, 1], [2, 1, 1]], [[1, 0, 0, 0], [1, 0, 0, 1]])
        >>> bool((M[1] == quadric_from_axes([3, 0, 0], [2, 1, 1], [1, 0, 0, 1])).all())
        True
        >>> quadrics_from_axes([[0, 0], [1, 1]], [[1, 1], [1, -1]])
        Traceback (most recent call last):
        ...
        ValueError: row 1: semi-axes must be positive, got [1.0, -1.0]
    """
    c, r, o = _axes_arrays(centers, semi_axes, orientations)
    errors = {} if checked else axes_row_errors(c, r, o, first=True)
    if errors:
        k, reason = next(iter(errors.items()))
        raise ValueError(f"row {k}: {reason}")
    M = _assemble_float(c, r, rotations_from_orientations(o, *c.shape))
    if unrepresentable_rows == "raise":
        nan_rows = np.flatnonzero(np.isnan(M).any(axis=(1, 2)))
        if nan_rows.size:
            k = int(nan_rows[0])
            raise ValueError(f"row {k}: {unrepresentable(c[k], r[k])}")
    return M


def _axes_arrays(centers: Any, semi_axes: Any, orientations: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """float64 arrays (N, d), (N, d) and (N,) angles or (N, 4) quaternions (or None); shapes checked."""
    c = np.asarray(centers, dtype=float)
    r = np.asarray(semi_axes, dtype=float)
    if c.ndim != 2 or c.shape[1] not in (2, 3) or r.shape != c.shape:
        raise ValueError(f"centers and semi_axes must both be (N, 2) or (N, 3) arrays, got {c.shape} and {r.shape}")
    if orientations is None:
        return c, r, None
    N, d = c.shape
    o = np.asarray(orientations, dtype=float)
    if d == 2 and o.shape in ((N,), (N, 1)):
        return c, r, o.reshape(N)
    if o.shape != (N, 4):
        want = "(N,) angles or (N, 4) quaternions" if d == 2 else "(N, 4) quaternions wxyz"
        raise ValueError(f"orientations must be {want} for {N} shapes, got shape {o.shape}")
    return c, r, o


FAR_FROM_ORIGIN = 2.0**26
"""A float shape whose centre is farther from the origin than this many times its smallest
semi-axis is refused. The constant term of its matrix, c^T S c - 1 with |S| ~ 1/a^2, rounds by a
few times 2^-53 (|c|/a)^2 relative to the shape's size, which from here on reaches the size of the
shape itself: the matrix may be any shape or none (unit circles 2 apart at x = 1e12 became one
overlapping pair, at x = 1e8 a "degenerate ellipse"). Below it the label is certified for the
float matrix, which is the shape to within that relative error (ill-conditioned bodies, such as a
1e-6 sphere at (5, 5, 5), stay accepted: their bounding spheres go to exact arithmetic); exact
parameters (``exact=True``) have no such limit."""


def _far_limit(r: np.ndarray) -> np.ndarray:
    """FAR_FROM_ORIGIN times each row's smallest semi-axis (inf past the float range: no centre is that far)."""
    with np.errstate(over="ignore"):
        return np.asarray(FAR_FROM_ORIGIN * r.min(axis=1, initial=np.inf), dtype=np.float64)


def axes_row_errors(centers: Any, semi_axes: Any, orientations: Any = None, *, first: bool = False,
                    matrices: bool = True) -> dict[int, str]:
    """Row -> why those parameters are no shape (the checks of :func:`quadrics_from_axes`).

    Args:
        centers: (N, d) floats, as for :func:`quadrics_from_axes`.
        semi_axes: (N, d) floats.
        orientations: (N, 4) quaternions, (N,) angles (2D) or None.
        first: stop at the first bad row.
        matrices: also refuse a centre so far from the origin (2^26 times the smallest
            semi-axis) that no float64 matrix holds the shape; False for the computations that
            read the parameters exactly and build no float matrix (the sweep).

    Returns:
        ``{row: reason}`` for rows with a non-finite number, a semi-axis <= 0, a zero quaternion
        or (2D) a quaternion that does not rotate about z; empty when all rows are shapes.

    Examples:
        >>> axes_row_errors([[0, 0], [1, float("nan")]], [[1, 1], [0, 1]])
        {1: 'centre and semi-axes must be finite numbers, got [1.0, nan] and [0.0, 1.0]'}
    """
    c, r, o = _axes_arrays(centers, semi_axes, orientations)
    N, d = c.shape
    if _all_shapes(c, r, o, matrices):
        return {}
    checks: list[tuple[Any, Any]] = [
        (~(np.isfinite(c).all(axis=1) & np.isfinite(r).all(axis=1)),
         lambda k: f"centre and semi-axes must be finite numbers, got {c[k].tolist()} and {r[k].tolist()}"),
        (~(r > 0).all(axis=1), lambda k: f"semi-axes must be positive, got {r[k].tolist()}"),
        (np.abs(c).max(axis=1, initial=0.0) > _far_limit(r) if matrices else np.zeros(N, dtype=bool),
         lambda k: f"centre {c[k].tolist()} is more than 2^26 times the smallest semi-axis ({float(r[k].min())!r}) from "
                   "the origin: the float64 matrix would not be this shape (its constant term rounds by as much as "
                   "the shape's own size); place the origin nearer the bodies"),
    ]
    if o is not None and o.ndim == 1:
        checks.append((~np.isfinite(o), lambda k: "orientation angle must be finite"))
    elif o is not None:
        finite = np.isfinite(o).all(axis=1)
        checks.append((~finite, lambda k: "orientation must be finite numbers"))
        checks.append((finite & ~(o != 0).any(axis=1), lambda k: "orientation quaternion is zero"))
        if d == 2:
            checks.append(((o[:, 1] != 0) | (o[:, 2] != 0), lambda k: "a 2D quaternion must rotate about z: (w, 0, 0, z)"))
    errors: dict[int, str] = {}
    bad_any = np.zeros(N, dtype=bool)
    for bad, reason in checks:
        rows = np.flatnonzero(bad & ~bad_any)
        bad_any |= bad
        for k in rows[:1] if first else rows:
            errors[int(k)] = reason(int(k))
        if first and errors:
            break
    return dict(sorted(errors.items()))


def _all_shapes(c: np.ndarray, r: np.ndarray, o: np.ndarray | None, matrices: bool) -> bool:
    """True when whole-array tests show every row passes :func:`axes_row_errors`' checks (most batches).

    Sufficient, not necessary (then the row-by-row checks decide): every number finite, every
    semi-axis positive, no centre beyond the limit of the smallest semi-axis of all, every
    quaternion of positive squared norm (2D: about z).
    """
    with np.errstate(over="ignore", under="ignore"):
        if not (np.isfinite(c).all() and np.isfinite(r).all() and (r > 0).all()):
            return False
        if matrices and c.size and not float(np.abs(c).max()) <= float(_far_limit(r.reshape(1, -1))[0]):
            return False
        if o is None:
            return True
        if not np.isfinite(o).all():
            return False
        if o.ndim == 1:
            return True
        if c.shape[1] == 2 and not ((o[:, 1] == 0).all() and (o[:, 2] == 0).all()):
            return False
        return bool((np.einsum("ij,ij->i", o, o) > 0).all())


def rotations_from_orientations(o: np.ndarray | None, N: int, d: int) -> np.ndarray:
    """(N, d, d) rotation matrices (body -> world) of N orientations, as :func:`quadric_from_axes` reads them.

    ``o``: (N, 4) quaternions wxyz, (N,) angles (2D) or None; finite and non-zero (checked by
    :func:`axes_row_errors`).

    3D: quaternions wxyz, divided by |q|^2 (the operations of :func:`rotation_from_quaternion`);
    2D: angles (``math.cos``/``math.sin``, as for one shape) or quaternions (w, 0, 0, z); None:
    identity.
    """
    if o is None:
        return np.broadcast_to(np.eye(d), (N, d, d))
    if o.ndim == 1:
        # math.cos/sin, not np.cos: numpy's SIMD versions may differ in the last bit
        co = np.fromiter((math.cos(t) for t in o.tolist()), dtype=float, count=N)
        si = np.fromiter((math.sin(t) for t in o.tolist()), dtype=float, count=N)
        return np.stack([np.stack([co, -si], axis=1), np.stack([si, co], axis=1)], axis=1)
    rows, n = rotation_numerator([o[:, 0], o[:, 1], o[:, 2], o[:, 3]])
    R = np.stack([np.stack([v / n for v in row], axis=1) for row in rows], axis=1)
    return R[:, :2, :2] if d == 2 else R


def origin_moved(M: Sequence[Sequence[Any]], t: Sequence[Any]) -> list[list[Any]]:
    """G^T M G with G = [[I, t], [0, 1]]: the same shape in coordinates whose origin is the point t.

    The shape moves by -t (to move a shape by s, pass t = -s). Ring-generic: it runs on
    ``fmpq`` (an exact translate), and :mod:`core.fixed.kernelgen` traces it into the filter's
    float kernel with certified radii, so both paths perform one formula.

    Args:
        M: (d+1) x (d+1) symmetric matrix (nested sequences; the upper triangle is read).
        t: d numbers.

    Returns:
        Nested lists, symmetric: Q unchanged, m' = Q t + m, m'_nn = t^T Q t + 2 m.t + m_nn.

    Examples:
        >>> from flint import fmpq
        >>> unit = quadric_from_axes([0, 0], [1, 1], exact=True)
        >>> origin_moved(unit, [fmpq(-2), fmpq(0)]) == quadric_from_axes([2, 0], [1, 1], exact=True)
        True
    """
    d = len(M) - 1
    out = [[M[min(i, j)][max(i, j)] for j in range(d + 1)] for i in range(d + 1)]
    Qt = []
    for i in range(d):
        acc = M[i][d]
        for j in range(d):
            acc = acc + M[min(i, j)][max(i, j)] * t[j]
        Qt.append(acc)
        out[i][d] = out[d][i] = acc  # (Q t + m)_i
    last = M[d][d]
    for i in range(d):
        last = last + t[i] * (Qt[i] + M[i][d])  # t^T Q t + 2 m.t + m_nn
    out[d][d] = last
    return out


def _assemble_float(c: np.ndarray, r: np.ndarray, R: np.ndarray) -> np.ndarray:
    """[[Q, -Q c], [-c^T Q, c^T Q c - 1]], Q = R diag(1/r^2) R^T, for (N, d) c, r and (N, d, d) R.

    The float operations of the one-shape formula, elementwise: the upper triangle of Q is
    summed over k in order and mirrored (rounding must not make the matrix non-symmetric).

    A shape whose matrix in this form is not representable (1/r^2 overflows or underflows: semi-axes
    beyond about 2^±511, e.g. 1e-160 or 1e160) is built at the scale s = 2^e of its largest
    number instead and put back exactly: with Q', m', k' its matrix for c / s, r / s, the matrix
    s D M' D (D = diag(1/s, .., 1/s, 1)) = [[Q' / s, m'], [m'^T, s k']] describes the same shape
    (a positive multiple), every entry a normal float. Where even that leaves the range (a body
    far smaller than its distance from the origin at the ends of the range, e.g. semi-axes 1e-304
    at 1e-299), the multiple 2^q [[Q' / s^2, m' / s], [m'^T / s, k']] with q centring the entries'
    exponents is taken (:func:`_balanced`). Shapes the plain form holds are unchanged; a shape no
    multiple holds (its entries would span more than 2^2040) is a row of NaN.
    """
    with np.errstate(over="ignore", under="ignore", invalid="ignore", divide="ignore"):  # found and mended below
        M = _assemble_plain(c, r, R)
    d = c.shape[1]
    out_of_range = ~_in_range(M, d)
    fixable = out_of_range & np.isfinite(c).all(axis=1) & np.isfinite(r).all(axis=1) & (r > 0).all(axis=1)
    if fixable.any():
        k = np.flatnonzero(fixable)
        big = np.maximum(np.abs(c[k]).max(axis=1), r[k].max(axis=1))
        e = np.frexp(big)[1]
        s = np.ldexp(1.0, e)[:, None]  # a power of 2: the divisions below are exact
        with np.errstate(over="ignore", under="ignore", invalid="ignore", divide="ignore"):
            Mp = _assemble_plain(c[k] / s, r[k] / s, R[k])
            Ms = Mp.copy()
            Ms[:, :d, :d] /= s[:, :, None]
            Ms[:, d, d] *= s[:, 0]
        still = ~_in_range(Ms, d)
        if still.any():
            Ms[still] = _balanced(Mp[still], e[still], d)
        M[k] = Ms
        M[k[~_in_range(Ms, d)]] = np.nan
    return M


def _in_range(M: np.ndarray, d: int) -> np.ndarray:
    """Rows whose every entry is finite and whose Q has normal (not underflowed) diagonal entries."""
    Q_diag = np.abs(M[:, np.arange(d), np.arange(d)])
    ok: np.ndarray = np.isfinite(M).all(axis=(1, 2)) & (Q_diag >= np.finfo(np.float64).tiny).all(axis=1)
    return ok


def _balanced(Mp: np.ndarray, e: np.ndarray, d: int) -> np.ndarray:
    """The shape's matrix times the power of two that centres its entries' exponents.

    That is 2^q [[Q' / s^2, m' / s], [m'^T / s, k']] (s = 2^e) from M' = [[Q', m'], [m'^T, k']],
    the matrix for c / s, r / s; NaN rows where the exponents span more than 2040 (or M' itself
    is out of range).
    """

    def expo(x: np.ndarray) -> np.ndarray:  # |x| in [2^(E-1), 2^E)
        e: np.ndarray = np.frexp(x)[1].astype(np.int64)
        return e

    Q, m, k = Mp[:, :d, :d], Mp[:, :d, d], Mp[:, d, d]
    with np.errstate(invalid="ignore"):
        q_max = expo(np.abs(Q).max(axis=(1, 2))) - 2 * e
        q_min = expo(np.abs(Q[:, np.arange(d), np.arange(d)]).min(axis=1)) - 2 * e
        m_abs = np.abs(m).max(axis=1)
        m_e = np.where(m_abs > 0, expo(m_abs) - e, q_max)
        k_e = np.where(k != 0, expo(np.abs(k)), q_max)
    hi = np.maximum(np.maximum(q_max, m_e), k_e)
    lo = np.minimum(q_min, k_e)
    q = -((hi + lo) // 2)
    out = np.empty_like(Mp)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):  # rows that do not fit become NaN below
        out[:, :d, :d] = np.ldexp(Q, (q - 2 * e)[:, None, None])
        out[:, :d, d] = out[:, d, :d] = np.ldexp(m, (q - e)[:, None])
        out[:, d, d] = np.ldexp(k, q)
    fits = np.isfinite(Mp).all(axis=(1, 2)) & (hi + q <= 1020) & (lo + q >= -1020)
    out[~fits] = np.nan
    return out


def _assemble_plain(c: np.ndarray, r: np.ndarray, R: np.ndarray) -> np.ndarray:
    """:func:`_assemble_float`'s formula as written, in floats (non-finite where it overflows)."""
    N, d = c.shape
    inv_r2 = 1 / (r * r)
    M = np.empty((N, d + 1, d + 1))
    for i in range(d):
        for j in range(i, d):
            acc = R[:, i, 0] * inv_r2[:, 0] * R[:, j, 0]
            for k in range(1, d):
                acc = acc + R[:, i, k] * inv_r2[:, k] * R[:, j, k]
            M[:, i, j] = M[:, j, i] = acc
    Qc = []
    for i in range(d):
        acc = M[:, i, 0] * c[:, 0]
        for j in range(1, d):
            acc = acc + M[:, i, j] * c[:, j]
        Qc.append(acc)
    cQc = c[:, 0] * Qc[0]
    for i in range(1, d):
        cQc = cQc + c[:, i] * Qc[i]
    for i in range(d):
        M[:, i, d] = M[:, d, i] = -Qc[i]
    M[:, d, d] = cQc - 1
    return M


def _orientation_matrix(d: int, orientation: Any, exact: bool) -> Any:
    one, zero = (fmpq(1), fmpq(0)) if exact else (1.0, 0.0)
    if orientation is None:
        return [[one if i == j else zero for j in range(d)] for i in range(d)]
    if d == 3 or (d == 2 and isinstance(orientation, Sequence) and len(orientation) == 4):
        if len(orientation) != 4:
            raise ValueError("a 3D orientation is a quaternion (w, x, y, z)")
        R = rotation_from_quaternion(orientation, exact=exact)
        if d == 2:
            if exact and (R[0][2] != 0 or R[1][2] != 0 or R[2][0] != 0 or R[2][1] != 0):
                raise ValueError("a 2D quaternion must rotate about z: (w, 0, 0, z)")
            return [[R[0][0], R[0][1]], [R[1][0], R[1][1]]]
        return R
    if exact:
        raise ValueError("an exact 2D orientation is a quaternion (w, 0, 0, z); an angle is a float")
    theta = float(orientation[0] if isinstance(orientation, Sequence) else orientation)
    if not math.isfinite(theta):
        raise ValueError("orientation angle must be finite")
    co, si = math.cos(theta), math.sin(theta)
    return [[co, -si], [si, co]]


def axes_from_quadric(M: Any, *, validate: bool = True) -> ShapeParams:
    """Centre, semi-axes and orientation of an ellipse/ellipsoid matrix (floats, for drawing).

    Args:
        M: the matrix (any accepted input form; a float array when ``validate=False``).
        validate: check exactly that M is an ellipse/ellipsoid first (:func:`validate_quadric`).
            ``False`` is the float-only path the scene takes at every t-step; it raises
            ValueError when the float matrix does not describe an ellipse/ellipsoid.

    Examples:
        >>> p = axes_from_quadric(quadric_from_axes([1, 2], [3, 1], 0.5))
        >>> [round(v, 9) for v in (*p.center, *p.semi_axes, *p.orientation)]
        [1.0, 2.0, 3.0, 1.0, 0.5]
    """
    if validate:
        A = np.array([[float(v) for v in row] for row in validate_quadric(M)], dtype=float)
    else:
        A = np.asarray(M, dtype=float)
        if A[0, 0] < 0:
            A = -A
    d = A.shape[0] - 1
    Q, m = A[:d, :d], A[:d, d]
    c = -np.linalg.solve(Q, m)
    k = float(c @ Q @ c - A[d, d])
    w, V = np.linalg.eigh(Q / k) if k > 0 else (np.zeros(d), np.eye(d))
    if not (k > 0 and np.all(w > 0)):
        raise ValueError("the float matrix is not an ellipse/ellipsoid")
    # eigh sorts eigenvalues ascending, so semi-axes come out decreasing; keep det V = +1
    r = 1.0 / np.sqrt(w)
    if np.linalg.det(V) < 0:
        V[:, -1] = -V[:, -1]
    center = tuple(float(v) for v in c)
    axes = tuple(float(v) for v in r)
    if d == 2:
        angle = math.atan2(V[1, 0], V[0, 0])
        # an ellipse axis is a direction up to sign: report the angle in (-pi/2, pi/2]
        if angle > math.pi / 2:
            angle -= math.pi
        elif angle <= -math.pi / 2:
            angle += math.pi
        return ShapeParams(center, axes, (angle,))
    return ShapeParams(center, axes, _quaternion_from_rotation(V))


def _quaternion_from_rotation(R: np.ndarray) -> tuple[float, float, float, float]:
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > 0:
        s = 2.0 * math.sqrt(tr + 1.0)
        q = (0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s)
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2.0 * math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = ((R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s)
    elif R[1, 1] > R[2, 2]:
        s = 2.0 * math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = ((R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = ((R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s)
    n = math.sqrt(sum(v * v for v in q))
    s = 1.0 if q[0] >= 0 else -1.0
    return tuple(float(s * v / n) for v in q)  # type: ignore[return-value]


def symmetric_part(E: ExactMatrix, name: str = "matrix") -> ExactMatrix:
    """The exact symmetric part (E + E^T)/2 of a square rational matrix (the quadratic form).

    Raises:
        ValueError: the asymmetry exceeds :data:`SYMMETRY_TOLERANCE` (a mistake, not rounding);
            the message gives its size and suggests ``(A + A.T) / 2``.

    Examples:
        >>> S = symmetric_part([[fmpq(1), fmpq(1, 3)], [fmpq(1, 3) + fmpq(1, 2**60), fmpq(1)]])
        >>> S[0][1] == S[1][0] == fmpq(1, 3) + fmpq(1, 2**61)
        True
    """
    n = len(E)
    if all(E[i][j] == E[j][i] for i in range(n) for j in range(i + 1, n)):
        return E
    m = [max(max(abs(E[i][k]), abs(E[k][i])) for k in range(n)) for i in range(n)]
    tol2 = fmpq(SYMMETRY_TOLERANCE.numerator**2, SYMMETRY_TOLERANCE.denominator**2)
    for i in range(n):
        for j in range(i + 1, n):
            diff = E[i][j] - E[j][i]
            if diff != 0 and diff * diff > tol2 * m[i] * m[j]:
                from .numbers import format_rational

                scale = math.sqrt(float(m[i]) * float(m[j])) if m[i] * m[j] > 0 else 0.0
                rel = abs(float(diff)) / scale if scale > 0 else math.inf
                def short(v: fmpq) -> str:
                    return str(v) if len(str(v)) <= 24 else format_rational(v, 8)

                raise ValueError(
                    f"{name} is not symmetric: entry ({i},{j}) = {short(E[i][j])} but "
                    f"({j},{i}) = {short(E[j][i])}, a difference of {rel:.2g} relative to "
                    f"the scale of rows {i} and {j} (rounding is accepted up to "
                    f"{float(SYMMETRY_TOLERANCE):.2g}); if this is rounding, pass (A + A.T) / 2"
                )
    half = fmpq(1, 2)
    return [[E[i][j] if i == j else (E[i][j] + E[j][i]) * half for j in range(n)] for i in range(n)]


def interior_sign(minor_signs: Sequence[int]) -> int | None:
    """The sign that normalises a matrix: +1, -1, or None if no sign makes it definite.

    +1 if the leading principal minors of a quadratic block are all positive (definite), -1 if
    they alternate -, +, -, ... (negative definite: the matrix is a flipped ellipse or
    ellipsoid), None otherwise. The one normalisation rule of static and moving shapes.

    Examples:
        >>> interior_sign([1, 1]), interior_sign([-1, 1]), interior_sign([1, -1])
        (1, -1, None)
    """
    if all(s > 0 for s in minor_signs):
        return 1
    if all(s == (-1 if k % 2 == 0 else 1) for k, s in enumerate(minor_signs)):
        return -1
    return None


def not_a_quadric_message(name: str, n: int) -> str:
    """Why a matrix whose quadratic block is not definite is refused."""
    kind = "ellipse" if n == 3 else "ellipsoid"
    other = (
        "a hyperbola, parabola or degenerate conic"
        if n == 3
        else "a hyperboloid, paraboloid, cylinder, cone or degenerate quadric"
    )
    return f"{name} is not an {kind}: its quadratic part is indefinite or semidefinite ({other})"


def normalised_quadratic_part(M: Any, *, name: str = "matrix") -> ExactMatrix:
    """Exact symmetric part of M with a positive definite quadratic block (signs flipped if needed).

    Checks shape, readable finite entries, symmetry up to rounding (:func:`symmetric_part`) and
    definiteness (Sylvester's criterion on the leading minors); the sign of det, which completes
    :func:`validate_quadric`, is left to the caller (the exact classifier reads it off the
    pencil: det A = a_n, det B = a_0).
    """
    try:
        rows = _rows(M, name)
        n = len(rows)
        E = symmetric_part([[_entry(v, name, i, j) for j, v in enumerate(row)] for i, row in enumerate(rows)], name)
    except ValueError as e:
        raise InvalidInput.of(e, matrix=name) from None
    minors = [determinant([row[:k] for row in E[:k]]) for k in range(1, n)]
    flip = interior_sign([sign(m) for m in minors])
    if flip == 1:
        return E
    if flip == -1:
        return [[-v for v in row] for row in E]
    raise InvalidInput(not_a_quadric_message(name, n), matrix=name)


def check_determinant_sign(det_sign: int, n: int, name: str) -> None:
    """Raise unless det < 0 (given the sign of det of the normalised matrix)."""
    kind = "ellipse" if n == 3 else "ellipsoid"
    if det_sign == 0:
        raise InvalidInput(f"{name} is a degenerate {kind} (det = 0: a single point)", matrix=name)
    if det_sign > 0:
        raise InvalidInput(f"{name} has an empty interior: no real points (det > 0), not an {kind}", matrix=name)


def validate_quadric(M: Any, *, name: str = "matrix") -> ExactMatrix:
    """Check that M is an ellipse (3x3) or ellipsoid (4x4) and return it exactly, normalised.

    Args:
        M: nested sequence or array of numbers (see module docstring for accepted types).
        name: what to call the matrix in error messages (e.g. "A").

    Returns:
        Nested lists of ``fmpq`` with interior X^T M X < 0 (signs flipped if needed).

    Raises:
        InvalidInput: (a ValueError naming ``name``) wrong shape, not symmetric, NaN/inf or
            unreadable entry, quadratic part not definite, degenerate (det = 0) or empty (no
            real points).

    Examples:
        >>> validate_quadric([[-1, 0, 0], [0, -1, 0], [0, 0, 1]])   # flipped unit circle
        [[1, 0, 0], [0, 1, 0], [0, 0, -1]]
        >>> validate_quadric([[1, 0, 0], [0, -1, 0], [0, 0, -1]])
        Traceback (most recent call last):
        ...
        core.errors.InvalidInput: matrix is not an ellipse: its quadratic part is indefinite or semidefinite (a hyperbola, parabola or degenerate conic)
    """
    E = normalised_quadratic_part(M, name=name)
    d = determinant(E)
    check_determinant_sign(sign(d), len(E), name)
    return E


def _rows(M: Any, name: str) -> list[list[Any]]:
    expected = "a 3x3 (ellipse) or 4x4 (ellipsoid) matrix"
    if isinstance(M, np.ndarray):
        if M.ndim != 2:
            raise ValueError(f"{name} must be {expected}, got an array of shape {M.shape}")
        rows = [list(r) for r in M]  # numpy scalars kept: long doubles are read exactly
    else:
        if isinstance(M, str | bytes) or not isinstance(M, Sequence):
            raise ValueError(f"{name} must be {expected} (nested lists or an array), got {type(M).__name__}")
        try:
            rows = [list(r) for r in M]
        except TypeError:
            raise ValueError(f"{name} must be {expected} (nested lists or an array): a row is not a list") from None
        if any(isinstance(r, str | bytes) for r in M):
            raise ValueError(f"{name} must be {expected}: a row is a string")
    n = len(rows)
    if n not in (3, 4) or any(len(r) != n for r in rows):
        shape = f"{n}x{'/'.join(sorted({str(len(r)) for r in rows})) or 0}"
        raise ValueError(f"{name} must be {expected}, got {shape}")
    return rows


def _entry(v: Any, name: str, i: int, j: int) -> fmpq:
    try:
        return to_fmpq(v)
    except ValueError as e:
        raise ValueError(f"{name} entry ({i},{j}): {e}") from None
