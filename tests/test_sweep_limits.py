"""The sweep's guards for a server: pairs counted before any is built, ``progress`` as the budget hook.

As :func:`core.contacts` (tests/test_broadphase_chunks.py): ``sweep_contacts(..., max_pairs=M)``
refuses crowded bodies with :class:`TooManyPairs` after counting and before building a pair;
``progress(done, total)`` runs between the chunks of the broad phase and the batches of the
narrow phase, and raising from it stops the sweep there. Golden values: combinatorics (n(n-1)/2
pairs among n bodies at one point), the narrow phase run on every pair (no broad phase), and
the sweep in one chunk.
"""

from __future__ import annotations

import numpy as np
import pytest

from bench.sweep_data import moving_bodies
from core import Relation, sweep_contacts
from core.bodies import broadphase
from core.bodies import sweep as sweep_module
from core.bodies.broadphase import TooManyPairs
from core.moving.first_contact import first_contacts
from core.moving.linear import read_linear_motions


def crowd(n: int, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n unit bodies all at the origin, each moving by one unit along x (every pair overlaps)."""
    c0 = np.zeros((n, d))
    c1 = c0.copy()
    c1[:, 0] = 1.0
    return c0, c1, np.ones((n, d))


@pytest.mark.parametrize("n, d", [(10, 3), (2000, 2), (10_000, 3)])
def test_a_crowd_is_refused_before_any_pair_is_built(n, d, monkeypatch):
    def no_building(*args):
        raise AssertionError("a pair was built")

    monkeypatch.setattr(broadphase, "_build", no_building)
    pairs = n * (n - 1) // 2
    with pytest.raises(TooManyPairs) as e:
        sweep_contacts(*crowd(n, d), max_pairs=pairs - 1)
    assert (e.value.pairs, e.value.limit) == (pairs, pairs - 1)
    assert isinstance(e.value, ValueError)
    assert str(e.value).startswith(f"{pairs:,} pairs of bodies to examine")


def test_at_the_limit_every_pair_of_a_crowd_is_found():
    n = 40
    res = sweep_contacts(*crowd(n, 3), max_pairs=n * (n - 1) // 2)
    i, j = np.triu_indices(n, 1)
    assert res.i.tolist() == i.tolist() and res.j.tolist() == j.tolist()
    assert (res.relation == Relation.OVERLAP).all() and (res.t_hi == 0.0).all()
    assert res.counts["broad"] == res.counts["candidates"] == n * (n - 1) // 2


@pytest.mark.parametrize("bad", [-1, 1.5, True, "10"])
def test_max_pairs_must_be_a_count(bad):
    with pytest.raises(ValueError, match="max_pairs must be a non-negative integer or None"):
        sweep_contacts(*crowd(3, 2), max_pairs=bad)


def test_unknown_method_is_refused_even_without_candidates():
    with pytest.raises(ValueError, match="unknown method 'float'; valid options: adaptive, exact"):
        sweep_contacts([[0.0, 0.0]], [[1.0, 0.0]], [[1.0, 1.0]], method="float")  # type: ignore[arg-type]


@pytest.mark.parametrize("periodic", [False, True])
def test_in_chunks_the_sweep_equals_the_narrow_phase_on_every_pair(periodic, monkeypatch):
    """Tiny broad-phase chunks and narrow-phase batches give the pairs of the narrow phase on all pairs."""
    m = moving_bodies(90, fraction=0.3, rotate=True, seed=7)
    box = None
    c0, c1 = m.centers0, m.centers1
    if periodic:  # the same bodies in a box just larger than their midpoints' span
        side = float(np.ptp((c0 + c1) / 2, axis=0).max()) + 0.5  # pairs across the faces
        box = (side,) * 3
    args = (c0, c1, m.semi_axes, m.orientations0, m.orientations1)
    whole = sweep_contacts(*args, box=box)
    monkeypatch.setattr(broadphase, "_PAIRS_PER_CHUNK", 50)
    monkeypatch.setattr(sweep_module, "_BATCH", 7)
    calls: list[tuple[int, int]] = []
    res = sweep_contacts(*args, box=box, progress=lambda done, total: calls.append((done, total)))
    for name in ("i", "j", "t_lo", "t_hi", "relation", "certified_by"):
        assert getattr(res, name).tolist() == getattr(whole, name).tolist(), name
    assert (res.image is None) == (not periodic)
    if periodic:
        assert res.image.tolist() == whole.image.tolist() and (res.image != 0).any()
    assert res.counts == whole.counts
    assert [res.time(k).to_dict() for k in range(len(res))] == [whole.time(k).to_dict() for k in range(len(whole))]
    if not periodic:  # independent of the broad phase: the narrow phase on all pairs
        bodies, _ = read_linear_motions(*args)
        i, j = np.triu_indices(90, 1)
        every = first_contacts(bodies, i, j)
        meet = np.flatnonzero(every.relation != Relation.SEPARATE)
        assert list(zip(res.i.tolist(), res.j.tolist(), strict=True)) == list(zip(i[meet].tolist(), j[meet].tolist(), strict=True))
        assert res.t_lo.tolist() == every.t_lo[meet].tolist() and res.relation.tolist() == every.relation[meet].tolist()
    assert len(res) > 20
    total = calls[0][1]
    assert calls[0] == (0, total) and calls[-1] == (total, total) and total >= res.counts["broad"]
    assert all(t == total for _, t in calls)
    assert [d for d, _ in calls] == sorted(d for d, _ in calls)
    assert len(calls) > total // 50  # between the chunks, not only at the ends


def test_raising_from_progress_stops_the_sweep_in_the_broad_phase(monkeypatch):
    """The budget hook stops the building of pairs; the narrow phase is never reached."""
    monkeypatch.setattr(broadphase, "_PAIRS_PER_CHUNK", 1000)
    narrow: list[int] = []
    real = sweep_module.first_contacts
    monkeypatch.setattr(sweep_module, "first_contacts", lambda *a, **k: narrow.append(1) or real(*a, **k))
    built: list[int] = []
    real_build = broadphase._build
    monkeypatch.setattr(broadphase, "_build", lambda *a: built.append(1) or real_build(*a))
    calls: list[int] = []

    def budget(done: int, total: int) -> None:
        if len(calls) > 3:
            raise TimeoutError(f"over budget after {done} of {total}")
        calls.append(done)

    n = 400  # 79,800 pairs: 80 chunks of 1000
    with pytest.raises(TimeoutError, match="over budget after"):
        sweep_contacts(*crowd(n, 3), progress=budget)
    assert narrow == []
    assert len(built) < 20  # stopped within a round of chunks, not after all 80


def test_raising_from_progress_stops_the_narrow_phase(monkeypatch):
    """Between the narrow phase's float batches (one batch of every candidate: progress inside it)."""
    m = moving_bodies(300, fraction=0.3, rotate=True, seed=2)
    seen: list[tuple[int, int]] = []
    real = sweep_module.first_contacts

    def spy(*a, **k):
        seen.append((len(a[1]), k["progress"] is not None))
        return real(*a, **{**k, "chunk": 16})

    monkeypatch.setattr(sweep_module, "first_contacts", spy)
    calls = 0

    def budget(done: int, total: int) -> None:
        nonlocal calls
        calls += 1
        if seen:  # inside the narrow phase
            raise TimeoutError("over budget in the narrow phase")

    with pytest.raises(TimeoutError, match="narrow phase"):
        sweep_contacts(*m.arguments(), progress=budget)
    assert len(seen) == 1 and seen[0][0] > 16 and seen[0][1]
