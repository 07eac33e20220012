"""Benchmark of ``BodyIndex``: new bodies asked against an index (the Monte Carlo inner loop).

    python bench/bench_index.py                # 100,000 indexed ellipsoids, 10,000 new ones (~2 min)
    python bench/bench_index.py --quick        # 20,000 indexed, 2,000 new (a few seconds)
    python bench/bench_index.py --write        # also bench/results/index.json and bench/REPORT.md's rows

Bodies: :func:`bench.bodies_data.random_bodies` at packing fraction 0.3 (random centres,
orientations, semi-axes (1, U(0.5, 1), U(0.5, 1)) shuffled), indexed; the new bodies are drawn
the same way over the same region. Three spaces: open, a periodic cube, and a tilted periodic
box of the same volume (HOOMD tilt factors xy = 0.5, xz = 0.3, yz = -0.4). Columns: build (the
index, bounding spheres included), one new body per ``query`` call from Python (median and 90th
percentile wall time over the new bodies, and the median CPU time of the process), and in open
space the anchor measured in the same loop, call for call: a user's own lines,
``scipy.spatial.cKDTree.query_ball_point`` (radius: the largest semi-axis of the new body plus
the largest indexed one) then ``core.classify`` of the pairs found; a batch (all the new bodies
in one call; best of 3, wall and CPU time of the process); trial moves (``query(trial,
exclude=rows)`` with ``trial`` a :class:`core.Bodies` of random indexed rows moved by N(0, 0.1)
per coordinate, its matrices built in the call; best of 3: candidate pairs per second, and the CPU time of the process; and the
same moves given as matrices); one
accepted move (``update`` of one row, median); and the check: the pairs, relations, certifiers
and images of the batch and of the trial moves against :func:`core.contacts` on the union
(differences must be 0). Targets (issue 54): one query >= 2x faster than the cKDTree pipeline
(median against median), trial moves >= 1 M candidate pairs/s.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

from bench.bodies_data import random_bodies
from bench.render import published
from core import Bodies, BodyIndex, bodies_from_axes, classify, contacts, warm_up
from core.fixed.compiled import get_threads

TILT = (0.5, 0.3, -0.4)


def placed(n: int, side: float, space: str, seed: int) -> np.ndarray:
    """n random bodies filling the cube of the index's side (wrapped into the tilted cell)."""
    b = random_bodies(n, fraction=0.3, seed=seed)
    return bodies_from_axes(wrapped(b.centers * (side / b.side), side, space), b.semi_axes, b.orientations)


def wrapped(c: np.ndarray, side: float, space: str) -> np.ndarray:
    """Centres wrapped into the box's cell (the cube, or the tilted cell); open space: as they are."""
    if space == "box":
        return c - side * np.floor(c / side)
    if space == "tilted":
        H = cell(side)
        f = np.linalg.solve(H, c.T).T
        return (f - np.floor(f)) @ H.T
    return c


def cell(side: float) -> np.ndarray:
    xy, xz, yz = TILT
    return np.array([[side, xy * side, xz * side], [0, side, yz * side], [0, 0, side]])


def box_of(space: str, side: float) -> tuple[float, ...] | None:
    if space == "open":
        return None
    if space == "box":
        return (side, side, side)
    return (side, side, side, *TILT)


def differences(index_hits, Q: np.ndarray, Qnew: np.ndarray, box: tuple[float, ...] | None, exclude: np.ndarray | None = None) -> tuple[int, int]:
    """(pairs, differences) of the batch against contacts on the union (without the pairs (k, exclude[k]))."""
    N = len(Q)
    res = contacts(np.concatenate([Q, Qnew]), box=box)
    want = {}
    for k in np.flatnonzero((res.i < N) & (res.j >= N)).tolist():
        img = None if res.image is None else tuple((-res.image[k]).tolist())
        want[(int(res.j[k]) - N, int(res.i[k]))] = (int(res.relation[k]), int(res.certified_by[k]), img)
    if exclude is not None:
        want = {key: v for key, v in want.items() if key[1] != exclude[key[0]]}
    got = {}
    for k in range(len(index_hits)):
        img = None if index_hits.image is None else tuple(index_hits.image[k].tolist())
        got[(int(index_hits.i[k]), int(index_hits.j[k]))] = (int(index_hits.relation[k]), int(index_hits.certified_by[k]), img)
    return len(want), len(set(want.items()) ^ set(got.items()))


def anchor_one(tree, Q: np.ndarray, reach: float, c: np.ndarray, radius: float, q: np.ndarray) -> int:
    """The user's own lines for one new body: the centres within reach, then classify; pairs not separate."""
    idx = np.asarray(tree.query_ball_point(c, reach + radius), dtype=np.int64)
    rel = classify(Q[idx], np.broadcast_to(q, (idx.size, *q.shape)))
    return int(np.count_nonzero(rel))


def run(n: int, m: int, space: str) -> dict[str, float]:
    """Every figure of one space (see the module docstring)."""
    b = random_bodies(n, fraction=0.3, seed=1)
    side = b.side
    Q = placed(n, side, space, seed=1)
    new = random_bodies(m, fraction=0.3, seed=2)
    Qnew = placed(m, side, space, seed=2)
    box = box_of(space, side)
    t0 = time.perf_counter()
    index = BodyIndex(Q, box=box)
    build = time.perf_counter() - t0
    tree = None
    if space == "open":
        from scipy.spatial import cKDTree

        tree = cKDTree(b.centers * (side / b.side))
        reach = float(b.semi_axes.max())
        centres, radius = new.centers * (side / new.side), new.semi_axes.max(axis=1)
    index.query(Qnew[:50])  # warm
    wall, cpu, kd, same = [], [], [], 0
    for k in range(m):  # the index and the anchor call for call: the same load on both
        q = Qnew[k]
        w, c = time.perf_counter(), time.process_time()
        hits = index.query(q)
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
        if tree is not None:
            w = time.perf_counter()
            found = anchor_one(tree, Q, reach, centres[k], float(radius[k]), q)
            kd.append(time.perf_counter() - w)
            same += found == len(hits)
    batch, batch_cpu = [], []
    for _ in range(3):
        t, c = time.perf_counter(), time.process_time()
        hits = index.query(Qnew)
        batch.append(time.perf_counter() - t)
        batch_cpu.append(time.process_time() - c)
    pairs, diff = differences(hits, Q, Qnew, box)
    rng = np.random.default_rng(3)
    rows = rng.choice(n, size=m, replace=False)
    moved = wrapped(wrapped(b.centers[rows], side, space) + rng.normal(scale=0.1, size=(m, 3)), side, space)
    trial_wall, trial_cpu = [], []
    for _ in range(3):
        t, c = time.perf_counter(), time.process_time()
        trial = Bodies(moved, b.semi_axes[rows], b.orientations[rows])  # what a Monte Carlo code holds
        moves = index.query(trial, exclude=rows)
        trial_wall.append(time.perf_counter() - t)
        trial_cpu.append(time.process_time() - c)
    candidates = int(moves.counts["candidates"])
    trial_q = bodies_from_axes(moved, b.semi_axes[rows], b.orientations[rows])
    matrix_wall = []
    for _ in range(3):  # the same moves given as matrices: the query alone, without building them
        t = time.perf_counter()
        index.query(trial_q, exclude=rows)
        matrix_wall.append(time.perf_counter() - t)
    trial_pairs, trial_diff = differences(moves, Q, trial_q, box, rows)
    updates = []
    for k in rng.choice(n, size=min(2000, n), replace=False).tolist():
        q = Qnew[k % m]
        t = time.perf_counter()
        index.update([k], q)
        updates.append(time.perf_counter() - t)
    out: dict[str, float] = {
        "space": space,  # type: ignore[dict-item]
        "build_s": build,
        "one_us": 1e6 * float(np.median(wall)),
        "one_p90_us": 1e6 * float(np.percentile(wall, 90)),
        "one_cpu_us": 1e6 * float(np.median(cpu)),
        "batch_s": min(batch),
        "batch_cpu_s": min(batch_cpu),
        "trial_s": min(trial_wall),
        "trial_cpu_s": min(trial_cpu),
        "trial_candidates": candidates,
        "trial_rate": candidates / min(trial_wall),
        "trial_matrices_s": min(matrix_wall),
        "trial_matrices_rate": candidates / min(matrix_wall),
        "trial_pairs": trial_pairs,
        "update_us": 1e6 * float(np.median(updates)),
        "pairs": pairs,
        "found": len(hits),
        "differences": diff + trial_diff,
    }
    if kd:
        out |= {"anchor_us": 1e6 * float(np.median(kd)), "anchor_p90_us": 1e6 * float(np.percentile(kd, 90)), "anchor_same": same}
        out["speedup"] = out["anchor_us"] / out["one_us"]
    return out


HEAD = (
    "| space | build s | one query us | p90 us | cpu us | cKDTree + classify us | speedup | batch s | batch cpu s "
    "| trial moves s | trial cpu s | candidates | M candidates/s | as matrices: M candidates/s | update us | pairs | differences |"
)


def row(r: dict[str, float]) -> str:
    """One markdown row of the table."""
    anchor = f"{r['anchor_us']:.0f} | {r['speedup']:.1f}x" if "anchor_us" in r else "- | -"
    return (
        f"| {r['space']} | {r['build_s']:.2f} | {r['one_us']:.0f} | {r['one_p90_us']:.0f} | {r['one_cpu_us']:.0f} | {anchor} | "
        f"{r['batch_s']:.3f} | {r['batch_cpu_s']:.3f} | {r['trial_s']:.3f} | {r['trial_cpu_s']:.3f} | {r['trial_candidates']:,} | {r['trial_rate'] / 1e6:.2f} | {r['trial_matrices_rate'] / 1e6:.2f} | "
        f"{r['update_us']:.0f} | {r['pairs']:,} | {r['differences']} |"
    )


def targets(rows: list[dict[str, float]], n: int) -> list[str]:
    """The target rows of issue 54 item 5 (markdown)."""
    o = next(r for r in rows if "speedup" in r)
    worst = min(rows, key=lambda r: r["trial_rate"])
    diff = sum(int(r["differences"]) for r in rows)
    ok1, ok2 = o["speedup"] >= 2.0, worst["trial_rate"] >= 1e6
    each = ", ".join(f"{r['space']} {r['trial_rate'] / 1e6:.2f}" for r in rows)
    each_cpu = ", ".join(f"{r['space']} {r['trial_candidates'] / r['trial_cpu_s'] / 1e6:.2f}" for r in rows)
    each_q = ", ".join(f"{r['space']} {r['trial_matrices_rate'] / 1e6:.2f}" for r in rows)
    return [
        "| target | measured | verdict |",
        "|---|---|---|",
        f"| one new body against {n:,}: `BodyIndex.query` >= 2x faster than cKDTree.query_ball_point + classify (same run, median) "
        f"| {o['one_us']:.0f} us against {o['anchor_us']:.0f} us: {o['speedup']:.1f}x (same pairs in {o['anchor_same']:,} of "
        f"the queries) | {'met' if ok1 else 'missed'} |",
        f"| trial moves `query(Bodies, exclude=rows)` >= 1 M candidate pairs/s | worst {worst['trial_rate'] / 1e6:.2f} M/s "
        f"({worst['space']}); {each}; the same moves as matrices (no parameters to build): {each_q}; per CPU second of the "
        f"process (both threads counted, less sensitive to a loaded machine): {each_cpu} | {'met' if ok2 else 'missed'} |",
        f"| equal to `contacts` on the union | {diff} differences (batches and trial moves, all spaces) | {'met' if diff == 0 else 'missed'} |",
    ]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="small sizes (a few seconds)")
    p.add_argument("--write", action="store_true", help="write bench/results/index.json and render bench/REPORT.md")
    args = p.parse_args(argv)
    command = "python bench/bench_index.py" + (" --quick" if args.quick else "") + " --write"
    with published("index-quick" if args.quick else "index", command=command, write=args.write):
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    """Time the index in open space, a periodic cube and a tilted box; print the tables."""
    n, m = (20_000, 2_000) if args.quick else (100_000, 10_000)
    warm_up()
    load0 = " ".join(f"{x:.1f}" for x in os.getloadavg())
    title = f"{m:,} new ellipsoids against {n:,} indexed, packing fraction 0.3, {get_threads()} threads, load average {load0}"
    print(f"**BodyIndex: {title}**\n")
    print(HEAD)
    print("|" + "|".join("---" for _ in HEAD.split("|")[1:-1]) + "|")
    rows = []
    for space in ("open", "box", "tilted"):
        r = run(n, m, space)
        rows.append(r)
        print(row(r), flush=True)
    load1 = " ".join(f"{x:.1f}" for x in os.getloadavg())
    print("\n**Targets**\n")
    print("\n".join(targets(rows, n)))
    print(f"\nload average at the end {load1}")
    return 0 if sum(int(r["differences"]) for r in rows) == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
