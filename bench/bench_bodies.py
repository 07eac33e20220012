"""Benchmark of the contact search among N ellipsoids (``core.contacts``): time, scaling, misses.

    python bench/bench_bodies.py            # N = 62.5k, 250k, 1M at packing fraction 0.3 (~1 min)
    python bench/bench_bodies.py --quick    # N = 15.6k, 62.5k (a few seconds)
    python -m bench.bench_bodies --write    # also write the contacts section of bench/REPORT.md

Bodies: :func:`bench.bodies_data.random_bodies` (uniform random centres in a cube sized for the
packing fraction, random orientations, semi-axes (1, U(0.5, 1), U(0.5, 1)) shuffled; overlaps
allowed: a benchmark of the search, not a packing generator). Columns: build (the matrices from
the parameters), bounds (certified bounding spheres), broad (grids and sphere tests), narrow
(certified classify of the candidates), contacts (the whole ``contacts`` call: the first call
at that size in the process), total (build + contacts), candidate pairs, contacts, and how the
candidates were certified (float filter / exact arithmetic). Then the 4x scaling ratio of the
last two sizes; the uncertified pipeline a user would otherwise write beside ``contacts`` (best
of 3, interleaved); and a brute-force check (every pair classified) on a smaller set: missed
and extra pairs.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

from bench.bodies_data import random_bodies
from core import bodies_from_axes, classify, contacts, warm_up
from core.fixed.compiled import get_threads

REPORT = Path(__file__).with_name("REPORT.md")
BEGIN, END = "<!-- bodies:begin -->", "<!-- bodies:end -->"
TARGET_SECONDS = 2.0
"""Issue 24.5: ``contacts`` on 1 M random ellipsoids (packing fraction 0.3) within 2 s."""


def run(n: int, *, fraction: float, periodic: bool, seed: int = 0) -> dict[str, float]:
    """One search; returns the row of the table."""
    b = random_bodies(n, fraction=fraction, seed=seed)
    t0 = time.perf_counter()
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    t1 = time.perf_counter()
    res = contacts(Q, box=(b.side,) * 3 if periodic else None)
    t2 = time.perf_counter()
    return {
        "n": n,
        "build": t1 - t0,
        "bounds": res.seconds["bounds"],
        "broad": res.seconds["broad"],
        "narrow": res.seconds["narrow"],
        "search": t2 - t1,
        "total": t2 - t0,
        "candidates": res.counts["candidates"],
        "contacts": len(res),
        "float": res.counts["float"],
        "exact": res.counts["exact"],
    }


def pipeline_row(n: int, *, fraction: float, seed: int = 0) -> dict[str, float]:
    """The pipeline a user would otherwise write, beside ``contacts``: uncertified, same bodies.

    scipy's ``cKDTree.query_pairs`` on bounding spheres (centre, largest semi-axis; one thread),
    the pairs whose spheres meet, then the paper's tree in plain C without any error bound
    (``bench/baseline_tree.c``, one thread) on those candidates. Times include building the
    matrices in both (the same routine). Returns both times and contact counts.
    """
    from scipy.spatial import cKDTree

    from bench import baseline

    b = random_bodies(n, fraction=fraction, seed=seed)
    baseline.build()
    certified = pipeline = search = cpu = float("inf")
    for _ in range(3):  # best of 3 each, interleaved (shared machine)
        t0 = time.perf_counter()
        Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
        t1, c1 = time.perf_counter(), time.process_time()
        res = contacts(Q)
        certified = min(certified, time.perf_counter() - t0)
        search = min(search, time.perf_counter() - t1)
        cpu = min(cpu, time.process_time() - c1)
        t0 = time.perf_counter()
        Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
        r = b.semi_axes.max(axis=1)
        pairs = cKDTree(b.centers).query_pairs(2 * float(r.max()), output_type="ndarray")
        i, j = pairs[:, 0], pairs[:, 1]
        d2 = ((b.centers[i] - b.centers[j]) ** 2).sum(axis=1)
        keep = d2 <= (r[i] + r[j]) ** 2
        i, j = i[keep], j[keep]
        codes = baseline.baseline_codes(Q[i], Q[j])
        pipeline = min(pipeline, time.perf_counter() - t0)
    return {"n": n, "certified": certified, "search": search, "cpu": cpu, "pipeline": pipeline, "contacts": len(res),
            "pipeline_contacts": int(np.count_nonzero(codes != 0)), "candidates": int(i.size)}


def brute_force_check(n: int, *, fraction: float) -> tuple[int, int, int]:
    """(pairs found, missed, extra) against classifying every pair (open space)."""
    b = random_bodies(n, fraction=fraction, seed=11)
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    got = contacts(Q)
    i, j = np.triu_indices(n, 1)
    found = set(zip(got.i.tolist(), got.j.tolist(), strict=True))
    truth: set[tuple[int, int]] = set()
    step = 1 << 21
    for s in range(0, i.size, step):
        a, c = i[s : s + step], j[s : s + step]
        rel = classify(Q[a], Q[c])
        keep = rel != 0
        truth.update(zip(a[keep].tolist(), c[keep].tolist(), strict=True))
    return len(found), len(truth - found), len(found - truth)


def lattice(n: int) -> dict[str, float]:
    """Touching unit-diameter spheres on an n x n x n lattice: every neighbour pair is tangent,
    which only exact arithmetic certifies (the exact path's cost per pair)."""
    c = np.array(np.meshgrid(*(np.arange(n, dtype=float),) * 3, indexing="ij")).reshape(3, -1).T
    Q = bodies_from_axes(c, np.full_like(c, 0.5))
    t0 = time.perf_counter()
    res = contacts(Q)
    t = time.perf_counter() - t0
    assert res.counts["tangent"] == 3 * n * n * (n - 1)
    return {"n": len(c), "total": t, "tangent": res.counts["tangent"], "exact": res.counts["exact"]}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="small sizes (a few seconds)")
    p.add_argument("--fraction", type=float, default=0.3, help="packing fraction (default 0.3)")
    p.add_argument("--periodic", action="store_true", help="also run every size in a periodic box")
    p.add_argument("--write", action="store_true", help="write bench/results/bodies.json and render bench/REPORT.md")
    args = p.parse_args(argv)
    sizes = [15_625, 62_500] if args.quick else [62_500, 250_000, 1_000_000]
    started, load = time.time(), os.getloadavg()
    warm_up()
    out: list[str] = []

    def say(line: str = "") -> None:
        print(line, flush=True)
        out.append(line)

    say(f"# contacts among N ellipsoids, packing fraction {args.fraction}, {get_threads()} threads, load average {load[0]:.1f}")
    head = (
        f"| {'N':>9} | box | {'build':>6} | {'bounds':>6} | {'broad':>6} | {'narrow':>6} | {'contacts':>8} | {'total':>6} | "
        f"{'candidates':>10} | {'contacts':>9} | {'float':>9} | {'exact':>5} |"
    )
    say(head)
    say("|" + "|".join("-" * (len(c)) for c in head.split("|")[1:-1]) + "|")
    rows = []
    for periodic in (False, True) if args.periodic else (False,):
        for n in sizes:
            r = run(n, fraction=args.fraction, periodic=periodic)
            rows.append((periodic, r))
            say(
                f"| {n:>9,} | {'yes' if periodic else 'no':>3} | {r['build']:6.2f} | {r['bounds']:6.2f} | {r['broad']:6.2f} | "
                f"{r['narrow']:6.2f} | {r['search']:8.2f} | {r['total']:6.2f} | {r['candidates']:>10,} | {r['contacts']:>9,} | "
                f"{r['float']:>9,} | {r['exact']:>5,} |"
            )
    say()
    open_rows = [r for periodic, r in rows if not periodic]
    if len(open_rows) >= 2:
        a, b = open_rows[-2], open_rows[-1]
        say(f"* scaling: {b['n'] / a['n']:.0f}x the bodies costs {b['total'] / a['total']:.2f}x the time (target <= 6x)")
    cmp = pipeline_row(sizes[-1], fraction=args.fraction)
    ratio = cmp["pipeline"] / cmp["certified"]
    say(
        f"* `contacts` on {cmp['n']:,} ellipsoids: best of 3 {cmp['search']:.2f} s wall, {cmp['cpu']:.2f} s CPU of the "
        f"process (first call in the process {open_rows[-1]['search']:.2f} s; target <= {TARGET_SECONDS:.0f} s for 1,000,000)"
    )
    say(
        f"* beside the uncertified pipeline (scipy cKDTree.query_pairs on bounding spheres + the C tree, one thread), "
        f"{cmp['n']:,} bodies, matrices built in both, best of 3 interleaved: certified {cmp['certified']:.2f} s "
        f"({cmp['contacts']:,} contacts), pipeline {cmp['pipeline']:.2f} s ({cmp['pipeline_contacts']:,} contacts from "
        f"{cmp['candidates']:,} candidates): certified at **{ratio:.2f}x** the pipeline's speed (target >= 1x)"
    )
    lat = lattice(8 if args.quick else 16)
    say(
        f"* touching lattice: {lat['n']:,} spheres, {lat['tangent']:,} tangent pairs (all certified exactly) in "
        f"{lat['total']:.2f} s: {1e6 * lat['total'] / lat['exact']:.0f} us per exact pair"
    )
    n = 2_000 if args.quick else 8_000
    found, missed, extra = brute_force_check(n, fraction=args.fraction)
    say(f"* brute force on {n:,} bodies ({n * (n - 1) // 2:,} pairs classified): {found:,} contacts, {missed} missed, {extra} extra")
    if args.write:
        from .render import publish

        command = "python -m bench.bench_bodies" + (" --quick" if args.quick else "") + (" --periodic" if args.periodic else "") + " --write"
        print(f"wrote {publish('bodies', command=command, markdown=chr(10).join(out), seconds=round(time.time() - started), load_average=f'{load[0]:.1f} at the start, {os.getloadavg()[0]:.1f} at the end')}")
    return 0 if missed == 0 and extra == 0 else 1


def write_section(text: str) -> None:
    """Replace (or append) the contacts section of bench/REPORT.md, between its markers."""
    old = REPORT.read_text() if REPORT.exists() else ""
    pattern = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END) + "\n?", re.S)
    new = pattern.sub(lambda _: text, old) if pattern.search(old) else old.rstrip("\n") + "\n\n" + text
    REPORT.write_text(new)


if __name__ == "__main__":
    raise SystemExit(main())
