"""Float estimates and float helpers for one pair or stacks (the estimates never certify).

The same straight-line code runs on Python floats (one pair: microseconds, the scene's drag path)
and on numpy arrays of shape (N,) (N pairs at once); a matrix is a nested list of such elements.
Here: 2x2 / 3x3 symmetric inverses by cofactors, the centred form of a float matrix, and a
safeguarded Newton iteration for the maximiser of the contact function (f is concave,
f'(0) > 0 > f'(1), see :mod:`core.witness.contact_function`). The estimates only *start*
certified computations: the exact bracket of
:class:`~core.witness.contact_function.ContactFunction` or the certified classifications of
:mod:`core.witness.floatcert`. Also the type-generic helpers (``where``, ``down``, ``up``, ...)
that let :mod:`core.witness.floatcert` run one code on both kinds.
"""

from __future__ import annotations

import math
from typing import Any, cast

import numpy as np
import numpy.typing as npt

__all__ = [
    "maximise",
    "centred",
    "inverse",
    "where",
    "down",
    "up",
    "is_array",
    "lists",
    "stacked",
    "Real",
]

_TOL = 4.0 * 2.0**-52

Real = float | npt.NDArray[np.float64]
"""A float (one pair) or an (N,) array of floats (a stack): the one code runs on both."""


def is_array(x: Any) -> bool:
    """True for numpy arrays (a stack), False for Python floats (one pair)."""
    return isinstance(x, np.ndarray)


def where(cond: Any, a: Any, b: Any) -> Real:
    """``a if cond else b`` elementwise (np.where for arrays)."""
    if isinstance(cond, bool | np.bool_):
        return cast(Real, a if cond else b)
    return cast(Real, np.where(cond, a, b))


def down(x: Any) -> Real:
    """The next float below x: a lower bound of the exact result of one correctly rounded operation."""
    return cast(Real, np.nextafter(x, -np.inf) if is_array(x) else math.nextafter(x, -math.inf))


def up(x: Any) -> Real:
    """The next float above x."""
    return cast(Real, np.nextafter(x, np.inf) if is_array(x) else math.nextafter(x, math.inf))


def lists(M: np.ndarray) -> list[list[Any]]:
    """(N, n, n) stack -> nested lists of contiguous (N,) arrays; (n, n) -> nested lists of floats."""
    if M.ndim == 2:
        return cast(list[list[Any]], M.tolist())
    n = M.shape[-1]
    return [[np.ascontiguousarray(M[:, i, j]) for j in range(n)] for i in range(n)]


def stacked(M: list[list[Any]]) -> np.ndarray:
    """Inverse of :func:`lists`: (N, n, n) from lists of arrays, (n, n) from lists of floats."""
    arr = np.array(M, dtype=np.float64)
    return arr if arr.ndim == 2 else np.moveaxis(arr, -1, 0)


def inverse(C: list[list[Any]]) -> list[list[Any]]:
    """C^-1 for a symmetric 2x2 or 3x3 C (cofactors)."""
    if len(C) == 2:
        det = C[0][0] * C[1][1] - C[0][1] * C[0][1]
        return [[C[1][1] / det, -C[0][1] / det], [-C[0][1] / det, C[0][0] / det]]
    c00 = C[1][1] * C[2][2] - C[1][2] * C[1][2]
    c01 = C[0][2] * C[1][2] - C[0][1] * C[2][2]
    c02 = C[0][1] * C[1][2] - C[0][2] * C[1][1]
    c11 = C[0][0] * C[2][2] - C[0][2] * C[0][2]
    c12 = C[0][1] * C[0][2] - C[0][0] * C[1][2]
    c22 = C[0][0] * C[1][1] - C[0][1] * C[0][1]
    det = C[0][0] * c00 + C[0][1] * c01 + C[0][2] * c02
    return [[c00 / det, c01 / det, c02 / det], [c01 / det, c11 / det, c12 / det], [c02 / det, c12 / det, c22 / det]]


def mat_vec(M: list[list[Any]], v: list[Any]) -> list[Any]:
    """M v."""
    return [dot(row, v) for row in M]


def dot(u: list[Any], v: list[Any]) -> Real:
    """Dot product u . v."""
    out = u[0] * v[0]
    for a, b in zip(u[1:], v[1:], strict=True):
        out = out + a * b
    return cast(Real, out)


def centred(M: list[list[Any]]) -> tuple[list[Any], list[list[Any]], Any]:
    """(centre c, Q^-1, size k) of a normalised float matrix [[Q, m], [m^T, a]].

    The inverse shape matrix is S = k Q^-1. This k = -m.c - a loses digits to cancellation when
    the centre is far out compared with the size; :mod:`core.witness.floatcert` encloses it
    accurately instead.
    """
    d = len(M) - 1
    Qinv = inverse([row[:d] for row in M[:d]])
    m = [M[i][d] for i in range(d)]
    c = [-v for v in mat_vec(Qinv, m)]
    return c, Qinv, -dot(m, c) - M[d][d]


def scaled(k: Any, M: list[list[Any]]) -> list[list[Any]]:
    """The matrix k M."""
    return [[k * x for x in row] for row in M]


def _derivatives(SA: Any, SB: Any, delta: list[Any], lam: Any) -> tuple[Any, Any, Any, list[Any]]:
    """f, f', f'' and y = C^-1 delta at lambda (formulas of ContactFunction.values)."""
    d = len(delta)
    Cinv = inverse([[SA[i][j] * (1 - lam) + SB[i][j] * lam for j in range(d)] for i in range(d)])
    D = [[SB[i][j] - SA[i][j] for j in range(d)] for i in range(d)]
    y = mat_vec(Cinv, delta)
    phi = dot(delta, y)
    Dy = mat_vec(D, y)
    psi = dot(y, Dy)
    chi = dot(Dy, mat_vec(Cinv, Dy))
    w = lam * (1 - lam)
    f1 = (1 - 2 * lam) * phi - w * psi
    f2 = -2 * phi - 2 * (1 - 2 * lam) * psi + 2 * w * chi
    return w * phi, f1, f2, y


def maximise(SA: Any, SB: Any, delta: list[Any], *, iterations: int = 60) -> tuple[Real, Real, list[Real]]:
    """Float estimate of (lambda*, s* = f(lambda*), y(lambda*)).

    Args:
        SA: d x d nested list, the inverse shape matrix of A; elements floats or (N,) arrays.
        SB: the same for B.
        delta: c_B - c_A, d elements of the same kind.
        iterations: cap on Newton/bisection steps (converges in about 5-8).

    Returns:
        lambda*, s* (0 where the centres coincide) and the normal direction y there.
    """
    scalar = not is_array(delta[0])
    # start: lambda = w_A / (w_A + w_B), w = support width along delta (exact for two spheres)
    wa = dot(delta, mat_vec(SA, delta))
    wb = dot(delta, mat_vec(SB, delta))
    if scalar:
        if not (wa > 0 and wb > 0):
            return 0.5, 0.0, [0.0] * len(delta)
        ok: Any = True
        ra: Any = math.sqrt(wa)
        rb: Any = math.sqrt(wb)
    else:
        ok = (wa > 0) & (wb > 0)
        ra, rb = np.sqrt(np.where(ok, wa, 1.0)), np.sqrt(np.where(ok, wb, 1.0))
    lam = ra / (ra + rb)
    lo, hi = lam * 0.0, lam * 0.0 + 1.0
    for _ in range(iterations):
        _, f1, f2, _ = _derivatives(SA, SB, delta, lam)
        lo = where(f1 > 0, lam, lo)
        hi = where(f1 < 0, lam, hi)
        step = f1 / f2
        new = lam - step
        done = (abs(step) <= _TOL * lam) | (f1 == 0)
        inside = (new > lo) & (new < hi)
        lam = where(inside | done, new, 0.5 * (lo + hi))  # Newton, or bisection when it leaves [lo, hi]
        if bool(np.all(done | ~np.asarray(ok))):
            break
    f, _, _, y = _derivatives(SA, SB, delta, lam)
    return lam, where(ok, f, 0.0), y
