"""Smoke test of bench/bench_sweep.py: tiny sets, zero misses, sampling misses grazing contacts, the
report section is written and survives a rerun of the full report (bench/report.py)."""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from bench import bench_sweep, report, static
from bench import datasets as D
from bench.sweep_data import concat, grazing_pairs, random_pairs, start_pairs


def test_pair_sets_know_their_answers():
    g = grazing_pairs(4, seed=2)
    assert all(isinstance(t, Fraction) and 0 < t < 1 for t in g.t_exact)
    assert start_pairs(2).t_exact == [0, 0]
    assert grazing_pairs(3, offset=2.0**-40).t_exact == [None] * 3
    assert grazing_pairs(3, offset=-(2.0**-40)).t_exact is None  # not known by construction
    both = concat(g, random_pairs(3, seed=1))
    assert both.centers0.shape == (14, 3) and (both.centers0[8:, 1] - both.centers0[:8, 1].max() > 100).all()


def test_correctness_rows_are_clean():
    for name, m in [("graze", grazing_pairs(3, seed=4)), ("random", random_pairs(6, rotate=True, seed=5))]:
        r = bench_sweep.correctness(name, m)
        assert (r["missed"], r["extra"], r["outside"], r["wrong"]) == (0, 0, 0, 0)
        assert r["float"] + r["exact"] == r["candidates"] >= r["meet"]


def test_sampling_misses_grazing_contacts():
    s = bench_sweep.sampling(grazing_pairs(5, seed=6), (10,))
    assert s["contacts"] == 5 and s["rows"][0]["missed"] >= 4  # a touch at a rational t* between samples


def test_report_section_is_written_and_kept(tmp_path, monkeypatch):
    path = tmp_path / "REPORT.md"
    path.write_text("# Benchmark report\n\nold body\n")
    monkeypatch.setattr(bench_sweep, "REPORT", path)
    bench_sweep.write_section(f"{bench_sweep.BEGIN}\n## Moving many bodies\nrun 1\n{bench_sweep.END}\n")
    bench_sweep.write_section(f"{bench_sweep.BEGIN}\n## Moving many bodies\nrun 2\n{bench_sweep.END}\n")
    text = path.read_text()
    assert text.count("## Moving many bodies") == 1 and "run 2" in text and "old body" in text
    # a full report rerun keeps the section
    st = static.run_static(quick=True, datasets=[D.random_pairs(2, 4, seed=1)], log=lambda s: None)
    out = report.write_report(st, None, None, outdir=tmp_path, command="pytest", info={}, profiles={}, seconds=1.0)
    assert "run 2" in out.read_text() and bench_sweep.BEGIN in out.read_text()


def test_sample_matrices_are_the_bodies_at_that_time():
    m = random_pairs(2, seed=3)
    from core.moving.linear import read_linear_motions
    from core.moving.motions import matrix_at_exact

    bodies, _ = read_linear_motions(*m.arguments())
    Q = bench_sweep.sample_at(bodies, 0.25)
    exact = matrix_at_exact(bodies.motion(1), "1/4")
    assert np.allclose(Q[1], np.array([[float(v) for v in row] for row in exact]), rtol=1e-12, atol=1e-12)
