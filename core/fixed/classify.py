"""``classify(A, B)``: one function for one pair or broadcast stacks of pairs (shapely-2 style).

Float filter first (:mod:`core.fixed.filters`: sound, may abstain), exact rationals only for the pairs it
could not certify (:mod:`core.fixed.exact`), in the manner of CGAL's filtered predicates.
:func:`classify_detailed` is the same pipeline, reporting per pair which arithmetic certified the
answer and, with ``on_invalid="mark"``, why a pair is invalid.

Inputs are read exactly: float16/32/64 and long double arrays are the binary rationals they hold
(float32 stacks go to the filter as they are: half the bytes, widened exactly inside it)
(a long double that is not a float64 value goes to the exact path, never rounded), numpy integers
are integers, object arrays may hold Fractions, fmpq, ints or number strings.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, overload

import numpy as np

from ..errors import InvalidInput
from ..filtered import Certifier, Predicate, Stats, predicate
from ..formulae.decision import RULE_RELATION
from ..options import METHODS, ON_INVALID, Method, OnInvalid, check_options
from ..relation import Relation
from ..shapes.numbers import binary64_array
from ..shapes.quadrics import Matrix, Stack, validate_quadric
from . import compiled
from .exact import classify_exact, valid_float_matrix
from .filters import _RELATION_OF, certified_valid, classify_float_counted
from .lazy import LazyArray, is_dask_array

__all__ = [
    "classify",
    "classify_detailed",
    "classify_pairs",
    "Classification",
    "Certifier",
    "Method",
    "METHODS",
    "OnInvalid",
    "ON_INVALID",
    "Stats",
]

_CLASSIFY: Predicate = predicate("classify")
"""The counters of ``classify`` / ``classify_detailed`` (:func:`core.filter_stats`)."""


@dataclass
class Classification:
    """Relations of a batch with, per pair, the arithmetic that certified each one.

    ``relation`` and ``certified_by`` have the broadcast batch shape (0-d for one pair);
    ``errors`` maps the flat index of each invalid pair to the reason (``on_invalid="mark"``).
    """

    relation: np.ndarray
    """int8 :class:`Relation` codes."""
    certified_by: np.ndarray
    """int8 :class:`Certifier` codes."""
    errors: dict[int, str] = field(default_factory=dict)
    """Flat pair index -> why the pair is invalid (only with ``on_invalid="mark"``)."""

    @property
    def escalated(self) -> int:
        """Pairs decided by exact arithmetic."""
        return int(np.count_nonzero(self.certified_by == Certifier.EXACT))


def _as_array(x: Any, name: str) -> np.ndarray:
    """Float64 array if every entry is exactly a binary64 value, else an object array (exact input).

    Never rounds: a long double or a big integer that is not a float64 value keeps its exact
    value in an object array (the exact path then reads it).
    """
    arr = _read_array(x, name)
    if arr.ndim < 2:
        raise ValueError(
            f"{name} must be a 3x3 (ellipse) or 4x4 (ellipsoid) matrix, or a stack (..., n, n) of them; "
            f"got {'a scalar' if arr.ndim == 0 else f'shape {arr.shape}'}"
        )
    return arr


def _read_array(x: Any, name: str) -> np.ndarray:
    if isinstance(x, np.ndarray):
        kind = x.dtype.kind
        if x.dtype == np.float64 or x.dtype == np.float32:  # float32: the filter reads it as it is
            return x
        if kind == "b":
            raise ValueError(f"{name} holds booleans, not numbers")
        if kind == "c":
            raise ValueError(f"{name} holds complex numbers; a quadric matrix is real")
        if kind in "fiu":
            f = binary64_array(x)
            return x.astype(object) if f is None else f
    try:
        arr = np.asarray(x, dtype=object)
    except ValueError:
        raise ValueError(f"{name} is ragged: rows of different lengths") from None
    if arr.ndim < 2:
        return arr
    f = binary64_array(arr)  # exact inputs that are binary64 values can use the float filter
    return arr if f is None else f


def _single_float_pair(A: Any, B: Any) -> bool:
    """One float64 (n, n) pair, n = 3 or 4: the scene's drag, served without the batch machinery."""
    return (
        type(A) is np.ndarray
        and type(B) is np.ndarray
        and A.dtype == np.float64
        and B.dtype == np.float64
        and A.ndim == 2
        and A.shape == B.shape
        and A.shape[0] in (3, 4)
        and A.shape[0] == A.shape[1]
    )


@overload
def classify(A: Matrix, B: Matrix, *, method: Method = ..., on_invalid: OnInvalid = ..., stats: Stats | None = ...) -> Relation: ...
@overload
def classify(A: Stack, B: Stack | Matrix, *, method: Method = ..., on_invalid: OnInvalid = ..., stats: Stats | None = ...) -> np.ndarray: ...
@overload
def classify(A: Matrix, B: Stack, *, method: Method = ..., on_invalid: OnInvalid = ..., stats: Stats | None = ...) -> np.ndarray: ...
@overload
def classify(A: object, B: object, *, method: Method = ..., on_invalid: OnInvalid = ..., stats: Stats | None = ...) -> Relation | np.ndarray | LazyArray: ...
def classify(
    A: Any,
    B: Any,
    *,
    method: Method = "adaptive",
    on_invalid: OnInvalid = "raise",
    stats: Stats | None = None,
) -> Relation | np.ndarray | LazyArray:
    """Certified relative position of two ellipses (3x3) or ellipsoids (4x4).

    Args:
        A: one matrix (n, n), or a stack (..., n, n) that broadcasts against B's.
            Entries: floats of any width (exact binary rationals), ints, Fractions, fmpq, or
            strings like "3/7" / "0.1" (exact decimals). Signs may be flipped (positive
            interior). The exact symmetric part (A + A^T)/2 is classified (the quadratic form);
            a matrix symmetric only up to rounding is accepted, a clearly asymmetric one is not
            (:data:`core.shapes.quadrics.SYMMETRY_TOLERANCE`).
        B: the same for B (both ellipses or both ellipsoids).
        method: "adaptive" (default: float filter, exact only where it abstains), "float"
            (filter only, may return UNDECIDED) or "exact" (rationals throughout).
        on_invalid: "raise" (default) a ValueError for the first invalid pair, or "mark" it
            :attr:`Relation.INVALID` and classify the others (why: :func:`classify_detailed`).
        stats: optional :class:`Stats` to count pairs and escalations.

    Returns:
        A :class:`Relation` for one pair; an int8 array of Relation codes with the broadcast
        batch shape for stacks; a lazy ``dask.array`` of those codes when A or B is a dask
        array (computed chunk by chunk on the workers: :mod:`core.fixed.lazy`).

    Raises:
        ValueError: wrong shape, clearly non-symmetric, NaN/inf, not an ellipse/ellipsoid (the
            message names the matrix and, for stacks, the index of the pair), or an unknown
            option. Every method checks its input; ``method="float"`` validates exactly the
            pairs it cannot certify.

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
        >>> classify([circle(0), [[1, 0, 0], [0, -1, 0], [0, 0, -1]]], circle(5), on_invalid="mark").tolist()
        [0, -2]
    """
    check_options(method, on_invalid)
    if is_dask_array(A) or is_dask_array(B):  # lazy: chunk by chunk on the dask workers
        from .lazy import classify_lazy

        return classify_lazy(_classify_block, A, B, method=method, on_invalid=on_invalid)
    if _single_float_pair(A, B) and (method == "adaptive" or (method == "float" and compiled.warm_up(wait=False))):
        # a drag in the scene: microseconds. Until the compiled kernels are loaded the adaptive
        # path goes straight to exact (~0.1 ms, faster than numpy on one pair)
        warm = compiled.warm_up(wait=False)
        code, _ = _CLASSIFY.one(
            lambda: _rule_code(A, B),
            lambda: _exact_code(A, B, 0, True, on_invalid, {}),
            method if warm else "exact",
            stats=stats,
        )
        if code is None:  # "float" and the filter abstained: invalid input is still an error
            code = _checked_code(A, B, 0, True, on_invalid, {}, bool(certified_valid(A[None], B[None])[0]))
        return Relation(code)
    res = _classify(A, B, method, on_invalid, None, certifiers=False, stats=stats)
    if res.relation.ndim == 0:
        return Relation(int(res.relation))
    return res.relation


def _classify_block(a: np.ndarray, b: np.ndarray, *, method: Method, on_invalid: OnInvalid) -> np.ndarray:
    """Codes of one chunk of a dask computation (numpy stacks; a 0-d batch stays an array)."""
    return classify_detailed(a, b, method=method, on_invalid=on_invalid).relation


def classify_detailed(
    A: Any,
    B: Any,
    *,
    method: Method = "adaptive",
    on_invalid: OnInvalid = "raise",
    progress: Callable[[int, int], None] | None = None,
) -> Classification:
    """:func:`classify` with, per pair, the arithmetic that certified it and the invalid reasons.

    Same arguments and guarantee as :func:`classify`; the result's arrays have the broadcast
    batch shape (0-d for one pair). ``progress(k, m)`` is called before the k-th of the m pairs
    that need exact arithmetic (or exact validation): a progress bar, or a time budget (an
    exception it raises stops the work and propagates).

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> r = classify_detailed([circle(0), circle(3)], circle(2.0))
        >>> r.relation.tolist(), [str(Certifier(c)) for c in r.certified_by]
        ([1, 2], ['exact', 'float'])
    """
    check_options(method, on_invalid)
    return _classify(A, B, method, on_invalid, progress, certifiers=True)


def classify_pairs(a: np.ndarray, b: np.ndarray, method: Method = "adaptive") -> tuple[np.ndarray, np.ndarray]:
    """(relation, certified_by) of float64 stacks (N, n, n) of valid bodies: :func:`classify_detailed`'s answers.

    For the bodies' narrow phases (a one-body query of :class:`core.BodyIndex` classifies a
    handful of pairs), whose matrices are float64 and already proven valid (their bounding
    spheres): under "adaptive" one call of the compiled filter, and :func:`classify_detailed` only
    on the pairs it leaves (which it runs through the same filter again, then its second stage
    and exact arithmetic), so every answer and certifier is the one :func:`classify_detailed`
    gives the whole stack; no checks of shapes, types or options, no broadcasting. Other
    methods, or no extension: :func:`classify_detailed` itself.
    """
    if method != "adaptive" or not compiled.available():
        res = classify_detailed(a, b, method=method)
        return res.relation, res.certified_by
    codes, undecided = compiled.mapped(a, b, _RELATION_OF)
    by = np.ones(codes.size, dtype=np.int8)  # Certifier.FLOAT
    if not undecided:
        _CLASSIFY.count(codes.size, 0, 0)
        return codes, by
    rows = np.flatnonzero(codes == Relation.UNDECIDED)
    _CLASSIFY.count(codes.size - rows.size, 0, 0)
    res = classify_detailed(a[rows], b[rows])
    codes[rows], by[rows] = res.relation, res.certified_by
    return codes, by


def _classify(
    A: Any,
    B: Any,
    method: Method,
    on_invalid: OnInvalid,
    progress: Callable[[int, int], None] | None,
    *,
    certifiers: bool,
    stats: Stats | None = None,
) -> Classification:
    """:func:`classify_detailed`, or for :func:`classify` (``certifiers=False``) a leaner result.

    :func:`classify` reads only the relations (its ``stats`` are fed by :mod:`core.filtered`):
    when the float filter decides every pair, ``certified_by`` is then a read-only broadcast of
    FLOAT (no pass over the batch, no second array written).
    """
    a = _as_array(A, "A")
    b = _as_array(B, "B")
    n = a.shape[-1]
    if a.shape[-2:] != (n, n) or n not in (3, 4):
        raise ValueError(
            f"A must be a 3x3 (ellipse) or 4x4 (ellipsoid) matrix, or a stack (..., n, n) of them; got trailing shape {a.shape[-2:]}"
        )
    if b.shape[-2:] != (n, n):
        raise ValueError(
            f"B has trailing shape {b.shape[-2:]} but A is {n}x{n}: both must be ellipses or both ellipsoids"
        )
    try:
        batch_shape = np.broadcast_shapes(a.shape[:-2], b.shape[:-2])
    except ValueError:
        raise ValueError(f"batch shapes {a.shape[:-2]} and {b.shape[:-2]} do not broadcast") from None
    scalar = batch_shape == ()
    codes, by, errors = _classify_flat(
        _flatten(a, batch_shape, n), _flatten(b, batch_shape, n), method, scalar, on_invalid, progress, certifiers=certifiers, stats=stats
    )
    return Classification(codes.reshape(batch_shape), by.reshape(batch_shape), errors)


def _flatten(x: np.ndarray, batch_shape: tuple[int, ...], n: int) -> np.ndarray:
    """(N, n, n) view or copy; broadcasting only when needed (a broadcast view is read-only)."""
    if x.shape[:-2] != batch_shape:
        x = np.broadcast_to(x, (*batch_shape, n, n))
        return np.ascontiguousarray(x.reshape(-1, n, n))
    return x.reshape(-1, n, n)


def _where(i: int, scalar: bool) -> str:
    return "" if scalar else f"pair {i}: "


def _validate_pair(a: Any, b: Any) -> None:
    """Raise ValueError (naming A or B) unless both matrices are valid ellipses/ellipsoids."""
    if valid_float_matrix(a) and valid_float_matrix(b):  # float64: exact, in integers
        return
    validate_quadric(a, name="A")
    validate_quadric(b, name="B")


def _rule_code(A: np.ndarray, B: np.ndarray) -> int | None:
    """The compiled filter's relation of one float pair, or None where it abstains."""
    rule = compiled.rule_one(np.ascontiguousarray(A), np.ascontiguousarray(B))
    return int(RULE_RELATION[rule]) if rule >= 0 else None


def _exact_code(a: Any, b: Any, i: int, scalar: bool, on_invalid: str, errors: dict[int, str]) -> int:
    """Exact relation code of pair i; an invalid pair raises or is marked (:func:`_invalid`)."""
    try:
        return int(classify_exact(a, b).relation)
    except ValueError as e:
        return _invalid(e, i, scalar, on_invalid, errors)


def _checked_code(a: Any, b: Any, i: int, scalar: bool, on_invalid: str, errors: dict[int, str], proven: bool) -> int:
    """UNDECIDED for pair i under "float" once it is known valid; else raise or mark it (:func:`_invalid`).

    Valid: ``proven`` by the filter's own validity proof, else checked exactly.
    """
    try:
        if not proven:
            _validate_pair(a, b)
        return int(Relation.UNDECIDED)
    except ValueError as e:
        return _invalid(e, i, scalar, on_invalid, errors)


def _invalid(e: ValueError, i: int, scalar: bool, on_invalid: str, errors: dict[int, str]) -> int:
    """``on_invalid`` for invalid pair i: raise its :class:`core.InvalidInput` naming the pair, or mark it INVALID."""
    if on_invalid == "raise":
        raise InvalidInput.of(e).at_pair(None if scalar else i, _where(i, scalar)) from None
    errors[i] = str(e)
    return int(Relation.INVALID)


def _classify_flat(
    a: np.ndarray,
    b: np.ndarray,
    method: str,
    scalar: bool,
    on_invalid: str,
    progress: Callable[[int, int], None] | None = None,
    *,
    certifiers: bool = True,
    stats: Stats | None = None,
) -> tuple[np.ndarray, np.ndarray, dict[int, str]]:
    """Codes, certifiers and invalid reasons for (N, n, n) stacks (``certifiers``: see :func:`_classify`).

    One evaluation of the ``classify`` predicate (:mod:`core.filtered`): the float filter
    (float64 or float32 input; other input goes to exact under "adaptive"), exact arithmetic
    pair by pair on what it leaves; under "float" the pairs it leaves are validated only.
    """
    N = a.shape[0]
    errors: dict[int, str] = {}
    floats = a.dtype.kind == "f" and b.dtype.kind == "f"
    if floats and a.dtype != b.dtype:  # float32 against float64: widen (exact)
        a, b = a.astype(np.float64), b.astype(np.float64)

    def float_stage(_: None) -> tuple[np.ndarray, np.ndarray | None]:
        if not floats:  # exact input under "float": nothing certified, every pair validated below
            return np.full(N, Relation.UNDECIDED, dtype=np.int8), np.ones(N, dtype=bool)
        codes, all_decided = classify_float_counted(a, b, scalar=scalar)
        return codes, None if all_decided else codes == Relation.UNDECIDED

    def exact_stage(_: None, codes: np.ndarray, todo: np.ndarray) -> np.ndarray | None:
        failed = np.zeros(todo.size, dtype=bool)
        for k, i in enumerate(todo.tolist()):
            if progress is not None:
                progress(k, todo.size)
            codes[i] = _exact_code(a[i], b[i], i, scalar, on_invalid, errors)
            failed[k] = codes[i] == Relation.INVALID
        return failed if errors else None

    codes, by, unsure = _CLASSIFY.run(
        None,
        N,
        float_stage,
        exact_stage,
        method if floats or method != "adaptive" else "exact",
        blank=lambda _: np.full(N, Relation.UNDECIDED, dtype=np.int8),
        stats=stats,
    )
    if method == "float" and unsure.size:  # no exact classification, but invalid input is still an error
        # the filter's own validity proof spares the exact check where it holds (near tangency:
        # valid pairs whose relation no float sign decides); the same proof its labels rest on
        proven = certified_valid(a[unsure], b[unsure]) if floats else np.zeros(unsure.size, dtype=bool)
        for k, i in enumerate(unsure.tolist()):
            if progress is not None:
                progress(k, unsure.size)
            codes[i] = _checked_code(a[i], b[i], i, scalar, on_invalid, errors, bool(proven[k]))
    if certifiers and not by.flags.writeable:  # classify_detailed's arrays are the caller's to keep
        by = np.array(by)
    return codes, by, errors
