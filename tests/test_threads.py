"""The compiled filter's batch threads: a forked child, the calling thread's own part."""

from __future__ import annotations

import multiprocessing
import os

import numpy as np
import pytest

import core
from core import Relation, quadric_from_axes
from core.fixed import compiled

pytestmark = pytest.mark.skipif(not compiled.available(), reason="needs the compiled filter")

GAPS = {3.0: Relation.SEPARATE, 2.0: Relation.TANGENT, 1.0: Relation.OVERLAP}
"""Unit spheres with centres this far apart: their relation by geometry."""


def _pairs(count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """count pairs of unit spheres and their true relations: separate and overlapping in turn,
    tangent every 1000th pair (the float filter leaves those to exact arithmetic, ~0.1 ms each)."""
    gap = [2.0 if k % 1000 == 0 else (3.0 if k % 2 else 1.0) for k in range(count)]
    A = np.broadcast_to(np.array(quadric_from_axes([0, 0, 0], [1, 1, 1]), dtype=float), (count, 4, 4)).copy()
    B = np.stack([np.array(quadric_from_axes([g, 0, 0], [1, 1, 1]), dtype=float) for g in (1.0, 2.0, 3.0)])
    B = B[np.array([int(g) - 1 for g in gap])]
    want = np.array([int(GAPS[g]) for g in gap], dtype=np.int8)
    return A, B, want


def _child(A: np.ndarray, B: np.ndarray, queue) -> None:
    queue.put(np.asarray(core.classify(A, B)).tobytes())


@pytest.mark.skipif(not hasattr(os, "fork"), reason="fork only")
def test_a_forked_child_classifies_after_its_parent_did():
    """multiprocessing with fork (Linux's default before Python 3.14): the parent's batch
    threads do not exist in the child; its classify once queued work that no thread ran and
    hung forever. The child must answer, with the true relations."""
    A, B, want = _pairs(3 * compiled._MIN_CHUNK)  # enough pairs for the batch to be split over threads
    before = compiled._state["threads"]
    compiled.set_threads(2)
    try:
        assert (np.asarray(core.classify(A, B)) == want).all()  # the parent's pool now exists
        ctx = multiprocessing.get_context("fork")
        queue = ctx.Queue()
        child = ctx.Process(target=_child, args=(A, B, queue))
        child.start()
        try:
            got = np.frombuffer(queue.get(timeout=60), dtype=np.int8)
        finally:
            child.kill()
            child.join()
        assert (got == want).all()
    finally:
        compiled._state["threads"] = before


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_every_part_of_a_split_batch_is_classified(threads):
    """The calling thread classifies the first part and the pool the rest: every pair gets its
    relation, whatever the split (1 thread: no pool; 3 threads on 2 cores: parts of unequal luck)."""
    A, B, want = _pairs(3 * compiled._MIN_CHUNK + 7)
    before = compiled._state["threads"]
    compiled.set_threads(threads)
    try:
        got = np.asarray(core.classify(A, B))
        rules, undecided = compiled.mapped(A, B, np.arange(256, dtype=np.int64).astype(np.int8), threads=threads)
    finally:
        compiled._state["threads"] = before
    assert (got == want).all()
    assert undecided == int((rules == -1).sum()) > 0  # the tangent pairs: the float filter leaves them to exact arithmetic
