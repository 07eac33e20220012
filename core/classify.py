"""``classify(A, B)``: one function for one pair or broadcast stacks of pairs (shapely-2 style).

Float filter first (:mod:`core.filters`: sound, may abstain), exact rationals only for the pairs it
could not certify (:mod:`core.exact`), in the manner of CGAL's filtered predicates.
"""

from __future__ import annotations

from typing import Any, Literal, overload

import numpy as np
import numpy.typing as npt

from .exact import classify_exact
from .fastpath import classify_one
from .filters import classify_float
from .rationals import to_fmpq
from .relation import Relation

__all__ = ["classify", "Method", "METHODS", "Stats"]

Method = Literal["adaptive", "float", "exact"]
METHODS: tuple[str, ...] = ("adaptive", "float", "exact")


class Stats:
    """Counters of filter calls and failures (CGAL's profiler), filled when passed to classify."""

    def __init__(self) -> None:
        self.pairs = 0
        """Pairs classified."""
        self.escalated = 0
        """Pairs the float filter left UNDECIDED (sent to exact under ``adaptive``)."""

    def __repr__(self) -> str:
        return f"Stats(pairs={self.pairs}, escalated={self.escalated})"


def _check_method(method: str) -> None:
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; valid options: {', '.join(METHODS)}")


def _as_array(x: Any, name: str) -> np.ndarray:
    """Float64 array if every entry is a binary float/int, else an object array (exact input)."""
    if isinstance(x, np.ndarray) and x.dtype.kind in "fiu":
        return x.astype(np.float64, copy=False) if x.dtype.kind == "f" else _int_array(x)
    try:
        arr = np.asarray(x, dtype=object)
    except ValueError:
        raise ValueError(f"{name} is ragged: rows of different lengths") from None
    if arr.ndim < 2:
        raise ValueError(f"{name} must be a 3x3 or 4x4 matrix (or a stack of them), got shape {arr.shape}")
    flat = arr.reshape(-1)
    if all(type(v) is float or type(v) is np.float64 for v in flat):
        return arr.astype(np.float64)
    out = np.empty(flat.shape, dtype=np.float64)
    for k, v in enumerate(flat):  # exact inputs that are binary64 values can use the float filter
        f = _as_exact_float(v)
        if f is None:
            return arr
        out[k] = f
    return out.reshape(arr.shape)


def _as_exact_float(v: Any) -> float | None:
    """v as a float if it is exactly a (finite) binary64 value, else None."""
    if type(v) is float or type(v) is np.float64:
        return float(v)
    if isinstance(v, bool | np.bool_):
        return None
    try:
        q = to_fmpq(v)
    except ValueError:
        return None
    if abs(q.p) >= 2**53 or q.q & (q.q - 1) or q.q > 2**60:  # not a small dyadic rational
        return None
    return int(q.p) / int(q.q)


def _int_array(x: np.ndarray) -> np.ndarray:
    if x.size and np.abs(x).max() >= 2**53:
        return x.astype(object)
    return x.astype(np.float64)


@overload
def classify(A: Any, B: Any, *, method: Method = ..., stats: Stats | None = ...) -> Relation: ...
@overload
def classify(
    A: npt.ArrayLike, B: npt.ArrayLike, *, method: Method = ..., stats: Stats | None = ...
) -> npt.NDArray[np.int8]: ...
def classify(A: Any, B: Any, *, method: Method = "adaptive", stats: Stats | None = None) -> Any:
    """Certified relative position of two ellipses (3x3) or ellipsoids (4x4).

    Args:
        A, B: one matrix each (n, n), or stacks (..., n, n) that broadcast against each other.
            Entries: floats (exact binary rationals), ints, Fractions, fmpq, or strings like
            "3/7" / "0.1" (exact decimals). Signs may be flipped (positive interior).
        method: "adaptive" (default: float filter, exact only where it abstains), "float"
            (filter only, may return UNDECIDED) or "exact" (rationals throughout).
        stats: optional :class:`Stats` to count pairs and escalations.

    Returns:
        A :class:`Relation` for one pair; an int8 array of Relation codes with the broadcast
        batch shape for stacks.

    Raises:
        ValueError: wrong shape, non-symmetric, NaN/inf, not an ellipse/ellipsoid (the message
            names the matrix and, for stacks, the index of the pair), or unknown method.

    Guarantee:
        Never a wrong Relation; UNDECIDED only when ``method="float"``.

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> classify(circle(0), circle(2))
        <Relation.TANGENT: 1>
        >>> str(classify(circle(0), circle(3), method="float"))
        'separate'
        >>> classify([circle(0), circle(1)], circle(5)).tolist()     # a batch of two
        [0, 0]
    """
    _check_method(method)
    if (
        method == "adaptive"
        and type(A) is np.ndarray
        and type(B) is np.ndarray
        and A.dtype == np.float64
        and B.dtype == np.float64
        and A.ndim == 2
        and A.shape == B.shape
        and A.shape[0] in (3, 4)
        and A.shape[0] == A.shape[1]
    ):  # one float pair (a drag in the scene): skip the batch machinery
        code = classify_one(A, B, wait=False)
        if stats is not None:
            stats.pairs += 1
            stats.escalated += code == Relation.UNDECIDED
        if code != Relation.UNDECIDED:
            return Relation(code)
        return classify_exact(A, B).relation
    a = _as_array(A, "A")
    b = _as_array(B, "B")
    n = a.shape[-1]
    if a.shape[-2:] != (n, n) or n not in (3, 4):
        raise ValueError(f"A must be 3x3 or 4x4 (or a stack of them), got trailing shape {a.shape[-2:]}")
    if b.shape[-2:] != (n, n):
        raise ValueError(f"B has trailing shape {b.shape[-2:]} but A is {n}x{n}: both must be ellipses or both ellipsoids")
    try:
        batch_shape = np.broadcast_shapes(a.shape[:-2], b.shape[:-2])
    except ValueError:
        raise ValueError(f"batch shapes {a.shape[:-2]} and {b.shape[:-2]} do not broadcast") from None
    scalar = batch_shape == ()
    a = _flatten(a, batch_shape, n)
    b = _flatten(b, batch_shape, n)
    codes, undecided = _classify_flat(a, b, method, scalar)
    if stats is not None:
        stats.pairs += codes.shape[0]
        stats.escalated += undecided
    if scalar:
        return Relation(int(codes[0]))
    return codes.reshape(batch_shape)


def _flatten(x: np.ndarray, batch_shape: tuple[int, ...], n: int) -> np.ndarray:
    """(N, n, n) view or copy; broadcasting only when needed (a broadcast view is read-only)."""
    if x.shape[:-2] != batch_shape:
        x = np.broadcast_to(x, (*batch_shape, n, n))
        return np.ascontiguousarray(x.reshape(-1, n, n))
    return x.reshape(-1, n, n)


def _where(i: int, scalar: bool) -> str:
    return "" if scalar else f"pair {i}: "


def _classify_flat(a: np.ndarray, b: np.ndarray, method: str, scalar: bool) -> tuple[np.ndarray, int]:
    """Codes for (N, n, n) stacks and the number of pairs the float filter did not decide."""
    N = a.shape[0]
    codes = np.full(N, Relation.UNDECIDED, dtype=np.int8)
    if method != "exact" and a.dtype == np.float64 and b.dtype == np.float64:
        codes = classify_float(a, b, scalar=scalar)
    undecided = np.flatnonzero(codes == Relation.UNDECIDED)
    if method == "float":
        return codes, undecided.size
    for i in undecided:
        try:
            codes[i] = classify_exact(a[i], b[i]).relation
        except ValueError as e:
            raise ValueError(_where(int(i), scalar) + str(e)) from None
    return codes, undecided.size
