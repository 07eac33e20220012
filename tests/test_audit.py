"""``python -m app audit`` (issue 54.2): a certified check of a trajectory, against closed forms.

Spheres give exact truth: two spheres touch when their centres are r_i + r_j apart (dyadic numbers
here, so the file's floats are the exact values), and a straight-line step's first contact is the
root of a quadratic.
"""

from __future__ import annotations

import csv
import io
import subprocess
import sys
from fractions import Fraction

import numpy as np
import pytest

from app.audit_cli import frames_argument, header
from app.cli import main


def dump(path, frames, *, box=(10.0, 10.0, 10.0), boundary="pp pp pp", shuffle=None):
    """A LAMMPS dump of spheres: each frame a list of (id, x, y, z, radius), written in the given order."""
    with open(path, "w") as f:
        for step, rows in enumerate(frames):
            order = list(range(len(rows))) if shuffle is None else shuffle[step]
            f.write(f"ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{len(rows)}\nITEM: BOX BOUNDS {boundary}\n")
            f.write("".join(f"{-L / 2!r} {L / 2!r}\n" for L in box))
            f.write("ITEM: ATOMS id type x y z shapex shapey shapez\n")
            for k in order:
                i, x, y, z, r = rows[k]
                f.write(f"{i} 1 {x!r} {y!r} {z!r} {2 * r!r} {2 * r!r} {2 * r!r}\n")


def report(path) -> list[dict[str, str]]:
    return list(csv.DictReader(open(path)))


def frames_of_four(shift: float) -> list[list[tuple]]:
    """Frame 0: ids 1-2 tangent, ids 3-4 apart; frame 1: ids 3-4 overlap by ``shift``."""
    f0 = [(1, 0.0, 0.0, 0.0, 0.5), (2, 1.0, 0.0, 0.0, 0.5), (3, 0.0, 3.0, 0.0, 0.5), (4, 2.0, 3.0, 0.0, 0.5)]
    f1 = [(1, 0.0, 0.0, 0.0, 0.5), (2, 1.25, 0.0, 0.0, 0.5), (3, 0.0, 3.0, 0.0, 0.5), (4, 1.0 - shift, 3.0, 0.0, 0.5)]
    return [f0, f1]


def test_frames_argument():
    assert frames_argument(":") == slice(None, None) and frames_argument("2:") == slice(2, None)
    with pytest.raises(Exception, match="--frames takes A:B"):
        frames_argument("a:b")


def test_an_overlap_exits_3_and_is_listed_with_the_files_ids(tmp_path, capsys):
    dump(tmp_path / "run.dump", frames_of_four(2.0**-30), shuffle=[[3, 1, 0, 2], [2, 0, 3, 1]])  # any atom order
    assert main(["audit", str(tmp_path / "run.dump"), "--out", str(tmp_path / "r.csv"), "--jobs", "1"]) == 3
    err = capsys.readouterr().err
    assert "OVERLAP: 1 overlapping pairs; first: frame 1: bodies 2 (id 3) and 3 (id 4)" in err
    rows = report(tmp_path / "r.csv")
    assert list(rows[0]) == header(3, True).split(",")
    got = [(r["frame"], r["id_i"], r["id_j"], r["relation"], r["t_lo"], r["t_hi"]) for r in rows]
    assert got == [("0", "1", "2", "tangent", "", ""), ("1", "3", "4", "overlap", "", "")]  # ids sorted: rows by id


def test_tangent_pairs_are_no_violation(tmp_path, capsys):
    dump(tmp_path / "run.dump", [frames_of_four(0.0)[0]] * 3)
    assert main(["audit", str(tmp_path / "run.dump"), "--out", str(tmp_path / "r.csv"), "--jobs", "1"]) == 0
    assert "no pair overlaps" in capsys.readouterr().err
    assert [r["frame"] for r in report(tmp_path / "r.csv")] == ["0", "1", "2"]


def test_between_lists_first_contacts_across_a_face_with_their_image(tmp_path):
    """Spheres of radius 1/4: id 7 crosses the face x = 5 (4.75 -> -4.75 wrapped: +0.5), id 9 stands at (-5, 1/2),
    whose image (5, 1/2) it grazes at t = 1/2 (distance 1/2 = the radii); both frames are apart."""
    f0 = [(7, 4.75, 0.0, 0.0, 0.25), (9, -5.0, 0.5, 0.0, 0.25)]
    f1 = [(7, -4.75, 0.0, 0.0, 0.25), (9, -5.0, 0.5, 0.0, 0.25)]
    dump(tmp_path / "run.dump", [f0, f1])
    out = tmp_path / "r.csv"
    assert main(["audit", str(tmp_path / "run.dump"), "--out", str(out), "--between", "--jobs", "1"]) == 0
    (step,) = report(out)
    assert (step["frame"], step["id_i"], step["id_j"], step["image_x"], step["relation"]) == ("0", "7", "9", "1", "tangent")
    assert Fraction(step["t_lo"]) <= Fraction(1, 2) <= Fraction(step["t_hi"]) and step["certified_by"] in ("float", "exact")
    assert main(["audit", str(tmp_path / "run.dump"), "--out", str(out), "--jobs", "1"]) == 0 and report(out) == []


def test_2d_folder_of_frames_has_no_image_z_and_frames_slice(tmp_path):
    folder = tmp_path / "frames"
    folder.mkdir()
    for k in range(12):
        x = 1.0 + 0.125 * k  # body 1 comes closer: tangent at k = 8 (x = 2), overlapping after
        (folder / f"f{k}.csv").write_text(f"x,y,a,b,angle\n0,0,1,1,0\n{x!r},0,1,1,0\n")
    out = tmp_path / "r.csv"
    assert main(["audit", str(folder), "--out", str(out), "--box", "20,20", "--frames", "2:12", "--jobs", "1"]) == 3
    rows = report(out)
    assert list(rows[0]) == header(2, False).split(",")
    assert [(r["frame"], r["relation"]) for r in rows] == [(str(k), "overlap") for k in range(2, 8)] + [("8", "tangent")]
    glob = main(["audit", str(folder / "f1*.csv"), "--out", str(out), "--box", "20,20", "--jobs", "1"])
    assert glob == 3 and [(r["frame"], r["relation"]) for r in report(out)] == [("0", "overlap")]  # f1, f10, f11


def test_a_bad_body_is_exit_2_naming_the_frame(tmp_path, capsys):
    frames = frames_of_four(0.0)
    frames[1][2] = (3, float("nan"), 3.0, 0.0, 0.5)
    dump(tmp_path / "run.dump", frames)
    assert main(["audit", str(tmp_path / "run.dump"), "--out", str(tmp_path / "r.csv"), "--jobs", "1"]) == 2
    err = capsys.readouterr().err
    assert "run.dump: frame 1: body 2 (id 3)" in err and not (tmp_path / "r.csv").exists()


def test_worker_processes_give_the_same_report_as_one(tmp_path):
    rng = np.random.default_rng(3)
    c = rng.uniform(-5, 5, (300, 3))
    frames = []
    for _ in range(6):
        c = c + rng.uniform(-0.2, 0.2, c.shape)
        c = c - 10 * np.floor(c / 10 + 0.5)  # wrapped
        frames.append([(k + 1, *c[k].tolist(), 0.4) for k in range(300)])
    dump(tmp_path / "run.dump", frames)
    one, two = tmp_path / "one.csv", tmp_path / "two.csv"
    rc1 = main(["audit", str(tmp_path / "run.dump"), "--out", str(one), "--between", "--jobs", "1", "--quiet"])
    rc2 = main(["audit", str(tmp_path / "run.dump"), "--out", str(two), "--between", "--jobs", "2", "--quiet"])
    assert rc1 == rc2 == 3 and one.read_text() == two.read_text() and len(report(one)) > 20


def test_the_command_streams_to_stdout_with_a_summary_on_stderr(tmp_path):
    dump(tmp_path / "run.dump", frames_of_four(0.0))
    done = subprocess.run([sys.executable, "-m", "app", "audit", str(tmp_path / "run.dump"), "--out", "-", "--jobs", "1"],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    rows = list(csv.DictReader(io.StringIO(done.stdout)))
    assert [r["relation"] for r in rows] == ["tangent", "tangent"] and "audited 2 frames of 4 ellipsoids" in done.stderr


@pytest.mark.dask
def test_frames_spread_over_a_dask_cluster_give_the_same_report(tmp_path):
    distributed = pytest.importorskip("distributed")
    frames = [frames_of_four(0.0)[0], frames_of_four(2.0**-30)[1], frames_of_four(0.0)[0]]
    dump(tmp_path / "run.dump", frames)
    here, there = tmp_path / "here.csv", tmp_path / "there.csv"
    assert main(["audit", str(tmp_path / "run.dump"), "--out", str(here), "--between", "--jobs", "1", "--quiet"]) == 3
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        rc = main(["audit", str(tmp_path / "run.dump"), "--out", str(there), "--between", "--scheduler", cluster.scheduler_address, "--quiet"])
    assert rc == 3 and there.read_text() == here.read_text()


def test_a_gap_of_1e_12_far_from_the_origin_is_a_gap(tmp_path):
    """The file's numbers are the bodies: semi-axes (1/8, 4, 1/8) and (2, 4, 1/4) touch across the plane
    x = 320.125 when 2.125 apart along x; moved 2^-40 apart they are separate, 2^-40 closer they overlap.
    (Float matrices of these bodies, 320 from the origin, round their constant terms by more than 2^-40.)"""
    d = 2.0**-40
    for shift, rc, relations in ((d, 0, []), (0.0, 0, ["tangent"]), (-d, 3, ["overlap"])):
        x = 322.125 + shift
        (tmp_path / "f.csv").write_text("x,y,z,a,b,c,qw,qx,qy,qz\n"
                                        f"320,440,480,0.125,4,0.125,1,0,0,0\n{x!r},440,480,2,4,0.25,1,0,0,0\n")
        assert main(["audit", str(tmp_path / "f.csv"), "--out", str(tmp_path / "r.csv"), "--jobs", "1", "--quiet"]) == rc
        assert [r["relation"] for r in report(tmp_path / "r.csv")] == relations, shift
