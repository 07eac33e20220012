"""core.Box, core.Bodies and the pair tables' shared writer (issue 53): values at the boundary."""

from __future__ import annotations

import io
from fractions import Fraction

import numpy as np
import pytest

from core import Bodies, BodyIndex, Box, Relation, bodies_from_axes, contacts, sweep_contacts


def test_every_accepted_box_form_gives_the_same_box():
    assert Box.from_any((10, 8, 6), 3) == Box(10, 8, 6) == Box.from_any(np.array([10.0, 8.0, 6.0]), 3)
    assert Box.from_any((10, 8, 6, 0, 0, 0), 3) == Box(10, 8, 6)  # no tilt: orthogonal
    assert Box.from_any((10, 8, 0.5), 2) == Box(10, 8, xy=0.5) == Box.from_any((10, 8, 0, 0.5, 0, 0), 2)
    assert Box.from_any(Box(3, 4), 2) == Box(3, 4)
    assert Box.from_any(None, 3) is None
    assert hash(Box(1, 2, 3)) == hash(Box.from_any([1, 2, 3], 3))
    assert Box(10, 8, 6).to_tuple() == (10.0, 8.0, 6.0)
    assert Box(10, 8, 6, 0.5, 0, -0.25).to_tuple() == (10.0, 8.0, 6.0, 0.5, 0.0, -0.25)
    assert Box(10, 8, xy=0.5).dimensions == 2 and Box(10, 8, xy=0.5).tilted and not Box(10, 8).tilted


@pytest.mark.parametrize(
    "args, kwargs, match",
    [
        ((10, -1), {}, "positive finite sides"),
        ((10, float("nan"), 3), {}, "positive finite sides"),
        ((10, 10), {"xz": 0.5}, "2D box has no tilt"),
        ((10, True), {}, "real number"),
        ((10, 10, 10), {"xy": float("inf")}, "positive finite|float range"),
    ],
)
def test_a_bad_box_is_refused_with_what_is_wrong(args, kwargs, match):
    with pytest.raises(ValueError, match=match):
        Box(*args, **kwargs)


def test_from_any_refuses_a_box_of_the_other_dimension():
    with pytest.raises(ValueError, match="2D box for 3D bodies"):
        Box.from_any(Box(1, 1), 3)
    with pytest.raises(ValueError, match="expected 3 positive finite sides"):
        Box.from_any((1, 1), 3)


def test_vectors_and_heights_of_a_tilted_box():
    b = Box(10, 8, 4, xy=0.5, xz=0.25, yz=-0.5)
    # columns a1 = (Lx, 0, 0), a2 = (xy Ly, Ly, 0), a3 = (xz Lz, yz Lz, Lz)
    assert b.vectors.tolist() == [[10.0, 4.0, 1.0], [0.0, 8.0, -2.0], [0.0, 0.0, 4.0]]
    a1, a2, a3 = b.vectors.T
    n1 = np.cross(a2, a3)  # the height across the faces a2-a3: |a1 . n1| / |n1|
    assert b.heights[0] == pytest.approx(abs(a1 @ n1) / np.linalg.norm(n1), rel=1e-11)
    assert b.heights[0] <= abs(a1 @ n1) / np.linalg.norm(n1)  # a lower bound
    assert b.volume == 320.0


def _dyadic(rng, shape, scale):
    """Floats that are multiples of 2^-20: sums and differences of them stay exact."""
    return np.round(rng.uniform(-scale, scale, shape) * 2**20) / 2**20


@pytest.mark.parametrize("box", [Box(10, 8, 6), Box(10, 8, 6, 0.5, -0.25, 0.125), Box(10, 8), Box(10, 8, xy=-0.5)])
def test_wrap_moves_points_by_whole_lattice_vectors_into_the_centred_cell(box):
    rng = np.random.default_rng(3)
    p = _dyadic(rng, (400, box.dimensions), 40)
    w = box.wrap(p)
    f = box.fractional(w)
    assert (f >= -0.5 - 1e-12).all() and (f < 0.5 + 1e-12).all()
    k = box.images(p)
    # exact check: p - w is k1 a1 + k2 a2 (+ k3 a3) with the box's exact numbers
    Lx, Ly, Lz, xy, xz, yz = (Fraction(v) for v in (*box.to_tuple(), 0, 0, 0, 0)[:6]) if box.tilted else (
        Fraction(box.Lx), Fraction(box.Ly), Fraction(box.Lz or 0), Fraction(0), Fraction(0), Fraction(0))
    for row in range(0, 400, 37):
        kk = [int(v) for v in k[row]]
        exact = [kk[0] * Lx + kk[1] * xy * Ly + (kk[2] * xz * Lz if box.dimensions == 3 else 0), kk[1] * Ly + (kk[2] * yz * Lz if box.dimensions == 3 else 0)]
        if box.dimensions == 3:
            exact.append(kk[2] * Lz)
        assert [Fraction(float(v)) for v in p[row] - w[row]] == exact


@pytest.mark.parametrize("box", [Box(10, 8, 6), Box(10, 8, 6, 0.5, -0.25, 0.125), Box(10, 8), Box(10, 8, xy=0.5)])
def test_unwrap_recovers_the_true_displacement_of_wrapped_frames(box):
    """Frames of a trajectory wrapped as a simulation stores them: bodies cross every face."""
    rng = np.random.default_rng(11)
    d = box.dimensions
    c0 = box.wrap(_dyadic(rng, (500, d), 6))
    step = _dyadic(rng, (500, d), 1.5)  # |step| < half the smallest height: one image is nearest
    c1_true = c0 + step
    c1 = box.wrap(c1_true)
    assert (box.images(c1_true) != 0).any()  # some bodies do cross a face
    ends, k = box.unwrap(c0, c1)
    assert np.array_equal(ends, c1_true)
    assert np.array_equal(ends - c0, step)
    assert np.array_equal(box.shifts(k), c1 - ends)


def test_unwrap_of_the_issues_two_spheres():
    ends, k = Box(10, 10, 10).unwrap([[4.95, 0, 0], [-4.95, 0, 0]], [[-4.85, 0, 0], [4.85, 0, 0]])
    assert k[:, 0].tolist() == [-1, 1]
    assert (ends - [[4.95, 0, 0], [-4.95, 0, 0]])[:, 0] == pytest.approx([0.2, -0.2], abs=1e-14)


def test_bodies_build_matrices_once_and_keep_ids_and_box():
    c, r, q = [[0, 0, 0], [1, 0, 0]], [[0.5, 0.5, 0.5]] * 2, [[1, 0, 0, 0]] * 2
    b = Bodies(c, r, q, ids=[7, 3], box=(4, 4, 4))
    assert np.array_equal(b.matrices, bodies_from_axes(c, r, q))
    assert b.box == Box(4, 4, 4) and b.ids.tolist() == [7, 3] and b.name(1) == "body 1 (id 3)"
    with pytest.raises(ValueError, match="ids must be 2 integers"):
        Bodies(c, r, q, ids=[1])
    with pytest.raises(ValueError, match="of one shape"):
        Bodies(c, [[1, 1]] * 2)
    m = Bodies.from_matrices(b.matrices, ids=[1, 2])
    assert not m.has_parameters and len(m) == 2 and m.dimensions == 3


def test_ordered_like_matches_frames_by_id():
    a = Bodies([[0, 0], [1, 0], [2, 0]], [[0.1, 0.1]] * 3, ids=[5, 6, 7])
    b = Bodies([[2.5, 0], [0.5, 0], [1.5, 0]], [[0.1, 0.1]] * 3, ids=[7, 5, 6])
    assert b.ordered_like(a).centers[:, 0].tolist() == [0.5, 1.5, 2.5]
    with pytest.raises(ValueError, match="same ids"):
        Bodies([[0, 0]] * 3, [[0.1, 0.1]] * 3, ids=[5, 6, 8]).ordered_like(a)


def test_contacts_of_bodies_carry_their_ids_box_and_write_one_csv():
    b = Bodies([[0, 0], [1, 0], [2.5, 0]], [[0.5, 0.5]] * 3, [0.0] * 3, ids=[100, 200, 300], box=(3, 3))
    res = contacts(b)
    assert res.box == Box(3, 3) and res.ids.tolist() == [100, 200, 300]
    want = contacts(bodies_from_axes([[0, 0], [1, 0], [2.5, 0]], [[0.5, 0.5]] * 3, [0.0] * 3), box=(3, 3))
    assert res.i.tolist() == want.i.tolist() and res.relation.tolist() == want.relation.tolist()
    out = io.StringIO()
    res.to_csv(out)
    lines = out.getvalue().splitlines()
    assert lines[0] == "i,j,relation,certified_by,image_x,image_y,image_z,id_i,id_j"
    assert lines[1].split(",")[:3] == ["0", "1", "tangent"] and lines[1].split(",")[-2:] == ["100", "200"]
    assert lines[2].split(",")[:5] == ["0", "2", "overlap", res.columns()["certified_by"][1], "-1"]
    rows = list(res.rows())
    assert rows[1]["image"] == [-1, 0] and rows[1]["image_z"] == 0 and rows[1]["id_j"] == 300
    assert "id_i" not in want.columns()  # no ids: no id columns


def test_sweep_of_two_frames_reorders_by_id_and_writes_its_brackets():
    start = Bodies([[0, 0], [3, 0], [0, 5]], [[1, 1]] * 3, ids=[5, 6, 7])
    end = Bodies([[0, 5], [1, 0], [0, 0]], [[1, 1]] * 3, ids=[7, 6, 5])  # listed in another order
    res = sweep_contacts(start, end)
    want = sweep_contacts([[0, 0], [3, 0], [0, 5]], [[0, 0], [1, 0], [0, 5]], [[1, 1]] * 3)
    assert (res.i.tolist(), res.j.tolist()) == (want.i.tolist(), want.j.tolist()) == ([0], [1])
    assert res.time(0).decimal(5) == "0.5" and str(Relation(int(res.relation[0]))) == "tangent"
    out = io.StringIO()
    res.to_csv(out)
    header, row = out.getvalue().splitlines()
    assert header == "i,j,t_lo,t_hi,relation,certified_by,image_x,image_y,image_z,id_i,id_j"
    values = row.split(",")
    assert float(values[2]) == res.t_lo[0] and float(values[3]) == res.t_hi[0] and values[-2:] == ["5", "6"]
    with pytest.raises(ValueError, match="keep their shape"):
        sweep_contacts(start, Bodies([[0, 5], [1, 0], [0, 0]], [[1, 1], [1, 2], [1, 1]], ids=[7, 6, 5]))


def test_body_index_takes_the_box_as_a_keyword():
    Q = bodies_from_axes([[0, 0], [2.5, 0]], [[1, 1]] * 2)
    new = bodies_from_axes([[4, 0]], [[1, 1]])
    with pytest.warns(DeprecationWarning, match="keyword"):
        old = BodyIndex(Q, (5, 5)).query(new)
    hits = BodyIndex(Q, box=(5, 5)).query(new)
    assert hits.j.tolist() == old.j.tolist() == [0, 1] and hits.box == Box(5, 5)
    assert hits.shifts().tolist() == [[5.0, 0.0], [0.0, 0.0]]  # body 0's image at x = 5
    assert BodyIndex(Bodies([[0, 0], [2.5, 0]], [[1, 1]] * 2, box=(5, 5))).box == Box(5, 5)


def test_invalid_input_says_which_pair_and_matrix():
    from core import InvalidInput, classify

    circle = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]
    hyperbola = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
    with pytest.raises(InvalidInput) as one:
        classify(circle, hyperbola)
    assert (one.value.pair, one.value.matrix) == (None, "B") and str(one.value).startswith("B is not an ellipse")
    with pytest.raises(InvalidInput) as batch:
        classify([circle, circle, hyperbola], circle)
    assert (batch.value.pair, batch.value.matrix) == (2, "A") and str(batch.value).startswith("pair 2: A is not an ellipse")
    assert batch.value.reason.startswith("A is not an ellipse")
    with pytest.raises(InvalidInput) as entry:
        classify([[1, 0, 0], [0, 1, 0], [0, 0, float("nan")]], circle)
    assert entry.value.matrix == "A" and "entry (2,2)" in str(entry.value)
    assert isinstance(entry.value, ValueError)
