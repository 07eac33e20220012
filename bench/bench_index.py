"""Benchmark of ``BodyIndex``: new bodies asked against an index (the Monte Carlo inner loop).

    python bench/bench_index.py            # 100,000 indexed ellipsoids, 10,000 new ones (~1 min)
    python bench/bench_index.py --quick    # 20,000 indexed, 2,000 new (a few seconds)

Bodies: :func:`bench.bodies_data.random_bodies` at packing fraction 0.3 (random centres,
orientations, semi-axes (1, U(0.5, 1), U(0.5, 1)) shuffled), indexed; the new bodies are drawn
the same way over the same region. Three spaces: open, a periodic cube, and a tilted periodic
box of the same volume (HOOMD tilt factors xy = 0.5, xz = 0.3, yz = -0.4). Columns: build (the
index, bounding spheres included), one new body per ``query`` call from Python (median and 90th
percentile wall time over the new bodies, and the median CPU time of the process: the machine is
shared, so wall times carry other jobs' load), a batch (all the new bodies in one call; best
of 3, wall and CPU time of the process: its two threads' CPU seconds add up), one accepted move (``update`` of one row, median), and the check: the batch's pairs,
relations, certifiers and images against :func:`core.contacts` on the union (differences must
be 0). Targets: one query <= 200 us (median), a batch of 10,000 <= 0.2 s.
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
from core import BodyIndex, bodies_from_axes, contacts, warm_up
from core.fixed.compiled import get_threads

TILT = (0.5, 0.3, -0.4)


def placed(n: int, side: float, space: str, seed: int) -> np.ndarray:
    """n random bodies filling the cube of the index's side (wrapped into the tilted cell)."""
    b = random_bodies(n, fraction=0.3, seed=seed)
    c = b.centers * (side / b.side)
    if space == "tilted":
        H = cell(side)
        f = np.linalg.solve(H, c.T).T
        c = (f - np.floor(f)) @ H.T
    return bodies_from_axes(c, b.semi_axes, b.orientations)


def cell(side: float) -> np.ndarray:
    xy, xz, yz = TILT
    return np.array([[side, xy * side, xz * side], [0, side, yz * side], [0, 0, side]])


def box_of(space: str, side: float) -> tuple[float, ...] | None:
    if space == "open":
        return None
    if space == "box":
        return (side, side, side)
    return (side, side, side, *TILT)


def differences(index_hits, Q: np.ndarray, Qnew: np.ndarray, box: tuple[float, ...] | None) -> tuple[int, int]:
    """(pairs, differences) of the batch against contacts on the union."""
    N = len(Q)
    res = contacts(np.concatenate([Q, Qnew]), box=box)
    want = {}
    for k in np.flatnonzero((res.i < N) & (res.j >= N)).tolist():
        img = None if res.image is None else tuple((-res.image[k]).tolist())
        want[(int(res.j[k]) - N, int(res.i[k]))] = (int(res.relation[k]), int(res.certified_by[k]), img)
    got = {}
    for k in range(len(index_hits)):
        img = None if index_hits.image is None else tuple(index_hits.image[k].tolist())
        got[(int(index_hits.i[k]), int(index_hits.j[k]))] = (int(index_hits.relation[k]), int(index_hits.certified_by[k]), img)
    return len(want), len(set(want.items()) ^ set(got.items()))


def run(n: int, m: int, space: str) -> dict[str, float]:
    b = random_bodies(n, fraction=0.3, seed=1)
    side = b.side
    Q = placed(n, side, space, seed=1)
    Qnew = placed(m, side, space, seed=2)
    box = box_of(space, side)
    t0 = time.perf_counter()
    index = BodyIndex(Q, box=box)
    build = time.perf_counter() - t0
    index.query(Qnew[:50])  # warm
    wall, cpu = [], []
    for k in range(m):
        q = Qnew[k]
        w, c = time.perf_counter(), time.process_time()
        index.query(q)
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
    batch, batch_cpu = [], []
    for _ in range(3):
        t, c = time.perf_counter(), time.process_time()
        hits = index.query(Qnew)
        batch.append(time.perf_counter() - t)
        batch_cpu.append(time.process_time() - c)
    pairs, diff = differences(hits, Q, Qnew, box)
    rng = np.random.default_rng(3)
    moves = []
    for k in rng.choice(n, size=min(2000, n), replace=False).tolist():
        new = Qnew[k % m]
        t = time.perf_counter()
        index.update([k], new)
        moves.append(time.perf_counter() - t)
    return {
        "build": build,
        "one": float(np.median(wall)),
        "one90": float(np.percentile(wall, 90)),
        "cpu": float(np.median(cpu)),
        "batch": min(batch),
        "batch_cpu": min(batch_cpu),
        "update": float(np.median(moves)),
        "pairs": pairs,
        "found": len(hits),
        "diff": diff,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="small sizes (a few seconds)")
    p.add_argument("--write", action="store_true", help="write bench/results/index.json and render bench/REPORT.md")
    args = p.parse_args(argv)
    command = "python bench/bench_index.py" + (" --quick" if args.quick else "") + " --write"
    with published("index", command=command, write=args.write):
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    """Time the index in open space, a periodic cube and a tilted box; print the table."""
    n, m = (20_000, 2_000) if args.quick else (100_000, 10_000)
    warm_up()
    load = " ".join(f"{x:.1f}" for x in os.getloadavg())
    print(f"# BodyIndex: {m:,} new ellipsoids against {n:,} indexed, packing fraction 0.3, {get_threads()} threads, load average {load}")
    head = (
        f"| {'space':>6} | {'build s':>7} | {'one query us':>12} | {'p90 us':>7} | {'cpu us':>6} | "
        f"{'batch s':>7} | {'batch cpu s':>11} | {'update us':>9} | {'pairs':>6} | {'differences':>11} |"
    )
    print(head)
    print("|" + "|".join("-" * len(c) for c in head.split("|")[1:-1]) + "|")
    worst = {"one": 0.0, "batch": 0.0, "diff": 0}
    for space in ("open", "box", "tilted"):
        r = run(n, m, space)
        print(
            f"| {space:>6} | {r['build']:7.2f} | {1e6 * r['one']:12.0f} | {1e6 * r['one90']:7.0f} | {1e6 * r['cpu']:6.0f} | "
            f"{r['batch']:7.3f} | {r['batch_cpu']:11.3f} | {1e6 * r['update']:9.0f} | {r['pairs']:>6,} | {r['diff']:>11} |",
            flush=True,
        )
        worst = {"one": max(worst["one"], r["one"]), "batch": max(worst["batch"], r["batch"]), "diff": worst["diff"] + r["diff"]}
    load = " ".join(f"{x:.1f}" for x in os.getloadavg())
    print(f"\none query: worst median {1e6 * worst['one']:.0f} us (target <= 200 us); batch of {m:,}: worst {worst['batch']:.3f} s (target <= 0.2 s for 10,000)")
    print(f"differences from contacts on the union: {worst['diff']} (must be 0); load average at the end {load}")
    return 0 if worst["diff"] == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
