"""``python -m app sweep START END --out EVENTS``: files in, certified first contacts out.

Goldens: the grazing constructions of bench/sweep_data.py (touch exactly at a known rational t*)
and the library call on the same parameters (the command line adds only files)."""

from __future__ import annotations

import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from app.bodyfiles import write_bodies_csv
from app.cli import main
from app.sweep_cli import EVENTS_HEADER, read_events_csv
from bench.sweep_data import grazing_pairs, random_pairs
from core import Relation, sweep_contacts

ROOT = Path(__file__).resolve().parent.parent


def write_pair(tmp_path: Path, m, *, dim: int = 3) -> tuple[Path, Path]:
    start, end = tmp_path / "start.csv", tmp_path / "end.csv"
    o0, o1 = m.orientations0, m.orientations1 if m.orientations1 is not None else m.orientations0
    if dim == 2:  # the files hold angles: theta = 2 atan2(z, w)
        o0 = np.array([2 * np.arctan2(q[3], q[0]) for q in np.atleast_2d(o0)]) if np.ndim(o0) == 2 else o0
        o1 = np.array([2 * np.arctan2(q[3], q[0]) for q in np.atleast_2d(o1)]) if np.ndim(o1) == 2 else o1
    write_bodies_csv(start, m.centers0, m.semi_axes, o0)
    write_bodies_csv(end, m.centers1, m.semi_axes, o1)
    return start, end


def test_sweep_command_writes_exact_brackets(tmp_path, capsys):
    m = grazing_pairs(6, seed=3)
    start, end = write_pair(tmp_path, m)
    out = tmp_path / "events.csv"
    assert main(["sweep", str(start), str(end), "--out", str(out)]) == 0
    assert out.read_text().splitlines()[0] == EVENTS_HEADER == "i,j,t_lo,t_hi,relation,certified_by,image_x,image_y,image_z"
    i, j, lo, hi, rel = read_events_csv(out)
    assert i.tolist() == [0, 2, 4, 6, 8, 10] and j.tolist() == [1, 3, 5, 7, 9, 11]
    assert (rel == Relation.TANGENT).all() and (hi - lo <= 1e-9).all()
    for k, t in enumerate(m.t_exact):
        assert Fraction(lo[k]) <= t <= Fraction(hi[k])  # exactly, after the round trip through the file
    text = capsys.readouterr().err  # messages on stderr; stdout carries only data
    assert "wrote 6 first contacts" in text and "certified by" in text
    assert not list(tmp_path.glob(".events.csv.*"))  # no temporary file left


def test_sweep_command_to_stdout(tmp_path, capsys):
    m = grazing_pairs(2, seed=4)
    start, end = write_pair(tmp_path, m)
    assert main(["sweep", str(start), str(end), "--out", "-", "--quiet"]) == 0
    captured = capsys.readouterr()
    lines = captured.out.splitlines()
    assert lines[0] == EVENTS_HEADER and len(lines) == 3 and captured.err == ""
    i, j, lo, hi, rel, by, *image = lines[1].split(",")  # pair 0
    assert by in ("float", "exact") and image == ["0", "0", "0"]
    assert Fraction(float(lo)) <= m.t_exact[0] <= Fraction(float(hi))


def test_sweep_command_equals_the_library(tmp_path):
    m = random_pairs(30, rotate=True, seed=4)
    start, end = write_pair(tmp_path, m)
    out = tmp_path / "ev.csv"
    assert main(["sweep", str(start), str(end), "--out", str(out), "--quiet"]) == 0
    want = sweep_contacts(*m.arguments())
    i, j, lo, hi, rel = read_events_csv(out)
    assert i.tolist() == want.i.tolist() and j.tolist() == want.j.tolist()
    assert lo.tolist() == want.t_lo.tolist() and hi.tolist() == want.t_hi.tolist() and rel.tolist() == want.relation.tolist()


def test_sweep_command_2d_and_box(tmp_path):
    c0 = np.array([[0.5, 5.0], [9.5, 5.0], [5.0, 5.0]])
    c1 = c0 + [[0.0, 0.0], [-0.25, 0.0], [0.0, 1.0]]
    r = np.array([[0.5, 0.5], [0.5, 0.5], [1.0, 0.5]])
    ang = np.zeros(3)
    write_bodies_csv(tmp_path / "s.csv", c0, r, ang)
    write_bodies_csv(tmp_path / "e.csv", c1, r, ang)
    out = tmp_path / "ev.csv"
    assert main(["sweep", str(tmp_path / "s.csv"), str(tmp_path / "e.csv"), "--out", str(out), "--box", "10,10", "--quiet"]) == 0
    i, j, lo, hi, rel = read_events_csv(out)
    assert (i.tolist(), j.tolist()) == ([0], [1])  # across the face x = 0 / 10: 1 + 0.25 t apart: touch at t = 0 only
    assert lo[0] == hi[0] == 0.0 and rel[0] == Relation.TANGENT


def test_sweep_command_unwraps_a_periodic_trajectory(tmp_path, capsys):
    # body 1 crosses the face x = 10 between the frames (stored wrapped, as simulations do)
    c0 = np.array([[9.0, 5.0, 5.0], [9.75, 5.0, 5.0], [5.0, 2.0, 5.0]])
    c1 = np.array([[9.0, 5.0, 5.0], [0.25, 5.0, 5.0], [5.0, 2.0, 5.0]])
    r = np.array([[0.5, 0.5, 0.5]] * 3)
    q = np.tile([1.0, 0.0, 0.0, 0.0], (3, 1))
    write_bodies_csv(tmp_path / "s.csv", c0, r, q)
    write_bodies_csv(tmp_path / "e.csv", c1, r, q)
    out = tmp_path / "ev.csv"
    assert main(["sweep", str(tmp_path / "s.csv"), str(tmp_path / "e.csv"), "--out", str(out), "--box", "10,10,10"]) == 0
    assert "1 bodies crossed a face" in capsys.readouterr().err
    i, j, lo, hi, rel = read_events_csv(out)
    assert (i.tolist(), j.tolist(), rel.tolist()) == ([0], [1], [Relation.OVERLAP])  # 0.75 apart at t = 0


def test_sweep_command_in_a_tilted_box_unwraps_along_the_box_vectors(tmp_path, capsys):
    """A tilted box (8, 8, 8, xy = 0.5: a2 = (4, 8, 0)): body 1 crosses the face y = 8 and is stored
    wrapped by a2. Unwrapped along a2 it moves from (5, 7.75, 4) to (5, 8.5, 4); its image -a2
    comes from y = -0.25 towards body 0 at (1, 1, 4): 1.25 - 0.75 t = 1, tangent at t* = 1/3
    exactly. (Unwrapping by whole sides, as in an orthogonal box, would move it 4 along x.)"""
    c0 = np.array([[1.0, 1.0, 4.0], [5.0, 7.75, 4.0]])
    c1 = np.array([[1.0, 1.0, 4.0], [1.0, 0.5, 4.0]])  # (5, 8.5, 4) - a2, as a simulation stores it
    r = np.array([[0.5, 0.5, 0.5]] * 2)
    q = np.tile([1.0, 0.0, 0.0, 0.0], (2, 1))
    write_bodies_csv(tmp_path / "s.csv", c0, r, q)
    write_bodies_csv(tmp_path / "e.csv", c1, r, q)
    out = tmp_path / "ev.csv"
    assert main(["sweep", str(tmp_path / "s.csv"), str(tmp_path / "e.csv"), "--out", str(out), "--box", "8,8,8,0.5,0,0"]) == 0
    assert "1 bodies crossed a face" in capsys.readouterr().err
    i, j, lo, hi, rel = read_events_csv(out)
    assert (i.tolist(), j.tolist(), rel.tolist()) == ([0], [1], [Relation.TANGENT])
    assert Fraction(lo[0]) <= Fraction(1, 3) <= Fraction(hi[0]) and hi[0] - lo[0] <= 1e-9


def test_sweep_command_errors(tmp_path, capsys):
    m = grazing_pairs(2, seed=1)
    start, end = write_pair(tmp_path, m)
    other = tmp_path / "other.csv"
    write_bodies_csv(other, m.centers1, m.semi_axes * 2, m.orientations1)
    assert main(["sweep", str(start), str(other), "--out", str(tmp_path / "x.csv")]) == 2
    assert "body 0 (line 2): the semi-axes differ" in capsys.readouterr().err
    short = tmp_path / "short.csv"
    write_bodies_csv(short, m.centers1[:3], m.semi_axes[:3], m.orientations1[:3])
    assert main(["sweep", str(start), str(short), "--out", str(tmp_path / "x.csv")]) == 2
    assert "END must hold the same bodies" in capsys.readouterr().err
    bad = tmp_path / "bad.csv"
    axes = m.semi_axes.copy()
    axes[2, 1] = -1.0
    write_bodies_csv(bad, m.centers0, axes, m.orientations0)
    write_bodies_csv(tmp_path / "bad_end.csv", m.centers1, axes, m.orientations1)
    args = ["sweep", str(bad), str(tmp_path / "bad_end.csv"), "--out", str(tmp_path / "x.csv")]
    assert main(args) == 2
    assert "body 2 (line 4)" in capsys.readouterr().err and not (tmp_path / "x.csv").exists()
    assert main([*args, "--on-invalid", "mark", "--quiet"]) == 0
    assert "invalid body 2 (line 4)" in capsys.readouterr().err
    i, j, *_ = read_events_csv(tmp_path / "x.csv")
    assert (i.tolist(), j.tolist()) == ([0], [1])  # pair 1 (bodies 2, 3) left out
    assert main(["sweep", str(start), str(tmp_path / "missing.csv"), "--out", str(tmp_path / "y.csv")]) == 2
    assert "cannot read" in capsys.readouterr().err


def test_events_file_round_trip(tmp_path):
    # three circles meeting at t = 1/3, 0.1 and at t = 0 (overlapping): brackets that are no short decimals
    from core import sweep_contacts

    res = sweep_contacts([[0, 0], [3, 0], [10, 0], [11.5, 0], [20, 0], [22.5, 0]],
                         [[0, 0], [0, 0], [10, 0], [11.5, 0], [20, 0], [21.5, 0]], [[1, 1]] * 6)
    with open(tmp_path / "e.csv", "w") as f:
        res.to_csv(f)
    i, j, lo, hi, rel = read_events_csv(tmp_path / "e.csv")
    assert len(lo) == 3 and lo.tolist() == res.t_lo.tolist() and hi.tolist() == res.t_hi.tolist()  # floats read back exactly
    assert rel.tolist() == res.relation.tolist() and (tmp_path / "e.csv").read_text().startswith(EVENTS_HEADER + "\n")
    with pytest.raises(ValueError, match="header"):
        (tmp_path / "bad.csv").write_text("a,b\n")
        read_events_csv(tmp_path / "bad.csv")


def test_sweep_command_progress_on_stderr(tmp_path):
    m = random_pairs(4, seed=2)
    start, end = write_pair(tmp_path, m)
    res = subprocess.run(
        [sys.executable, "-m", "app", "sweep", str(start), str(end), "--out", str(tmp_path / "e.csv")],
        cwd=ROOT, capture_output=True, text=True, timeout=300, check=False,
    )
    assert res.returncode == 0, res.stderr
    assert "read 8 moving ellipsoids" in res.stderr and "wrote" in res.stderr and res.stdout == ""


def test_sweep_command_method_exact(tmp_path, capsys):
    # --method exact: every pair certified by exact arithmetic, the same brackets' t* as adaptive
    m = grazing_pairs(3, seed=5)
    start, end = write_pair(tmp_path, m)
    out = tmp_path / "events.csv"
    assert main(["sweep", str(start), str(end), "--out", str(out), "--method", "exact", "--quiet"]) == 0
    rows = [line.split(",") for line in out.read_text().splitlines()[1:]]
    assert len(rows) == 3 and {r[5] for r in rows} == {"exact"}
    for r, t in zip(rows, m.t_exact, strict=True):
        assert Fraction(float(r[2])) <= t <= Fraction(float(r[3]))
    with pytest.raises(SystemExit) as e:  # no float-only sweep
        main(["sweep", str(start), str(end), "--out", str(out), "--method", "float"])
    assert e.value.code == 2 and "invalid choice: 'float'" in capsys.readouterr().err
