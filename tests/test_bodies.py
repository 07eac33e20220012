"""Contacts among N bodies (core.bodies): builder, bounding spheres, broad phase, contacts.

References are independent of the code under test: all-pairs brute force with the certified
two-body ``classify`` (open space), exact rational translates of every lattice image
(periodic boxes), exact lattice cases (touching spheres: every neighbour tangent) and sampled
boundary points for the bounding spheres.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from flint import fmpq

from bench.bodies_data import random_bodies
from core import (
    Certifier,
    Contacts,
    Relation,
    bodies_from_axes,
    classify,
    contacts,
    quadric_from_axes,
)
from core.bodies.bounds import bounding_spheres
from core.bodies.broadphase import candidate_pairs
from core.shapes.quadrics import axes_row_errors, origin_moved, rotation_from_quaternion


def build(b):
    return bodies_from_axes(b.centers, b.semi_axes, b.orientations)


# ------------------------------------------------------------------------------ builder


@pytest.mark.parametrize("dim", [2, 3])
def test_builder_is_quadric_from_axes_bit_for_bit(dim):
    b = random_bodies(300, dim=dim, seed=3)
    b.centers *= 10.0 ** np.random.default_rng(1).integers(-3, 6, (300, 1))  # centres far and near
    Q = build(b)
    for k in range(300):
        one = quadric_from_axes(b.centers[k], b.semi_axes[k], b.orientations[k] if dim == 3 else float(b.orientations[k]))
        assert Q[k].tobytes() == one.tobytes()


def test_builder_axis_aligned_and_row_errors():
    Q = bodies_from_axes([[0, 0, 0], [1, 2, 3]], [[1, 2, 3], [1, 1, 1]])
    assert Q[1].tobytes() == quadric_from_axes([1, 2, 3], [1, 1, 1]).tobytes()
    with pytest.raises(ValueError, match=r"^row 2: centre and semi-axes must be finite"):
        bodies_from_axes([[0, 0], [1, 1], [np.nan, 0]], [[1, 1]] * 3)
    with pytest.raises(ValueError, match=r"^row 1: orientation quaternion is zero"):
        bodies_from_axes([[0, 0, 0], [1, 1, 1]], [[1, 1, 1]] * 2, [[1, 0, 0, 0], [0, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"must be \(N, 4\) quaternions"):
        bodies_from_axes([[0, 0, 0]], [[1, 1, 1]], [0.5])
    errs = axes_row_errors([[0, 0], [1, 1], [2, 2]], [[1, 1], [-1, 1], [1, 0]])
    assert errs == {1: "semi-axes must be positive, got [-1.0, 1.0]", 2: "semi-axes must be positive, got [1.0, 0.0]"}


def test_builder_mark_gives_nan_rows_that_contacts_reports():
    Q = bodies_from_axes([[0, 0], [1, 0], [5, 5]], [[0.5, 0.5], [-1, 1], [0.5, 0.5]], [0.0, 0.0, 0.0], on_invalid="mark")
    assert np.isnan(Q[1]).all() and not np.isnan(Q[[0, 2]]).any()
    res = contacts(Q, on_invalid="mark")
    assert list(res.invalid) == [1] and "body 1" in res.invalid[1] and len(res) == 0


@pytest.mark.parametrize("dim", [2, 3])
def test_builder_beyond_the_range_of_1_over_r2_keeps_the_shape(dim):
    """Was: semi-axes past ~1e±154 made 1/r^2 overflow or underflow, so a valid body became a matrix of
    inf/0 ("not a finite number", "not an ellipsoid"). Now such a body is built at its own power-of-2
    scale: the matrix is a positive multiple of the exact one, entry for entry within a few ulps
    (checked in rationals against quadric_from_axes(exact=True)), and the pairs classify as the
    geometry says; bodies the plain form holds keep their bits."""
    rng = np.random.default_rng(7)
    q = rng.normal(size=(4,)) if dim == 3 else [math.cos(0.35), 0.0, 0.0, math.sin(0.35)]  # 2D: a turn about z
    for scale in (2.0**-700, 1e-300, 1e-160, 1e160, 1e300, 2.0**700):
        c = rng.uniform(-3, 3, dim) * scale
        r = rng.uniform(0.5, 2, dim) * scale
        F = quadric_from_axes(c, r, q)
        assert np.isfinite(F).all() and (np.abs(np.diag(F)) >= np.finfo(float).tiny).all(), scale
        E = quadric_from_axes(c, r, q, exact=True)  # the exact matrix of the same floats
        # both in the coordinates y = x / scale, where every entry of the exact matrix is of order 1
        D = [fmpq(*float(scale).as_integer_ratio())] * dim + [fmpq(1)]
        G = [[E[i][j] * D[i] * D[j] for j in range(dim + 1)] for i in range(dim + 1)]
        Fq = [[fmpq(*float(F[i, j]).as_integer_ratio()) * D[i] * D[j] for j in range(dim + 1)] for i in range(dim + 1)]
        lam = Fq[0][0] / G[0][0]  # F = lam E up to rounding: entry errors within 2^-44 of the largest entry
        big = max(abs(G[i][j]) for i in range(dim + 1) for j in range(dim + 1))
        assert lam > 0 and all(abs(Fq[i][j] / lam - G[i][j]) <= big / 2**44 for i in range(dim + 1) for j in range(dim + 1)), scale
        gap = float(r[0]) * 2.0  # along axis 0 of an axis-aligned pair: apart by 3 r, by 1.5 r
        far = bodies_from_axes([np.zeros(dim), np.eye(dim)[0] * 1.5 * gap], [r, r])
        near = bodies_from_axes([np.zeros(dim), np.eye(dim)[0] * 0.75 * gap], [r, r])
        assert classify(far[0], far[1]) == Relation.SEPARATE and classify(near[0], near[1]) == Relation.OVERLAP, scale
        assert [len(contacts(far)), len(contacts(near))] == [0, 1]
    b = random_bodies(200, dim=dim, seed=5)
    assert build(b).tobytes() == _plain_build(b).tobytes()  # in range: the plain formula's bits
    import warnings

    with warnings.catch_warnings():  # semi-axes near the top of the range: no overflow warning reaches the user
        warnings.simplefilter("error")
        huge = bodies_from_axes([np.zeros(dim), np.eye(dim)[0] * 2.0**1001], [[2.0**1000] * dim] * 2)
    assert classify(huge[0], huge[1]) == Relation.TANGENT


def _exact_in_y(M, scale, dim):
    """The rational matrix of M in the coordinates y = x / scale (entries of order 1 for a shape of that scale)."""
    D = [fmpq(*float(scale).as_integer_ratio())] * dim + [fmpq(1)]
    get = (lambda i, j: M[i][j]) if isinstance(M, list) else (lambda i, j: fmpq(*float(M[i, j]).as_integer_ratio()))
    return [[get(i, j) * D[i] * D[j] for j in range(dim + 1)] for i in range(dim + 1)]


@pytest.mark.parametrize("scale", [2.0**-1000, 2.0**-990, 2.0**990, 2.0**1000])
def test_builder_small_body_far_from_the_origin_at_the_ends_of_the_range(scale):
    """Was: a body 10^4 times smaller than its distance from the origin, at coordinates near 2^±1000,
    came out of bodies_from_axes as a matrix of inf (even at its own scale 1/r^2 leaves the range),
    with no error until classify named an entry the user never typed. Its entries span ~2^1990, which
    a float64 matrix holds once multiplied by the right power of two: built so, it is a positive
    multiple of the exact matrix of the same floats (checked in rationals), and the pairs get the
    label of the exact shapes (exact arithmetic on quadric_from_axes(exact=True))."""
    rng = np.random.default_rng(11)
    n = 12
    big = rng.uniform(50, 100, (n, 3)) * scale
    small = rng.uniform(1e-3, 1e-2, (n, 3)) * scale
    cs = np.zeros((n, 3))
    cs[:, 0] = big[:, 0] + small[:, 0] * np.where(np.arange(n) % 2, 0.99, 1.01)  # in and out of the big body's end
    A = bodies_from_axes(np.zeros((n, 3)), big)
    B = bodies_from_axes(cs, small)
    assert np.isfinite(B).all()
    for k in range(n):
        E = quadric_from_axes(cs[k], small[k], exact=True)
        G, Fq = _exact_in_y(E, scale, 3), _exact_in_y(B[k], scale, 3)
        lam = Fq[0][0] / G[0][0]
        top = max(abs(v) for row in G for v in row)
        assert lam > 0 and all(abs(Fq[i][j] / lam - G[i][j]) <= top / 2**44 for i in range(4) for j in range(4)), k
        want = classify(quadric_from_axes(np.zeros(3), big[k], exact=True), E, method="exact")
        assert classify(A[k], B[k]) == want == (Relation.SEPARATE if k % 2 == 0 else Relation.OVERLAP), k


def test_builder_says_when_no_float_matrix_holds_the_shape():
    """A shape no float64 matrix holds (semi-axes 2^1000 at 2^1021 from the origin: its entries span
    2^2042 whatever power of two multiplies them) is refused with a message saying why and what to
    do, never returned as inf; a marked row is NaN; the exact builder still takes it. The one-shape
    builder refuses what the many-shape one refuses (here a centre past FAR_FROM_ORIGIN)."""
    c, r = [2.0**-10, 0.0, 0.0], [2.0**-1040] * 3  # 2^1030 radii from the origin, past 2^26: refused earlier
    with pytest.raises(ValueError, match="more than 2\\^26"):
        quadric_from_axes(c, r)
    c, r = [2.0**1021, 0.0, 0.0], [2.0**1000] * 3  # 2^21 radii away at the top of the range: entries span 2^2042
    with pytest.raises(ValueError, match="no float64 matrix holds this shape"):
        quadric_from_axes(c, r)
    with pytest.raises(ValueError, match="^row 1: .*no float64 matrix holds this shape"):
        bodies_from_axes([[0.0, 0, 0], c], [[1.0, 1, 1], r])
    Q = bodies_from_axes([[0.0, 0, 0], c], [[1.0, 1, 1], r], on_invalid="mark")
    assert np.isnan(Q[1]).all() and np.isfinite(Q[0]).all()
    assert quadric_from_axes(c, r, exact=True)[3][3] == fmpq(2**42 - 1)  # (2^21)^2 - 1


def _plain_build(b):
    from core.shapes.quadrics import _assemble_plain, rotations_from_orientations

    c, r = np.asarray(b.centers, float), np.asarray(b.semi_axes, float)
    return _assemble_plain(c, r, rotations_from_orientations(b.orientations, *c.shape))


# ------------------------------------------------------------------------------ bounding spheres


def test_bounding_spheres_contain_sampled_boundary_points():
    rng = np.random.default_rng(7)
    b = random_bodies(400, dim=3, ratio=8.0, seed=5)
    Q = build(b)
    s = bounding_spheres(Q)
    assert not s.invalid
    u = rng.normal(size=(64, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    for k in range(0, 400, 7):
        R = rotation_from_quaternion(b.orientations[k])
        pts = b.centers[k] + (u * b.semi_axes[k]) @ R.T
        dist = np.linalg.norm(pts - s.centers[k], axis=1)
        assert dist.max() <= s.radii[k]
        assert s.radii[k] <= b.semi_axes[k].max() * 1.001  # and tight (lambda shrunk by 2^-10)


@pytest.mark.parametrize("k", [-700, -300, 300, 700])
def test_bounding_spheres_at_any_float_scale_in_floats(k):
    """Was: bodies far from size 1 spread their entries over decades the float bound could not
    follow, so each sphere took exact arithmetic (100,000 bodies at 1e150: 37 s) or LAPACK's path
    (1e-150: 1.9 s). Now the same proof runs in the bodies' own units (space scaled by a power of
    two, exact): every sphere in floats, containing boundary points sampled from the parameters
    (scaled exactly by 2^k), and as tight as at scale 1."""
    rng = np.random.default_rng(7)
    b = random_bodies(200, dim=3, ratio=8.0, seed=5)
    f = 2.0**k
    Q = bodies_from_axes(np.asarray(b.centers) * f, np.asarray(b.semi_axes) * f, b.orientations)
    s = bounding_spheres(Q)
    assert not s.invalid and s.exact == 0
    u = rng.normal(size=(64, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    for j in range(0, 200, 7):
        R = rotation_from_quaternion(b.orientations[j])
        pts = (b.centers[j] + (u * b.semi_axes[j]) @ R.T) * f
        dist = np.linalg.norm((pts - s.centers[j]) / f, axis=1) * f  # without squares past the float range
        assert dist.max() <= s.radii[j]
        assert s.radii[j] <= b.semi_axes[j].max() * f * 1.001


def test_bounding_spheres_of_ill_conditioned_flipped_and_invalid_bodies():
    axes = np.array([[1e-4, 1, 1], [1e-2, 1e-2, 1], [1, 1, 1], [1e-6, 1, 1]])
    q = np.random.default_rng(0).normal(size=(4, 4))
    Q = bodies_from_axes(np.full((4, 3), 5.0), axes, q)
    Q[2] = -Q[2]  # a flipped sign is the same ellipsoid
    s = bounding_spheres(Q)
    assert not s.invalid and s.exact >= 1  # the thinnest need exact arithmetic
    # the float matrix of a 1e-6-thin body is not the ideal one (m = -Q c rounds at 1e12 * 5
    # and moves its centre by ~3e-4): only the first three are within 1e-9 of the ideal shape
    assert np.all(s.radii[:3] >= 1.0) and np.all(s.radii <= 1.5) and s.radii[3] >= 0.999
    assert np.allclose(s.centers, 5.0, atol=1e-3)
    bad = np.stack([np.diag([1.0, 1, 1, 1]), np.diag([1.0, -1, 1, -1]), np.full((4, 4), np.nan), Q[2]])
    bad[3, 0, 1] += 0.1  # asymmetric far beyond rounding
    s = bounding_spheres(bad)
    assert sorted(s.invalid) == [0, 1, 2, 3]
    assert s.invalid[0].startswith("body 0 has an empty interior")
    assert s.invalid[1].startswith("body 1 is not an ellipsoid")
    assert s.invalid[2].startswith("body 2 entry (0,0): not a finite number")
    assert s.invalid[3].startswith("body 3 is not symmetric")


# ------------------------------------------------------------------------------ broad phase


def _sphere_pairs(c, r, box=None):
    """All pairs whose spheres meet (closed), by brute force; (i, j, image)."""
    out = {}
    for i in range(len(c)):
        if not np.isfinite(r[i]):
            continue
        for j in range(i + 1, len(c)):
            if not np.isfinite(r[j]):
                continue
            d = c[j] - c[i]
            k = np.zeros(c.shape[1])
            if box is not None:
                k = -np.rint(d / box)
                d = d + k * box
            if np.sqrt(d @ d) <= r[i] + r[j]:
                out[(i, j)] = tuple(int(v) for v in k)
    return out


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("periodic", [False, True])
def test_broad_phase_finds_every_pair_whose_spheres_meet(dim, periodic):
    rng = np.random.default_rng(11 + dim + 2 * periodic)
    for trial in range(12):
        n = int(rng.integers(2, 250))
        r = rng.uniform(0.1, 1.0, n)
        if trial % 3 == 0:  # radii over two decades: several levels of the grid
            r *= 10 ** rng.uniform(0, 2, n)
        if periodic:
            box = rng.uniform(4, 12, dim)
            r = np.minimum(r, box.min() / 4.5)
            c = rng.uniform(0, 1, (n, dim)) * box
        else:
            box = None
            c = rng.uniform(-20, 20, (n, dim))
        if trial % 4 == 1:
            r[rng.integers(0, n, 2)] = np.nan  # invalid bodies are left out
        got = candidate_pairs(c, r, box=None if box is None else np.asarray(box))
        pairs = list(zip(got.i.tolist(), got.j.tolist(), strict=True))
        assert len(set(pairs)) == len(pairs) and all(i < j for i, j in pairs)
        want = _sphere_pairs(c, r, box)
        assert set(pairs) == set(want)
        if periodic:
            assert {p: tuple(k) for p, k in zip(pairs, got.image.tolist(), strict=True)} == want


def test_broad_phase_tiny_box_with_one_or_two_cells_per_axis():
    c = np.array([[0.1, 0.1], [1.9, 0.2], [1.0, 1.9], [0.5, 1.0]])
    r = np.full(4, 0.45)
    for box in ([2.0, 2.0], [2.0, 3.9]):
        got = candidate_pairs(c, r, box=np.array(box))
        want = _sphere_pairs(c, r, np.array(box))
        assert dict(zip(zip(got.i.tolist(), got.j.tolist(), strict=True), map(tuple, got.image.tolist()), strict=True)) == want


# ------------------------------------------------------------------------------ contacts: brute force


def _brute_open(Q):
    n = len(Q)
    i, j = np.triu_indices(n, 1)
    rel = classify(Q[i], Q[j])
    keep = rel != Relation.SEPARATE
    return set(zip(i[keep].tolist(), j[keep].tolist(), rel[keep].tolist(), strict=True))


def _as_set(res: Contacts):
    return set(zip(res.i.tolist(), res.j.tolist(), res.relation.tolist(), strict=True))


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed", [0, 1])
def test_contacts_equal_brute_force_open(dim, seed):
    b = random_bodies(260, dim=dim, fraction=0.35, ratio=3.0, seed=seed)
    Q = build(b)
    res = contacts(Q)
    assert _as_set(res) == _brute_open(Q)
    assert res.i.dtype == np.int64 and res.relation.dtype == np.int8
    assert np.all(res.i < res.j) and np.all(np.diff(res.i * len(Q) + res.j) > 0)  # sorted by (i, j)
    assert res.counts["candidates"] == res.counts["float"] + res.counts["exact"] >= len(res)
    assert len(res) > 50


@pytest.mark.parametrize("k", [-1000, -700, 700, 900])
def test_contacts_at_any_float_scale_equal_brute_force_as_fast_as_at_scale_1(k):
    """Bodies scaled by 2^k: the pairs of every-pair classification (no broad phase, no bounding
    spheres), every sphere in floats, and the broad phase as tight as at scale 1 (was: squares
    past the float range kept ~6x the candidates at 2^-900 .. 2^-1000 and 2^900)."""
    b = random_bodies(260, dim=3, fraction=0.35, ratio=3.0, seed=3)
    f = 2.0**k
    Q = bodies_from_axes(np.asarray(b.centers) * f, np.asarray(b.semi_axes) * f, b.orientations)
    res = contacts(Q)
    assert _as_set(res) == _brute_open(Q) and len(res) > 50
    assert res.counts["exact_bounds"] == 0
    assert res.counts["candidates"] == contacts(build(b)).counts["candidates"]


def test_contacts_polydisperse_and_flipped_signs_equal_brute_force():
    rng = np.random.default_rng(4)
    b = random_bodies(200, dim=3, seed=9)
    b.semi_axes *= 10 ** rng.uniform(-1, 0.7, (200, 1))  # radii over 1.7 decades: grid levels
    Q = build(b)
    Q[::3] *= -1.0  # a flipped matrix is the same body
    assert _as_set(contacts(Q)) == _brute_open(Q)


def _exact(M):
    return [[fmpq(*float(v).as_integer_ratio()) for v in row] for row in M]


def _brute_periodic(Q, box, reach):
    """Every pair against every image k in {-1,0,1}^d, exactly translated (rational matrices)."""
    n, d = len(Q), Q.shape[-1] - 1
    out = set()
    centres = np.array([-np.linalg.solve(M[:d, :d], M[:d, d]) for M in Q])
    exact = [_exact(M) for M in Q]
    for i in range(n):
        for j in range(i + 1, n):
            for k in itertools.product((-1, 0, 1), repeat=d):
                s = np.array(k) * box
                if np.linalg.norm(centres[j] + s - centres[i]) > 1.5 * (reach[i] + reach[j]):
                    continue  # far beyond the largest semi-axes: cannot meet
                moved = origin_moved(exact[j], [-fmpq(*float(v).as_integer_ratio()) for v in s])
                A = np.array(exact[i], dtype=object)
                rel = classify(A, np.array(moved, dtype=object))
                if rel != Relation.SEPARATE:
                    out.add((i, j, int(rel)))
    return out


@pytest.mark.parametrize("dim", [2, 3])
def test_contacts_equal_brute_force_periodic(dim):
    b = random_bodies(40 if dim == 3 else 60, dim=dim, fraction=0.4, seed=2)
    Q = build(b)
    box = np.full(dim, b.side)
    res = contacts(Q, box=box)
    want = _brute_periodic(Q, box, b.semi_axes.max(axis=1))
    assert _as_set(res) == want
    assert res.image is not None and (np.abs(res.image).sum(axis=1) > 0).sum() >= 3  # pairs across faces


# ------------------------------------------------------------------------------ exact lattices


def _lattice(n, dim):
    return np.array(list(itertools.product(range(n), repeat=dim)), dtype=float)


@pytest.mark.parametrize("dim", [2, 3])
def test_touching_spheres_on_a_lattice_every_neighbour_tangent(dim):
    n = 5 if dim == 3 else 8
    c = _lattice(n, dim)
    Q = bodies_from_axes(c, np.full_like(c, 0.5))  # radius 1/2, integer centres: exact floats
    res = contacts(Q)
    neighbours = {(a, b) for a in range(len(c)) for b in range(a + 1, len(c)) if np.abs(c[a] - c[b]).sum() == 1}
    assert set(zip(res.i.tolist(), res.j.tolist(), strict=True)) == neighbours
    assert np.all(res.relation == Relation.TANGENT) and np.all(res.certified_by == Certifier.EXACT)
    assert res.counts["tangent"] == len(neighbours) == dim * n ** (dim - 1) * (n - 1)


@pytest.mark.parametrize("dim", [2, 3])
def test_touching_spheres_in_a_periodic_box_touch_across_faces(dim):
    n = 4
    c = _lattice(n, dim)
    Q = bodies_from_axes(c, np.full_like(c, 0.5))
    res = contacts(Q, box=[float(n)] * dim)
    assert len(res) == dim * n**dim  # every site has 2 dim neighbours on the torus
    assert np.all(res.relation == Relation.TANGENT)
    across = np.abs(res.image).sum(axis=1) == 1
    assert across.sum() == dim * n ** (dim - 1)  # one layer of pairs across each face direction
    assert res.per_body().tolist() == [Relation.TANGENT] * n**dim


def test_touching_ellipsoids_on_a_lattice():
    c = _lattice(3, 3) * np.array([2.0, 1.0, 0.5])  # axes (1, 1/2, 1/4): touching along x, y, z
    Q = bodies_from_axes(c, np.tile([1.0, 0.5, 0.25], (len(c), 1)), np.tile([1.0, 0, 0, 0], (len(c), 1)))
    res = contacts(Q)
    assert len(res) == 3 * 9 * 2 and np.all(res.relation == Relation.TANGENT)
    res = contacts(Q, method="float")  # the filter never certifies a tangency
    assert np.all(res.relation == Relation.UNDECIDED) and res.counts["undecided"] == 54


# ------------------------------------------------------------------------------ options and errors


def test_methods_agree_and_exact_certifies_everything_exactly():
    Q = build(random_bodies(40, dim=2, fraction=0.4, seed=1))
    a, e = contacts(Q), contacts(Q, method="exact")
    assert _as_set(a) == _as_set(e) and np.all(e.certified_by == Certifier.EXACT)


def test_bad_bodies_name_the_row():
    Q = build(random_bodies(10, dim=3, seed=1))
    Q[6, 1, 1] = np.nan
    with pytest.raises(ValueError, match=r"^body 6 entry \(1,1\): not a finite number"):
        contacts(Q)
    Q[6] = np.diag([1.0, 1.0, -1.0, -1.0])
    with pytest.raises(ValueError, match=r"^body 6 is not an ellipsoid"):
        contacts(Q)
    res = contacts(Q, on_invalid="mark")
    assert list(res.invalid) == [6] and res.per_body()[6] == Relation.INVALID
    assert 6 not in res.i and 6 not in res.j
    with pytest.raises(ValueError, match=r"Q must be an \(N, 3, 3\) stack"):
        contacts(np.zeros((3, 4)))
    with pytest.raises(ValueError, match="unknown method 'fast'"):
        contacts(Q, method="fast")


def test_periodic_errors_name_the_body():
    c = np.array([[0.5, 0.5], [2.0, 2.0], [3.5, 1.0]])
    Q = bodies_from_axes(c, [[0.3, 0.3], [1.8, 0.3], [0.3, 0.3]], [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"^body 1 is too large for the periodic box"):
        contacts(Q, box=(4, 4))
    with pytest.raises(ValueError, match=r"^body 2: centre x = 3.5 is more than one box side \(Lx = 2.9\)"):
        contacts(Q, box=(2.9, 10))
    with pytest.raises(ValueError, match=r"box: expected 2 positive finite sides"):
        contacts(Q, box=(4, 4, 4, 4))  # (4, 4, 4) is a tilted 2D box (Lx, Ly, xy)


def test_empty_and_single_body():
    assert len(contacts(np.zeros((0, 4, 4)))) == 0
    one = contacts(bodies_from_axes([[0, 0, 0]], [[1, 1, 1]]), box=(10, 10, 10))
    assert len(one) == 0 and one.counts["candidates"] == 0
    assert one.summary() == "1 bodies, 0 candidate pairs, 0 contacts (0 tangent, 0 overlap)"


def test_summary_and_rows():
    Q = bodies_from_axes([[0, 0], [1, 0], [1.5, 0]], [[0.5, 0.5]] * 3)
    res = contacts(Q)
    assert res.to_rows() == [(0, 1, "tangent"), (1, 2, "overlap")]
    assert res.certified_counts() == {"float": 1, "exact": 1}
    assert res.summary() == (
        "3 bodies, 2 candidate pairs, 2 contacts (1 tangent, 1 overlap); "
        "certified by the float filter 1, by exact arithmetic 1"
    )
    assert math.isfinite(res.seconds["total"])


# ------------------------------------------------------------------------------ the shifted filter


@pytest.mark.parametrize("dim", [2, 3])
def test_filter_on_translated_pairs_never_contradicts_exact(dim):
    """classify_translated(A, B, s) against the exact relation of A and the exact translate of B
    by s, on pairs that are near tangency once B is moved (gaps 1e-3 .. 1e-15, both sides)."""
    from bench.datasets import near_tangent_pairs
    from core.fixed.exact import classify_exact
    from core.fixed.filters import classify_translated
    from core.formulae.decision import RULE_RELATION
    from core.shapes.quadrics import symmetric_part

    rng = np.random.default_rng(dim)
    decided = 0
    for gap in (1e-3, 1e-9, 1e-15):
        for sign in (1, -1):
            ds = near_tangent_pairs(dim, 12, gap=gap, sign=sign, seed=int(gap * 1e3) + sign + dim)
            s = rng.choice([-1.0, 1.0], size=(len(ds.A), dim)) * rng.uniform(1, 40, (len(ds.A), dim))
            s = np.ldexp(np.round(np.ldexp(s, 8)), -8)  # lattice vectors with short mantissas, like k * L
            # B placed one lattice vector away, so that B moved by s is the near-tangent partner
            B = np.array([origin_moved(M.tolist(), v.tolist()) for M, v in zip(ds.B, s, strict=True)])
            rules = classify_translated(ds.A, B, s)
            for k in range(len(ds.A)):
                moved = origin_moved(symmetric_part(_exact(B[k])), [-fmpq(*float(v).as_integer_ratio()) for v in s[k]])
                truth = classify_exact(_exact(ds.A[k]), moved).relation
                if rules[k] >= 0:
                    decided += 1
                    assert RULE_RELATION[rules[k]] == truth, (gap, sign, k)
    assert decided >= 30  # the filter decides most of them (the rest go to exact arithmetic)
