"""Files of bodies and pairs, and the ``contacts`` / ``classify`` commands (round trips)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from app.bodyfiles import read_bodies, read_pairs_csv, write_pairs_csv
from app.cli import main
from bench.bodies_data import random_bodies
from core import Relation, bodies_from_axes, classify, contacts

ROOT = Path(__file__).resolve().parents[1]


def write_csv(path, b, *, header=None):
    dim = b.centers.shape[1]
    cols = header or ("x,y,z,a,b,c,qw,qx,qy,qz" if dim == 3 else "x,y,a,b,angle")
    o = b.orientations if dim == 3 else b.orientations[:, None]
    rows = np.concatenate([b.centers, b.semi_axes, o], axis=1)
    path.write_text(cols + "\n" + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows))
    return path


@pytest.mark.parametrize("dim", [2, 3])
def test_contacts_command_round_trip(tmp_path, capsys, dim):
    b = random_bodies(600, dim=dim, seed=3)
    src = write_csv(tmp_path / "bodies.csv", b)
    out = tmp_path / "pairs.csv"
    assert main(["contacts", str(src), "--out", str(out)]) == 0
    i, j, rel = read_pairs_csv(out)
    want = contacts(bodies_from_axes(b.centers, b.semi_axes, b.orientations))
    assert np.array_equal(i, want.i) and np.array_equal(j, want.j) and np.array_equal(rel, want.relation)
    captured = capsys.readouterr()
    assert captured.out == ""  # stdout carries data only
    assert f"wrote {len(want):,} pairs to {out}" in captured.err and want.summary() in captured.err
    assert out.read_text().startswith("i,j,relation,certified_by,image_x,image_y,image_z\n")


def test_contacts_command_periodic_box_and_npz(tmp_path):
    b = random_bodies(500, dim=3, seed=5)
    np.savez(tmp_path / "p.npz", centers=b.centers, semi_axes=b.semi_axes, orientations=b.orientations)
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    np.savez(tmp_path / "q.npz", Q=Q)
    side = f"{b.side!r},{b.side!r},{b.side!r}"
    want = contacts(Q, box=(b.side,) * 3)
    for name in ("p.npz", "q.npz"):
        out = tmp_path / f"{name}.csv"
        assert main(["contacts", str(tmp_path / name), "--out", str(out), "--box", side, "--quiet"]) == 0
        i, j, rel = read_pairs_csv(out)
        assert np.array_equal(i, want.i) and np.array_equal(j, want.j) and np.array_equal(rel, want.relation)


def test_tangent_lattice_file(tmp_path):
    c = np.array([[x, y] for x in range(4) for y in range(3)], dtype=float)
    path = tmp_path / "lattice.csv"
    path.write_text("x,y,a,b,angle\n" + "".join(f"{x},{y},0.5,0.5,0\n" for x, y in c))
    out = tmp_path / "pairs.csv"
    assert main(["contacts", str(path), "--out", str(out), "--quiet"]) == 0
    lines = out.read_text().splitlines()
    assert lines[0] == "i,j,relation,certified_by,image_x,image_y,image_z" and len(lines) == 1 + 17
    assert all(ln.endswith(",tangent,exact,0,0,0") for ln in lines[1:])  # tangency is certified exactly, always


def test_bad_files_name_the_line(tmp_path, capsys):
    b = random_bodies(5, dim=3, seed=1)
    bad = write_csv(tmp_path / "bad.csv", b)
    lines = bad.read_text().splitlines()
    lines[4] = ",".join(["1", "2", "3", "1", "-1", "1", "1", "0", "0", "0"])  # body 3: a negative axis
    bad.write_text("\n".join(lines) + "\n")
    assert main(["contacts", str(bad), "--out", str(tmp_path / "o.csv"), "--quiet"]) == 2
    assert "body 3 (line 5): semi-axes must be positive, got [1.0, -1.0, 1.0]" in capsys.readouterr().err
    assert main(["contacts", str(bad), "--out", str(tmp_path / "o.csv"), "--quiet", "--on-invalid", "mark"]) == 0
    assert "invalid body 3 (line 5): semi-axes must be positive" in capsys.readouterr().err
    lines[2] = "1,2,x,1,1,1,1,0,0,0"
    bad.write_text("\n".join(lines) + "\n")
    assert main(["contacts", str(bad), "--out", str(tmp_path / "o.csv")]) == 2
    assert "line 3, column 3: could not convert string 'x' to float64" in capsys.readouterr().err
    (tmp_path / "h.csv").write_text("x,y,z,r\n1,2,3,4\n")
    assert main(["contacts", str(tmp_path / "h.csv"), "--out", str(tmp_path / "o.csv")]) == 2
    assert "the header must name the columns x,y,z,a,b,c,qw,qx,qy,qz" in capsys.readouterr().err
    assert main(["contacts", str(tmp_path / "missing.csv"), "--out", str(tmp_path / "o.csv")]) == 2
    assert "cannot read" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["contacts", str(bad), "--out", "o.csv", "--box", "1,x"])


def test_classify_command_round_trip(tmp_path, capsys):
    b = random_bodies(400, dim=3, seed=8)
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    A, B = Q[:200], Q[200:]
    A[0] = bodies_from_axes([[0, 0, 0]], [[1, 1, 1]])[0]
    B[0] = bodies_from_axes([[2, 0, 0]], [[1, 1, 1]])[0]
    np.savez(tmp_path / "pairs.npz", A=A, B=B)
    assert main(["classify", str(tmp_path / "pairs.npz"), "--out", str(tmp_path / "labels.npy")]) == 0
    labels = np.load(tmp_path / "labels.npy")
    assert labels.dtype == np.int8 and np.array_equal(labels, classify(A, B)) and labels[0] == Relation.TANGENT
    assert "wrote 200 labels" in capsys.readouterr().err
    np.savez(tmp_path / "wrong.npz", A=A)
    assert main(["classify", str(tmp_path / "wrong.npz"), "--out", str(tmp_path / "x.npy")]) == 2
    assert "expected arrays A and B" in capsys.readouterr().err


def test_pairs_csv_writer_reader():
    import io

    from core import Box, Contacts

    res = Contacts(np.array([0, 3]), np.array([5, 4]), np.array([1, 2], np.int8), np.array([1, 2], np.int8), 6,
                   box=Box(10, 10), image=np.array([[0, 0], [-1, 1]], np.int8))
    f = io.StringIO()
    write_pairs_csv(f, res)
    assert f.getvalue() == "i,j,relation,certified_by,image_x,image_y,image_z\n0,5,tangent,float,0,0,0\n3,4,overlap,exact,-1,1,0\n"
    res.ids = np.array([10, 11, 12, 13, 14, 15])
    f = io.StringIO()
    write_pairs_csv(f, res, {"scale_lo": np.array([0.5, 1.0]), "scale_hi": np.array([0.75, 1.0]), "contained": np.array(["no", "A"])})
    assert f.getvalue().splitlines() == [
        "i,j,relation,certified_by,image_x,image_y,image_z,scale_lo,scale_hi,contained,id_i,id_j",
        "0,5,tangent,float,0,0,0,0.5,0.75,no,10,15", "3,4,overlap,exact,-1,1,0,1.0,1.0,A,13,14",
    ]
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "p.csv"
        p.write_text(f.getvalue())
        assert [a.tolist() for a in read_pairs_csv(p)] == [[0, 3], [5, 4], [1, 2]]


def test_read_bodies_keeps_parameters_and_errors(tmp_path):
    b = random_bodies(10, dim=2, seed=2)
    b.semi_axes[4, 0] = 0.0
    s = read_bodies(write_csv(tmp_path / "b.csv", b))
    assert s.dim == 2 and len(s) == 10 and list(s.errors) == [4] and np.isnan(s.Q[4]).all()
    assert np.array_equal(s.centers, b.centers) and s.where(4) == "body 4 (line 6)"


def test_contacts_command_runs_as_a_program(tmp_path):
    b = random_bodies(300, dim=3, seed=4)
    src = write_csv(tmp_path / "b.csv", b)
    r = subprocess.run(
        [sys.executable, "-m", "app", "contacts", str(src), "--out", str(tmp_path / "o.csv")],
        capture_output=True, text=True, cwd=ROOT, timeout=120, check=False,
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout == "" and "300 bodies" in r.stderr and "read 300 ellipsoids" in r.stderr
