"""Files of simulation codes (app.readers): round trips through each format.

Each file is written with the format's own library (gsd, extxyz, pyarrow, numpy; LAMMPS dumps
in LAMMPS's documented ``dump custom`` layout, their box and positions cross-checked with
lammpsio), read back, and the contacts found from the file must equal the library call on the
same numbers (same pairs, relations, images).
"""

from __future__ import annotations

import numpy as np
import pytest

from app.cli import main
from app.readers import format_of, read_bodies, read_bodies_bytes
from bench.bodies_data import random_bodies
from core import Relation, bodies_from_axes, contacts

gsd_hoomd = pytest.importorskip("gsd.hoomd")
lammpsio = pytest.importorskip("lammpsio")
extxyz = pytest.importorskip("extxyz")
pq = pytest.importorskip("pyarrow.parquet")
pa = pytest.importorskip("pyarrow")


def same_contacts(a, b):
    assert np.array_equal(a.i, b.i) and np.array_equal(a.j, b.j) and np.array_equal(a.relation, b.relation)
    assert (a.image is None) == (b.image is None)
    if a.image is not None:
        assert np.array_equal(a.image, b.image)


def hoomd_bodies(n=400, seed=1):
    """Random ellipsoids of 3 types centred in a box [-L/2, L/2)^3, as HOOMD holds them (float32)."""
    rng = np.random.default_rng(seed)
    b = random_bodies(n, dim=3, seed=seed, fraction=0.3)
    semi = np.array([[1.0, 0.5, 0.5], [0.75, 0.75, 0.5], [0.5, 0.5, 0.5]])
    typeid = rng.integers(0, 3, n)
    pos = (b.centers - b.side / 2).astype(np.float32)
    q = b.orientations.astype(np.float32)
    return pos, q, typeid, semi, np.float32(b.side)


def write_gsd(path, frames):
    with gsd_hoomd.open(str(path), "w") as t:
        for step, (pos, q, typeid, semi, L, tilt) in enumerate(frames):
            f = gsd_hoomd.Frame()
            f.configuration.step = step
            f.configuration.box = [L, L, L, *tilt]
            f.particles.N = len(pos)
            f.particles.position = pos
            f.particles.orientation = q
            f.particles.types = ["A", "B", "C"]
            f.particles.typeid = typeid
            f.particles.type_shapes = [{"type": "Ellipsoid", "a": float(a), "b": float(b), "c": float(c)} for a, b, c in semi]
            t.append(f)


def test_gsd_round_trip_frames_and_box(tmp_path, capsys):
    first = hoomd_bodies(300, seed=1)
    last = hoomd_bodies(400, seed=2)
    write_gsd(tmp_path / "run.gsd", [(*first, (0, 0, 0)), (*last, (0, 0, 0))])
    for frame, (pos, q, typeid, semi, L) in ((None, last), (0, first), (-1, last), (1, last)):
        s = read_bodies(tmp_path / "run.gsd", frame=frame)
        assert s.box == (float(L),) * 3 and s.frame == (0 if frame == 0 else 1)
        Q = bodies_from_axes(pos.astype(np.float64), semi[typeid], q.astype(np.float64))
        assert np.array_equal(s.Q, Q)
        same_contacts(contacts(s.Q, box=s.box), contacts(Q, box=(float(L),) * 3))
    out = tmp_path / "pairs.csv"
    assert main(["contacts", str(tmp_path / "run.gsd"), "--out", str(out), "--frame", "0", "--quiet"]) == 0
    pos, q, typeid, semi, L = first
    want = contacts(bodies_from_axes(pos.astype(np.float64), semi[typeid], q.astype(np.float64)), box=(float(L),) * 3)
    lines = out.read_text().splitlines()
    assert len(lines) == 1 + len(want) and len(want) > 50
    assert any(not ln.endswith(",0,0,0") for ln in lines[1:])  # pairs across the faces carry their image
    assert main(["contacts", str(tmp_path / "run.gsd"), "--out", str(out), "--frame", "5"]) == 2
    assert "no frame 5: the file has 2 frames (0..1; -1 is the last)" in capsys.readouterr().err


def test_gsd_spheres_2d_and_refusals(tmp_path, capsys):
    with gsd_hoomd.open(str(tmp_path / "s.gsd"), "w") as t:
        f = gsd_hoomd.Frame()
        f.configuration.box = [10, 10, 0, 0, 0, 0]
        f.configuration.dimensions = 2
        f.particles.N = 3
        f.particles.position = np.array([[0, 0, 0], [1, 0, 0], [3, 0, 0]], np.float32)
        f.particles.types = ["disc"]
        f.particles.typeid = [0, 0, 0]
        f.particles.type_shapes = [{"type": "Sphere", "diameter": 1.0}]
        t.append(f)
    s = read_bodies(tmp_path / "s.gsd")
    assert s.dim == 2 and s.box == (10.0, 10.0)
    c = contacts(s.Q, box=s.box)
    assert list(zip(c.i.tolist(), c.j.tolist(), c.relation.tolist(), strict=True)) == [(0, 1, Relation.TANGENT)]
    with gsd_hoomd.open(str(tmp_path / "poly.gsd"), "w") as t:
        f = gsd_hoomd.Frame()
        f.particles.N = 1
        f.particles.types = ["P"]
        f.particles.type_shapes = [{"type": "ConvexPolyhedron", "vertices": [[0, 0, 0]]}]
        t.append(f)
    with pytest.raises(ValueError, match="type 'P' has the shape 'ConvexPolyhedron': only Ellipsoid and Sphere"):
        read_bodies(tmp_path / "poly.gsd")


def test_tilted_box_flows_through_to_contacts_and_the_command(tmp_path):
    pos, q, typeid, semi, L = hoomd_bodies(300, seed=5)
    tilt = (0.5, -0.5, 0.25)
    H = np.array([[L, tilt[0] * L, tilt[1] * L], [0, L, tilt[2] * L], [0, 0, L]], dtype=np.float64)
    f = np.linalg.solve(H, pos.astype(np.float64).T).T
    pos = ((f - np.round(f)) @ H.T).astype(np.float32)  # wrapped into the tilted cell, as HOOMD holds them
    write_gsd(tmp_path / "tilted.gsd", [(pos, q, typeid, semi, L, tilt)])
    s = read_bodies(tmp_path / "tilted.gsd")
    assert s.box == (float(L), float(L), float(L), *tilt)  # HOOMD's six numbers, unchanged
    want = contacts(bodies_from_axes(pos.astype(np.float64), semi[typeid], q.astype(np.float64)), box=s.box)
    assert len(want) > 50 and (np.abs(want.image).sum(axis=1) > 0).sum() > 5  # pairs across the tilted faces
    same_contacts(contacts(s.Q, box=s.box), want)
    out = tmp_path / "pairs.csv"
    assert main(["contacts", str(tmp_path / "tilted.gsd"), "--out", str(out), "--quiet"]) == 0
    rows = [ln.split(",") for ln in out.read_text().splitlines()[1:]]
    assert [(int(r[0]), int(r[1]), r[2], tuple(int(x) for x in r[4:7])) for r in rows] == [
        (int(i), int(j), str(Relation(int(r))), tuple(int(x) for x in k)) for i, j, r, k in zip(want.i, want.j, want.relation, want.image, strict=True)
    ]
    # LAMMPS: a tilted dump (tilt lengths) becomes the same kind of box, and the command runs on it
    b = random_bodies(60, dim=3, seed=3)
    lammps_dump(tmp_path / "t.dump", [(b.centers, 2 * b.semi_axes, b.orientations)], tilt=(1.0, 0.5, 0.25))
    t = read_bodies(tmp_path / "t.dump")
    assert t.box is not None and len(t.box) == 6
    assert main(["contacts", str(tmp_path / "t.dump"), "--out", str(out), "--quiet"]) == 0
    assert len(out.read_text().splitlines()) == 1 + len(contacts(t.Q, box=t.box))


def lammps_dump(path, frames, *, tilt=None, boundary="pp pp pp", order=None):
    """A dump as LAMMPS's ``dump custom ... id type x y z shapex shapey shapez quatw quati quatj quatk`` writes it."""
    with open(path, "w") as f:
        for step, (pos, diam, q) in enumerate(frames):
            n = len(pos)
            lo, hi = pos.min(axis=0) - 2.0, pos.max(axis=0) + 2.0
            f.write(f"ITEM: TIMESTEP\n{step * 100}\nITEM: NUMBER OF ATOMS\n{n}\n")
            if tilt is None:
                f.write(f"ITEM: BOX BOUNDS {boundary}\n" + "".join(f"{float(lo[k])!r} {float(hi[k])!r}\n" for k in range(3)))
            else:  # bounds of the tilted box's bounding box, as LAMMPS writes them
                xy, xz, yz = tilt
                blo = [lo[0] + min(0.0, xy, xz, xy + xz), lo[1] + min(0.0, yz), lo[2]]
                bhi = [hi[0] + max(0.0, xy, xz, xy + xz), hi[1] + max(0.0, yz), hi[2]]
                f.write(f"ITEM: BOX BOUNDS xy xz yz {boundary}\n" + "".join(f"{float(blo[k])!r} {float(bhi[k])!r} {float(tilt[k])!r}\n" for k in range(3)))
            f.write("ITEM: ATOMS id type x y z shapex shapey shapez quatw quati quatj quatk\n")
            for k in order if order is not None else range(n):
                f.write(f"{k + 1} 1 " + " ".join(repr(float(v)) for v in [*pos[k], *diam[k], *q[k]]) + "\n")
    return lo, hi


def test_lammps_dump_round_trip_diameters_ids_and_box(tmp_path):
    b = random_bodies(300, dim=3, seed=7)
    b2 = random_bodies(300, dim=3, seed=8)
    rng = np.random.default_rng(0)
    order = rng.permutation(300)  # LAMMPS writes atoms in any order
    lo, hi = lammps_dump(tmp_path / "run.dump", [(b.centers, 2 * b2.semi_axes, b2.orientations), (b.centers, 2 * b.semi_axes, b.orientations)], order=order)
    s = read_bodies(tmp_path / "run.dump")
    snap = list(lammpsio.DumpFile(str(tmp_path / "run.dump")))[-1]  # lammpsio's own reading of the same file
    assert np.array_equal(snap.position, b.centers) and s.frame == 1
    assert s.box == tuple(float(v) for v in hi - lo)
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)  # shapex.. are diameters: halved
    assert np.array_equal(s.Q, Q)
    same_contacts(contacts(s.Q), contacts(Q))
    s0 = read_bodies(tmp_path / "run.dump", frame=0)
    assert np.array_equal(s0.Q, bodies_from_axes(b.centers, b2.semi_axes, b2.orientations))
    assert s.where(3) == "body 3 (id 4)"


def test_lammps_tilted_open_and_mixed_boundaries(tmp_path):
    b = random_bodies(20, dim=3, seed=3)
    lo, hi = lammps_dump(tmp_path / "t.dump", [(b.centers, 2 * b.semi_axes, b.orientations)], tilt=(1.0, 0.5, 0.25))
    s = read_bodies(tmp_path / "t.dump")
    snap = next(iter(lammpsio.DumpFile(str(tmp_path / "t.dump"))))
    L = snap.box.high - snap.box.low
    assert np.allclose(L, hi - lo, rtol=0, atol=1e-12)
    assert s.box == (*(float(v) for v in L), 1.0 / L[1], 0.5 / L[2], 0.25 / L[2])  # tilt lengths -> HOOMD factors
    lammps_dump(tmp_path / "open.dump", [(b.centers, 2 * b.semi_axes, b.orientations)], boundary="ff ff ff")
    assert read_bodies(tmp_path / "open.dump").box is None
    # a slab (issue 54.4): periodic in x and y, open in z: z padded beyond any image's reach
    lo, hi = lammps_dump(tmp_path / "mixed.dump", [(b.centers, 2 * b.semi_axes, b.orientations)], boundary="pp pp ff")
    slab = read_bodies(tmp_path / "mixed.dump")
    extent = float(np.ptp(b.centers[:, 2]))
    assert slab.box.Lx == hi[0] - lo[0] and slab.box.Lz >= extent + 4 * float(b.semi_axes.max())
    far = contacts(slab.Q, box=(slab.box.Lx, slab.box.Ly, 1e6))  # open along z: no image of z can be nearest
    same_contacts(contacts(slab), far)
    lammps_dump(tmp_path / "tilted-slab.dump", [(b.centers, 2 * b.semi_axes, b.orientations)], tilt=(1.0, 0.5, 0.25), boundary="pp pp ff")
    with pytest.raises(ValueError, match=r"tilted \(xz = .*\) along an open axis"):
        read_bodies(tmp_path / "tilted-slab.dump")
    (tmp_path / "atoms.dump").write_text("ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 1\n0 1\nITEM: ATOMS id x y z\n1 0 0 0\n")
    with pytest.raises(ValueError, match="no column shapex, shapey, shapez"):
        read_bodies(tmp_path / "atoms.dump")


def test_extended_xyz_as_ovito_writes_it_round_trip(tmp_path):
    b = random_bodies(300, dim=3, seed=9)
    L = float(np.ceil(b.side))  # the C writer prints the Lattice with 8 decimals: a side it holds exactly
    frame = extxyz.Frame(
        natoms=300, cell=np.diag([L, L, L]), pbc=np.array([True, True, True]),
        arrays={"species": np.array(["Type1"] * 300), "pos": b.centers, "orientation": b.orientations[:, [1, 2, 3, 0]],
                "aspherical_shape": b.semi_axes, "id": np.arange(1, 301)},
    )
    extxyz.write_dicts(str(tmp_path / "a.xyz"), [frame, frame], format_dict={"R": "%.17g", "I": "%d", "S": "%s", "L": "%s"})
    s = read_bodies(tmp_path / "a.xyz")
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    assert np.array_equal(s.Q, Q) and s.box == (L, L, L) and s.frame == 1
    same_contacts(contacts(s.Q, box=s.box), contacts(Q, box=(L, L, L)))
    # OVITO's quaternion order is x y z w: a 90 degree turn about z, long axis onto y, touches a sphere at y = 3
    (tmp_path / "turn.xyz").write_text(
        '2\nLattice="20 0 0 0 20 0 0 0 20" Properties=species:S:1:pos:R:3:orientation:R:4:aspherical_shape:R:3\n'
        "A 0 0 0 0 0 1 1 2 1 1\nB 0 3 0 0 0 0 1 1 1 1\n"
    )
    c = contacts(read_bodies(tmp_path / "turn.xyz").Q)
    assert c.relation.tolist() == [Relation.TANGENT]


def test_csv_with_extra_columns_parquet_and_npz_box(tmp_path):
    b = random_bodies(500, dim=3, seed=12)
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    want = contacts(Q)
    cols = ["x", "y", "z", "a", "b", "c", "qw", "qx", "qy", "qz"]
    values = np.concatenate([b.centers, b.semi_axes, b.orientations], axis=1)
    order = [9, 3, 0, 1, 2, 4, 5, 6, 7, 8]  # any column order
    with open(tmp_path / "b.csv", "w") as f:
        f.write("id,type," + ",".join(cols[k].upper() for k in order) + ",note\n")
        for k, row in enumerate(values.tolist()):
            f.write(f'{k},"big, round",' + ",".join(repr(row[c]) for c in order) + ",x\n")
    assert np.array_equal(read_bodies(tmp_path / "b.csv").Q, Q)
    table = pa.table({"id": np.arange(500), "type": ["A"] * 500, **{c: values[:, k] for k, c in enumerate(cols)}})
    pq.write_table(table, tmp_path / "b.parquet", row_group_size=128)
    s = read_bodies(tmp_path / "b.parquet")
    assert np.array_equal(s.Q, Q)
    same_contacts(contacts(s.Q), want)
    np.savez(tmp_path / "b.npz", centers=b.centers, semi_axes=b.semi_axes, orientations=b.orientations, box=[b.side] * 3)
    s = read_bodies(tmp_path / "b.npz")
    assert s.box == (float(b.side),) * 3 and np.array_equal(s.Q, Q)
    assert np.array_equal(read_bodies_bytes((tmp_path / "b.parquet").read_bytes(), "upload.parquet").Q, Q)  # the scene's upload
    bad = tmp_path / "ragged.csv"
    bad.write_text("x,y,a,b,angle\n0,0,1,1,0\n1,0,1,1,0,7\n")
    with pytest.raises(ValueError, match="line 3: 6 values but 5 columns in the header"):
        read_bodies(bad)


def test_format_is_told_from_the_name_or_the_bytes():
    assert [format_of(n) for n in ("a.gsd", "a.dump", "a.lammpstrj", "a.xyz", "a.parquet", "a.npz", "a.csv")] == [
        "gsd", "lammps", "lammps", "xyz", "parquet", "npz", "csv"]
    assert format_of("-", b"ITEM: TIMESTEP\n0\n") == "lammps"
    assert format_of("-", b"2\nLattice=\"1 0 0 0 1 0 0 0 1\" Properties=pos:R:3\n") == "xyz"


def test_extended_xyz_frames_are_read_alone_blank_ends_empty_frames_and_crlf(tmp_path):
    """The checked scan hands the parser one frame: any frame of many, after a frame of 0 atoms
    (which crashes the C parser), with blank lines at the end or CRLF line ends."""
    props = 'Properties=species:S:1:pos:R:3:aspherical_shape:R:3 pbc="F F F"'
    frames = [(2, "A 0 0 0 1 1 1\nB 2 0 0 1 1 1\n"), (0, ""), (2, "A 0 0 0 1 1 1\nB 2.5 0 0 1 1 1\n"), (1, "A 0 0 0 1 1 1\n")]
    path = tmp_path / "frames.xyz"
    path.write_text("".join(f"{n}\n{props}\n{rows}" for n, rows in frames) + "\n\n  \n")
    got = [read_bodies(path, frame=k) for k in range(4)]
    assert [len(s) for s in got] == [2, 0, 2, 1] and [s.frame for s in got] == [0, 1, 2, 3]
    assert read_bodies(path).frame == 3 and read_bodies(path, frame=-2).centers.tolist() == [[0, 0, 0], [2.5, 0, 0]]
    assert contacts(got[0].Q).relation.tolist() == [Relation.TANGENT] and len(contacts(got[2].Q)) == 0
    with pytest.raises(ValueError, match=r"frames.xyz: no frame 4: the file has 4 frames"):
        read_bodies(path, frame=4)
    crlf = tmp_path / "crlf.xyz"
    crlf.write_bytes(f"2\r\n{props}\r\nA 0 0 0 1 1 1\r\nB 2 0 0 1 1 1\r\n".encode())
    assert np.array_equal(read_bodies(crlf).Q, got[0].Q)
    mid = tmp_path / "mid.xyz"
    mid.write_text(f"2\n{props}\nA 0 0 0 1 1 1\nB 2 0 0 1 1 1\n\n2\n{props}\nA 0 0 0 1 1 1\nB 2 0 0 1 1 1\n")
    with pytest.raises(ValueError, match=r"mid.xyz: line 5: a blank line where frame 1 should start with its atom count"):
        read_bodies(mid)


def test_text_tables_with_a_bom_crlf_and_long_extra_values_read_as_before(tmp_path):
    b = random_bodies(50, dim=3, seed=5)
    values = np.concatenate([b.centers, b.semi_axes, b.orientations], axis=1)
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    rows = "".join(",".join(repr(v) for v in row) + f',"{"n" * 200_000}"\r\n' for row in values.tolist())
    path = tmp_path / "bom.csv"
    path.write_bytes(("\ufeffx,y,z,a,b,c,qw,qx,qy,qz,note\r\n" + rows).encode())
    assert np.array_equal(read_bodies(path).Q, Q)  # a value of 200,000 characters in a column not read
    dump = tmp_path / "crlf.dump"
    dump.write_bytes(b"ITEM: TIMESTEP\r\n0\r\nITEM: NUMBER OF ATOMS\r\n2\r\nITEM: BOX BOUNDS pp pp pp\r\n0 10\r\n0 10\r\n0 10\r\n"
                     b"ITEM: ATOMS id type x y z shapex shapey shapez\r\n1 1 1 1 1 2 2 2\r\n2 1 3 1 1 2 2 2\r\n")
    s = read_bodies(dump)
    assert s.centers.tolist() == [[1, 1, 1], [3, 1, 1]] and contacts(s.Q).relation.tolist() == [Relation.TANGENT]


# --- issue 54.4: valid input is read; ids ----------------------------------------------------


def test_extended_xyz_without_a_lattice_is_open_space_and_keeps_its_ids(tmp_path):
    (tmp_path / "open.xyz").write_text(
        "3\nProperties=species:S:1:pos:R:3:radius:R:1:id:I:1\n"
        "A 0 0 0 0.5 10\nA 1 0 0 0.5 20\nA 30 0 0 0.5 30\n"
    )
    s = read_bodies(tmp_path / "open.xyz")
    assert s.box is None and s.ids.tolist() == [10, 20, 30]
    c = contacts(s)
    assert (c.i.tolist(), c.j.tolist(), c.relation.tolist()) == ([0], [1], [Relation.TANGENT])
    assert c.pair_ids()[0].tolist() == [10] and c.pair_ids()[1].tolist() == [20]


def test_extended_xyz_2d_cell_with_pbc_t_t_f_is_read_as_ellipses(tmp_path):
    # ellipses a = 1, b = 0.5 at x = 0.25 and 9.75 in a 10 x 10 periodic plane: they meet across x = 10
    (tmp_path / "flat.xyz").write_text(
        '2\nLattice="10 0 0 0 10 0 0 0 3" pbc="T T F" Properties=species:S:1:pos:R:3:aspherical_shape:R:3\n'
        "A 0.25 5 0 1 0.5 7\nA 9.75 5 0 1 0.5 7\n"
    )
    s = read_bodies(tmp_path / "flat.xyz")
    assert s.dimensions == 2 and s.box == (10.0, 10.0) and s.semi_axes.tolist() == [[1.0, 0.5]] * 2
    c = contacts(s)
    assert c.relation.tolist() == [Relation.OVERLAP] and c.image.tolist() == [[-1, 0]]
    slab = read_bodies(tmp_path / "flat.xyz", dim=3)  # --dim 3: ellipsoids in a slab, open along z (padded)
    assert slab.dimensions == 3 and slab.box.Lz >= 4 * 7 and slab.box.Lx == 10


def test_lammps_2d_dump_is_read_as_ellipses(tmp_path):
    """LAMMPS' dimension 2: z bounds -0.5 0.5, z = 0, shapez 1 (ignored), turned about z."""
    c, s = 1.0, 1.0  # (1, 0, 0, 1): exactly 90 degrees about z (any length): the long axis (2) along y
    (tmp_path / "flat.dump").write_text(
        "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp pp\n0 20\n0 20\n-0.5 0.5\n"
        "ITEM: ATOMS id type x y z shapex shapey shapez quatw quati quatj quatk\n"
        f"7 1 5 5 0 4 1 1 {c!r} 0 0 {s!r}\n9 1 5 7.5 0 1 1 1 1 0 0 0\n"
    )
    b = read_bodies(tmp_path / "flat.dump")
    assert b.dimensions == 2 and b.box == (20.0, 20.0) and b.ids.tolist() == [7, 9]
    assert b.semi_axes.tolist() == [[2.0, 0.5], [0.5, 0.5]]
    res = contacts(b)  # the long axis reaches y = 7, the circle of radius 1/2 at y = 7.5 starts there
    assert res.relation.tolist() == [Relation.TANGENT] and res.pair_ids()[1].tolist() == [9]
    assert read_bodies(tmp_path / "flat.dump", dim=3).dimensions == 3  # --dim 3 keeps the file's 3D


def test_dim_2_reads_a_3d_file_of_a_plane_and_refuses_bodies_off_it(tmp_path):
    (tmp_path / "p.csv").write_text("x,y,z,a,b,c,qw,qx,qy,qz\n0,0,0,1,1,1,1,0,0,0\n2,0,0,1,1,1,1,0,0,0\n")
    flat = read_bodies(tmp_path / "p.csv", dim=2)
    assert flat.dimensions == 2 and contacts(flat).relation.tolist() == [Relation.TANGENT]
    (tmp_path / "q.csv").write_text("x,y,z,a,b,c,qw,qx,qy,qz\n0,0,0,1,1,1,1,0,0,0\n2,0,0.5,1,1,1,1,0,0,0\n")
    with pytest.raises(ValueError, match=r"body 1 \(line 3\) has z = 0.5: 2D bodies lie in the plane z = 0"):
        read_bodies(tmp_path / "q.csv", dim=2)


def test_csv_and_parquet_id_columns_become_the_bodies_ids(tmp_path):
    (tmp_path / "ids.csv").write_text("id,x,y,a,b,angle\n101,0,0,1,1,0\n7,2,0,1,1,0\n55,9,0,1,1,0\n")
    s = read_bodies(tmp_path / "ids.csv")
    assert s.ids.tolist() == [101, 7, 55] and s.where(1) == "body 1 (line 3)"
    assert contacts(s).pair_ids()[1].tolist() == [7]
    (tmp_path / "bad.csv").write_text("id,x,y,a,b,angle\n1.5,0,0,1,1,0\n")
    with pytest.raises(ValueError, match=r"line 2: id 1.5 is not an integer"):
        read_bodies(tmp_path / "bad.csv")
