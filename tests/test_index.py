"""``BodyIndex``: a reusable index asked about new bodies (core.bodies.index).

The reference is :func:`core.contacts` on the union of the indexed and the new bodies (its own
tests check it against brute force): the index must give exactly its pairs between an indexed
and a new body, with the same relations, certifiers and images (the image of the indexed body
here is minus the image of the new body there), in open space, in orthogonal and tilted
periodic boxes, one query at a time and in batches, and after moves, for matrices and for
core.Bodies. The float bounding spheres themselves are checked against exact arithmetic in
tests/test_sphere_proof.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from bench.bodies_data import random_bodies
from core import Bodies, BodyIndex, Certifier, Relation, bodies_from_axes, contacts
from core.fixed import compiled

TILTED_3D = (9.0, 8.0, 8.5, 0.4, -0.5, 0.3)
TILTED_2D = (9.0, 8.0, -0.45)


def cell(box, d):
    """Box vectors as columns (placing bodies; rounding is harmless there)."""
    if box is None or len(box) == d:
        return None
    if d == 2:
        Lx, Ly, xy = box
        return np.array([[Lx, xy * Ly], [0, Ly]])
    Lx, Ly, Lz, xy, xz, yz = box
    return np.array([[Lx, xy * Ly, xz * Lz], [0, Ly, yz * Lz], [0, 0, Lz]])


def bodies(n, d, box, seed, size=0.6):
    """n random bodies (semi-axes up to ``size``) in one cell of the box (or a cube)."""
    rng = np.random.default_rng(seed)
    side = 9.0
    if box is not None and len(box) == d:
        c = rng.uniform(0, 1, (n, d)) * np.array(box, dtype=float)
    elif box is not None:
        c = rng.uniform(-0.5, 0.5, (n, d)) @ cell(box, d).T
    else:
        c = rng.uniform(0, side, (n, d))
    semi = rng.uniform(0.3, 1.0, (n, d)) * size
    orient = rng.normal(size=(n, 4)) if d == 3 else rng.uniform(0, np.pi, n)
    return bodies_from_axes(c, semi, orient)


def expected(Q, Qnew, box, method="adaptive"):
    """The pairs (new row, indexed body) of contacts on the union, with relation, certifier, image."""
    N = len(Q)
    res = contacts(np.concatenate([Q, Qnew]), box=box, method=method)
    out = {}
    for k in range(len(res)):
        a, b = int(res.i[k]), int(res.j[k])
        if a < N <= b:
            image = None if res.image is None else tuple(-int(x) for x in res.image[k])
            out[(b - N, a)] = (int(res.relation[k]), int(res.certified_by[k]), image)
    return out


def as_dict(hits):
    out = {}
    for k in range(len(hits)):
        image = None if hits.image is None else tuple(int(x) for x in hits.image[k])
        out[(int(hits.i[k]), int(hits.j[k]))] = (int(hits.relation[k]), int(hits.certified_by[k]), image)
    return out


CASES = [(3, None), (2, None), (3, (9.0, 8.0, 8.5)), (2, (9.0, 8.0)), (3, TILTED_3D), (2, TILTED_2D)]


@pytest.mark.parametrize("d, box", CASES)
def test_queries_equal_contacts_on_the_union(d, box):
    Q = bodies(300 if d == 3 else 200, d, box, seed=1)
    Qnew = bodies(60, d, box, seed=2)
    index = BodyIndex(Q, box=box)
    want = expected(Q, Qnew, box)
    hits = index.query(Qnew)  # a batch
    assert as_dict(hits) == want
    assert np.all(np.diff(hits.i * len(Q) + hits.j) > 0)  # sorted by (i, j)
    one_by_one = {}
    for k in range(len(Qnew)):  # one at a time: the short path
        single = index.query(Qnew[k])
        assert np.all(single.i == 0)
        one_by_one.update({(k, j): v for (_, j), v in as_dict(single).items()})
    assert one_by_one == want
    assert len(want) > 20
    if box is not None:
        assert sum(1 for v in want.values() if any(v[2])) >= 3  # pairs across the faces
        shifts = hits.shifts()
        assert shifts is not None and shifts.shape == (len(hits), d)
    assert hits.counts["candidates"] >= len(hits) and hits.counts["queries"] == len(Qnew)


@pytest.mark.parametrize("d, box", [(3, None), (3, TILTED_3D), (2, (9.0, 8.0))])
def test_a_large_batch_of_trial_moves_in_any_order(d, box):
    """Thousands of trial moves of random rows (asked in grid order, split over threads, the
    outputs grown past their first size) answer like contacts on the union, sorted by (i, j)."""
    rng = np.random.default_rng(21)
    Q = bodies(1500, d, box, seed=11, size=0.5)
    index = BodyIndex(Q, box=box)
    rows = rng.integers(0, len(Q), 5000)  # > 2 ranges of 2048 new bodies: two threads
    big = bodies(5000, d, box, seed=12, size=1.6)  # many pairs each: more than the first outputs hold
    trial = np.where((np.arange(5000) % 2 == 0)[:, None, None], big, Q[rows])
    compiled.set_threads(2)
    try:
        hits = index.query(trial, exclude=rows)
    finally:
        compiled.set_threads(None)
    assert np.all(np.diff(hits.i * len(Q) + hits.j) > 0)
    want = {key: v for key, v in expected(Q, trial, box).items() if key[1] != rows[key[0]]}
    assert as_dict(hits) == want and len(want) > 8 * 5000
    assert not any((int(i), int(j)) for i, j in zip(hits.i, hits.j, strict=True) if j == rows[i])


@pytest.mark.parametrize("d, box", CASES)
def test_updates_move_bodies_without_rebuilding(d, box):
    rng = np.random.default_rng(5)
    Q = bodies(250, d, box, seed=3)
    index = BodyIndex(Q, box=box)
    table = index._table
    for step in range(4):
        rows = rng.choice(len(Q), size=40, replace=False)
        moved = bodies(40, d, box, seed=10 + step)
        index.update(rows, moved)
        Q = Q.copy()
        Q[rows] = moved
        assert np.array_equal(index.Q, Q)
    assert index._table is table or index._table.shape[1] > table.shape[1]  # grown only, never rebuilt
    Qnew = bodies(50, d, box, seed=4)
    assert as_dict(index.query(Qnew)) == expected(Q, Qnew, box) != {}
    fresh = BodyIndex(Q, box=box)
    assert as_dict(fresh.query(Qnew)) == as_dict(index.query(Qnew))


def test_monte_carlo_moves_exclude_the_body_itself():
    """A trial move of body k asks about the moved body against all but k; accepted moves update."""
    rng = np.random.default_rng(2)
    b = random_bodies(400, dim=3, fraction=0.2, seed=6)
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    box = (b.side,) * 3
    index = BodyIndex(Q, box=box)
    accepted = 0
    for _ in range(60):
        k = int(rng.integers(len(Q)))
        c = (b.centers[k] + rng.normal(scale=0.3, size=3)) % b.side
        trial = bodies_from_axes(c[None], b.semi_axes[k][None], b.orientations[k][None])
        hits = index.query(trial, exclude=k)
        assert k not in hits.j.tolist()
        others = np.delete(np.arange(len(Q)), k)
        want = expected(Q[others], trial, box)
        assert as_dict(hits) == {(0, int(others[j])): v for (_, j), v in want.items()}
        if not len(hits):
            index.update([k], trial)
            Q[k], b.centers[k] = trial[0], c
            accepted += 1
    assert accepted > 5
    assert as_dict(index.query(Q[:5])) == expected(Q, Q[:5], box)  # each finds itself: overlap
    assert all((i, i) in as_dict(index.query(Q[:5])) for i in range(5))


def test_touching_exactly_certified_like_contacts():
    Q = bodies_from_axes([[0, 0, 0], [3, 0, 0]], [[1, 1, 1]] * 2)
    index = BodyIndex(Q)
    hits = index.query(bodies_from_axes([[1.5, 0, 0]], [[0.5, 0.5, 0.5]]))
    assert hits.relation.tolist() == [Relation.TANGENT] * 2 and hits.certified_by.tolist() == [Certifier.EXACT] * 2
    far = index.query(bodies_from_axes([[1.5, 0, 2.0**-20]], [[0.5, 0.5, 0.5]]))  # its matrix is exact
    assert len(far) == 0 and far.counts["candidates"] == 2  # the spheres meet; the bodies do not
    assert index.query(bodies_from_axes([[50, 50, 50]], [[0.5, 0.5, 0.5]])).counts["candidates"] == 0  # off the grid
    assert index.query(bodies_from_axes([[1.5, 0, 0]], [[0.5, 0.5, 0.5]]), exclude=0).j.tolist() == [1]


def test_a_new_body_larger_than_every_indexed_one():
    """Its reach spans several cells: every body it touches is still found (batch and alone)."""
    Q = bodies(3000, 3, None, seed=8, size=0.25)
    rng = np.random.default_rng(3)
    big = bodies_from_axes(rng.uniform(1, 8, (8, 3)), rng.uniform(0.5, 3.0, (8, 3)), rng.normal(size=(8, 4)))
    index = BodyIndex(Q)
    want = expected(Q, big, None)
    assert as_dict(index.query(big)) == want and len(want) > 100
    for k in range(len(big)):
        assert as_dict(index.query(big[k])) == {(0, j): v for (i, j), v in want.items() if i == k}
    # spheres of radius 2 each touched by six of radius 1/4 at the ends of its axes (exact):
    # the small ones sit 2.25 away, up to 5 cells of 0.5: a reach one cell short misses some
    centres = rng.integers(8, 64, (12, 3)) / 8.0
    ring = np.concatenate([np.eye(3), -np.eye(3)]) * 2.25
    touching = bodies_from_axes((centres[:, None, :] + ring).reshape(-1, 3), np.full((72, 3), 0.25))
    spheres = bodies_from_axes(centres, np.full((12, 3), 2.0))
    index2 = BodyIndex(np.concatenate([bodies(500, 3, None, seed=9, size=0.25), touching]))
    for k in range(12):
        hits = index2.query(spheres[k])
        assert set(range(500 + 6 * k, 506 + 6 * k)) <= set(hits.j[hits.relation == Relation.TANGENT].tolist())
    index.update([0], big[:1])  # an indexed body grows: queries look further
    assert as_dict(index.query(Q[5:40])) == expected(index.Q, Q[5:40], None)
    assert as_dict(index.query(Q[7])) == {(0, j): v for (i, j), v in expected(index.Q, Q[7:8], None).items()}


def test_invalid_bodies_raise_or_are_marked():
    Q = bodies(20, 3, None, seed=1)
    bad = Q[:3].copy()
    bad[1] = np.diag([1.0, 1.0, -1.0, -1.0])
    with pytest.raises(ValueError, match=r"^new body 1 is not an ellipsoid"):
        BodyIndex(Q).query(bad)
    marked = BodyIndex(Q, on_invalid="mark").query(bad)
    assert list(marked.invalid) == [1] and 1 not in marked.i.tolist() and marked.any().tolist() == [True, False, True]
    with pytest.raises(ValueError, match=r"^body 5 is not an ellipsoid"):
        BodyIndex(np.concatenate([Q[:5], bad[1:2]]))
    index = BodyIndex(Q)
    before = index.Q.copy()
    with pytest.raises(ValueError, match=r"^body 7 is not an ellipsoid"):
        index.update([7], bad[1])
    assert np.array_equal(index.Q, before)  # unchanged on an error
    with pytest.raises(ValueError, match="rows must be distinct"):
        index.update([3, 3], Q[:2])
    with pytest.raises(ValueError, match=r"rows must be in \[0, 20\)"):
        index.update([20], Q[0])
    with pytest.raises(ValueError, match="new bodies are 3x3 matrices but the index holds 4x4"):
        index.query(bodies_from_axes([[0, 0]], [[1, 1]]))
    marking = BodyIndex(Q, on_invalid="mark")
    marking.update([7], bad[1])
    assert 7 in marking.invalid and 7 not in marking.query(Q).j.tolist()


def test_size_rule_in_a_box_names_the_body():
    Q = bodies(30, 3, TILTED_3D, seed=2)
    index = BodyIndex(Q, box=TILTED_3D)
    huge = bodies_from_axes([[0, 0, 0]], [[3.5, 3.5, 3.5]])  # 3.5 + 0.6 > 7.24 / 2 (the smallest height)
    with pytest.raises(ValueError, match=r"^new body 0 is too large for the periodic box"):
        index.query(huge)
    with pytest.raises(ValueError, match=r"^body 4 is too large for the periodic box"):
        index.update([4], huge)


def test_one_body_path_and_its_fallbacks_answer_like_contacts():
    """One new body takes the compiled spheres; bodies they do not certify (symmetric only up to
    rounding, ill-conditioned, signs flipped, far from size 1) take the general path: the same
    answers as contacts either way, and the short path's counts add up."""
    rng = np.random.default_rng(7)
    Q = bodies(400, 3, None, seed=4)
    index = BodyIndex(Q)
    c = rng.uniform(0, 9, (12, 3))
    semi = rng.uniform(0.6, 1.5, (12, 3))
    semi[:3, 0] *= 2e-6  # discs of axis ratio ~1e6 (their matrices still the shapes): no fast float sphere
    new = bodies_from_axes(c, semi, rng.normal(size=(12, 4)))
    new[3] *= -1.0  # the same body, signs flipped
    new[4, 0, 1] = np.nextafter(new[4, 0, 1], np.inf)  # symmetric only up to rounding
    statuses = compiled.spheres(new)[2].tolist() if compiled.spheres_available() else []
    want = expected(Q, new, None)
    got = {}
    for k in range(len(new)):
        single = index.query(new[k])
        got.update({(k, j): v for (_, j), v in as_dict(single).items()})
        counts = single.counts
        assert counts["queries"] == 1 and counts["candidates"] >= len(single) and counts["float"] + counts["exact"] == counts["candidates"]
    assert got == want and len(want) > 10 and len({k for k, _ in want if k < 5}) >= 3
    if statuses:  # the fallbacks were taken where the compiled proof abstains
        assert statuses[4] == compiled.SPHERE_OTHER and compiled.SPHERE_NONE in statuses[:3] and statuses[3] <= 1


@pytest.mark.parametrize("method", ["float", "exact"])
@pytest.mark.parametrize("box", [None, (9.0, 8.0, 8.5)])
def test_methods_like_contacts(method, box):
    """method="float" (UNDECIDED where the filter abstains) and "exact", one body at a time and in a
    batch: the answers and certifiers of contacts with that method, with touching pairs among them."""
    Q = bodies(120, 3, box, seed=6)
    Qnew = np.concatenate([bodies(12, 3, box, seed=7), Q[:3]])  # copies of indexed bodies: overlaps
    touching = bodies_from_axes([[2.0, 2.0, 2.0], [3.0, 2.0, 2.0]], [[0.5, 0.5, 0.5]] * 2)
    Q = np.concatenate([Q, touching[:1]])
    Qnew = np.concatenate([Qnew, touching[1:]])
    index = BodyIndex(Q, box=box, method=method)
    want = expected(Q, Qnew, box, method)
    assert as_dict(index.query(Qnew)) == want
    got = {}
    for k in range(len(Qnew)):
        single = index.query(Qnew[k])
        got.update({(k, j): v for (_, j), v in as_dict(single).items()})
        c = single.counts
        assert c["float"] + c["exact"] + c["undecided"] <= c["candidates"]
    assert got == want
    tangent = want[(len(Qnew) - 1, len(Q) - 1)]
    assert tangent == ((int(Relation.UNDECIDED), int(Certifier.NONE), tangent[2]) if method == "float" else (int(Relation.TANGENT), int(Certifier.EXACT), tangent[2]))


def test_new_bodies_from_parameters():
    """query and update take core.Bodies (a Monte Carlo code's trial: centre, semi-axes, orientation):
    the answers of their matrices; a row whose parameters are no shape is named, or marked."""
    b = random_bodies(300, dim=3, fraction=0.2, seed=9)
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    index = BodyIndex(Q)
    rng = np.random.default_rng(4)
    rows = rng.choice(300, size=20, replace=False)
    c = b.centers[rows] + rng.normal(scale=0.4, size=(20, 3))
    trial = Bodies(c, b.semi_axes[rows], b.orientations[rows])
    assert as_dict(index.query(trial, exclude=rows)) == as_dict(index.query(trial.matrices, exclude=rows))
    for k in range(3):
        one = Bodies(c[k : k + 1], b.semi_axes[rows[k : k + 1]], b.orientations[rows[k : k + 1]])
        assert as_dict(index.query(one, exclude=int(rows[k]))) == as_dict(index.query(one.matrices[0], exclude=int(rows[k])))
    bad = Bodies(c[:3], np.array([[1.0, 1.0, 1.0], [1.0, -1.0, 1.0], [0.5, 0.5, 0.5]]))
    with pytest.raises(ValueError, match=r"^new body 1: semi-axes must be positive"):
        index.query(bad)
    marked = BodyIndex(Q, on_invalid="mark").query(bad)
    assert list(marked.invalid) == [1] and "semi-axes must be positive" in marked.invalid[1] and 1 not in marked.i.tolist()
    index.update(rows[:2], Bodies(c[:2], b.semi_axes[rows[:2]], b.orientations[rows[:2]]))
    moved = Q.copy()
    moved[rows[:2]] = trial.matrices[:2]
    assert np.array_equal(index.Q, moved)
    with pytest.raises(ValueError, match=rf"^body {rows[1]}: semi-axes must be positive"):
        index.update(rows[:3], bad)


def test_empty_index_and_empty_queries():
    index = BodyIndex(np.zeros((0, 4, 4)))
    assert len(index.query(bodies(3, 3, None, seed=1))) == 0
    index = BodyIndex(bodies(10, 3, None, seed=1))
    assert len(index.query(np.zeros((0, 4, 4)))) == 0


@pytest.mark.parametrize("scale", [2.0**-700, 1e-160, 1e160, 2.0**700])
def test_an_index_at_any_float_scale_finds_the_contacts_without_warnings(scale):
    """Bodies past ~1e±154 (their squared distances overflow): the index answers what it answers at
    scale 1 (three unit spheres in a row, the middle one overlapping both ends; new bodies asked
    one at a time and together) and no RuntimeWarning reaches the user (was: 'overflow encountered
    in multiply' from the near test, whose inf keeps it conservative)."""
    import warnings

    c = np.array([[0.0, 0, 0], [1.5, 0, 0], [3.0, 0, 0], [9.0, 0, 0]])
    r = np.ones((4, 3))
    new_c, new_r = np.array([[4.5, 0, 0], [0.0, 3.0, 0]]), np.ones((2, 3))

    def answers(s):
        index = BodyIndex(bodies_from_axes(c * s, r * s))
        together = index.query(bodies_from_axes(new_c * s, new_r * s))
        one = index.query(bodies_from_axes(new_c[:1] * s, new_r[:1] * s))
        return (together.i.tolist(), together.j.tolist(), together.relation.tolist(),
                one.i.tolist(), one.j.tolist(), one.relation.tolist())

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = answers(scale)
    want = answers(1.0)
    assert want == ([0], [2], [int(Relation.OVERLAP)], [0], [2], [int(Relation.OVERLAP)])
    assert got == want


BAD_ROWS_3D = [  # (centre, semi-axes, quaternion, what the reason says)
    ([np.nan, 0, 0], [1, 1, 1], [1, 0, 0, 0], "finite"),
    ([0, 0, 0], [1, np.inf, 1], [1, 0, 0, 0], "finite"),
    ([0, 0, 0], [1, -1, 1], [1, 0, 0, 0], "positive"),
    ([0, 0, 0], [1, 0.0, 1], [1, 0, 0, 0], "positive"),
    ([1e9, 0, 0], [1, 1e-2, 1], [1, 0, 0, 0], "2^26"),
    ([0, 0, 0], [1, 1, 1], [0, 0, 0, 0], "zero"),
    ([0, 0, 0], [1, 1, 1], [1, np.nan, 0, 0], "finite"),
]


@pytest.mark.parametrize("bad", BAD_ROWS_3D)
def test_parameters_checked_once_and_every_bad_row_named(bad, monkeypatch):
    """A batch of trial moves' parameters is checked once (core.Bodies keeps the matrices and the
    reasons), and the whole-array shortcut of the check never lets a bad row through."""
    import core.bodies.build as build
    from core.shapes.quadrics import axes_row_errors, quadric_from_axes

    b = random_bodies(200, dim=3, fraction=0.2, seed=5)
    c, r, o = b.centers.copy(), b.semi_axes.copy(), b.orientations.copy()
    assert axes_row_errors(c, r, o) == {}
    c[77], r[77], o[77] = bad[0], bad[1], bad[2]
    calls = []
    monkeypatch.setattr(build, "axes_row_errors", lambda *a, **k: calls.append(1) or axes_row_errors(*a, **k))
    trial = Bodies(c, r, o)
    Q, errors = trial.matrices, trial.errors
    assert len(calls) == 1 and list(errors) == [77] and bad[3] in errors[77]
    assert np.isnan(Q[77]).all() and np.array_equal(Q[76], quadric_from_axes(c[76], r[76], o[76]))
    assert axes_row_errors(c, r, o) == errors


def test_tiny_quaternions_and_2d_rotations_pass_the_check():
    """Quaternions whose squares underflow are still rotations; a 2D quaternion must turn about z."""
    from core.shapes.quadrics import axes_row_errors

    c, r = np.zeros((3, 3)), np.ones((3, 3))
    assert axes_row_errors(c, r, np.array([[1e-170, 0, 0, 0], [0, 0, 0, 1e-200], [1, 0, 0, 0]])) == {}
    errors = axes_row_errors(np.zeros((2, 2)), np.ones((2, 2)), np.array([[1.0, 0, 0, 0], [1.0, 0, 0.5, 0]]))
    assert list(errors) == [1] and "about z" in errors[1]


def test_new_bodies_spheres_are_bounding_spheres():
    """The index's short way to new bodies' spheres gives bounding_spheres' spheres bit for bit,
    and names an invalid body by its row (the general stages answer for it)."""
    from core.bodies.bounds import bounding_spheres
    from core.bodies.index import _certified_spheres

    Q = bodies(300, 3, None, seed=8)
    Q[5] = np.diag([1.0, 1.0, 1.0, 1.0])  # empty interior: no shape
    Q[9, 0, 1] = np.nextafter(Q[9, 0, 1], 1.0)  # not exactly symmetric: the general stages
    c, rad, invalid = _certified_spheres(Q.copy())
    want = bounding_spheres(Q.copy())
    assert list(invalid) == [5] and invalid == want.invalid and invalid[5].startswith("body 5 ")
    assert np.array_equal(rad, want.radii, equal_nan=True) and np.array_equal(c[rad == rad], want.centers[rad == rad])


@pytest.mark.parametrize("d, box", CASES)
def test_accepted_moves_one_at_a_time(d, box):
    """update of one row (an accepted move: its centre placed in Python floats) leaves the index
    answering like a fresh one and like contacts on the union."""
    rng = np.random.default_rng(12)
    Q = bodies(200, d, box, seed=13)
    index = BodyIndex(Q, box=box)
    moved = bodies(30, d, box, seed=14)
    for k, row in enumerate(rng.choice(len(Q), size=30, replace=False).tolist()):
        index.update([row], moved[k])
        Q[row] = moved[k]
    Qnew = bodies(60, d, box, seed=15)
    assert as_dict(index.query(Qnew)) == as_dict(BodyIndex(Q, box=box).query(Qnew)) == expected(Q, Qnew, box) != {}
