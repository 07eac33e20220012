"""One filtered evaluation for every witness (CGAL's ``Filtered_predicate``, for constructions).

Every public witness (:mod:`core.witness.api`) is the same three steps over a pair or a stack:

1. read the pairs once (:func:`read_pairs`): validate them and certify their relation with
   :func:`core.classify` (its ``method``); pairs without an answer get a :class:`NoWitness` that
   says why (invalid input, a relation without this witness, a relation the float filter left
   undecided);
2. the **float stage**, vectorised over the stack, certified, allowed to abstain
   (:mod:`core.witness.floatcert`), for binary64 input unless ``method="exact"``;
3. the **exact stage**, pair by pair, for what the floats left (steps 2 and 3 are one
   evaluation of a :class:`core.filtered.Predicate`, one per witness, counted by
   :func:`core.filter_stats`): never under ``method="float"``
   (those pairs are ``NoWitness(kind="undecided")``, as ``classify`` answers UNDECIDED). A pair
   whose exact stage fails (never expected) becomes ``NoWitness(kind="failed")``: in a stack, one
   hard pair never costs the others their answers.

:func:`finish` then applies ``on_invalid`` and gives one result for one pair, an object array of
results with the batch shape for stacks (so a stack of one gives what one pair gives, in array
form).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Literal, TypeVar

import numpy as np
import numpy.typing as npt

from ..filtered import Certifier, Predicate
from ..fixed.classify import classify, classify_detailed
from ..options import Method, OnInvalid
from ..relation import Relation
from ..shapes.numbers import binary64_array
from .centred import centred_pair
from .contact_function import ContactFunction
from .floatcert import FloatPairs, prepare

__all__ = ["NoWitness", "NoWitnessKind", "Pairs", "WitnessArray", "read_pairs", "filtered", "finish"]

WitnessArray = npt.NDArray[np.object_]
"""Results of a stack: an object array with the batch shape, one result (or NoWitness) per pair."""

NoWitnessKind = Literal["invalid", "none", "undecided", "failed"]

"""Integers of smaller magnitude are exact binary64 values."""


@dataclass(frozen=True)
class NoWitness:
    """A pair without the witness asked for, and why.

    ``kind``: "invalid" (not an ellipse/ellipsoid; relation INVALID), "none" (the relation has
    no such witness: a plane of a pair that is not separate, a point of a separate pair),
    "undecided" (``method="float"`` and the floats could not certify it) or "failed" (an error
    in the exact computation: never expected, please report the pair).
    """

    relation: Relation
    kind: NoWitnessKind
    reason: str

    def __bool__(self) -> bool:
        return False


@dataclass
class Pairs:
    """A pair or a stack of pairs, read once: flat (N, n, n) arrays and certified relations."""

    shape: tuple[int, ...]
    """Batch shape (() for one pair)."""
    a: np.ndarray
    """(N, n, n): float64 when every entry is a binary64 value, else object (exact input)."""
    b: np.ndarray
    relation: np.ndarray
    """(N,) int8 certified relations (UNDECIDED only under ``method="float"``, INVALID marked)."""
    certified_by: np.ndarray
    """(N,) int8 :class:`core.Certifier` of each relation."""
    errors: dict[int, str]
    method: Method
    _functions: dict[int, ContactFunction] = field(default_factory=dict)

    @property
    def size(self) -> int:
        """Number of pairs N."""
        return int(self.relation.size)

    @cached_property
    def floats(self) -> FloatPairs | None:
        """The float preparation (binary64 input only), computed once for every float stage."""
        if self.a.dtype != np.float64 or self.b.dtype != np.float64:
            return None
        return prepare(self.a, self.b)

    def rows(self, i: int) -> tuple[list[list[Any]], list[list[Any]]]:
        """Pair i as nested lists of the numbers given (for the exact stage)."""
        return self.a[i].tolist(), self.b[i].tolist()

    def contact_function(self, i: int) -> ContactFunction:
        """The exact contact function of pair i (built once, shared by the witnesses of one call)."""
        if i not in self._functions:
            self._functions[i] = ContactFunction(*centred_pair(*self.rows(i)))
        return self._functions[i]


def _as_array(x: Any) -> np.ndarray:
    """Float64 if every entry is exactly a binary64 value, else an object array (never rounds)."""
    f = binary64_array(x, typed=True)  # exact numbers (Fraction, fmpq, str) keep the exact path
    if f is not None:
        return f
    return x.astype(object) if isinstance(x, np.ndarray) else np.asarray(x, dtype=object)


def _flat(x: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    n = x.shape[-1]
    return np.ascontiguousarray(np.broadcast_to(x, (*shape, n, n))).reshape(-1, n, n)


def read_pairs(A: Any, B: Any, method: Method) -> Pairs:
    """Validate and flatten a pair or stacks (broadcast), with their certified relations.

    Raises:
        ValueError: wrong shapes, or a matrix that is not a matrix of numbers (the message says
            what); invalid ellipses/ellipsoids are marked, not raised, here.
    """
    if type(A) is np.ndarray and type(B) is np.ndarray and A.ndim == 2 and A.shape == B.shape and A.dtype == B.dtype == np.float64:
        try:  # one float pair (the scene's drag): classify's fast path
            rel = classify(A, B, method=method)
            codes, by, errors = np.array([rel], np.int8), np.array([Certifier.NONE], np.int8), {}
        except ValueError as e:
            codes, by, errors = np.array([Relation.INVALID], np.int8), np.array([Certifier.NONE], np.int8), {0: str(e)}
        return Pairs((), A[None], B[None], codes, by, errors, method)
    res = classify_detailed(A, B, method=method, on_invalid="mark")
    shape = tuple(res.relation.shape)
    a, b = _as_array(A), _as_array(B)
    if a.dtype != b.dtype:
        a, b = a.astype(object), b.astype(object)
    return Pairs(shape, _flat(a, shape), _flat(b, shape), res.relation.reshape(-1), res.certified_by.reshape(-1), dict(res.errors), method)


T = TypeVar("T")


def filtered(
    pairs: Pairs,
    *,
    what: str,
    missing: Callable[[Relation], str | None],
    float_stage: Callable[[Pairs, np.ndarray], dict[int, T]] | None,
    exact_stage: Callable[[Pairs, int], T],
    counter: Predicate,
) -> list[T | NoWitness]:
    """The witness of every pair: float stage first, exact stage for what it leaves.

    The pairs with an answer by their relation alone (invalid, undecided, no such witness) get
    their :class:`NoWitness` first; the others are one evaluation of ``counter``
    (:class:`core.filtered.Predicate`: the control flow, ``method``, the counters). Input the
    floats cannot read (exact numbers) goes to the exact stage under "adaptive".

    Args:
        pairs: the pairs (:func:`read_pairs`).
        what: the witness's name, for messages ("separating plane").
        missing: for a relation without this witness, the reason (else None).
        float_stage: certified float results for the pairs of a mask (vectorised; may omit
            any), or None when floats cannot give this witness.
        exact_stage: the exact result of pair i (its relation is certified).
        counter: the predicate that runs and counts this witness.

    Returns:
        One result or :class:`NoWitness` per pair, in flat order.
    """
    out: list[T | NoWitness | None] = [None] * pairs.size
    for i in range(pairs.size):
        rel = Relation(int(pairs.relation[i]))
        if rel == Relation.INVALID:
            out[i] = NoWitness(rel, "invalid", pairs.errors.get(i, "not an ellipse/ellipsoid"))
        elif rel == Relation.UNDECIDED:
            out[i] = NoWitness(rel, "undecided", "the float filter could not certify the relation (method='float')")
        elif (why := missing(rel)) is not None:
            out[i] = NoWitness(rel, "none", why)
    todo = np.flatnonzero(np.array([o is None for o in out], dtype=bool))
    if not todo.size:
        return [o for o in out if o is not None]
    method = pairs.method
    floats = float_stage is not None and method != "exact" and pairs.floats is not None
    if not floats and method == "adaptive":  # no float stage for this input: exact, not a float failure
        method = "exact"

    def floated(_: None) -> tuple[np.ndarray, np.ndarray | None]:
        values = np.empty(todo.size, dtype=object)
        if not floats:  # "float" without a float stage: every pair stays undecided
            return values, np.ones(todo.size, dtype=bool)
        assert float_stage is not None
        mask = np.zeros(pairs.size, dtype=bool)
        mask[todo] = True
        where = np.cumsum(mask) - 1  # pair index -> its position in todo
        decided = np.zeros(todo.size, dtype=bool)
        for i, r in float_stage(pairs, mask).items():
            values[where[i]] = r
            decided[where[i]] = True
        return values, None if decided.all() else ~decided

    def exact(_: None, values: np.ndarray, idx: np.ndarray) -> np.ndarray | None:
        failed = np.zeros(idx.size, dtype=bool)
        for k, pos in enumerate(idx.tolist()):
            i = int(todo[pos])
            try:  # one pair's trouble stays that pair's: the others keep their answers
                values[pos] = exact_stage(pairs, i)
            except (ArithmeticError, RuntimeError, ValueError) as e:
                values[pos] = NoWitness(Relation(int(pairs.relation[i])), "failed", f"{what}: {e} (please report this pair)")
                failed[k] = True
        return failed if failed.any() else None

    values, _, _ = counter.run(None, int(todo.size), floated, exact, method, blank=lambda _: np.empty(todo.size, dtype=object))
    for pos, i in enumerate(todo.tolist()):
        v = values[pos]
        if v is None:  # "float": the floats could not certify it
            rel = Relation(int(pairs.relation[i]))
            v = NoWitness(rel, "undecided", f"the floats could not certify the {what} (method='float'; 'adaptive' finishes it exactly)")
        out[i] = v
    return [o for o in out if o is not None]


def finish(results: list[T | NoWitness], pairs: Pairs, on_invalid: OnInvalid) -> T | NoWitness | WitnessArray:
    """Apply ``on_invalid`` and shape the answer: one result for one pair, an object array for stacks.

    Raises:
        ValueError: ``on_invalid="raise"`` and a pair is invalid or has no such witness (the
            message names the pair in a stack).
        RuntimeError: one pair whose exact computation failed (in a stack it stays marked).
    """
    scalar = pairs.shape == ()
    if on_invalid == "raise":
        for i, r in enumerate(results):
            if isinstance(r, NoWitness) and r.kind in ("invalid", "none"):
                raise ValueError(r.reason if scalar else f"pair {i}: {r.reason}")
    if scalar:
        r0 = results[0]
        if isinstance(r0, NoWitness) and r0.kind == "failed":
            raise RuntimeError(r0.reason)
        return r0
    arr = np.empty(len(results), dtype=object)
    for i, r in enumerate(results):
        arr[i] = r
    return arr.reshape(pairs.shape)
