"""Certified float determinants of small stacked matrices: value, proven error bound, exact scale.

A determinant is evaluated by the ring-generic Laplace formula of :func:`core.formulae.pencil.determinant`;
its float kernel and error constant are traced from that formula by
:func:`core.fixed.errorbound.build_kernel` (the machinery behind the filter's kernels) once, by
:mod:`core.witness.detgen`, and committed as core/witness/_det_kernels.py (checked for drift by
the tests, as the filter's kernels are), so
``|computed - det| <= C * M + floor`` with M >= the permanent of |rows| (product of absolute row
sums). Each row is first multiplied by a power of two that brings its largest entry into [1, 2)
(exact; it keeps every leaf <= 2, so nothing overflows and the underflow floor applies), and the
total exponent is returned so that callers can recover the value itself:
det(original) = 2^exponent * det(scaled). A sign is certain when |value| > bound;
:mod:`core.witness.floatcert` uses it for a certified lower bound of det Q (the smallest eigenvalue).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt

from . import _det_kernels
from .floats import Real

__all__ = ["det_with_bound"]


def _kernel(n: int) -> tuple[Callable[..., Any], float, float]:
    """(function, constant, underflow floor) for n x n determinants (core/witness/_det_kernels.py)."""
    try:
        fn = getattr(_det_kernels, f"det{n}")
    except AttributeError:
        raise ValueError(f"no determinant kernel for {n}x{n} matrices (generated sizes: 2, 3)") from None
    return fn, getattr(_det_kernels, f"DET{n}_CONSTANT"), getattr(_det_kernels, f"DET{n}_FLOOR")


class _Rows:
    """``M[i, j]`` indexing (what the generated kernel reads) over nested lists."""

    __slots__ = ("rows",)

    def __init__(self, rows: list[list[Any]]) -> None:
        self.rows = rows

    def __getitem__(self, ij: tuple[int, int]) -> Any:
        return self.rows[ij[0]][ij[1]]


def det_with_bound(M: Any) -> tuple[Real, Real, int | npt.NDArray[np.int64]]:
    """Determinants of n x n float matrices, n = 2 or 3, certified.

    Args:
        M: nested lists (n x n) of Python floats (one matrix) or of (N,) arrays (N matrices),
            or an (N, n, n) array.

    Returns:
        (value, bound, exponent): ``|value - det(scaled)| <= bound`` where scaled has each row
        multiplied by a power of two, and det(M) = 2^exponent * det(scaled) exactly.

    Examples:
        >>> v, b, e = det_with_bound(np.array([[[3.0, 1.0], [1.0, 2.0]]]))
        >>> float(np.ldexp(v, e)[0]), bool(b[0] < 1e-14)
        (5.0, True)
        >>> v, b, e = det_with_bound([[3.0, 1.0], [1.0, 2.0]])
        >>> float(v * 2.0**e)
        5.0
    """
    if isinstance(M, np.ndarray):
        M = [[np.ascontiguousarray(M[:, i, j]) for j in range(M.shape[-1])] for i in range(M.shape[-1])]
    n = len(M)
    rows = []
    total = 0
    shift: Any
    for row in M:
        if isinstance(row[0], np.ndarray):
            mx = np.maximum.reduce([np.abs(x) for x in row])
            _, e = np.frexp(np.where(np.isfinite(mx), mx, 1.0))
            shift = 1 - e  # largest |entry| of the row now in [1, 2)
            rows.append([np.ldexp(x, shift) for x in row])
        else:
            mx = max(abs(x) for x in row)
            shift = 1 - (math.frexp(mx)[1] if math.isfinite(mx) else 0)
            rows.append([math.ldexp(x, shift) for x in row])
        total = total + shift
    fn, C, floor = _kernel(n)
    value, perm = fn(_Rows(rows))
    return value, C * perm + floor, -total
