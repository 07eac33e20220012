"""Float estimates of the contact function's maximiser, for one pair or stacks (never certify).

The same straight-line code runs on Python floats (one pair: a few microseconds, the scene's drag
path) and on numpy arrays of shape (N,) (N pairs at once): 2x2 / 3x3 symmetric solves by
cofactors and a safeguarded Newton iteration on f' (f is concave, f'(0) > 0 > f'(1), see
:mod:`core.witness.contact_function`). The results only *start* certified computations: the
exact bracket of :class:`core.witness.contact_function.ContactFunction` or the scaled
classifications of :mod:`core.witness.batch`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["maximise", "centred_floats", "stack_lists"]

_TOL = 4.0 * 2.0**-52


def _solve(C: list[list[Any]], v: list[Any]) -> list[Any]:
    """C^-1 v for a symmetric 2x2 or 3x3 C (cofactors; elements float or ndarray)."""
    if len(v) == 2:
        det = C[0][0] * C[1][1] - C[0][1] * C[0][1]
        return [(C[1][1] * v[0] - C[0][1] * v[1]) / det, (C[0][0] * v[1] - C[0][1] * v[0]) / det]
    c00 = C[1][1] * C[2][2] - C[1][2] * C[1][2]
    c01 = C[0][2] * C[1][2] - C[0][1] * C[2][2]
    c02 = C[0][1] * C[1][2] - C[0][2] * C[1][1]
    c11 = C[0][0] * C[2][2] - C[0][2] * C[0][2]
    c12 = C[0][1] * C[0][2] - C[0][0] * C[1][2]
    c22 = C[0][0] * C[1][1] - C[0][1] * C[0][1]
    det = C[0][0] * c00 + C[0][1] * c01 + C[0][2] * c02
    return [
        (c00 * v[0] + c01 * v[1] + c02 * v[2]) / det,
        (c01 * v[0] + c11 * v[1] + c12 * v[2]) / det,
        (c02 * v[0] + c12 * v[1] + c22 * v[2]) / det,
    ]


def _mat_vec(M: list[list[Any]], v: list[Any]) -> list[Any]:
    return [sum((M[i][j] * v[j] for j in range(1, len(v))), M[i][0] * v[0]) for i in range(len(v))]


def _dot(u: list[Any], v: list[Any]) -> Any:
    return sum((a * b for a, b in zip(u[1:], v[1:])), u[0] * v[0])


def _derivatives(SA: Any, SB: Any, delta: list[Any], lam: Any) -> tuple[Any, Any, Any, list[Any]]:
    """f, f', f'' and y = C^-1 delta at lambda (formulas of ContactFunction.values)."""
    d = len(delta)
    C = [[SA[i][j] * (1 - lam) + SB[i][j] * lam for j in range(d)] for i in range(d)]
    D = [[SB[i][j] - SA[i][j] for j in range(d)] for i in range(d)]
    y = _solve(C, delta)
    phi = _dot(delta, y)
    Dy = _mat_vec(D, y)
    psi = _dot(y, Dy)
    chi = _dot(Dy, _solve(C, Dy))
    w = lam * (1 - lam)
    f1 = (1 - 2 * lam) * phi - w * psi
    f2 = -2 * phi - 2 * (1 - 2 * lam) * psi + 2 * w * chi
    return w * phi, f1, f2, y


def _where(cond: Any, a: Any, b: Any) -> Any:
    if isinstance(cond, bool | np.bool_):
        return a if cond else b
    return np.where(cond, a, b)


def maximise(SA: Any, SB: Any, delta: list[Any], *, iterations: int = 60) -> tuple[Any, Any, list[Any]]:
    """Float estimate of (lambda*, s* = f(lambda*), y(lambda*)).

    Args:
        SA, SB: d x d nested lists (inverse shape matrices), elements floats or (N,) arrays.
        delta: c_B - c_A, d elements of the same kind.
        iterations: cap on Newton/bisection steps (converges in about 5-8).

    Returns:
        lambda*, s* (0 where the centres coincide) and the normal direction y there.
    """
    scalar = not isinstance(delta[0], np.ndarray)
    # start: lambda = w_A / (w_A + w_B), w = support width along delta (exact for two spheres)
    wa = _dot(delta, _mat_vec(SA, delta))
    wb = _dot(delta, _mat_vec(SB, delta))
    if scalar:
        if wa <= 0 or wb <= 0:
            return 0.5, 0.0, [0.0] * len(delta)
        ra, rb = wa**0.5, wb**0.5
    else:
        ok = (wa > 0) & (wb > 0)
        ra, rb = np.sqrt(np.where(ok, wa, 1.0)), np.sqrt(np.where(ok, wb, 1.0))
    lam = ra / (ra + rb)
    lo, hi = lam * 0.0, lam * 0.0 + 1.0
    for _ in range(iterations):
        f, f1, f2, y = _derivatives(SA, SB, delta, lam)
        lo = _where(f1 > 0, lam, lo)
        hi = _where(f1 < 0, lam, hi)
        new = lam - f1 / f2
        bad = ~((new > lo) & (new < hi)) if not scalar else not lo < new < hi
        new = _where(bad, 0.5 * (lo + hi), new)
        step = abs(new - lam)
        lam = new
        if scalar:
            if step <= _TOL * max(lam, 1e-300) or f1 == 0:
                break
        elif bool(np.all((step <= _TOL * np.maximum(lam, 1e-300)) | (f1 == 0) | ~ok)):
            break
    f, _, _, y = _derivatives(SA, SB, delta, lam)
    if not scalar:
        f = np.where(ok, f, 0.0)
    return lam, f, y


def centred_floats(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(centre (N, d), S (N, d, d), k (N,)) of a stack (N, n, n) of normalised float matrices."""
    d = A.shape[-1] - 1
    M, m, a = A[:, :d, :d], A[:, :d, d], A[:, d, d]
    Minv = np.linalg.inv(M)
    c = -np.einsum("nij,nj->ni", Minv, m)
    k = -np.einsum("ni,ni->n", m, c) - a
    return c, k[:, None, None] * Minv, k


def stack_lists(S: np.ndarray, v: np.ndarray) -> tuple[list[list[np.ndarray]], list[np.ndarray]]:
    """(N, d, d) and (N, d) arrays as nested lists of (N,) arrays (the generic code's layout)."""
    d = v.shape[-1]
    return [[np.ascontiguousarray(S[:, i, j]) for j in range(d)] for i in range(d)], [
        np.ascontiguousarray(v[:, i]) for i in range(d)
    ]
