"""Tilted (triclinic) periodic boxes: ``contacts(Q, box=(Lx, Ly, Lz, xy, xz, yz))``.

References are independent of the code under test: lattice vectors and cell heights from exact
rationals (``fractions.Fraction``), every pair against all 3^d images translated exactly
(``fmpq_mat``: G^T M G) and classified by the oracle of ``tests/oracle.py`` (positive roots of
the exact P(T), not the paper's formulae), exact tangencies built by hand in dyadic boxes, and
one lattice written two ways (an orthogonal box and a strongly tilted box of the same lattice).
"""

from __future__ import annotations

import itertools
import math
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from flint import fmpq, fmpq_mat

from core import Certifier, Relation, bodies_from_axes, contacts
from core.bodies.details import pair_details
from core.bodies.periodic import cell_heights, lattice_shifts, read_box

sys.path.insert(0, str(Path(__file__).parent))
from oracle import oracle_relation  # noqa: E402

RELATIONS = {"separate": Relation.SEPARATE, "tangent": Relation.TANGENT, "overlap": Relation.OVERLAP}


# ----------------------------------------------------------------------------- independent helpers


def exact_vector(box, k):
    """k1 a1 + k2 a2 (+ k3 a3) exactly, from HOOMD's six numbers (2D: Lx, Ly, xy)."""
    if len(k) == 2:
        Lx, Ly, xy = (Fraction(float(v)) for v in box)
        return [k[0] * Lx + k[1] * xy * Ly, k[1] * Ly]
    Lx, Ly, Lz, xy, xz, yz = (Fraction(float(v)) for v in box)
    return [k[0] * Lx + k[1] * xy * Ly + k[2] * xz * Lz, k[1] * Ly + k[2] * yz * Lz, k[2] * Lz]


def nearest_float(q: Fraction) -> float:
    """Round to nearest, ties to even, by hand (the two floats around q, then the nearer)."""
    below = float(q.numerator // q.denominator) if abs(q) > 2**60 else q.numerator / q.denominator
    while Fraction(below) > q:
        below = math.nextafter(below, -math.inf)
    while Fraction(math.nextafter(below, math.inf)) <= q:
        below = math.nextafter(below, math.inf)
    if Fraction(below) == q:
        return below
    above = math.nextafter(below, math.inf)
    dl, da = q - Fraction(below), Fraction(above) - q
    if dl != da:
        return below if dl < da else above
    return below if int(below.hex().split("p")[0][-1], 16) % 2 == 0 else above


def basis(box, d):
    """Float box vectors as columns (for placing bodies; rounding is harmless there)."""
    if d == 2:
        Lx, Ly, xy = box
        return np.array([[Lx, xy * Ly], [0, Ly]], dtype=float)
    Lx, Ly, Lz, xy, xz, yz = box
    return np.array([[Lx, xy * Ly, xz * Lz], [0, Ly, yz * Lz], [0, 0, Lz]], dtype=float)


def exact(M):
    return [[fmpq(*float(v).as_integer_ratio()) for v in row] for row in M]


def moved(M, s):
    """The body of matrix M moved by the rational vector s: G^T M G, G = [[I, -s], [0, 1]]."""
    n = len(M)
    G = [[fmpq(int(i == j)) for j in range(n)] for i in range(n)]
    for a in range(n - 1):
        G[a][n - 1] = -fmpq(s[a].numerator, s[a].denominator)
    G = fmpq_mat(G)
    out = G.transpose() * fmpq_mat(exact(M)) * G
    return [[out[i, j] for j in range(n)] for i in range(n)]


def brute_force(Q, box):
    """{(i, j): (image, relation)} over every pair and all 3^d images, exactly (the oracle)."""
    n, d = len(Q), Q.shape[-1] - 1
    out = {}
    for i in range(n):
        A = exact(Q[i])
        for j in range(i + 1, n):
            for k in itertools.product((-1, 0, 1), repeat=d):
                v = [Fraction(nearest_float(x)) for x in exact_vector(box, k)]  # the documented v(k)
                rel = RELATIONS[oracle_relation(A, moved(Q[j], v))]
                if rel != Relation.SEPARATE:
                    assert (i, j) not in out, "two images of one body touch: the size rule is broken"
                    out[(i, j)] = (k, int(rel))
    return out


def as_dict(res):
    return {(int(i), int(j)): (tuple(int(x) for x in k), int(r)) for i, j, k, r in zip(res.i, res.j, res.image, res.relation, strict=True)}


def bodies_near_images(box, d, n, seed, scale):
    """n bodies in one cell (fractional coordinates in [-1/2, 1/2)), half of them placed just at
    contact distance from an image of another body (across faces, edges and corners)."""
    rng = np.random.default_rng(seed)
    H = basis(box, d)
    f = rng.uniform(-0.5, 0.5, (n, d))
    semi = rng.uniform(0.6, 1.0, (n, d)) * scale
    for m in range(1, n, 2):  # bodies m - 1 and m at opposite faces, edges or corners k: m's image k meets m - 1
        k = rng.integers(-1, 2, d) if m % 4 == 1 else rng.choice([-1, 1], d)  # every other one a corner
        if not k.any():
            continue
        t = (semi[m - 1].mean() + semi[m].mean()) * rng.uniform(0.5, 0.95) / np.linalg.norm(H @ k)
        f[m - 1] = np.where(k != 0, (0.5 - 0.5 * t) * k, f[m - 1])
        f[m] = f[m - 1] + (t - 1) * k + rng.uniform(-0.2, 0.2, d) * t
    centers = f @ H.T
    orient = rng.normal(size=(n, 4)) if d == 3 else rng.uniform(0, np.pi, n)
    return bodies_from_axes(centers, semi, orient)


# ----------------------------------------------------------------------------- the lattice


@pytest.mark.parametrize("seed", range(4))
def test_lattice_vectors_are_the_nearest_floats_of_the_exact_ones(seed):
    rng = np.random.default_rng(seed)
    box = (*rng.uniform(1, 20, 3), *rng.uniform(-2.5, 2.5, 3))
    L = read_box(box, 3)
    k = rng.integers(-3, 4, (60, 3))
    got = lattice_shifts(L, k)
    want = np.array([[nearest_float(x) for x in exact_vector(box, row)] for row in k.tolist()])
    assert got.tobytes() == want.tobytes()
    unit = np.array(list(itertools.product((-1, 0, 1), repeat=3)))
    assert lattice_shifts(L, unit).tobytes() == np.array([[nearest_float(x) for x in exact_vector(box, r)] for r in unit.tolist()]).tobytes()
    box2 = (box[0], box[1], box[3])
    k2 = rng.integers(-3, 4, (30, 2))
    want2 = np.array([[nearest_float(x) for x in exact_vector(box2, r)] for r in k2.tolist()])
    assert lattice_shifts(read_box(box2, 2), k2).tobytes() == want2.tobytes()


def test_lattice_vectors_round_where_the_sum_is_not_a_float():
    box = (10.0, 10.0, 10.0, 0.3, 0.0, 0.0)  # 0.3 * 10 = 3.0000000000000000166... exactly
    v = lattice_shifts(read_box(box, 3), np.array([[1, 1, 0]]))[0]
    assert Fraction(v[0]) != exact_vector(box, (1, 1, 0))[0]  # 13.00000000000000001665 is no float
    assert v[0] == 13.0 and v[1] == 10.0


def test_orthogonal_boxes_keep_k_times_L():
    L = read_box((3.7, 2.1, 9.3), 3)
    k = np.array(list(itertools.product((-1, 0, 1), repeat=3)))
    assert lattice_shifts(L, k).tobytes() == (k * np.array([3.7, 2.1, 9.3])).tobytes()
    assert read_box((3.7, 2.1, 9.3, 0, 0, 0), 3).tolist() == [3.7, 2.1, 9.3]  # no tilt: orthogonal


@pytest.mark.parametrize("box", [(6.0, 5.0, 5.5, 0.37, -0.61, 0.45), (7.0, 6.5, 8.0, 1.7, -2.3, 0.9), (5.0, 5.0, 5.0, 0.5, 0.5, 0.5)])
def test_cell_heights_are_lower_bounds_of_the_exact_heights(box):
    """h_a^2 = V^2 / |a_b x a_c|^2 exactly (the distance between the faces spanned by a_b, a_c)."""
    a = [[Fraction(float(x)) for x in col] for col in zip(*[exact_vector(box, k) for k in ((1, 0, 0), (0, 1, 0), (0, 0, 1))], strict=True)]
    cols = [[a[r][c] for r in range(3)] for c in range(3)]

    def cross(u, w):
        return [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]

    V = Fraction(box[0]) * Fraction(box[1]) * Fraction(box[2])
    got = cell_heights(read_box(box, 3), 3)
    for axis in range(3):
        b, c = [x for x in range(3) if x != axis]
        n2 = sum(x * x for x in cross(cols[b], cols[c]))
        h2 = V * V / n2
        assert Fraction(float(got[axis])) ** 2 <= h2 <= (Fraction(float(got[axis])) * (1 + Fraction(1, 10**9))) ** 2


# ----------------------------------------------------------------------------- brute force


BOXES_3D = [
    (6.0, 5.0, 5.5, 0.37, -0.61, 0.45),
    (5.0, 5.0, 5.0, 0.5, 0.5, 0.5),  # HOOMD's usual limit of the tilt factors
    (5.0, 6.0, 7.0, -0.5, 0.5, -0.5),
    (7.0, 6.5, 8.0, 1.7, -2.3, 0.9),  # far beyond it: thin, strongly sheared cells
]


@pytest.mark.parametrize("box", BOXES_3D)
def test_tilted_contacts_equal_brute_force_over_all_27_images(box):
    L = read_box(box, 3)
    h = float(np.min(cell_heights(L, 3)))
    Q = bodies_near_images(box, 3, 18, seed=int(box[0] * 10), scale=0.2 * h)
    res = contacts(Q, box=box)
    want = brute_force(Q, box)
    assert as_dict(res) == want
    across = [k for k, _ in want.values() if any(k)]
    assert len(across) >= 4 and any(sum(map(abs, k)) >= 2 for k in across)  # faces and edges/corners
    shifts = res.shifts()
    assert shifts is not None and shifts.tobytes() == lattice_shifts(L, res.image).tobytes()
    assert res.box is not None and res.box.tolist() == list(box)


@pytest.mark.parametrize("box", [(6.0, 5.0, 0.43), (5.0, 7.0, -1.6)])
def test_tilted_contacts_2d_equal_brute_force_over_all_9_images(box):
    L = read_box(box, 2)
    h = float(np.min(cell_heights(L, 2)))
    Q = bodies_near_images(box, 2, 24, seed=5, scale=0.2 * h)
    res = contacts(Q, box=box)
    assert as_dict(res) == brute_force(Q, box)
    assert (np.abs(res.image).sum(axis=1) > 0).sum() >= 3
    hoomd = contacts(Q, box=(box[0], box[1], 0.0, box[2], 0.0, 0.0))  # a 2D HOOMD frame's six numbers
    assert as_dict(hoomd) == as_dict(res)


@pytest.mark.parametrize(
    "k",
    [(1, 0, 0), (0, -1, 0), (0, 0, 1), (1, 1, 0), (-1, 0, 1), (0, 1, -1), (1, 1, 1), (-1, 1, -1), (1, -1, -1)],
)
def test_exact_tangency_across_tilted_faces_edges_and_corners(k):
    """Two spheres of radius 1/2 touch exactly, body 1's image k against body 0 (dyadic box: the
    lattice vectors are exact); found, certified tangent by exact arithmetic, with that image."""
    box = (8.0, 8.0, 8.0, 0.5, -0.25, 0.375)
    L = read_box(box, 3)
    v = lattice_shifts(L, np.array([k]))[0]
    assert [Fraction(x) for x in v] == exact_vector(box, k)  # exact here
    H = basis(box, 3)
    c0 = H @ (0.375 * np.array(k, dtype=float))  # near the face / edge / corner of k
    for u in np.vstack([np.eye(3), -np.eye(3)]):  # a unit contact direction keeping both in one cell
        c1 = c0 + u - v  # |c0 - (c1 + v)| = 1 exactly
        if np.all(np.abs(np.linalg.solve(H, c1) - np.linalg.solve(H, c0)) <= 1):
            break
    else:
        raise AssertionError("no direction keeps the two centres in one cell")
    Q = bodies_from_axes([c0, c1], [[0.5, 0.5, 0.5]] * 2)
    res = contacts(Q, box=box)
    assert as_dict(res) == {(0, 1): (k, int(Relation.TANGENT))}
    assert res.certified_by.tolist() == [Certifier.EXACT]
    d = pair_details(Q, res)  # the contact scale of the exact translate: mu* = 1
    assert d.scale_lo[0] <= 1.0 <= d.scale_hi[0] and d.contained_names() == ["no"]
    apart = bodies_from_axes([c0, c1 + u * 2.0**-40], [[0.5, 0.5, 0.5]] * 2)
    assert len(contacts(apart, box=box)) == 0  # 2^-40 further: separate
    closer = contacts(bodies_from_axes([c0, c1 - u * 2.0**-40], [[0.5, 0.5, 0.5]] * 2), box=box)
    assert as_dict(closer) == {(0, 1): (k, int(Relation.OVERLAP))}  # 2^-40 closer: overlap


def test_one_lattice_written_orthogonal_and_tilted_gives_the_same_contacts():
    """(8, 8, 8) and (8, 8, 8, 1, 1, 1) (a2 = (8, 8, 0) = a1 + e2 L, a3 = (8, 8, 8)) are one lattice:
    the same bodies (wrapped into each cell, exactly) touch the same images (the same vectors)."""
    rng = np.random.default_rng(11)
    n = 60
    c = np.round(rng.uniform(0, 8, (n, 3)) * 1024) / 1024  # dyadic: wrapping by lattice vectors is exact
    radius = np.round(rng.uniform(0.5, 1.35, n) * 64) / 64  # spheres: matrices exact, r1 + r2 < 8 / sqrt(2) / 2
    tilted = (8.0, 8.0, 8.0, 1.0, 1.0, 1.0)
    H = basis(tilted, 3)
    w = np.floor(np.linalg.solve(H, c.T).T)
    c2 = c - w @ H.T  # the same points, moved by lattice vectors into the tilted cell
    assert np.all(np.linalg.solve(H, c2.T).T >= 0) and np.all(np.linalg.solve(H, c2.T).T < 1)
    a = contacts(bodies_from_axes(c, np.repeat(radius[:, None], 3, axis=1)), box=(8.0, 8.0, 8.0))
    b = contacts(bodies_from_axes(c2, np.repeat(radius[:, None], 3, axis=1)), box=tilted)
    assert np.array_equal(a.i, b.i) and np.array_equal(a.j, b.j) and np.array_equal(a.relation, b.relation)
    sa, sb = a.shifts(), b.shifts()
    assert sa is not None and sb is not None
    # displacement from body i to the image of j: c_j + v - c_i, the same vector in both boxes
    assert np.array_equal(c[a.j] + sa - c[a.i], c2[b.j] + sb - c2[b.i])
    assert len(a) > 40 and (a.image != b.image).any(axis=1).sum() > 5  # other images, the same vectors


def test_zero_tilt_is_the_orthogonal_box():
    Q = bodies_near_images((6.0, 5.0, 5.5, 0.0, 0.0, 0.0), 3, 40, seed=3, scale=1.0)
    a = contacts(Q, box=(6.0, 5.0, 5.5))
    b = contacts(Q, box=(6.0, 5.0, 5.5, 0.0, 0.0, 0.0))
    assert as_dict(a) == as_dict(b) and a.box.tolist() == b.box.tolist() == [6.0, 5.0, 5.5]


def test_dask_partitions_in_a_tilted_box_give_the_same_result():
    pytest.importorskip("dask")
    box = (12.0, 11.0, 13.0, 0.45, -0.3, 0.5)
    rng = np.random.default_rng(4)
    Q = bodies_from_axes(rng.uniform(-0.5, 0.5, (800, 3)) @ basis(box, 3).T, rng.uniform(0.4, 0.9, (800, 3)), rng.normal(size=(800, 4)))
    local = contacts(Q, box=box)
    spread = contacts(Q, box=box, scheduler="threads", partitions=5)
    assert as_dict(local) == as_dict(spread) and (np.abs(local.image).sum(axis=1) > 0).sum() > 20


# ----------------------------------------------------------------------------- errors


def test_errors_name_the_body_and_the_rule():
    box = (10.0, 10.0, 10.0, 1.0, 0.0, 0.0)  # h_x = 10 / sqrt(2)
    Q = bodies_from_axes([[0, 0, 0], [3, 3, 3]], [[1.8, 1, 1], [1.8, 1, 1]], [[1, 0, 0, 0]] * 2)
    with pytest.raises(ValueError, match=r"^body [01] is too large for the periodic box: .* half the smallest height of the cell \(7\.07107 / 2"):
        contacts(Q, box=box)
    assert len(contacts(Q, box=(10.0, 10.0, 10.0))) == 0  # orthogonal: 3.6 < 5, fine
    Q = bodies_from_axes([[0, 0, 0], [0, 9.5, 0], [5, 0, 0]], [[0.5] * 3] * 3)
    assert as_dict(contacts(Q, box=(10.0, 10.0, 10.0))) == {(0, 1): ((0, -1, 0), 2)}  # one orthogonal box: fine
    with pytest.raises(ValueError, match=r"^body 2: its centre is more than one box length from body 1's along the box vector a1"):
        contacts(Q, box=box)  # fractional x: (0, 9.5, 0) is at -0.95, (5, 0, 0) at 0.5
    with pytest.raises(ValueError, match="a 2D box has no tilt factors xz, yz"):
        contacts(bodies_from_axes([[0, 0]], [[1, 1]]), box=(10, 10, 0, 0.5, 0.5, 0))
    with pytest.raises(ValueError, match="box: expected 3 positive finite sides"):
        contacts(Q, box=(10, 10, -1, 0.5, 0, 0))
    with pytest.raises(ValueError, match="box: expected 3 positive finite sides"):
        contacts(Q, box=(10, 10, 10, 0.5))


# ----------------------------------------------------------------------------- the API and the scene


def test_api_takes_a_tilted_box():
    from fastapi.testclient import TestClient

    from app.api import create_api

    box = (6.0, 5.0, 5.5, 0.37, -0.61, 0.45)
    rng = np.random.default_rng(8)
    c = rng.uniform(-0.5, 0.5, (200, 3)) @ basis(box, 3).T
    semi = rng.uniform(0.2, 0.45, (200, 3))
    quat = rng.normal(size=(200, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    want = contacts(bodies_from_axes(c, semi, quat), box=box)
    with TestClient(create_api()) as client:
        r = client.post("/api/contacts", json={"bodies": np.concatenate([c, semi, quat], axis=1).tolist(), "box": list(box)})
        assert r.status_code == 200, r.text
        got = r.json()["pairs"]
        assert [(p["i"], p["j"], p["image"]) for p in got] == [(int(i), int(j), k.tolist()) for i, j, k in zip(want.i, want.j, want.image, strict=True)]
        assert (np.abs(want.image).sum(axis=1) > 0).sum() > 5
        r = client.post("/api/contacts", json={"bodies": [[0, 0, 0.5, 0.5, 0], [0.5, 4.5, 0.5, 0.5, 0]], "box": [5, 5, 0.1]})
        assert r.status_code == 200 and [(p["i"], p["j"], p["image"]) for p in r.json()["pairs"]] == [(0, 1, [0, -1])]


def test_scene_model_in_a_tilted_box_shows_the_image_at_its_lattice_vector():
    from app.readers.bodyset import from_parameters
    from app.scene.bodies.model import BodiesModel

    box = (8.0, 8.0, 8.0, 0.5, -0.25, 0.375)
    v = lattice_shifts(read_box(box, 3), np.array([[1, 1, 1]]))[0]
    c0 = np.array([3.0, 3.5, 3.0])
    c1 = c0 + np.array([1.0, 0.0, 0.0]) - v
    bodies = from_parameters(np.array([c0, c1]), np.full((2, 3), 0.5), np.tile([1.0, 0, 0, 0], (2, 1)), "two")
    m = BodiesModel(bodies, box)
    assert m.result.image.tolist() == [[1, 1, 1]]
    cfg, note = m.pair_config(0)
    assert [float(x) for x in cfg.to_dict()["B"]["center"]] == (c1 + v).tolist() and "tilted" in m.summary()


def test_scene_draws_the_tilted_cell_and_takes_a_typed_tilted_box(tmp_path):
    viser = pytest.importorskip("viser")
    from app.readers.bodyset import from_parameters
    from app.scene.bodies.bodies_view import BodiesView
    from app.scene.bodies.model import BodiesModel, parse_box

    box = (8.0, 8.0, 8.0, 0.5, -0.25, 0.375)
    c = np.array([[0.0, 0.0, 0.0], [2.0, 1.0, 0.5]])
    model = BodiesModel(from_parameters(c, np.full((2, 3), 0.5), np.tile([1.0, 0, 0, 0], (2, 1)), "two"), box)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        drawn = {}
        original = server.scene.add_line_segments

        def spy(name, points, *args, **kwargs):
            drawn[name] = np.asarray(points)
            return original(name, points, *args, **kwargs)

        server.scene.add_line_segments = spy  # type: ignore[method-assign]
        BodiesView(server, model)
        edges = drawn["/bodies/box"]  # the 12 edges of the parallelepiped a1, a2, a3
        assert edges.shape == (12, 2, 3)
        ends = np.unique(edges.reshape(-1, 3).astype(np.float64).round(4), axis=0)
        H = basis(box, 3)
        corners = np.array([H @ np.array(k, dtype=float) for k in itertools.product((0, 1), repeat=3)])
        got = {tuple(x) for x in (ends - ends.mean(axis=0)).round(4)}  # both about their centroids
        assert len(ends) == 8 and got == {tuple(x) for x in (corners - corners.mean(axis=0)).round(4)}
    finally:
        server.stop()
    from core import Box

    assert parse_box("8, 8, 8, 0.5, -0.25, 0.375", 3) == box and parse_box("5 5 0.5", 2) == Box(5.0, 5.0, xy=0.5)
    with pytest.raises(ValueError, match=r"^periodic box: expected 3 positive finite sides"):
        parse_box("8, 8, 8, 1", 3)


@pytest.mark.parametrize("box", [(8.0, 8.0, 8.0, 0.5, -0.25, 0.375), (8.0, 8.0, 0.75), (8.0, 8.0, 8.0, 1.5, -1.25, 0.875)])
def test_moving_bodies_in_a_tilted_box_equal_their_explicit_images(box):
    """Was: sweep_contacts refused tilted boxes. Now each pair's image k is chosen at the midpoints
    and j's whole path moves by v(k); the reference places all 3^d images of every body explicitly
    in open space (dyadic box and centres, so that c + v(k) is exact) and sweeps them there: the
    same pairs, images and first contact brackets. Bodies sit near the faces, edges and corners."""
    from core import sweep_contacts

    d = 2 if len(box) == 3 else 3
    L = read_box(box, d)
    H = basis(box, d)
    rng = np.random.default_rng(int(sum(box) * 8))
    n = 40
    h = float(np.min(cell_heights(L, d)))  # sizes within the one-image rule: swept radii below h / 4
    r = rng.uniform(0.06, 0.15, (n, d)) * h
    f = rng.uniform(-0.45, 0.45, (n, d))  # the midpoints' fractional coordinates
    for m in range(1, n // 2, 2):  # m's image k passes near m - 1 (across a face, edge or corner k)
        k = rng.integers(-1, 2, d) if m % 4 == 1 else rng.choice([-1, 1], d)
        if k.any():
            t = (r[m - 1].mean() + r[m].mean()) * rng.uniform(0.8, 1.2) / np.linalg.norm(H @ k)
            f[m - 1] = np.where(k != 0, (0.5 - 0.5 * t) * k, f[m - 1])
            f[m] = f[m - 1] + (t - 1) * k
    half = np.round(rng.uniform(-0.04, 0.04, (n, d)) * h * 2**10) / 2**10  # half the displacement
    mid = np.round((f @ H.T) * 2**10) / 2**10
    c0, c1 = mid - half, mid + half
    o0, o1 = (rng.normal(size=(n, 4)), rng.normal(size=(n, 4))) if d == 3 else (rng.uniform(0, 3, n), rng.uniform(0, 3, n))
    res = sweep_contacts(c0, c1, r, o0, o1, box=box)
    images = list(itertools.product((-1, 0, 1), repeat=d))
    v = lattice_shifts(L, np.array(images))
    assert all(Fraction(float(x)) == y for k, row in zip(images, v, strict=True) for x, y in zip(row, exact_vector(box, k), strict=True))
    big = sweep_contacts(np.concatenate([c0 + s for s in v]), np.concatenate([c1 + s for s in v]), np.concatenate([r] * len(v)),
                         np.concatenate([o0] * len(v)), np.concatenate([o1] * len(v)))
    home = images.index((0,) * d)
    want = {}
    for a, b, lo, hi, rel in zip(big.i.tolist(), big.j.tolist(), big.t_lo.tolist(), big.t_hi.tolist(), big.relation.tolist(), strict=True):
        (ia, ka), (ib, kb) = divmod(a, n)[::-1], divmod(b, n)[::-1]
        if ka == home and ia < ib:  # body ia against image kb of body ib
            want[(ia, ib)] = (images[kb], lo, hi, rel)
        elif kb == home and ib < ia:  # body ib against image ka of body ia
            want[(ib, ia)] = (images[ka], lo, hi, rel)
    got = {(int(i), int(j)): (tuple(int(x) for x in k), lo, hi, int(rel))
           for i, j, k, lo, hi, rel in zip(res.i, res.j, res.image, res.t_lo, res.t_hi, res.relation, strict=True)}
    assert got.keys() == want.keys()
    for key, (k, lo, hi, rel) in got.items():
        wk, wlo, whi, wrel = want[key]
        assert k == wk and rel == wrel and lo <= whi and wlo <= hi, (key, got[key], want[key])  # the certified brackets meet
    across = [k for k, *_ in got.values() if any(k)]
    assert len(across) >= 3 and any(sum(map(abs, k)) >= 2 for k in across)  # across faces and edges or corners
    shifts = res.shifts()
    assert shifts is not None and shifts.tobytes() == lattice_shifts(L, res.image).tobytes()
    assert res.box is not None and res.box.tolist() == L.tolist()
    k = next(k for k in range(len(res)) if res.t_lo[k] > 0)  # an exact time on request, with the pair's image
    t = res.time(k)
    assert t.compare(fmpq(*float(res.t_lo[k]).as_integer_ratio())) >= 0 and t.compare(fmpq(*float(res.t_hi[k]).as_integer_ratio())) <= 0
