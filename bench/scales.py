"""Bodies at any float scale: which arithmetic certifies them, and how long it takes.

The same random ellipsoid pairs (centres in a box of side 10, semi-axes 0.5 to 1.5, random
orientations) built with ``bodies_from_axes`` at scale s (centres and semi-axes times s), from
2^-1000 to 2^1000. ``classify`` (adaptive) certifies each pair with the float filter or exact
arithmetic; the table counts both, times the call and checks every label against
``method="exact"``::

    python -m bench.scales                 # 1,000 pairs per scale; contacts of 20,000 bodies; 5,000 moving
    python -m bench.scales --pairs 5000 --bodies 0 --moving 0

The float filter's second stage scales space by the power of two nearest the bodies' size
(``core.fixed.filters._balanced``), so far from size 1 the filter still certifies (before that
change: exact arithmetic for nearly every pair at 1e9, 1e30, 1e±150 and beyond).
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

import core
from bench.render import published
from core import Certifier, classify_detailed

__all__ = ["SCALES", "run_scales", "format_scales", "run_contacts", "format_contacts", "run_sweep", "format_sweep"]

SCALES = (2.0**-1000, 1e-300, 1e-150, 1e-30, 1e-9, 1.0, 1e9, 1e30, 1e150, 1e300, 2.0**1000)


def run_scales(pairs: int = 1000, repeats: int = 3, seed: int = 0) -> list[dict[str, Any]]:
    """One row per scale: pairs certified by the float filter / exactly, best time, labels = exact."""
    rng = np.random.default_rng(seed)
    n = 2 * pairs
    c, r, q = rng.uniform(0, 10, (n, 3)), rng.uniform(0.5, 1.5, (n, 3)), rng.normal(size=(n, 4))
    rows = []
    for s in SCALES:
        Q = core.bodies_from_axes(c * s, r * s, q)
        A, B = Q[:pairs], Q[pairs:]
        best = float("inf")
        for _ in range(repeats):
            t = time.perf_counter()
            res = classify_detailed(A, B)
            best = min(best, time.perf_counter() - t)
        exact = core.classify(A, B, method="exact")
        rows.append({
            "scale": s,
            "float": int(np.count_nonzero(res.certified_by == Certifier.FLOAT)),
            "exact": int(np.count_nonzero(res.certified_by == Certifier.EXACT)),
            "seconds": best,
            "right": bool((res.relation == exact).all()),
        })
    return rows


def format_scales(rows: list[dict[str, Any]]) -> str:
    """The markdown table."""
    out = ["| scale s | float filter | exact arithmetic | classify (best of 3) | labels = exact |", "|---:|---:|---:|---:|---|"]
    for r in rows:
        out.append(f"| {r['scale']:.3g} | {r['float']:,} | {r['exact']:,} | {r['seconds'] * 1e3:.1f} ms | {'yes' if r['right'] else 'NO'} |")
    return "\n".join(out)


def run_contacts(bodies: int = 20_000, seed: int = 1) -> list[dict[str, Any]]:
    """``contacts`` of the same random bodies (packing fraction 0.3) at each scale: time, phases, pairs = scale 1."""
    from bench.bodies_data import random_bodies

    b = random_bodies(bodies, seed=seed)
    rows, first = [], None
    for s in SCALES:
        Q = core.bodies_from_axes(np.asarray(b.centers) * s, np.asarray(b.semi_axes) * s, b.orientations)
        t = time.perf_counter()
        res = core.contacts(Q)
        total = time.perf_counter() - t
        pairs = res.to_rows()
        first = pairs if first is None else first
        rows.append({"scale": s, "seconds": total, "phases": dict(res.seconds), "candidates": res.counts["candidates"],
                     "exact_bounds": res.counts["exact_bounds"], "exact": res.counts["exact"], "same": pairs == first})
    return rows


def format_contacts(rows: list[dict[str, Any]]) -> str:
    """The markdown table of :func:`run_contacts`."""
    out = ["| scale s | contacts | bounding spheres | candidates | spheres exact | pairs exact | pairs = at the first scale |",
           "|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        out.append(f"| {r['scale']:.3g} | {r['seconds']:.2f} s | {r['phases'].get('bounds', 0):.2f} s | {r['candidates']:,} | "
                   f"{r['exact_bounds']:,} | {r['exact']:,} | {'yes' if r['same'] else 'NO'} |")
    return "\n".join(out)


def run_sweep(bodies: int = 5_000, seed: int = 0) -> list[dict[str, Any]]:
    """``sweep_contacts`` of the same moving bodies (:func:`bench.sweep_data.moving_bodies`) at each scale:
    time, broad-phase pairs, candidates, pairs certified exactly; contacts and relations = the first scale's."""
    from bench.sweep_data import moving_bodies

    m = moving_bodies(bodies, seed=seed)
    rows, first = [], None
    for s in SCALES:
        t = time.perf_counter()
        res = core.sweep_contacts(m.centers0 * s, m.centers1 * s, m.semi_axes * s, m.orientations0, m.orientations1)
        total = time.perf_counter() - t
        found = (res.i.tolist(), res.j.tolist(), res.relation.tolist())
        first = found if first is None else first
        rows.append({"scale": s, "seconds": total, "broad": res.counts["broad"], "candidates": res.counts["candidates"],
                     "exact": res.counts["exact"], "contacts": res.counts["contacts"], "same": found == first})
    return rows


def format_sweep(rows: list[dict[str, Any]]) -> str:
    """The markdown table of :func:`run_sweep`."""
    out = ["| scale s | sweep_contacts | swept balls meet | candidates | pairs exact | contacts | = at the first scale |",
           "|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        out.append(f"| {r['scale']:.3g} | {r['seconds']:.2f} s | {r['broad']:,} | {r['candidates']:,} | {r['exact']:,} | "
                   f"{r['contacts']:,} | {'yes' if r['same'] else 'NO'} |")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    """Print the tables."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--pairs", type=int, default=1000)
    p.add_argument("--bodies", type=int, default=20_000, help="bodies for the contacts table (0: skip it)")
    p.add_argument("--moving", type=int, default=5_000, help="moving bodies for the sweep_contacts table (0: skip it)")
    p.add_argument("--write", action="store_true", help="write bench/results/scales.json and render bench/REPORT.md")
    args = p.parse_args(argv)
    command = f"python -m bench.scales --pairs {args.pairs} --bodies {args.bodies} --moving {args.moving} --write"
    with published("scales", command=command, write=args.write):
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    """Print the tables."""
    print(f"# {args.pairs:,} random ellipsoid pairs per scale, bodies_from_axes(c * s, r * s, q), classify (adaptive)")
    print(format_scales(run_scales(args.pairs)))
    if args.bodies:
        print(f"\n# contacts of {args.bodies:,} random ellipsoids (packing fraction 0.3) at each scale, one call each")
        print(format_contacts(run_contacts(args.bodies)))
    if args.moving:
        print(f"\n# sweep_contacts of {args.moving:,} random moving, turning ellipsoids (packing fraction 0.3) at each scale, one call each")
        print(format_sweep(run_sweep(args.moving)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
