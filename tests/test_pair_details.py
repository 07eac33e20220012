"""Richer pair output (issue 26, item 4): contact-scale brackets and containment, certified.

Ground truth is closed-form, independent of the code: for two spheres mu* = |c1 - c2| / (r1 + r2)
(exact rationals), and sphere 2 lies inside sphere 1 exactly when |c1 - c2| + r2 <= r1.
"""

from __future__ import annotations

import numpy as np
from flint import arb, ctx, fmpq

from app.cli import main
from core import bodies_from_axes, contacts
from core.bodies.details import EQUAL, I_IN_J, J_IN_I, NO, UNCERTAIN, pair_details


def q(x: float) -> fmpq:
    return fmpq(*float(x).as_integer_ratio())


def test_spheres_against_the_closed_form():
    rng = np.random.default_rng(3)
    n = 300
    c = np.round(rng.uniform(0, 6, (n, 3)) * 64) / 64  # dyadic: the distances below are exact rationals
    r = np.round(rng.uniform(0.1, 1.2, n) * 64) / 64
    Q = bodies_from_axes(c, np.repeat(r[:, None], 3, axis=1))
    res = contacts(Q)
    d = pair_details(Q, res)
    assert len(res) > 200
    nested = decided = 0
    for k, (i, j) in enumerate(zip(res.i.tolist(), res.j.tolist(), strict=True)):
        dist2 = sum((q(c[i, a]) - q(c[j, a])) ** 2 for a in range(3))
        mu2 = dist2 / (q(r[i]) + q(r[j])) ** 2
        assert q(d.scale_lo[k]) ** 2 <= mu2 <= q(d.scale_hi[k]) ** 2  # the bracket holds mu*
        assert d.scale_hi[k] - d.scale_lo[k] <= 1e-8 * d.scale_hi[k]
        j_in_i = dist2 <= (q(r[i]) - q(r[j])) ** 2 and r[j] <= r[i]  # |c1 - c2| + r_j <= r_i
        i_in_j = dist2 <= (q(r[j]) - q(r[i])) ** 2 and r[i] <= r[j]
        code = int(d.contained[k])
        if code == UNCERTAIN:  # only a sphere touching the other from within (no strict proof exists)
            assert dist2 == (q(r[i]) - q(r[j])) ** 2, (i, j)
            continue
        decided += 1
        assert code == (EQUAL if (i_in_j and j_in_i) else I_IN_J if i_in_j else J_IN_I if j_in_i else NO), (i, j)
        nested += code in (I_IN_J, J_IN_I)
    assert nested >= 5 and decided >= len(res) - 5


def test_ellipsoids_nested_equal_and_touching_from_inside():
    rot = [0.9, 0.1, -0.3, 0.2]
    Q = bodies_from_axes(
        [[0, 0, 0], [0.1, 0, 0], [5, 5, 5], [5, 5, 5], [0, 0, 9], [0, 0, 9.5], [0, 1.5, 0]],
        [[2, 1, 1], [1, 0.5, 0.5], [1, 2, 3], [1, 2, 3], [1, 1, 1], [0.5, 0.5, 0.5], [1, 1, 1]],
        [rot, rot, rot, rot, [1, 0, 0, 0], [1, 0, 0, 0], rot],
    )
    # 0 holds 1 (half its size, a little off centre); 2 and 3 are the same set; 5 touches 4 from
    # within (inside, but no strict proof exists); 6 overlaps 0 and sticks out of it
    res = contacts(Q)
    d = dict(zip(zip(res.i.tolist(), res.j.tolist(), strict=True), pair_details(Q, res).contained.tolist(), strict=True))
    assert d[(0, 1)] == J_IN_I and d[(2, 3)] == EQUAL and d[(4, 5)] == UNCERTAIN and d[(0, 6)] == NO


def sphere_scale(A, B, shift):
    """mu* = |c_A - c_B'| / (r_A + r_B) of two sphere matrices (B moved by shift), in arb (a ball)."""

    def centre_radius(M, t):
        a = q(M[0, 0])
        c = [-q(M[k, 3]) / a + t[k] for k in range(3)]
        r2 = sum(q(M[k, 3]) ** 2 for k in range(3)) / a**2 - q(M[3, 3]) / a
        return c, arb(r2).sqrt()

    old = ctx.prec
    ctx.prec = 300
    try:
        (ca, ra), (cb, rb) = centre_radius(A, [0, 0, 0]), centre_radius(B, shift)
        return arb(sum((x - y) ** 2 for x, y in zip(ca, cb, strict=True))).sqrt() / (ra + rb)
    finally:
        ctx.prec = old


def test_a_pair_across_a_periodic_face_is_certified_on_the_image():
    Q = bodies_from_axes([[0.5, 10, 10], [19.8, 10, 10], [3.5, 10, 10]], [[2, 2, 2], [0.5, 0.5, 0.5], [1.25, 1.25, 1.25]])
    res = contacts(Q, box=(20, 20, 20))
    d = pair_details(Q, res)
    pairs = list(zip(res.i.tolist(), res.j.tolist(), strict=True))
    k = pairs.index((0, 1))
    assert res.image[k].tolist() == [-1, 0, 0] and d.contained[k] == J_IN_I  # the image of 1, at x = -0.2, lies in 0
    mu = sphere_scale(Q[0], Q[1], [-20, 0, 0])  # from the matrices (their entries are rounded, not the parameters)
    assert arb(q(d.scale_lo[k])) <= mu <= arb(q(d.scale_hi[k]))
    assert d.contained[pairs.index((0, 2))] == NO


def test_cli_with_scale_columns(tmp_path):
    (tmp_path / "b.csv").write_text("x,y,a,b,angle\n0,0,1,1,0\n2,0,1,1,0\n0.25,0,0.5,0.5,0\n")
    out = tmp_path / "p.csv"
    assert main(["contacts", str(tmp_path / "b.csv"), "--out", str(out), "--with", "scale", "--quiet"]) == 0
    lines = out.read_text().splitlines()
    assert lines[0] == "i,j,relation,certified_by,image_x,image_y,image_z,scale_lo,scale_hi,contained"
    assert lines[1] == "0,1,tangent,exact,0,0,0,1.0,1.0,no"
    row = lines[2].split(",")
    assert row[:7] == ["0", "2", "overlap", "float", "0", "0", "0"] and row[9] == "j_in_i"
    assert q(float(row[7])) * 6 <= 1 <= q(float(row[8])) * 6
    assert main(["contacts", str(tmp_path / "b.csv"), "--out", str(tmp_path / "p.npz"), "--with", "scale", "--quiet"]) == 0
    z = np.load(tmp_path / "p.npz")
    assert z["contained"].tolist() == ["no", "j_in_i"] and z["image"].shape == (2, 3) and z["certified_by"].tolist() == [2, 1]
