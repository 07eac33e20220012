"""N bodies in linear motion over one step t in [0, 1]: the exact motion each one describes.

Body k has semi-axes r (fixed), centre c(t) = c0 + t (c1 - c0) and orientation R(t) = R(q(t) /
|q(t)|) with q(t) = (1 - t) q0 + t q1 (3D: quaternions wxyz of any non-zero length; R(q / |q|)
= R~(q) / |q|^2 with R~ quadratic in q, so the matrix A(t) is a rational function of t: a
rational motion, paper Sections 3.4 / 4.4, Choi et al. 2009). 2D: the same with the half-angle
complex number z = w + i s (``(w, z)`` rotates by the angle 2 atg(s / w): R~(z) =
[[w^2 - s^2, -2 w s], [2 w s, w^2 - s^2]]); an angle theta is read as z = (cos(theta / 2),
sin(theta / 2)) in float64 (those floats, exactly), so z(t) turns the body from theta0 to theta1
through theta1 - theta0 (|theta1 - theta0| < 2 pi), monotonically (not at constant speed).
Without ``orientations1`` the orientation is constant (q(t) = q0).

Every number is read as the exact binary rational it is: the bodies are the exact shapes these
parameters describe (not float matrices built from them). ``q(t)`` must not vanish on [0, 1]:
q1 = -lambda q0 with lambda > 0 is refused.

:meth:`LinearMotions.motion` gives one body's exact :class:`core.moving.motions.Motion` (what
:func:`core.moving.first_contact.first_contact` and :func:`core.analyse` read);
:meth:`LinearMotions.packed` the float rows the certified float filter reads
(:mod:`core.moving.sweep_filter`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np
from flint import fmpq, fmpq_poly

from ..algebra.qsqrt import QSqrtPoly
from ..shapes.numbers import to_fmpq
from ..shapes.quadrics import quadric_from_axes
from .expressions import RationalFunction
from .motions import Motion

__all__ = ["LinearMotions", "read_linear_motions"]


@dataclass
class LinearMotions:
    """Parameters of N bodies moving linearly over t in [0, 1] (float64, read exactly)."""

    centers0: np.ndarray
    """(N, d) centres at t = 0."""
    centers1: np.ndarray
    """(N, d) centres at t = 1."""
    semi_axes: np.ndarray
    """(N, d) semi-axes (> 0)."""
    q0: np.ndarray
    """(N, 4) quaternions wxyz (3D) or (N, 2) half-angle numbers (w, s) (2D) at t = 0."""
    q1: np.ndarray
    """The same at t = 1 (equal to q0 for a constant orientation)."""
    _rows: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def dim(self) -> int:
        """2 (ellipses) or 3 (ellipsoids)."""
        return int(self.centers0.shape[1])

    def __len__(self) -> int:
        return int(self.centers0.shape[0])

    def motion(self, k: int, shift: Any = None) -> Motion:
        """Body k's exact motion (optionally moved by the float vector ``shift``, exactly).

        Its JSON form (``motion_to_dict``) is the expressions above; its matrix A(t) is built
        directly in Q[t] (:func:`_exact_matrix`: the same rational functions the expressions
        give, without parsing them).

        Examples:
            >>> m = read_linear_motions([[0, 0]], [[1, 0]], [[1, 1]])[0]
            >>> [str(e) for e in m.motion(0).matrix()[0]]
            ['1', '0', '-t']
        """
        d = self.dim
        s = [Fraction(0)] * d if shift is None else [_q(v) for v in shift]
        c0 = [_q(v) + s[a] for a, v in enumerate(self.centers0[k])]
        c1 = [_q(v) + s[a] for a, v in enumerate(self.centers1[k])]
        r = [_q(v) for v in self.semi_axes[k]]
        src: dict[str, Any] = {
            "shape": {"center": ["0"] * d, "semi_axes": [str(v) for v in r]},
            "translation": [_line(a, b) for a, b in zip(c0, c1, strict=True)],
        }
        q0 = [_q(v) for v in self.q0[k]]
        q1 = [_q(v) for v in self.q1[k]]
        if q0 == q1:
            src["shape"]["orientation"] = [str(v) for v in q0]
        else:
            src["rotation"] = {"quaternion": [_line(a, b) for a, b in zip(q0, q1, strict=True)]}
        return Motion(d, src, None, [_exact_matrix(c0, c1, r, q0, q1)])

    def matrix_at_start(self, k: int, shift: Any = None) -> list[list[fmpq]]:
        """Body k's exact matrix at t = 0 (optionally moved by ``shift``), without the motion.

        Examples:
            >>> b, _ = read_linear_motions([[1.0, 0.0]], [[5.0, 0.0]], [[1.0, 1.0]])
            >>> b.matrix_at_start(0)
            [[1, 0, -1], [0, 1, 0], [-1, 0, 0]]
        """
        c = [_q(v) for v in self.centers0[k]]
        if shift is not None:
            c = [a + _q(v) for a, v in zip(c, shift, strict=True)]
        q0 = [float(v) for v in self.q0[k]]
        orientation = q0 if self.dim == 3 else [q0[0], 0.0, 0.0, q0[1]]
        return quadric_from_axes(c, [float(v) for v in self.semi_axes[k]], orientation, exact=True)  # type: ignore[no-any-return]

    def matrix_at(self, k: int, t: Any, shift: Any = None) -> list[list[fmpq]]:
        """Body k's exact matrix at a rational t (optionally moved by ``shift``), without the motion.

        The same matrix as ``matrix_at_exact(self.motion(k, shift), t)`` (the motion's A(t) at t),
        built directly from c(t) = c0 + t (c1 - c0) and q(t) = (1 - t) q0 + t q1 (a fraction of
        the cost of building the motion: the scene colours many bodies at one t this way).

        Examples:
            >>> from core.moving.motions import matrix_at_exact
            >>> b, _ = read_linear_motions([[0.0, 0.0]], [[2.0, 0.0]], [[1.0, 1.0]])
            >>> b.matrix_at(0, "1/2") == matrix_at_exact(b.motion(0), "1/2"), b.matrix_at(0, 0.5)[0]
            (True, [1, 0, -1])
        """
        tq = to_fmpq(t)
        s = [fmpq(0)] * self.dim if shift is None else [_f(_q(v)) for v in shift]
        c = [_f(_q(a)) + tq * (_f(_q(b)) - _f(_q(a))) + e for a, b, e in zip(self.centers0[k], self.centers1[k], s, strict=True)]
        q = [(1 - tq) * _f(_q(a)) + tq * _f(_q(b)) for a, b in zip(self.q0[k], self.q1[k], strict=True)]
        orientation = q if self.dim == 3 else [q[0], fmpq(0), fmpq(0), q[1]]
        return quadric_from_axes(c, [_f(_q(v)) for v in self.semi_axes[k]], orientation, exact=True)  # type: ignore[no-any-return]

    def packed(self) -> np.ndarray:
        """(N, 17) rows c0, c1, r, q0, q1 (3D) or (N, 10) (2D), float64, C order (the filter's input; kept)."""
        if self._rows is None:
            self._rows = np.ascontiguousarray(np.concatenate([self.centers0, self.centers1, self.semi_axes, self.q0, self.q1], axis=1))
        return self._rows


def read_linear_motions(
    centers0: Any,
    centers1: Any,
    semi_axes: Any,
    orientations0: Any = None,
    orientations1: Any = None,
) -> tuple[LinearMotions, dict[int, str]]:
    """Read and check the parameters of N moving bodies (see the module docstring).

    Args:
        centers0: (N, d) centres at t = 0, d = 2 or 3.
        centers1: (N, d) centres at t = 1.
        semi_axes: (N, d) semi-axes.
        orientations0: 3D: (N, 4) quaternions wxyz (any non-zero length); 2D: (N,) angles in
            radians or (N, 4) quaternions (w, 0, 0, z) (a rotation by 2 atg(z / w)); None:
            axis-aligned.
        orientations1: the same at t = 1; None: constant orientation.

    Returns:
        (the bodies, {row: reason} for rows that describe no moving body: a non-finite number,
        a semi-axis <= 0, a zero quaternion, or a quaternion path through zero). Bad rows hold
        harmless stand-in values (a unit sphere at rest at the origin).

    Raises:
        ValueError: arrays of the wrong shape, or numbers that are not float64 values.

    Examples:
        >>> _, bad = read_linear_motions([[0, 0, 0], [1, 0, 0]], [[0, 0, 0], [2, 0, 0]], [[1, 1, 1], [1, -1, 1]])
        >>> bad
        {1: 'row 1: semi-axes must be positive, got [1.0, -1.0, 1.0]'}
    """
    c0 = _floats(centers0, "centers0")
    if c0.ndim != 2 or c0.shape[1] not in (2, 3):
        raise ValueError(f"centers0 must be an (N, 2) or (N, 3) array, got shape {c0.shape}")
    N, d = c0.shape
    c1 = _floats(centers1, "centers1")
    r = _floats(semi_axes, "semi_axes")
    for name, arr in (("centers1", c1), ("semi_axes", r)):
        if arr.shape != (N, d):
            raise ValueError(f"{name} must have the shape of centers0 {(N, d)}, got {arr.shape}")
    q0 = _orientations(orientations0, N, d, "orientations0")
    q1 = q0.copy() if orientations1 is None else _orientations(orientations1, N, d, "orientations1")
    bad: dict[int, str] = {}

    def mark(rows: Any, reason: Any) -> None:
        for k in np.flatnonzero(rows).tolist():
            bad.setdefault(int(k), f"row {k}: {reason(int(k))}")

    mark(~np.isfinite(c0).all(axis=1), lambda k: f"centers0 must be finite numbers, got {c0[k].tolist()}")
    mark(~np.isfinite(c1).all(axis=1), lambda k: f"centers1 must be finite numbers, got {c1[k].tolist()}")
    mark(~np.isfinite(r).all(axis=1), lambda k: f"semi-axes must be finite numbers, got {r[k].tolist()}")
    mark(~(r > 0).all(axis=1), lambda k: f"semi-axes must be positive, got {r[k].tolist()}")
    for name, q in (("orientations0", q0), ("orientations1", q1)):
        finite = np.isfinite(q).all(axis=1)
        mark(~finite, lambda k, name=name, q=q: f"{name} must be finite numbers, got {q[k].tolist()}")
        mark(finite & ~(q != 0).any(axis=1), lambda k, name=name: f"{name}: the quaternion is zero")
    mark(_through_zero(q0, q1), lambda k: "the orientation passes through zero: q1 = -lambda q0 (lambda > 0); flip the sign of q1")
    bad = dict(sorted(bad.items()))
    if bad:
        rows = np.array(list(bad))
        c0, c1, r, q0, q1 = (a.copy() for a in (c0, c1, r, q0, q1))
        c0[rows] = c1[rows] = 0.0
        r[rows] = 1.0
        q0[rows] = q1[rows] = 0.0
        q0[rows, 0] = q1[rows, 0] = 1.0
    return LinearMotions(c0, c1, r, q0, q1), bad


def _floats(x: Any, name: str) -> np.ndarray:
    """float64 array of exactly the given numbers (never rounded)."""
    arr = np.asarray(x)
    if arr.dtype.kind == "f":
        wide = arr.astype(np.float64)
        if arr.dtype.itemsize > 8 and not ((wide.astype(arr.dtype) == arr) | np.isnan(arr)).all():
            raise ValueError(f"{name} holds long doubles that are not float64 values")
        return wide
    if arr.dtype.kind in "iu":
        if arr.size and np.abs(arr.astype(object)).max() >= 2**53:
            raise ValueError(f"{name} holds integers beyond 2^53 (not float64 values)")
        return arr.astype(np.float64)
    if arr.dtype.kind == "b":
        raise ValueError(f"{name} must hold numbers, got booleans")
    try:
        out = arr.astype(np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must hold float numbers, got dtype {arr.dtype}") from None
    if arr.dtype == object:
        flat = arr.reshape(-1).tolist()
        for v, f in zip(flat, out.reshape(-1).tolist(), strict=True):
            if isinstance(v, bool) or (math.isfinite(f) and Fraction(v) != Fraction(f)):
                raise ValueError(f"{name} holds {v!r}, which is not a float64 value (the parameters are read exactly)")
    return out


def _orientations(o: Any, N: int, d: int, name: str) -> np.ndarray:
    """(N, 4) quaternions (3D) or (N, 2) half-angle numbers (w, s) (2D); identity for None."""
    if o is None:
        out = np.zeros((N, 4 if d == 3 else 2))
        out[:, 0] = 1.0
        return out
    arr = _floats(o, name)
    if d == 3:
        if arr.shape != (N, 4):
            raise ValueError(f"{name} must be (N, 4) quaternions wxyz for {N} bodies, got shape {arr.shape}")
        return arr
    if arr.shape in ((N,), (N, 1)):
        theta = arr.reshape(N).tolist()
        # math.cos/sin (correctly rounded in practice, the same bits everywhere); NaN stays NaN
        return np.array([[math.cos(v / 2), math.sin(v / 2)] if math.isfinite(v) else [math.nan, math.nan] for v in theta]).reshape(N, 2)
    if arr.shape == (N, 4):
        off = (arr[:, 1] != 0) | (arr[:, 2] != 0)
        if off.any():
            k = int(np.flatnonzero(off)[0])
            raise ValueError(f"row {k}: {name}: a 2D quaternion must rotate about z: (w, 0, 0, z)")
        return np.ascontiguousarray(arr[:, [0, 3]])
    raise ValueError(f"{name} must be (N,) angles or (N, 4) quaternions (w, 0, 0, z) for {N} ellipses, got shape {arr.shape}")


def _through_zero(q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Rows where (1 - t) q0 + t q1 = 0 for some t in [0, 1]: q1 = -lambda q0, lambda > 0 (exact).

    Each row is first scaled by a power of two (exact) so that its largest component is in
    [1/2, 1): then |q0|^2 |q1|^2 >= 1/16, and the float values of |q0|^2 |q1|^2 - (q0.q1)^2
    (zero iff parallel) and of q0.q1 (|q0.q1| >= 1/4 when parallel) are within 2^-40 of the
    exact ones; rows that these floats do not clear are checked in exact rationals.
    """
    out = np.zeros(q0.shape[0], dtype=bool)
    ok = np.isfinite(q0).all(axis=1) & np.isfinite(q1).all(axis=1) & (q0 != 0).any(axis=1) & (q1 != 0).any(axis=1)
    with np.errstate(all="ignore"):
        a = np.ldexp(q0, -np.frexp(np.abs(q0).max(axis=1))[1][:, None])
        b = np.ldexp(q1, -np.frexp(np.abs(q1).max(axis=1))[1][:, None])
        dot = (a * b).sum(axis=1)
        n2 = (a * a).sum(axis=1) * (b * b).sum(axis=1)
        maybe = ok & (dot < 2.0**-40) & ~(n2 - dot * dot > 2.0**-40)
    for k in np.flatnonzero(maybe).tolist():
        x = [Fraction(v) for v in q0[k].tolist()]
        y = [Fraction(v) for v in q1[k].tolist()]
        parallel = all(x[i] * y[j] == x[j] * y[i] for i in range(len(x)) for j in range(i + 1, len(x)))
        out[k] = parallel and sum(u * v for u, v in zip(x, y, strict=True)) < 0
    return out


def _exact_matrix(c0: list[Fraction], c1: list[Fraction], r: list[Fraction], q0: list[Fraction], q1: list[Fraction]) -> list[list[RationalFunction]]:
    """A(t) of one body, exactly: [[Q, -Q c], [-c^T Q, c^T Q c - 1]] with Q = R~ D R~^T / N^2.

    c(t) = c0 + t (c1 - c0), q(t) = q0 + t (q1 - q0), R~ the rotation numerator of q (R = R~ / N,
    N = |q|^2), D = diag(1 / r^2): the matrix :func:`core.moving.motions.motion_from_dict` builds
    from the same motion's expressions (one canonical form: reduced, monic denominator).
    """
    d = len(c0)
    c = [fmpq_poly([_f(a), _f(b - a)]) for a, b in zip(c0, c1, strict=True)]
    q = [fmpq_poly([_f(a), _f(b - a)]) for a, b in zip(q0, q1, strict=True)]
    if d == 3:
        w, x, y, z = q
        R = [
            [w * w + x * x - y * y - z * z, (x * y - w * z) * 2, (x * z + w * y) * 2],
            [(x * y + w * z) * 2, w * w - x * x + y * y - z * z, (y * z - w * x) * 2],
            [(x * z - w * y) * 2, (y * z + w * x) * 2, w * w - x * x - y * y + z * z],
        ]
    else:
        w, s = q
        R = [[w * w - s * s, -(w * s) * 2], [(w * s) * 2, w * w - s * s]]
    N = sum((v * v for v in q), fmpq_poly([0]))
    D = [fmpq(1) / (_f(v) * _f(v)) for v in r]
    Q = [[sum((R[i][k] * R[j][k] * D[k] for k in range(d)), fmpq_poly([0])) for j in range(d)] for i in range(d)]
    den = N * N
    Qc = [sum((Q[i][j] * c[j] for j in range(d)), fmpq_poly([0])) for i in range(d)]
    cQc = sum((c[i] * Qc[i] for i in range(d)), fmpq_poly([0]))

    def rf(num: fmpq_poly) -> RationalFunction:
        return RationalFunction(QSqrtPoly(num), den)

    M = [[rf(Q[i][j]) for j in range(d)] + [rf(-Qc[i])] for i in range(d)]
    M.append([rf(-v) for v in Qc] + [rf(cQc - den)])
    return M


def _f(x: Fraction) -> fmpq:
    return fmpq(x.numerator, x.denominator)


def _q(v: float) -> Fraction:
    return Fraction(float(v))


def _line(a: Fraction, b: Fraction) -> str:
    """The exact expression a + t (b - a)."""
    return str(a) if a == b else f"{a} + ({b - a})*t"
