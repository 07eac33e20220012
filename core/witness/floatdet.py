"""Certified float determinants of small stacked matrices: value, proven error bound, exact scale.

A determinant is evaluated by the ring-generic Laplace formula of :func:`core.pencil.determinant`;
its float kernel and error constant are traced from that formula by
:func:`core.errorbound.build_kernel` (the machinery behind the filter's kernels), so
``|computed - det| <= C * M + floor`` with M >= the permanent of |rows| (product of absolute row
sums). Each row is first multiplied by a power of two that brings its largest entry into [1, 2)
(exact; it keeps every leaf <= 2, so nothing overflows and the underflow floor applies), and the
total exponent is returned so that callers can recover the value itself:
det(original) = 2^exponent * det(scaled). A sign is certain when |value| > bound.
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from functools import cache
from typing import Any

import numpy as np

from ..errorbound import build_kernel
from ..pencil import determinant

__all__ = ["det_with_bound", "certified_sign"]


@cache
def _kernel(n: int) -> tuple[Callable[..., Any], float, float]:
    """(function, constant, underflow floor) for n x n determinants (generated once)."""
    names = [f"m{i}{j}" for i in range(n) for j in range(n)]

    def formula(L: dict[str, Any]) -> dict[str, Any]:
        M = [[L[f"m{i}{j}"] for j in range(n)] for i in range(n)]
        bound = None
        for row in M:
            r = sum((abs(x) for x in row[1:]), abs(row[0]))
            bound = r if bound is None else bound * r
        return {"det": determinant(M), "det_M": bound}

    k = build_kernel(
        f"det{n}",
        names,
        formula,
        style="permanent",
        leaf_max={nm: Fraction(2) for nm in names},
        leaf_exprs={f"m{i}{j}": (f"M[{i}, {j}]", "") for i in range(n) for j in range(n)},
        params=("M",),
    )
    namespace: dict[str, Any] = {}
    exec(compile(k.source, f"<witness det{n} kernel>", "exec"), namespace)  # noqa: S102 - generated here
    return namespace[f"det{n}"], k.constants[0], k.underflow_floor


def det_with_bound(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Determinants of a stack (N, n, n) of finite float matrices, n = 2..5, certified.

    Returns:
        (value, bound, exponent): ``|value - det(scaled)| <= bound`` where scaled has each row
        multiplied by a power of two, and det(M) = 2^exponent * det(scaled) exactly.

    Examples:
        >>> v, b, e = det_with_bound(np.array([[[3.0, 1.0], [1.0, 2.0]]]))
        >>> float(np.ldexp(v, e)[0]), bool(b[0] < 1e-14)
        (5.0, True)
    """
    M = np.asarray(M, dtype=np.float64)
    n = M.shape[-1]
    mx = np.abs(M).max(axis=-1)
    _, e = np.frexp(np.where(mx > 0, mx, 1.0))
    shift = 1 - e  # largest |entry| of each row now in [1, 2)
    scaled = np.ldexp(M, shift[..., None])
    fn, C, floor = _kernel(n)
    value, perm = fn(np.moveaxis(scaled, 0, -1).reshape(n, n, -1))
    return value, C * perm + floor, -shift.sum(axis=-1)


def certified_sign(M: np.ndarray) -> np.ndarray:
    """Sign of det for each matrix of a stack: +1, -1, or 0 when the float bound cannot tell."""
    v, b, _ = det_with_bound(M)
    return np.where(v > b, 1, np.where(v < -b, -1, 0)).astype(np.int8)
