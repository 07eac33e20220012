"""The broad phase counts before it builds, builds in chunks, and the search keeps memory near its answer.

Issue 21: 10,000 bodies at one point grew the server to 5.6 GB and never answered. Now the pairs
to examine are counted first (``max_pairs``: :class:`TooManyPairs` before any pair is built),
built in chunks (a crowded cell is cut inside its row of pairs), classified chunk by chunk, and
``progress`` (the budget hook) runs between chunks. Golden values: combinatorics (n(n-1)/2 pairs
among n bodies at one point) and brute force over every pair.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from core import Relation, bodies_from_axes, classify, contacts
from core.bodies import broadphase
from core.bodies.broadphase import BroadPhase, Candidates, TooManyPairs, candidate_pairs
from core.bodies.search import ContactsBuilder


def brute_pairs(c, r, box=None):
    """Every pair (i < j) whose closed spheres meet (minimum image in a box), with the image."""
    out = {}
    n = len(c)
    for i, j in itertools.combinations(range(n), 2):
        d = c[j] - c[i]
        k = np.zeros(c.shape[1])
        if box is not None:
            k = -np.rint(d / box)
            d = d + k * box
        if np.sqrt(d @ d) <= r[i] + r[j]:
            out[(i, j)] = tuple(int(v) for v in k)
    return out


def as_dict(cand):
    images = cand.image.tolist() if cand.image is not None else [None] * len(cand)
    pairs = list(zip(cand.i.tolist(), cand.j.tolist(), strict=True))
    assert len(set(pairs)) == len(pairs), "a pair came twice"
    return {p: (tuple(k) if k is not None else None) for p, k in zip(pairs, images, strict=True)}


@pytest.mark.parametrize("c", [2, 3, 4, 7, 50])
def test_triangle_enumerates_the_pairs_of_a_cell_in_order(c):
    total = c * (c - 1) // 2
    p, q = broadphase._triangle(np.arange(total), np.full(total, c))
    assert list(zip(p.tolist(), q.tolist(), strict=True)) == list(itertools.combinations(range(c), 2))


@pytest.mark.parametrize("n, d", [(2, 2), (10, 3), (1000, 3), (10_000, 2)])
def test_a_crowd_is_counted_without_building_a_pair(n, d, monkeypatch):
    """n bodies at one point: n(n-1)/2 pairs, counted in O(cells); max_pairs refuses before building."""

    def no_building(*args):
        raise AssertionError("a pair was built")

    monkeypatch.setattr(broadphase, "_build", no_building)
    plan = BroadPhase(np.zeros((n, d)), np.ones(n))
    assert plan.pairs == n * (n - 1) // 2
    with pytest.raises(TooManyPairs) as e:
        candidate_pairs(np.zeros((n, d)), np.ones(n), max_pairs=plan.pairs - 1)
    assert (e.value.pairs, e.value.limit) == (plan.pairs, plan.pairs - 1)
    assert str(e.value) == (
        f"{plan.pairs:,} pairs of bodies to examine (bodies close enough that their bounding spheres may meet), "
        f"over the limit of {plan.pairs - 1:,} (max_pairs)"
    )


@pytest.mark.parametrize("periodic", [False, True])
@pytest.mark.parametrize("size", [1, 5, 64])
def test_chunks_of_any_size_give_exactly_the_pairs_whose_spheres_meet(periodic, size):
    """Crowded cells (several bodies per cell, radii over two decades) cut into tiny chunks."""
    rng = np.random.default_rng(7 + periodic)
    for trial in range(6):
        d = 2 + trial % 2
        n = int(rng.integers(20, 90))
        r = rng.uniform(0.2, 1.0, n) * (10 ** rng.uniform(0, 1.5, n) if trial % 2 else 1)
        box = None
        if periodic:
            box = rng.uniform(12, 16, d)
            r = np.minimum(r, box.min() / 4.5)
            c = rng.uniform(0, 1, (n, d)) * box
        else:
            c = rng.uniform(-2, 2, (n, d))
        c[: n // 3] = c[0]  # a third of them at one point: one cell with many bodies
        plan = BroadPhase(c, r, box=box)
        parts, seen = [], 0
        for cand, examined in plan.chunks(size):
            assert examined - seen <= size and examined > seen
            seen = examined
            parts.append(cand)
        assert seen == plan.pairs
        got = as_dict(Candidates.concatenate(parts, d, periodic))
        want = brute_pairs(c, r, box)
        assert set(got) == set(want)
        if periodic:
            assert got == want
        assert plan.pairs >= len(got)


def test_contacts_of_a_crowd_match_brute_force_with_progress_between_chunks(monkeypatch):
    """Every pair of 300 ellipses at one point overlaps; progress runs during the broad phase too."""
    monkeypatch.setattr(broadphase, "_PAIRS_PER_CHUNK", 1000)
    n = 300
    rng = np.random.default_rng(3)
    Q = bodies_from_axes(np.zeros((n, 2)), rng.uniform(0.5, 1.0, (n, 2)), rng.uniform(0, 3, n))
    calls = []
    res = contacts(Q, progress=lambda done, total: calls.append((done, total)), chunk=5000)
    i, j = np.triu_indices(n, 1)
    want = classify(Q[i], Q[j])
    assert (want == Relation.OVERLAP).all()
    assert res.i.tolist() == i.tolist() and res.j.tolist() == j.tolist()
    assert (res.relation == Relation.OVERLAP).all()
    total = n * (n - 1) // 2
    assert calls[0] == (0, total) and calls[-1] == (total, total)
    assert all(t == total for _, t in calls)
    assert [d for d, _ in calls] == sorted(d for d, _ in calls)
    assert len(calls) > total // 5000  # between chunks, not only at the end
    with pytest.raises(TooManyPairs):
        contacts(Q, max_pairs=total - 1)


def test_raising_from_progress_stops_the_search_in_the_broad_phase(monkeypatch):
    monkeypatch.setattr(broadphase, "_PAIRS_PER_CHUNK", 1000)
    n = 400
    Q = bodies_from_axes(np.zeros((n, 3)), np.ones((n, 3)), np.tile([1.0, 0, 0, 0], (n, 1)))
    classified = []
    import core.bodies.search as search

    real = search.classify_candidates
    monkeypatch.setattr(search, "classify_candidates", lambda *a, **k: classified.append(1) or real(*a, **k))

    def budget(done, total):
        if done == 0 and len(calls) > 3:
            raise TimeoutError("over budget")
        calls.append(done)

    calls: list[int] = []
    with pytest.raises(TimeoutError):
        contacts(Q, progress=budget, chunk=10**9)  # one narrow batch at the very end: never reached
    assert classified == []


@pytest.mark.parametrize("periodic", [False, True])
def test_contacts_builder_packed_keys_equal_the_plain_arrays(periodic):
    """The 8-byte keys (and their unpacking) give what separate arrays and a lexsort give."""
    rng = np.random.default_rng(5)
    d, n, m = 3, 1000, 5000
    ii, jj = np.triu_indices(n, 1)
    pick = rng.permutation(ii.size)[:m]  # distinct pairs, as candidates are
    i, j = ii[pick], jj[pick]
    cand = Candidates(i, j, rng.integers(-1, 2, (m, d)).astype(np.int8) if periodic else None)
    rel = rng.choice(np.array([-1, 0, 1, 2], np.int8), m)
    by = rng.integers(0, 3, m).astype(np.int8)

    class Spheres:
        invalid: dict = {}
        exact = 0

    out = []
    for packed in (True, False):
        b = ContactsBuilder(d, periodic, n)
        b.packed = packed
        for s in range(0, m, 777):
            b.add(Candidates(cand.i[s : s + 777], cand.j[s : s + 777], None if cand.image is None else cand.image[s : s + 777]),
                  rel[s : s + 777], by[s : s + 777])
        out.append(b.result(n, None, Spheres()))
    a, b = out
    for name in ("i", "j", "relation", "certified_by"):
        assert getattr(a, name).tolist() == getattr(b, name).tolist()
        assert getattr(a, name).dtype == getattr(b, name).dtype
    assert (a.image is None) == (not periodic)
    if periodic:
        assert a.image.tolist() == b.image.tolist()
    keep = rel != 0
    order = np.lexsort((j[keep], i[keep]))
    assert a.i.tolist() == i[keep][order].tolist() and a.relation.tolist() == rel[keep][order].tolist()
    assert a.counts == b.counts and a.counts["candidates"] == m
