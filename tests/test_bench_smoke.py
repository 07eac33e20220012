"""Smoke test of the benchmarks (bench/): tiny sizes, table and report structure, zero wrong labels.

Not a timing test: it checks that each benchmark runs end to end, that the project's float /
adaptive / exact methods report no wrong label against the independent oracle, that the report
has its sections, and the baseline criterion on hand-checked circles.
"""

from __future__ import annotations

import doctest
import math

import numpy as np
import pytest

import bench  # noqa: F401
from bench import datasets as D
from bench import moving, report, scene_cost, static


def circle(x: float, r: float = 1.0) -> list[list[float]]:
    return [[1.0, 0.0, -x], [0.0, 1.0, 0.0], [-x, 0.0, x * x - r * r]]


def test_doctests_of_bench_modules():
    for mod in (D, static, moving):
        res = doctest.testmod(mod, optionflags=doctest.NORMALIZE_WHITESPACE)
        assert res.failed == 0, mod.__name__


def test_eig_baseline_on_hand_checked_circles():
    # unit circles at centre distance 3 (apart), 2 (touching), 1 (crossing), 0.5 inside radius 2
    A = np.array([circle(0), circle(0), circle(0), circle(0, 2.0)])
    B = np.array([circle(3), circle(2), circle(1), circle(0.5)])
    assert static.classify_eig(A, B, tol=1e-6).tolist() == [0, 1, 2, 2]
    # with the default 1e-9 the double eigenvalue -1 of the touching pair splits (by ~4e-8): separate
    assert static.classify_eig(A, B).tolist() == [0, 0, 2, 2]


def test_datasets_are_labelled_independently():
    ds = D.tangent_pairs(3, 4, seed=3)
    assert ds.truth.tolist() == [1, 1, 1, 1]  # exactly tangent by construction
    far = D.near_tangent_pairs(2, 4, gap=1e-3, sign=1, seed=1)
    into = D.near_tangent_pairs(2, 4, gap=1e-3, sign=-1, seed=1)
    assert far.truth.tolist() == [0] * 4 and into.truth.tolist() == [2] * 4
    assert D.is_valid_exact(np.array(circle(0))) and not D.is_valid_exact(-np.eye(3))
    with pytest.raises(ValueError, match="dim"):
        D.random_pairs(4, 3)


@pytest.fixture(scope="module")
def static_out():
    dsets = [
        D.random_pairs(2, 30, seed=5),
        D.random_pairs(3, 30, seed=5),
        D.tangent_pairs(2, 4, seed=5),
        D.tangent_pairs(3, 4, seed=5),
        D.near_tangent_pairs(3, 6, gap=1e-14, sign=1, seed=5),
        D.near_tangent_pairs(2, 6, gap=1e-14, sign=-1, seed=5),
        D.extreme_pairs(3, 6, kind="scaled-1e150", seed=5),
        D.extreme_pairs(2, 6, kind="centres-1e6", seed=5),
    ]
    return static.run_static(quick=True, datasets=dsets, log=lambda s: None)


def test_static_no_wrong_labels_for_project_methods(static_out):
    res = static_out["results"]
    for m in ("float", "adaptive", "exact", "numpy-eig"):
        assert {r.dataset for r in res if r.method == m} >= {"random 2D", "random 3D", "tangent 2D", "tangent 3D"}
    for r in res:
        assert r.n > 0 and r.pairs_per_s > 0 and math.isfinite(r.pairs_per_s)
        if r.method in ("float", "adaptive", "exact"):
            assert r.wrong == 0, (r.dataset, r.method)
        if r.method in ("adaptive", "exact"):
            assert r.undecided == 0
    tan = [r for r in res if r.family == "tangent" and r.method == "adaptive"]
    assert all(r.escalated == r.n for r in tan)  # a float filter can never certify tangency


def test_static_tables(static_out):
    table = static.format_table(static_out["results"])
    lines = table.splitlines()
    assert lines[0].startswith("| data set | method | pairs | pairs/s | wrong")
    assert any(line.startswith("| random 3D | adaptive |") for line in lines)
    assert any(line.startswith("| near + (all gaps) 3D | float |") for line in lines)
    gaps = static.format_gap_table(static_out["results"], 3)
    assert "| +1e-14 |" in gaps


def test_moving_sampling_misses_a_touch_and_analysis_checks_out():
    from core import analyse
    from core.moving.presets import preset_arguments

    args = preset_arguments("example-31")  # touch and leave at t = 4
    res = analyse(args["A_t"], args["B_t"], args["interval"])
    s = moving.compare_sampling(args, res, 100, wrong_check=20)
    assert s["events"] == 1 and s["found"] == 0 and s["missed"] == ["touch at 4"]
    chk = moving.check_analysis(args, res, points=2)
    assert chk["failures"] == [] and chk["checked"] >= 3
    graze = D.grazing_motion(3, seed=2)
    res = analyse(graze["A_t"], graze["B_t"], graze["interval"])
    assert [(e.kind, float(e)) for e in res.events] == [("touch", 0.0)]
    double = D.grazing_motion(2, depth="1/100", seed=2)
    res = analyse(double["A_t"], double["B_t"], double["interval"])
    assert [e.kind for e in res.events] == ["change", "change"]
    s = moving.compare_sampling(double, res, 1000, wrong_check=50)
    assert s["found"] == 2 and s["max_err"] <= s["h"] / 2 + 1e-12 and s["wrong"] == 0
    assert moving.check_analysis(double, res, points=2)["failures"] == []


def test_scene_cost_and_report(tmp_path, static_out):
    sc = scene_cost.run_scene_cost(quick=True, presets=("example-29",), repeats=5, cross_check=False, log=lambda s: None)
    kinds = [r["kind"] for r in sc["rows"]]
    assert kinds.count("drag") == 2 and kinds.count("t-step") == 4
    assert all(r["analyses"] == 0 for r in sc["rows"])  # t-steps and drags never re-run the analysis
    assert all(r["messages"] > 0 and r["median_ms"] > 0 for r in sc["rows"])
    mv = {"cases": [], "sizes": [10, 100], "degree": [{"trans": 1, "rot": 0, "skipped": "test"}]}
    path = report.write_report(static_out, mv, sc, outdir=tmp_path, command="pytest", info=report.machine_info(),
                               profiles={}, seconds=1.0)
    text = path.read_text()
    for section in ("## Machine", "## Targets", "## Reading", "## Static pairs", "## Moving shapes", "## Scene"):
        assert section in text
    assert "zero wrong labels everywhere" in text and "**VIOLATED**" not in text
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return
    assert (tmp_path / "figures" / "static_tradeoff.png").stat().st_size > 1000


def test_api_load_runs_end_to_end_and_reports():
    """bench/api_load.py against the real server, tiny sizes: every request answered, rows written."""
    from bench import api_load

    d = api_load.run_api_load(quick=True, batch_pairs=20, concurrency=4, per_client=3, log=lambda s: None)
    assert d["batch_2d"]["pairs"] == 20 and d["batch_3d"]["pairs"] == 20
    assert d["concurrency"]["requests"] == 12
    c = d["concurrency"]
    assert 0 < c["p50_ms"] <= c["p99_ms"] <= c["max_ms"]
    table = api_load.format_api(d)
    assert "API batch of 20 ellipse pairs" in table and "single-pair classify at concurrency 4 (12 requests)" in table
    rows = report.targets({"results": []}, None, d)
    assert [r[0].split(" (")[0].split(":")[0] for r in rows[-2:]] == ["API batch of 20 pairs", "single-pair classify at concurrency 4"]


def test_bench_bodies_runs_and_misses_nothing():
    from bench import bench_bodies

    row = bench_bodies.run(3000, fraction=0.3, periodic=True)
    assert row["candidates"] >= row["contacts"] > 0 and row["float"] + row["exact"] == row["candidates"]
    assert bench_bodies.brute_force_check(600, fraction=0.3)[1:] == (0, 0)
    lat = bench_bodies.lattice(4)
    assert lat["tangent"] == lat["exact"] == 3 * 16 * 3


def test_throughput_section_and_rows_replace_the_old_ones(tmp_path):
    from bench import throughput

    rows = [{"kind": "random", "dim": d, "all": 30e6, "one": 20e6, "baseline": 10e6, "read": 40e6, "f32_one": 22e6,
             "f32_all": 33e6, "baseline_right": 1.0, "f32_right": 1.0, "cores": 2,
             "cpu": {"certified": 25e6, "baseline": 12e6, "read": 50e6, "float32": 27e6}} for d in (3, 2)]
    tp = {"rows": rows, "structured": [{"name": "spheres 3D", "dim": 3, "n": 10, "rate": 15e6, "ratio": 0.5, "escalated": 0, "wrong": 0},
                                       {"name": "spheres 2D", "dim": 2, "n": 10, "rate": 25e6, "ratio": 0.9, "escalated": 0, "wrong": 0},
                                       {"name": "numpy-built 3D", "dim": 3, "n": 10, "rate": 12e6, "ratio": 0.4, "escalated": 0, "wrong": 0}],
          "hard": [{"name": "big-small +0.001 3D", "n": 10, "undecided": 0, "wrong": 0}],
          "first_call": {"pairs": 400, "import": 0.5, "first": 0.011, "second": 0.01, "ratio": 1.1, "variant": "avx2"},
          "size": 1000, "cores": 2, "variant": "avx2", "variants": ["baseline", "avx2"], "rounds": 3}
    report = tmp_path / "REPORT.md"
    report.write_text("# r\n\n## Targets\n\n| target | measured | verdict |\n|---|---|---|\n| other | x | met |\n"
                      "| cold start: kernels ready | 1 s | met |\n\n## Reading\n\n- a\n\n"
                      f"{throughput._SECTION}\n\nold tables\n\n## Static pairs\n\nkept\n")
    throughput.write_section(tp, report, command="test")
    text = report.read_text()
    assert "old tables" not in text and "cold start: kernels ready" not in text
    assert "| other | x | met |" in text and "## Static pairs\n\nkept" in text
    assert "2.00x (avx2 variant); by CPU time 2.08x | met |" in text
    assert "| first classify of 400 pairs in a fresh process" in text
    assert text.index("| first classify") < text.index("## Reading")
    throughput.write_section(tp, report, command="test")  # again: the rows are replaced, not added
    assert report.read_text().count("| first classify of 400 pairs") == 1


def test_stage_timer_finds_every_stage_boundary_of_the_block_driver():
    """bench.stage_cycles puts a time stamp before each of its marks in core/fixed/_blocks.h: every
    mark is there once, in the order of the stages (a reordered or renamed stage breaks the table)."""
    from bench import stage_cycles

    text = (stage_cycles.FIXED / "_blocks.h").read_text()
    body = text[text.index("int64_t CLASSIFY("):]
    places = [body.find("        " + mark) for mark in stage_cycles.MARKS]
    assert all(p >= 0 for p in places), [m for m, p in zip(stage_cycles.MARKS, places, strict=True) if p < 0]
    assert places == sorted(places)
    assert all(body.count("        " + mark) == 1 for mark in stage_cycles.MARKS)
    assert len(stage_cycles.STAGES) == len(stage_cycles.MARKS) - 1
