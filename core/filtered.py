"""One filtered evaluation for every certified ladder (CGAL's ``Filtered_predicate``, in Python).

Each certified answer of ``core`` is the same control flow: a **float stage** over a batch, sound
but allowed to abstain (its unsure mask), then an **exact stage** called only on the unsure
subset. :class:`Predicate` owns that flow and its counting, once, for classify, the witnesses,
explain, the motion signs, the bounding spheres and the sweep; each ladder keeps its own logic
(what a stage computes, what it writes, its structural cases) inside its stages.

``method=`` means the same everywhere (:data:`core.options.METHODS`): "adaptive" (float stage,
then exact on the unsure), "float" (float stage only: unsure stays unsure, certified NONE),
"exact" (exact stage for all; the float stage is not run).

Counters per named predicate (calls, pairs, float failures, exact pairs) are read with
:func:`filter_stats` (and reset with it); they are updated under a lock once per call, so they
stay right under threads, and the helper does no per-pair Python work.

This module sits beside :mod:`core.options` (it imports only numpy and the standard library)
because every package of ``core`` uses it: :class:`Certifier`'s codes are defined here once.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum
from typing import TypeVar

import numpy as np

__all__ = ["Certifier", "Stats", "FilterCounts", "Predicate", "predicate", "filter_stats"]


class Certifier(IntEnum):
    """Which arithmetic certified a pair's answer (int8 codes of the ``certified_by`` arrays)."""

    NONE = 0
    """Undecided (``method="float"``), invalid, or failed."""
    FLOAT = 1
    """The float stage, with proven error bounds."""
    EXACT = 2
    """Exact rational arithmetic."""

    def __str__(self) -> str:
        return self.name.lower()

    @staticmethod
    def counts(certified_by: np.ndarray) -> dict[str, int]:
        """Pairs per certifier in an array of codes: ``{"float": ..., "exact": ...}``."""
        by = np.bincount(np.asarray(certified_by, dtype=np.int64).ravel(), minlength=3)
        return {str(Certifier(k)): int(by[k]) for k in (Certifier.FLOAT, Certifier.EXACT)}


class Stats:
    """Counters of filter calls and failures (CGAL's profiler), filled when passed to ``classify``."""

    def __init__(self) -> None:
        self.pairs = 0
        """Pairs classified."""
        self.escalated = 0
        """Pairs the float filter did not decide (sent to exact under ``adaptive``, all of them
        under ``exact``, left UNDECIDED under ``float``)."""

    def __repr__(self) -> str:
        return f"Stats(pairs={self.pairs}, escalated={self.escalated})"


@dataclass(frozen=True)
class FilterCounts:
    """A snapshot of one predicate's counters (:func:`filter_stats`)."""

    calls: int
    """Evaluations (one per batch, or per single item)."""
    pairs: int
    """Items (pairs, bodies, signs) evaluated."""
    failures: int
    """Items the float stage ran on and left unsure (sent to exact under ``adaptive``)."""
    exact: int
    """Items sent to the exact stage (the failures under ``adaptive``, every item under ``exact``)."""

    @property
    def failure_rate(self) -> float:
        """``failures / pairs`` (0.0 before any pair)."""
        return self.failures / self.pairs if self.pairs else 0.0


I = TypeVar("I")  # noqa: E741  (the inputs of a batch)
V = TypeVar("V")  # the values a stage produces

_NO_INDEX = np.zeros(0, dtype=np.int64)
_NO_INDEX.flags.writeable = False
_FLOAT_CODE = bytes([Certifier.FLOAT])


def _all_float(size: int) -> np.ndarray:
    """A read-only (size,) int8 array of FLOAT without writing it (stride 0: ~1 us for any size)."""
    return np.ndarray((size,), np.int8, _FLOAT_CODE, 0, (0,))


class Predicate:
    """A named filtered predicate: the float -> exact control flow and its counters.

    Create one per ladder with :func:`predicate` (at import: :func:`filter_stats` then lists
    it before its first call), and call :meth:`run` for a batch or :meth:`one` for one item.
    """

    __slots__ = ("name", "_lock", "_calls", "_pairs", "_failures", "_exact")

    def __init__(self, name: str) -> None:
        self.name = name
        self._lock = threading.Lock()
        self._calls = self._pairs = self._failures = self._exact = 0

    def __repr__(self) -> str:
        return f"Predicate({self.name!r}, {self.counts()})"

    def count(self, pairs: int, failures: int, exact: int) -> None:
        """Add one call of ``pairs`` items, ``failures`` left unsure by floats, ``exact`` sent to exact."""
        with self._lock:
            self._calls += 1
            self._pairs += pairs
            self._failures += failures
            self._exact += exact

    def counts(self, *, reset: bool = False) -> FilterCounts:
        """The counters now (and set them to zero with ``reset``), read under the lock."""
        with self._lock:
            out = FilterCounts(self._calls, self._pairs, self._failures, self._exact)
            if reset:
                self._calls = self._pairs = self._failures = self._exact = 0
        return out

    def run(
        self,
        inputs: I,
        size: int,
        float_stage: Callable[[I], tuple[V, np.ndarray | None]],
        exact_stage: Callable[[I, V, np.ndarray], np.ndarray | None],
        method: str = "adaptive",
        *,
        blank: Callable[[I], V] | None = None,
        stats: Stats | None = None,
    ) -> tuple[V, np.ndarray, np.ndarray]:
        """Evaluate a batch of ``size`` items: float stage, unsure mask, exact stage on the unsure.

        Args:
            inputs: the batch, handed to the stages as it is.
            size: number of items in it.
            float_stage: ``inputs -> (values, unsure)``; ``unsure`` a (size,) bool mask of the
                items it could not certify, or None when it certified every one (known without
                a pass over the batch). Not called under ``method="exact"``.
            exact_stage: ``(inputs, values, idx)`` decides the items ``idx`` (sorted int64
                indices) exactly, writing into ``values`` in place; returns a bool mask over
                ``idx`` of the items it could not certify either (invalid input, a failure:
                certified NONE), or None. Never called under ``method="float"``, nor with an
                empty ``idx``.
            method: "adaptive", "float" or "exact" (module docstring; checked by the caller).
            blank: ``inputs -> values`` with every item still to decide, for ``method="exact"``.
            stats: a :class:`Stats` to add this call to, if any.

        Returns:
            ``(values, certified_by, unsure)``: ``certified_by`` int8 :class:`Certifier` codes,
            a read-only broadcast of FLOAT when the float stage certified everything (no pass,
            nothing written); ``unsure`` the indices the float stage left (every index under
            "exact"), read-only and empty when there are none.
        """
        if method == "exact":
            if blank is None:
                raise ValueError(f"{self.name}: method 'exact' needs the blank values of a batch")
            values = blank(inputs)
            unsure = np.arange(size, dtype=np.int64)
            by = np.zeros(size, dtype=np.int8)
            failures = 0
        else:
            values, mask = float_stage(inputs)
            if mask is None:  # the usual case: every item certified by floats
                self.count(size, 0, 0)
                if stats is not None:
                    stats.pairs += size
                return values, _all_float(size), _NO_INDEX
            unsure = np.flatnonzero(mask)
            by = (~mask).view(np.int8)  # Certifier.FLOAT is 1, NONE 0
            failures = int(unsure.size)
        to_exact = 0 if method == "float" else int(unsure.size)
        self.count(size, failures, to_exact)  # before the exact stage: a raise there is still counted
        if stats is not None:
            stats.pairs += size
            stats.escalated += int(unsure.size)
        if to_exact:
            failed = exact_stage(inputs, values, unsure)
            by[unsure] = Certifier.EXACT
            if failed is not None:
                by[unsure[failed]] = Certifier.NONE
        return values, by, unsure

    def one(
        self,
        float_stage: Callable[[], V | None],
        exact_stage: Callable[[], V],
        method: str = "adaptive",
        *,
        stats: Stats | None = None,
    ) -> tuple[V | None, Certifier]:
        """Evaluate one item: ``float_stage()`` (None when unsure), then ``exact_stage()`` if needed.

        The same ``method`` semantics and counters as :meth:`run`, without arrays (the scene's
        drag and the motion signs run this per item). An exception of ``exact_stage`` propagates
        (the item is counted as sent to exact).

        Returns:
            ``(value, certifier)``; ``(None, Certifier.NONE)`` when unsure under "float".
        """
        if method != "exact":
            v = float_stage()
            if v is not None:
                self.count(1, 0, 0)
                if stats is not None:
                    stats.pairs += 1
                return v, Certifier.FLOAT
            failed = 1
        else:
            failed = 0
        if stats is not None:
            stats.pairs += 1
            stats.escalated += 1
        if method == "float":
            self.count(1, failed, 0)
            return None, Certifier.NONE
        self.count(1, failed, 1)
        return exact_stage(), Certifier.EXACT


_PREDICATES: dict[str, Predicate] = {}
_REGISTRY_LOCK = threading.Lock()


def predicate(name: str) -> Predicate:
    """The predicate named ``name`` (created on first use; one per name, so counters add up)."""
    with _REGISTRY_LOCK:
        p = _PREDICATES.get(name)
        if p is None:
            p = _PREDICATES[name] = Predicate(name)
    return p


def filter_stats(*, reset: bool = False) -> dict[str, FilterCounts]:
    """Counters of every filtered predicate, by name: how often the float stage fails.

    Args:
        reset: set every counter to zero after reading it.

    Examples:
        >>> import core
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> _ = core.filter_stats(reset=True)
        >>> _ = core.classify([circle(0), circle(0)], [circle(2), circle(3)])   # tangent, separate
        >>> c = core.filter_stats()["classify"]
        >>> c.calls, c.pairs, c.failures, c.exact
        (1, 2, 1, 1)
    """
    with _REGISTRY_LOCK:
        items = sorted(_PREDICATES.items())
    return {name: p.counts(reset=reset) for name, p in items}
