"""Moving ellipses/ellipsoids: a matrix A(t) with rational-function entries in t (paper 3.4, 4.4).

Two input forms share one JSON format (used by the HTTP API, the scene and the presets):

* ``{"matrix": [[e, ...], ...]}``: the (n+1) x (n+1) symmetric matrix, entries are expressions in
  t (strings, see :mod:`core.moving.expressions`) or numbers;
* ``{"shape": {"center": [...], "semi_axes": [...], "orientation": ...},
  "translation": [...], "rotation": {"quaternion": [w, x, y, z]} | {"matrix": [[...]]},
  "scale": [...]}``: a body shape moved by ``x_world = L(t) x_body + c(t)`` with
  ``L = R(t) diag(scale(t))``. Every number may be an expression in t (also the shape's own
  parameters). Orientation: 3D quaternion wxyz (need not be unit); 2D ``[w, z]`` (rotation about
  z by the quaternion, exact) or a float angle in radians (then cos/sin are the binary
  rationals of their float values: the shape is then only a float-accurate rotation).
  A rotation quaternion with polynomial components gives a rational rotation (divided by |q|^2).

This is the paper's motion convention (NOTES.md): A(t) = M(t)^-T A0 M(t)^-1 with
M = [[L, c], [0, 1]]. We compute it as world centre ``c + L c0`` and quadratic block
``L^-T Q0 L^-1`` (L^-1 = adj(L)/det(L), exact), which is the same matrix.

Reading user text (the scene, the HTTP API, the library) goes through two public readers, one
grammar each, under the caller's size limits (:mod:`core.shapes.limits`):

* :func:`read_motion`: a motion in any accepted form, its matrix built at once: every
  expression is parsed exactly once, and an error names its place (``a.translation[0]: ...``);
* :func:`read_interval`: the interval I, a pair (lo, hi) or the text "lo, hi". An infinite end
  is None, "none", or -inf / inf / infinity / -infinity / +inf / +infinity (any case, on the
  right side: "-inf" only as lo), or a float infinity; a finite end is a number or a number
  string (``parse_number``: "1/3", "0.25", "1e-3").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from flint import fmpq

from ..formulae.pencil import determinant
from ..shapes.limits import Limits, using
from ..shapes.numbers import parse_number, to_fmpq
from ..shapes.quadrics import ShapeParams, axes_from_quadric
from ..shapes.rotation import rotation_numerator
from .expressions import RationalFunction, parse_expression

__all__ = [
    "Motion",
    "ExpressionError",
    "read_motion",
    "read_interval",
    "INFINITE_ENDS",
    "motion_from_dict",
    "motion_to_dict",
    "as_motion",
    "matrix_at",
    "matrix_at_exact",
    "shape_at",
]

RFMatrix = list[list[RationalFunction]]


def _expr_text(x: Any) -> str:
    if isinstance(x, str):
        return x.strip()
    if isinstance(x, bool):
        raise ValueError(f"a boolean is not an expression: {x!r}")
    if isinstance(x, int | float | fmpq):
        if isinstance(x, float) and not math.isfinite(x):
            raise ValueError(f"not a finite number: {x!r}")
        return str(to_fmpq(x)) if isinstance(x, float) else str(x)
    if isinstance(x, RationalFunction):
        return str(x)
    raise ValueError(f"expected an expression string or a number, got {type(x).__name__} {x!r}")


class ExpressionError(ValueError):
    """An expression of a motion could not be read: ``path`` is its place, ``reason`` why.

    The message is ``"{path}: {reason}"``, e.g. ``translation[0]: unexpected 'x' at position 3``.
    """

    def __init__(self, path: str, reason: str) -> None:
        super().__init__(f"{path}: {reason}")
        self.path = path
        self.reason = reason


def _parse(x: Any, where: str) -> RationalFunction:
    try:
        return parse_expression(_expr_text(x))
    except ValueError as e:
        raise ExpressionError(where, str(e)) from None


def _vector(x: Any, n: int | None, where: str) -> list[str]:
    if isinstance(x, str) or not isinstance(x, Sequence):
        raise ValueError(f"{where} must be a list of expressions, got {x!r}")
    if n is not None and len(x) != n:
        raise ValueError(f"{where} must have {n} entries, got {len(x)}")
    return [_expr_text(v) for v in x]


@dataclass(frozen=True)
class Motion:
    """One moving ellipse/ellipsoid, kept as the source expressions (see the module docstring).

    Build it with :func:`motion_from_dict` or :func:`as_motion`; ``matrix()`` gives the exact
    A(t) (cached). A Motion pickles with its matrix: a worker process can parse user text under
    a time budget and send the result back.
    """

    dim: int
    """2 (ellipse, 3x3 matrix) or 3 (ellipsoid, 4x4)."""
    source: dict[str, Any]
    """The normalised JSON form (expressions as strings); ``motion_to_dict`` returns a copy."""
    limits: Limits | None = field(default=None, repr=False, compare=False)
    """Size limits while the matrix is built (:mod:`core.shapes.limits`; None: those in force)."""
    _matrix: list[RFMatrix] = field(default_factory=list, repr=False, compare=False)
    _float_coeffs: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list, repr=False, compare=False)

    def matrix(self) -> RFMatrix:
        """A(t) exactly: (dim+1) x (dim+1) nested lists of :class:`RationalFunction`."""
        if not self._matrix:
            with using(self.limits):
                self._matrix.append(_build_matrix(self.source, self.dim))
        return self._matrix[0]

    def float_coefficients(self) -> tuple[np.ndarray, np.ndarray]:
        """Float coefficients of every entry's numerator and denominator, cached.

        Entries x degree, descending, sqrt(d) folded in: the scene evaluates A(t) at each
        t-step with them.
        """
        if not self._float_coeffs:
            entries = [e for row in self.matrix() for e in row]
            nums, dens = [], []
            for e in entries:
                p = [_to_float(c) for c in e.num.p.coeffs()] or [0.0]
                q = [_to_float(c) * math.sqrt(e.num.d) for c in e.num.q.coeffs()] or [0.0]
                size = max(len(p), len(q))
                nums.append([a + b for a, b in zip(p + [0.0] * (size - len(p)), q + [0.0] * (size - len(q)), strict=False)])
                dens.append([_to_float(c) for c in e.den.coeffs()] or [1.0])
            self._float_coeffs.append((_stack_descending(nums), _stack_descending(dens)))
        return self._float_coeffs[0]

    def sqrt_d(self) -> int:
        """The d of the sqrt(d) in the entries (1 if all are rational)."""
        ds = {e.d for row in self.matrix() for e in row} - {1}
        if len(ds) > 1:
            raise ValueError(f"entries use different square roots {sorted(ds)}: only one sqrt(d) allowed")
        return ds.pop() if ds else 1


def motion_from_dict(data: Any, *, limits: Limits | None = None) -> Motion:
    """Read a motion from its JSON form (see the module docstring); validates everything.

    Args:
        data: the JSON form (or a Motion, returned as it is).
        limits: size limits of the text and of the arithmetic building A(t)
            (:mod:`core.shapes.limits`; default: those in force, :data:`core.shapes.limits.LIBRARY`).

    Raises:
        ValueError: unknown keys, wrong sizes, unparsable expressions, a non-symmetric matrix,
            different square roots, or a size over ``limits``.

    Examples:
        >>> m = motion_from_dict({"shape": {"center": [0, 0], "semi_axes": [1, 1]},
        ...                       "translation": ["2*t", "0"]})
        >>> [str(e) for e in m.matrix()[0]]
        ['1', '0', '-2*t']
    """
    if isinstance(data, Motion):
        return data
    if not isinstance(data, dict):
        raise ValueError(f"a motion is a dict with 'matrix' or 'shape', got {type(data).__name__}")
    if "matrix" in data:
        extra = set(data) - {"matrix"}
        if extra:
            raise ValueError(f"unknown keys next to 'matrix': {sorted(extra)}")
        rows = data["matrix"]
        if isinstance(rows, str) or not isinstance(rows, Sequence) or len(rows) not in (3, 4):
            raise ValueError("'matrix' must be a 3x3 (ellipse) or 4x4 (ellipsoid) nested list")
        n = len(rows)
        msrc: dict[str, Any] = {"matrix": [_vector(r, n, f"matrix row {i}") for i, r in enumerate(rows)]}
        m = Motion(n - 1, msrc, limits)
        M = m.matrix()
        for i in range(n):
            for j in range(i + 1, n):
                if M[i][j] != M[j][i]:
                    raise ValueError(f"matrix is not symmetric: entry ({i},{j}) = {M[i][j]} but ({j},{i}) = {M[j][i]}")
        m.sqrt_d()
        return m
    if "shape" not in data:
        raise ValueError("a motion needs 'matrix' or 'shape' (with optional 'translation', 'rotation', 'scale')")
    extra = set(data) - {"shape", "translation", "rotation", "scale"}
    if extra:
        raise ValueError(f"unknown motion keys: {sorted(extra)}")
    shape = data["shape"]
    if not isinstance(shape, dict) or "center" not in shape or "semi_axes" not in shape:
        raise ValueError("'shape' must be a dict with 'center', 'semi_axes' and optional 'orientation'")
    extra = set(shape) - {"center", "semi_axes", "orientation"}
    if extra:
        raise ValueError(f"unknown shape keys: {sorted(extra)}")
    center = _vector(shape["center"], None, "shape.center")
    dim = len(center)
    if dim not in (2, 3):
        raise ValueError(f"shape.center must have 2 or 3 entries, got {dim}")
    src: dict[str, Any] = {"shape": {"center": center, "semi_axes": _vector(shape["semi_axes"], dim, "shape.semi_axes")}}
    ori = shape.get("orientation")
    if ori is not None:
        if dim == 2 and isinstance(ori, int | float) and not isinstance(ori, bool):
            if not math.isfinite(float(ori)):
                raise ValueError("shape.orientation angle must be finite")
            src["shape"]["orientation"] = float(ori)
        else:
            n_q = 4 if dim == 3 else (2 if isinstance(ori, Sequence) and len(ori) == 2 else 4)
            src["shape"]["orientation"] = _vector(ori, n_q, "shape.orientation")
    if data.get("translation") is not None:
        src["translation"] = _vector(data["translation"], dim, "translation")
    if data.get("scale") is not None:
        src["scale"] = _vector(data["scale"], dim, "scale")
    rot = data.get("rotation")
    if rot is not None:
        if not isinstance(rot, dict) or len(rot) != 1 or next(iter(rot)) not in ("quaternion", "matrix"):
            raise ValueError("'rotation' must be {'quaternion': [w, x, y, z]} or {'matrix': [[...]]}")
        if "quaternion" in rot:
            q = rot["quaternion"]
            n_q = 4 if dim == 3 else (2 if isinstance(q, Sequence) and len(q) == 2 else 4)
            src["rotation"] = {"quaternion": _vector(q, n_q, "rotation.quaternion")}
        else:
            rows = rot["matrix"]
            if isinstance(rows, str) or not isinstance(rows, Sequence) or len(rows) != dim:
                raise ValueError(f"rotation.matrix must be {dim}x{dim}")
            src["rotation"] = {"matrix": [_vector(r, dim, f"rotation.matrix row {i}") for i, r in enumerate(rows)]}
    m = Motion(dim, src, limits)
    m.sqrt_d()
    return m


def motion_to_dict(m: Motion) -> dict[str, Any]:
    """The JSON form of a motion (inverse of :func:`motion_from_dict`)."""
    import copy

    return copy.deepcopy(m.source)


def as_motion(x: Any, *, limits: Limits | None = None) -> Motion:
    """A :class:`Motion` from a Motion, a JSON dict, or an n x n nested list of expressions.

    ``limits``: size limits of the text (a Motion keeps its own).
    """
    if isinstance(x, Motion):
        return x
    if isinstance(x, dict):
        return motion_from_dict(x, limits=limits)
    if isinstance(x, np.ndarray):
        x = x.tolist()
    if isinstance(x, Sequence) and not isinstance(x, str):
        return motion_from_dict({"matrix": x}, limits=limits)
    raise ValueError(f"cannot read a motion from {type(x).__name__}")


def read_motion(data: Any, *, limits: Limits | None = None, name: str | None = None) -> Motion:
    """Read a motion from user input and build its exact matrix A(t): every expression parsed once.

    Args:
        data: a motion dict (:func:`motion_from_dict`), an n x n nested list of expressions, or a
            :class:`Motion` (returned as it is, its matrix built).
        limits: size limits of the text and of the arithmetic (:mod:`core.shapes.limits`;
            default: those in force). A server reads with :data:`core.shapes.limits.SERVER`,
            in a worker process.
        name: the motion's name in the caller's input; errors then read
            ``"{name}.{place}: {reason}"`` for an expression (``a.translation[0]: ...``) and
            ``"{name}: {reason}"`` otherwise.

    Raises:
        ValueError: the first problem, with its place (:class:`ExpressionError` for an
            expression).

    Examples:
        >>> read_motion({"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["2*t + x", "0"]}, name="a")
        Traceback (most recent call last):
        ...
        core.moving.motions.ExpressionError: a.translation[0]: unexpected 'x' at position 6: 2*t + x (allowed: numbers, t, + - * / ^, parentheses, sqrt(n))
    """
    try:
        m = as_motion(data, limits=limits)
        m.matrix()
        m.sqrt_d()
        return m
    except ExpressionError as e:
        if name is None:
            raise
        raise ExpressionError(f"{name}.{e.path}", e.reason) from None
    except ValueError as e:
        if name is None:
            raise
        raise ValueError(f"{name}: {e}") from None


INFINITE_ENDS = ("none", "inf", "+inf", "-inf", "infinity", "+infinity", "-infinity")
"""Texts of an infinite end of I (any case; a signed one must be on its side)."""


def _interval_end(x: Any, which: str, limits: Limits | None) -> fmpq | None:
    """One end of I (``which``: "lo" or "hi"): None for an infinite end, else the exact rational."""
    if x is None:
        return None
    if isinstance(x, float) and math.isinf(x):
        if (x < 0) == (which == "lo"):
            return None
        raise ValueError(f"interval {which} = {x} is on the wrong side")
    if isinstance(x, str) and x.strip().lower() in INFINITE_ENDS:
        text = x.strip().lower()
        if text == "none" or text.startswith("-") == (which == "lo"):  # "none": either end; "-inf": lo only
            return None
        raise ValueError(f"interval {which} = {x!r} is on the wrong side")
    try:
        return parse_number(x, limits) if isinstance(x, str) else to_fmpq(x)
    except ValueError as e:
        raise ValueError(f"interval {which}: {e}") from None


def read_interval(interval: Any, limits: Limits | None = None) -> tuple[fmpq | None, fmpq | None]:
    """The interval I = [lo, hi] from a pair (lo, hi) or the text "lo, hi" (";" also separates).

    The one grammar of intervals (scene, HTTP API, library): see the module docstring.

    Args:
        interval: (lo, hi) or "lo, hi".
        limits: size limits of number strings (:mod:`core.shapes.limits`; default: in force).

    Returns:
        (lo, hi) exact rationals, None for an infinite end; lo < hi.

    Raises:
        ValueError: not a pair, an unreadable end ("interval lo: ..."), an infinity on the wrong
            side, or lo >= hi.

    Examples:
        >>> read_interval(("-1/2", None)), read_interval("-infinity, 2.5"), read_interval("none; none")
        ((-1/2, None), (None, 5/2), (None, None))
        >>> read_interval("inf, 0")
        Traceback (most recent call last):
        ...
        ValueError: interval lo = 'inf' is on the wrong side
    """
    if isinstance(interval, str):
        parts: Any = [p.strip() for p in interval.replace(";", ",").split(",")]
        if len(parts) != 2 or not all(parts):
            raise ValueError(f"interval: expected 'lo, hi' (none, -inf or inf for an open end), got {interval[:60]!r}")
    elif isinstance(interval, Sequence) and len(interval) == 2:
        parts = interval
    else:
        raise ValueError(f"interval must be a pair (lo, hi), got {interval!r}")
    lo, hi = _interval_end(parts[0], "lo", limits), _interval_end(parts[1], "hi", limits)
    if lo is not None and hi is not None and not lo < hi:
        raise ValueError(f"empty interval: need lo < hi, got [{lo}, {hi}]")
    return lo, hi


# -------------------------------------------------------------------------------------------
# exact construction


def _rotation_from_quaternion(q: list[RationalFunction], dim: int) -> RFMatrix:
    if dim == 2 and len(q) == 4:
        if not (q[1].num.is_zero() and q[2].num.is_zero()):
            raise ValueError("a 2D quaternion must rotate about z: (w, 0, 0, z)")
        q = [q[0], q[3]]
    if len(q) != (4 if dim == 3 else 2):
        raise ValueError(f"a {dim}D rotation quaternion has {4 if dim == 3 else '2 or 4'} components, got {len(q)}")
    R, n = rotation_numerator(q)
    if n.num.is_zero():
        raise ValueError("rotation quaternion is identically zero")
    return [[v / n for v in r] for r in R]


def _inverse(M: RFMatrix, what: str) -> RFMatrix:
    n = len(M)
    det = determinant(M)
    if det.num.is_zero():
        raise ValueError(f"{what} is singular for every t")
    inv_det = det.inverse()
    adj = [[RationalFunction.constant(0)] * n for _ in range(n)]
    for i in range(n):
        for j in range(n):
            minor = [row[:j] + row[j + 1 :] for k, row in enumerate(M) if k != i]
            cof = determinant(minor) if n > 1 else RationalFunction.constant(1)
            adj[j][i] = cof * inv_det if (i + j) % 2 == 0 else -(cof * inv_det)
    return adj


def _build_matrix(src: dict[str, Any], dim: int) -> RFMatrix:
    if "matrix" in src:
        return [[_parse(v, f"matrix entry ({i},{j})") for j, v in enumerate(row)] for i, row in enumerate(src["matrix"])]
    shape = src["shape"]
    c0 = [_parse(v, f"shape.center[{i}]") for i, v in enumerate(shape["center"])]
    r = [_parse(v, f"shape.semi_axes[{i}]") for i, v in enumerate(shape["semi_axes"])]
    for i, ri in enumerate(r):
        if ri.num.is_zero():
            raise ValueError(f"shape.semi_axes[{i}] is zero")
    one, zero = RationalFunction.constant(1), RationalFunction.constant(0)
    ori = shape.get("orientation")
    if ori is None:
        R0 = [[one if i == j else zero for j in range(dim)] for i in range(dim)]
    elif isinstance(ori, float):
        co, si = to_fmpq(math.cos(ori)), to_fmpq(math.sin(ori))
        C, S = RationalFunction.constant(co), RationalFunction.constant(si)
        R0 = [[C, -S], [S, C]]
    else:
        R0 = _rotation_from_quaternion([_parse(v, f"shape.orientation[{i}]") for i, v in enumerate(ori)], dim)
    inv_r2 = [(ri * ri).inverse() for ri in r]
    Q0 = [[_sum(R0[i][k] * inv_r2[k] * R0[j][k] for k in range(dim)) for j in range(dim)] for i in range(dim)]
    # motion: L = R diag(scale), world centre c + L c0, quadratic block L^-T Q0 L^-1
    if "rotation" in src:
        rot = src["rotation"]
        if "quaternion" in rot:
            R = _rotation_from_quaternion([_parse(v, f"rotation.quaternion[{i}]") for i, v in enumerate(rot["quaternion"])], dim)
        else:
            R = [[_parse(v, f"rotation.matrix entry ({i},{j})") for j, v in enumerate(row)] for i, row in enumerate(rot["matrix"])]
    else:
        R = [[one if i == j else zero for j in range(dim)] for i in range(dim)]
    if "scale" in src:
        s = [_parse(v, f"scale[{i}]") for i, v in enumerate(src["scale"])]
        L = [[R[i][j] * s[j] for j in range(dim)] for i in range(dim)]
    else:
        L = R
    c = [_parse(v, f"translation[{i}]") for i, v in enumerate(src["translation"])] if "translation" in src else [zero] * dim
    is_identity = "rotation" not in src and "scale" not in src
    if is_identity:
        Q, cw = Q0, [c[i] + c0[i] for i in range(dim)]
    else:
        Li = _inverse(L, "the linear part L(t) of the motion")
        Q = [[_sum(Li[k][i] * Q0[k][m] * Li[m][j] for k in range(dim) for m in range(dim)) for j in range(dim)] for i in range(dim)]
        cw = [c[i] + _sum(L[i][k] * c0[k] for k in range(dim)) for i in range(dim)]
    Qc = [_sum(Q[i][j] * cw[j] for j in range(dim)) for i in range(dim)]
    cQc = _sum(cw[i] * Qc[i] for i in range(dim))
    M = [[Q[i][j] for j in range(dim)] + [-Qc[i]] for i in range(dim)]
    M.append([-v for v in Qc] + [cQc - 1])
    return M


def _sum(it: Any) -> RationalFunction:
    out = RationalFunction.constant(0)
    for v in it:
        out = out + v
    return out


# -------------------------------------------------------------------------------------------
# evaluation (drawing and tests)


def matrix_at(m: Any, t: float) -> np.ndarray:
    """Float matrix A(t) at a float t (display only: a float never decides a relation).

    Examples:
        >>> m = as_motion([["1", "0", "-t"], ["0", "1", "0"], ["-t", "0", "t^2 - 1"]])
        >>> matrix_at(m, 2.0).tolist()
        [[1.0, 0.0, -2.0], [0.0, 1.0, 0.0], [-2.0, 0.0, 3.0]]
    """
    motion = as_motion(m)
    num, den = motion.float_coefficients()
    t = float(t)
    vn = num[:, 0].copy()
    for k in range(1, num.shape[1]):  # Horner on all entries at once
        vn = vn * t + num[:, k]
    vd = den[:, 0].copy()
    for k in range(1, den.shape[1]):
        vd = vd * t + den[:, k]
    n = motion.dim + 1
    out: np.ndarray = (vn / vd).reshape(n, n)
    return out


def _to_float(c: fmpq) -> float:
    return int(c.p) / int(c.q)


def _stack_descending(rows: list[list[float]]) -> np.ndarray:
    """Ascending coefficient lists -> (len(rows), max degree + 1) array in descending order."""
    width = max(len(r) for r in rows)
    out = np.zeros((len(rows), width))
    for i, r in enumerate(rows):
        out[i, width - len(r) :] = r[::-1]
    return out


def matrix_at_exact(m: Any, t: Any) -> list[list[fmpq]]:
    """Exact rational A(t) at a rational t (ValueError if an entry is irrational or undefined)."""
    tq = to_fmpq(t)
    out = []
    for row in as_motion(m).matrix():
        r = []
        for e in row:
            den = e.den(tq)
            if den == 0:
                raise ValueError(f"a denominator vanishes at t = {tq}")
            a, b = e.num.at(tq)
            if b != 0:
                raise ValueError(f"entry {e} is irrational at t = {tq}")
            r.append(a / den)
        out.append(r)
    return out


def shape_at(m: Any, t: float) -> ShapeParams:
    """Centre, semi-axes and orientation at a float t (for drawing), via the float matrix."""
    return axes_from_quadric(matrix_at(m, t))
