"""The one filtered-evaluation helper (core/filtered.py, issue 53) and the ladders that run through it.

The helper's contract (the exact stage sees only the unsure subset, certified_by, method=,
counters, under threads), then for each converted ladder (classify, explain, the witnesses, the
motion signs, the bounding spheres, the sweep) that its counters move when a pair needs exact
arithmetic and not when the float stage decides.
"""

from __future__ import annotations

import sys
import threading
from concurrent.futures import ThreadPoolExecutor
from fractions import Fraction

import numpy as np
import pytest
from flint import fmpq, fmpq_poly

import core
from core import (
    Certifier,
    FilterCounts,
    Relation,
    Stats,
    bodies_from_axes,
    classify,
    classify_detailed,
    contact_point,
    contact_scale,
    distance,
    explain,
    filter_stats,
    quadric_from_axes,
    separating_plane,
    sweep_contacts,
)
from core.algebra.algebraic import RealAlgebraic
from core.algebra.qsqrt import QSqrtPoly
from core.bodies.bounds import bounding_spheres
from core.filtered import Predicate, predicate
from core.moving.signs import Signs


def circle(x: float, r: float = 1.0) -> np.ndarray:
    return np.array([[1.0, 0.0, -x], [0.0, 1.0, 0.0], [-x, 0.0, x * x - r * r]])


def moved(f, name: str) -> tuple[int, int, int, int]:
    """(calls, pairs, failures, exact) added to predicate ``name`` while ``f()`` runs."""
    before = filter_stats()[name]
    f()
    after = filter_stats()[name]
    return (after.calls - before.calls, after.pairs - before.pairs, after.failures - before.failures, after.exact - before.exact)


# ------------------------------------------------------------------------- the helper's contract


def _stages(unsure: np.ndarray | None, seen: list[np.ndarray], fail: frozenset[int] = frozenset()):
    """A float stage that leaves ``unsure`` (values 1 where decided, 0 elsewhere) and an exact
    stage that records the indices it gets, writes 2 there and fails on the items in ``fail``."""

    def float_stage(n: int) -> tuple[np.ndarray, np.ndarray | None]:
        values = np.ones(n, dtype=np.int64)
        if unsure is not None:
            values[unsure] = 0
        return values, unsure

    def exact_stage(n: int, values: np.ndarray, idx: np.ndarray) -> np.ndarray | None:
        seen.append(idx.copy())
        values[idx] = 2
        failed = np.isin(idx, sorted(fail))
        return failed if failed.any() else None

    return float_stage, exact_stage


def test_exact_stage_sees_only_the_unsure_and_certified_by_says_who_decided():
    p = Predicate("contract")
    unsure = np.array([False, True, False, True, True, False])
    seen: list[np.ndarray] = []
    f, e = _stages(unsure, seen, fail=frozenset({4}))
    values, by, left = p.run(6, 6, f, e, "adaptive")
    assert len(seen) == 1 and seen[0].tolist() == [1, 3, 4]  # once, on the unsure subset only
    assert left.tolist() == [1, 3, 4]
    assert values.tolist() == [1, 2, 1, 2, 2, 1]  # the float values kept where the floats decided
    assert by.tolist() == [Certifier.FLOAT, Certifier.EXACT, Certifier.FLOAT, Certifier.EXACT, Certifier.NONE, Certifier.FLOAT]
    assert p.counts() == FilterCounts(calls=1, pairs=6, failures=3, exact=3)


def test_all_decided_by_floats_never_calls_exact_and_writes_no_certifiers():
    p = Predicate("contract")
    seen: list[np.ndarray] = []
    f, e = _stages(None, seen)
    values, by, left = p.run(5, 5, f, e, "adaptive")
    assert seen == [] and left.size == 0 and values.tolist() == [1] * 5
    assert by.tolist() == [Certifier.FLOAT] * 5 and not by.flags.writeable  # a broadcast, nothing written
    # a mask with nothing set is the same answer, through a pass
    values, by, left = p.run(5, 5, *_stages(np.zeros(5, dtype=bool), seen), "adaptive")
    assert seen == [] and left.size == 0 and by.tolist() == [Certifier.FLOAT] * 5
    assert p.counts() == FilterCounts(calls=2, pairs=10, failures=0, exact=0)


def test_method_float_leaves_the_unsure_unsure_and_exact_skips_the_floats():
    unsure = np.array([True, False, True])
    p = Predicate("contract")
    seen: list[np.ndarray] = []
    values, by, left = p.run(3, 3, *_stages(unsure, seen), "float")
    assert seen == [] and values.tolist() == [0, 1, 0] and left.tolist() == [0, 2]
    assert by.tolist() == [Certifier.NONE, Certifier.FLOAT, Certifier.NONE]
    assert p.counts() == FilterCounts(calls=1, pairs=3, failures=2, exact=0)

    def no_floats(n: int) -> tuple[np.ndarray, np.ndarray | None]:
        raise AssertionError("the float stage ran under method='exact'")

    _, e = _stages(unsure, seen)
    values, by, left = p.run(3, 3, no_floats, e, "exact", blank=lambda n: np.full(n, -1))
    assert [s.tolist() for s in seen] == [[0, 1, 2]] and values.tolist() == [2, 2, 2]
    assert by.tolist() == [Certifier.EXACT] * 3 and left.tolist() == [0, 1, 2]
    assert p.counts(reset=True) == FilterCounts(calls=2, pairs=6, failures=2, exact=3)
    assert p.counts() == FilterCounts(0, 0, 0, 0)
    with pytest.raises(ValueError, match="needs the blank values"):
        p.run(3, 3, no_floats, e, "exact")


def test_one_item_follows_the_same_methods():
    p = Predicate("one")
    calls: list[str] = []

    def exact() -> str:
        calls.append("exact")
        return "exact answer"

    assert p.one(lambda: "float answer", exact, "adaptive") == ("float answer", Certifier.FLOAT)
    assert p.one(lambda: None, exact, "adaptive") == ("exact answer", Certifier.EXACT)
    assert p.one(lambda: None, exact, "float") == (None, Certifier.NONE)
    assert p.one(lambda: pytest.fail("floats under 'exact'"), exact, "exact") == ("exact answer", Certifier.EXACT)
    assert calls == ["exact", "exact"]
    assert p.counts() == FilterCounts(calls=4, pairs=4, failures=2, exact=2)

    def broken() -> str:
        raise ValueError("not an ellipse")

    with pytest.raises(ValueError, match="not an ellipse"):  # the error propagates, the attempt is counted
        p.one(lambda: None, broken, "adaptive")
    assert p.counts() == FilterCounts(calls=5, pairs=5, failures=3, exact=3)


def test_stats_are_fed_by_the_helper():
    p = Predicate("stats")
    stats = Stats()
    p.run(4, 4, *_stages(np.array([True, False, False, True]), []), "adaptive", stats=stats)
    p.run(4, 4, *_stages(None, []), "adaptive", stats=stats)
    p.run(2, 2, *_stages(np.array([True, False]), []), "float", stats=stats)
    p.run(3, 3, *_stages(None, []), "exact", blank=np.zeros, stats=stats)
    p.one(lambda: None, lambda: 1, "adaptive", stats=stats)
    p.one(lambda: 1, lambda: 1, "adaptive", stats=stats)
    assert (stats.pairs, stats.escalated) == (4 + 4 + 2 + 3 + 2, 2 + 0 + 1 + 3 + 1)


def test_counters_are_right_under_threads():
    """Workers count while a reader takes and resets snapshots: nothing is lost or counted twice."""
    p = Predicate("threads")
    unsure = np.array([True, False, True, False])
    rounds, threads = 300, 6
    fields = ("calls", "pairs", "failures", "exact")
    total = dict.fromkeys(fields, 0)
    stop = threading.Event()

    def add(c: FilterCounts) -> None:
        for f in fields:
            total[f] += getattr(c, f)

    def read() -> None:
        while not stop.is_set():
            add(p.counts(reset=True))

    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # switch threads as often as possible: a lost update would show
    try:
        barrier = threading.Barrier(threads)

        def work(_: int) -> None:
            barrier.wait()
            for _ in range(rounds):
                p.run(4, 4, *_stages(unsure, []), "adaptive")
                p.one(lambda: None, lambda: 0, "adaptive")

        reader = threading.Thread(target=read)
        reader.start()
        try:
            with ThreadPoolExecutor(threads) as pool:
                list(pool.map(work, range(threads)))
        finally:
            stop.set()
            reader.join()
    finally:
        sys.setswitchinterval(old)
    add(p.counts())
    n = rounds * threads
    assert list(total.values()) == [2 * n, 5 * n, 3 * n, 3 * n]


def test_classify_counters_under_the_thread_pool():
    tangent = np.stack([circle(0.0)] * 3), np.stack([circle(2.0), circle(5.0), circle(2.0)])  # 2 need exact
    before = filter_stats()["classify"]
    with ThreadPoolExecutor(4) as pool:
        out = list(pool.map(lambda _: classify(*tangent).tolist(), range(40)))
    after = filter_stats()["classify"]
    assert out == [[Relation.TANGENT, Relation.SEPARATE, Relation.TANGENT]] * 40
    assert (after.calls - before.calls, after.pairs - before.pairs, after.failures - before.failures) == (40, 120, 80)


def test_predicates_are_named_once_and_listed():
    assert predicate("classify") is predicate("classify")
    names = set(filter_stats())
    assert {"classify", "explain", "contact_scale", "separating_plane", "contact_point", "distance",
            "motion_sign", "bounding_sphere", "sweep_first_contact"} <= names
    assert core.Certifier is core.fixed.classify.Certifier and core.Stats is core.fixed.classify.Stats
    stats = filter_stats(reset=True)
    assert all(isinstance(c, FilterCounts) for c in stats.values())
    assert filter_stats()["classify"] == FilterCounts(0, 0, 0, 0)


# ------------------------------------------------------------------------- the ladders


def test_classify_counts_the_tangent_pair_sent_to_exact():
    assert moved(lambda: classify(circle(0), circle(3)), "classify") == (1, 1, 0, 0)  # one pair, the drag path
    assert moved(lambda: classify(circle(0), circle(2)), "classify") == (1, 1, 1, 1)
    assert moved(lambda: classify(circle(0), circle(2), method="float"), "classify") == (1, 1, 1, 0)
    assert moved(lambda: classify(circle(0), circle(3), method="exact"), "classify") == (1, 1, 0, 1)
    A, B = np.stack([circle(0)] * 3), np.stack([circle(2), circle(3), circle(0.5)])
    assert moved(lambda: classify(A, B), "classify") == (1, 3, 1, 1)
    assert moved(lambda: classify(A[1:], B[1:]), "classify") == (1, 2, 0, 0)
    res = classify_detailed(A, B)
    assert res.certified_by.tolist() == [Certifier.EXACT, Certifier.FLOAT, Certifier.FLOAT] and res.certified_by.flags.writeable
    # exact input (Fractions) is not a float failure: it goes straight to exact
    exact_input = [[1, 0, Fraction(-1, 3)], [0, 1, 0], [Fraction(-1, 3), 0, Fraction(1, 9) - 1]]
    assert moved(lambda: classify(exact_input, circle(5)), "classify") == (1, 1, 0, 1)
    stats = Stats()
    classify(A, B, stats=stats)
    classify(circle(0), circle(2), stats=stats)
    assert (stats.pairs, stats.escalated) == (4, 2)


def test_classify_marks_invalid_pairs_none():
    bad = np.diag([1.0, 1.0, 1.0])  # no real points
    res = classify_detailed(np.stack([circle(0), bad]), np.stack([circle(2), circle(2)]), on_invalid="mark")
    assert res.relation.tolist() == [Relation.TANGENT, Relation.INVALID]
    assert res.certified_by.tolist() == [Certifier.EXACT, Certifier.NONE] and list(res.errors) == [1]
    fl = classify_detailed(np.stack([circle(0), bad]), np.stack([circle(2), circle(2)]), method="float", on_invalid="mark")
    assert fl.relation.tolist() == [Relation.UNDECIDED, Relation.INVALID] and fl.certified_by.tolist() == [0, 0]
    with pytest.raises(ValueError, match="pair 1: "):
        classify(np.stack([circle(0), bad]), np.stack([circle(2), circle(2)]))


def test_explain_counts():
    assert moved(lambda: explain(circle(0), circle(3)), "explain") == (1, 1, 0, 0)
    assert moved(lambda: explain(circle(0), circle(2)), "explain") == (1, 1, 1, 1)
    exact_input = [["1", "0", "-1/3"], ["0", "1", "0"], ["-1/3", "0", "-8/9"]]
    assert moved(lambda: explain(exact_input, circle(5)), "explain") == (1, 1, 0, 1)


def _far_pair(shift: float) -> tuple[np.ndarray, np.ndarray]:
    """A separate pair whose centres lie ``shift`` out: at 1e4 the floats lose the contact scale."""
    A = quadric_from_axes([shift, shift, 0.0], [0.2, 0.3, 0.25], [0.9, 0.1, 0.2, 0.3])
    B = quadric_from_axes([shift + 0.5, shift + 0.3, 0.1], [0.1, 0.3, 0.2], [0.2, 0.8, 0.1, 0.3])
    return A, B


def test_witness_counters_move_only_when_a_pair_needs_exact():
    assert moved(lambda: contact_scale(*_far_pair(0.0), rtol=1e-10), "contact_scale") == (1, 1, 0, 0)
    assert moved(lambda: contact_scale(*_far_pair(1e4), rtol=1e-10), "contact_scale") == (1, 1, 1, 1)
    assert moved(lambda: distance(*_far_pair(0.0)), "distance") == (1, 1, 0, 0)
    assert moved(lambda: distance(*_far_pair(1e4)), "distance") == (1, 1, 1, 1)
    assert moved(lambda: separating_plane(circle(0), circle(3)), "separating_plane") == (1, 1, 0, 0)
    assert moved(lambda: separating_plane(circle(0), circle(2 + 2.0**-45)), "separating_plane") == (1, 1, 1, 1)
    assert moved(lambda: contact_point(circle(0), circle(1)), "contact_point") == (1, 1, 0, 0)  # overlap: a float point
    assert moved(lambda: contact_point(circle(0), circle(2)), "contact_point") == (1, 1, 1, 1)  # tangent: exact algebra
    # method="float": the pair the floats cannot finish is undecided, never exact
    near = circle(0), circle(2 + 2.0**-45)  # the floats certify the relation, not a plane
    out = separating_plane(*near, method="float", on_invalid="mark")
    assert not out and out.kind == "undecided"
    assert moved(lambda: separating_plane(*near, method="float", on_invalid="mark"), "separating_plane") == (1, 1, 1, 0)
    # pairs without this witness (a plane of a tangent pair) are not evaluated
    assert moved(lambda: separating_plane(circle(0), circle(2), on_invalid="mark"), "separating_plane") == (0, 0, 0, 0)
    # a stack: one call, the pairs the floats leave counted
    A = np.stack([circle(0)] * 3)
    B = np.stack([circle(2), circle(1), circle(0.5)])
    assert moved(lambda: contact_point(A, B), "contact_point") == (1, 3, 1, 1)


def test_motion_sign_counters():
    polys = {"a0": QSqrtPoly(fmpq_poly([-1, 2]))}  # 2t - 1

    def sign(point: fmpq | RealAlgebraic, t: float | None) -> int:
        return Signs(polys, point, set(), t)("a0")

    assert moved(lambda: sign(fmpq(1, 4), 0.25), "motion_sign") == (1, 1, 0, 0)  # the float Horner step
    assert moved(lambda: sign(fmpq(1, 2), 0.5), "motion_sign") == (1, 1, 1, 1)  # a zero: only exact tells
    assert sign(fmpq(1, 2), 0.5) == 0 and sign(fmpq(1, 4), 0.25) == -1
    assert moved(lambda: sign(fmpq(1, 3), None), "motion_sign") == (1, 1, 0, 1)  # not a float: exact
    assert moved(lambda: sign(RealAlgebraic.rational(fmpq(1, 3)), None), "motion_sign") == (1, 1, 0, 1)
    assert moved(lambda: Signs(polys, fmpq(1, 2), {"a0"}, 0.5)("a0"), "motion_sign") == (0, 0, 0, 0)  # known zero


def test_bounding_sphere_counters():
    q = np.random.default_rng(0).normal(size=(2, 4))
    Q = bodies_from_axes(np.full((2, 3), 5.0), np.array([[1.0, 2.0, 1.5], [1e-6, 1.0, 1.0]]), q)
    assert moved(lambda: bounding_spheres(Q[:1]), "bounding_sphere") == (1, 1, 0, 0)
    assert moved(lambda: bounding_spheres(Q), "bounding_sphere") == (1, 2, 1, 1)  # the 1e-6-thin body
    s = bounding_spheres(Q)
    assert s.exact == 1 and not s.invalid and np.isfinite(s.radii).all()
    empty = np.array([np.diag([1.0, 1.0, 1.0, 1.0])])  # no real points: exact names it
    assert moved(lambda: bounding_spheres(empty), "bounding_sphere") == (1, 1, 1, 1)
    s = bounding_spheres(empty)
    assert s.exact == 0 and list(s.invalid) == [0]


def test_sweep_counters():
    crossing = ([[0, 0], [3, 0]], [[0, 0], [1, 0]], [[1, 1]] * 2)  # circle 1 runs into circle 0
    grazing = ([[0, 0], [-5, 2]], [[0, 0], [5, 2]], [[1, 1]] * 2)  # touches (0, 1) at t = 1/2 and leaves
    assert moved(lambda: sweep_contacts(*crossing), "sweep_first_contact") == (1, 1, 0, 0)
    assert moved(lambda: sweep_contacts(*grazing), "sweep_first_contact") == (1, 1, 1, 1)
    res = sweep_contacts(*grazing)
    assert res.certified_by.tolist() == [Certifier.EXACT] and res.relation.tolist() == [Relation.TANGENT]
    assert res.counts["exact"] == 1 and res.time(0).compare(fmpq(1, 2)) == 0
