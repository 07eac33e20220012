"""Benchmark of certified first contacts among moving ellipsoids (``core.sweep_contacts``).

    python bench/bench_sweep.py             # everything (~10 min on 2 shared cores)
    python bench/bench_sweep.py --quick     # small sizes (~1 min)
    python bench/bench_sweep.py --report    # also write the section of bench/REPORT.md

1. Correctness against the exact analysis: pair sets (bench/sweep_data.py) with translation,
   rotation (3D and 2D), grazing contacts built exactly (touching once at a rational t*),
   tangency at t = 0, near misses 2^-40 (9.1e-13) outward and shallow overlaps 2^-40 inward;
   each pair's truth is :func:`core.analyse` of its exact motion (the first non-separate time).
   missed / extra / brackets not holding t* (or wider than 1e-9) / wrong relations.
2. One candidate pair: single-pair calls of the narrow phase on one core (``set_threads(1)``),
   median and 90th percentile, translation only and with rotation; the share that needed exact
   arithmetic and its median.
3. 100,000 moving ellipsoids (packing fraction 0.3, each moving up to its own size, random
   rotations) end to end on every core, with a sample of pairs checked against the analysis.
4. Uniform sampling of t with 10 / 100 / 1000 samples (the certified static ``contacts`` at each
   sample) on the same sets: the contacts it misses, and its time.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
import time
from pathlib import Path
from typing import Any

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np
from flint import fmpq

from bench.sweep_data import (
    Motions,
    concat,
    grazing_pairs,
    moving_bodies,
    random_pairs,
    start_pairs,
)
from core import (
    Certifier,
    Relation,
    analyse,
    bodies_from_axes,
    contacts,
    set_threads,
    sweep_contacts,
    warm_up,
)
from core.algebra.algebraic import RealAlgebraic
from core.fixed.compiled import get_threads
from core.moving.first_contact import first_contacts
from core.moving.linear import LinearMotions, read_linear_motions
from core.moving.sweep_filter import filter_status

REPORT = Path(__file__).with_name("REPORT.md")
BEGIN, END = "<!-- sweep:begin -->", "<!-- sweep:end -->"


def exact_truth(bodies: LinearMotions, i: int, j: int, shift: Any = None) -> tuple[RealAlgebraic | None, Relation | None]:
    """(t*, relation) of a pair by the full exact analysis of its exact motion (None: never meets)."""
    r = analyse(bodies.motion(i), bodies.motion(j, shift), (0, 1))
    rel = r.relation_at(0)
    if rel != Relation.SEPARATE:
        return RealAlgebraic.rational(fmpq(0)), rel
    return (r.events[0].time, r.events[0].relation) if r.events else (None, None)


def _q(x: float) -> fmpq:
    return fmpq(*float(x).as_integer_ratio())


# ----------------------------------------------------------------------------- 1. correctness


def correctness(name: str, m: Motions) -> dict[str, Any]:
    """Sweep one pair set and check every pair against the exact analysis."""
    t0 = time.perf_counter()
    res = sweep_contacts(*m.arguments())
    sweep_s = time.perf_counter() - t0
    bodies, _ = read_linear_motions(*m.arguments())
    found = {(int(a), int(b)): k for k, (a, b) in enumerate(zip(res.i, res.j, strict=True))}
    out = {"name": name, "pairs": len(bodies) // 2, "meet": 0, "missed": 0, "extra": 0, "outside": 0, "wrong": 0, "seconds": sweep_s}
    out["extra"] += sum(1 for a, b in found if not (a % 2 == 0 and b == a + 1))
    t0 = time.perf_counter()
    for p in range(len(bodies) // 2):
        t, rel = exact_truth(bodies, 2 * p, 2 * p + 1)
        k = found.get((2 * p, 2 * p + 1))
        if t is None:
            out["extra"] += k is not None
            continue
        out["meet"] += 1
        if k is None:
            out["missed"] += 1
            continue
        inside = t.compare(_q(res.t_lo[k])) >= 0 and t.compare(_q(res.t_hi[k])) <= 0 and res.t_hi[k] - res.t_lo[k] <= 1e-9
        out["outside"] += not inside
        out["wrong"] += int(res.relation[k]) != int(rel)  # type: ignore[arg-type]
    out["truth_seconds"] = time.perf_counter() - t0
    c = res.counts
    out["float"], out["exact"], out["candidates"] = c["float"], c["exact"], c["candidates"]
    return out


def pair_sets(quick: bool) -> list[tuple[str, Motions]]:
    k = 2 if quick else 1
    return [
        ("translation 3D", random_pairs(60 // k, seed=1)),
        ("translation 2D", random_pairs(60 // k, dim=2, seed=2)),
        ("rotation 3D", random_pairs(40 // k, rotate=True, seed=3)),
        ("rotation 2D", random_pairs(40 // k, dim=2, rotate=True, seed=4)),
        ("grazing 3D (exact t*)", grazing_pairs(30 // k, seed=5)),
        ("grazing 2D (exact t*)", grazing_pairs(20 // k, dim=2, seed=6)),
        ("tangent at t = 0", start_pairs(10 // k, seed=7)),
        ("near miss +2^-40", grazing_pairs(30 // k, offset=2.0**-40, seed=8)),
        ("shallow overlap -2^-40", grazing_pairs(20 // k, offset=-(2.0**-40), seed=9)),
    ]


# ----------------------------------------------------------------------------- 2. one pair


def per_pair(n_bodies: int, rotate: bool, samples: int) -> dict[str, Any]:
    """Single-pair calls of the narrow phase on candidate pairs of a moving set, one core."""
    m = moving_bodies(n_bodies, rotate=rotate, seed=11)
    res = sweep_contacts(*m.arguments())
    bodies = res.bodies
    from core.bodies.swept import swept_pairs, swept_spheres

    cand, _ = swept_pairs(bodies, swept_spheres(bodies, np.ones(len(bodies), bool)), None)
    rng = np.random.default_rng(1)
    pick = rng.choice(len(cand), size=min(samples, len(cand)), replace=False)
    set_threads(1)
    try:
        times, exact_times = [], []
        for k in pick.tolist():
            i, j = cand.i[k : k + 1], cand.j[k : k + 1]
            t0 = time.perf_counter()
            fc = first_contacts(bodies, i, j)
            dt = time.perf_counter() - t0
            times.append(dt)
            if fc.certified_by[0] == Certifier.EXACT:
                exact_times.append(dt)
        t0 = time.process_time()
        batch = first_contacts(bodies, cand.i[pick], cand.j[pick])
        batch_cpu = (time.process_time() - t0) / len(pick)
    finally:
        set_threads(None)
    us = np.array(times) * 1e6
    return {
        "rotate": rotate,
        "pairs": len(pick),
        "median_us": float(np.median(us)),
        "p90_us": float(np.percentile(us, 90)),
        "batch_us": batch_cpu * 1e6,
        "exact": len(exact_times),
        "exact_median_ms": float(np.median(exact_times) * 1e3) if exact_times else math.nan,
        "meet": int(np.count_nonzero(batch.relation != Relation.SEPARATE)),
    }


# ----------------------------------------------------------------------------- 3. large sets


def large(n: int, rotate: bool, check: int) -> dict[str, Any]:
    """End-to-end sweep of n moving bodies; ``check`` reported and ``check`` unreported candidate
    pairs compared with the exact analysis."""
    m = moving_bodies(n, rotate=rotate, seed=0)
    t0, c0 = time.perf_counter(), time.process_time()
    res = sweep_contacts(*m.arguments())
    total, cpu = time.perf_counter() - t0, time.process_time() - c0
    out: dict[str, Any] = {"n": n, "rotate": rotate, "total": total, "cpu": cpu, **res.counts}
    out.update({f"{k}_s": v for k, v in res.seconds.items()})
    bad = 0
    rng = np.random.default_rng(2)
    for k in rng.choice(len(res), size=min(check, len(res)), replace=False).tolist():
        t, rel = exact_truth(res.bodies, int(res.i[k]), int(res.j[k]))
        ok = t is not None and rel == res.relation[k] and t.compare(_q(res.t_lo[k])) >= 0 and t.compare(_q(res.t_hi[k])) <= 0
        bad += not ok
    from core.bodies.swept import swept_pairs, swept_spheres

    cand, _ = swept_pairs(res.bodies, swept_spheres(res.bodies, np.ones(n, bool)), None)
    reported = set(zip(res.i.tolist(), res.j.tolist(), strict=True))
    absent = [k for k in rng.permutation(len(cand))[: 5 * check].tolist() if (int(cand.i[k]), int(cand.j[k])) not in reported][:check]
    for k in absent:
        t, _ = exact_truth(res.bodies, int(cand.i[k]), int(cand.j[k]))
        bad += t is not None
    out["checked"] = min(check, len(res)) + len(absent)
    out["check_failures"] = bad
    return out


# ----------------------------------------------------------------------------- 4. sampling


def sample_at(bodies: LinearMotions, t: float) -> np.ndarray:
    """Float matrices of the bodies at time t (what a sampling code classifies)."""
    c = bodies.centers0 + t * (bodies.centers1 - bodies.centers0)
    q = (1 - t) * bodies.q0 + t * bodies.q1
    if bodies.dim == 2:
        q = np.stack([q[:, 0], 0 * q[:, 0], 0 * q[:, 0], q[:, 1]], axis=1)
    return bodies_from_axes(c, bodies.semi_axes, q)


def sampling(m: Motions, counts: tuple[int, ...]) -> dict[str, Any]:
    """Contacts of the sweep that uniform sampling misses, and its time, per sample count."""
    t0 = time.perf_counter()
    res = sweep_contacts(*m.arguments())
    sweep_s = time.perf_counter() - t0
    truth = set(zip(res.i.tolist(), res.j.tolist(), strict=True))
    rows = []
    for S in counts:
        found: set[tuple[int, int]] = set()
        t0 = time.perf_counter()
        for t in np.linspace(0.0, 1.0, S):
            c = contacts(sample_at(res.bodies, float(t)))
            found.update(zip(c.i.tolist(), c.j.tolist(), strict=True))
        rows.append({"samples": S, "seconds": time.perf_counter() - t0, "missed": len(truth - found), "extra": len(found - truth)})
    return {"contacts": len(truth), "sweep_seconds": sweep_s, "rows": rows}


# ----------------------------------------------------------------------------- output


def _table(head: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---:" if k else "---" for k in range(len(head))) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="small sizes (~1 min)")
    p.add_argument("--report", action="store_true", help="write bench/results/sweep.json and render bench/REPORT.md")
    p.add_argument("--n", type=int, default=None, help="bodies of the large run (default 100,000; --quick 20,000)")
    args = p.parse_args(argv)
    warm_up()
    filter_status()
    load = os.getloadavg()
    started = time.perf_counter()
    md: list[str] = []

    print(f"# certified first contacts among moving ellipsoids ({get_threads()} threads; {filter_status()})\n", flush=True)
    rows = []
    bad = 0
    for name, m in pair_sets(args.quick):
        r = correctness(name, m)
        bad += r["missed"] + r["extra"] + r["outside"] + r["wrong"]
        rows.append([r["name"], f"{r['pairs']}", f"{r['meet']}", f"{r['missed']}", f"{r['extra']}", f"{r['outside']}", f"{r['wrong']}",
                     f"{r['float']}", f"{r['exact']}", f"{1e3 * r['seconds']:.0f}"])
        print(f"  {name}: {r}", flush=True)
    t1 = _table(["set", "pairs", "meet", "missed", "extra", "t* outside", "wrong relation", "float", "exact", "sweep ms"], rows)
    print("\n" + t1 + "\n", flush=True)
    md += ["### Against the exact analysis\n", "Truth: `core.analyse` of each pair's exact motion (the first non-separate t); grazing sets also "
           "match their t* = s0 / (s0 + s1) by construction. 'float' / 'exact' = candidate pairs certified by the float filter / "
           "by exact arithmetic.\n", t1 + "\n"]

    rows = []
    pp = []
    for rotate in (False, True):
        r = per_pair(6_000 if args.quick else 20_000, rotate, 300 if args.quick else 1500)
        pp.append(r)
        rows.append(["rotation" if rotate else "translation only", f"{r['pairs']}", f"{r['median_us']:.0f}", f"{r['p90_us']:.0f}",
                     f"{r['batch_us']:.1f}", f"{r['exact']} ({100 * r['exact'] / r['pairs']:.2f} %)",
                     "-" if math.isnan(r["exact_median_ms"]) else f"{r['exact_median_ms']:.0f}"])
    t2 = _table(["motion", "candidate pairs", "median us (one call)", "p90 us", "us per pair in a batch (CPU)", "needed exact", "exact median ms"], rows)
    print(t2 + "\n", flush=True)
    md += ["### One candidate pair, one core\n", "Single-pair calls of the narrow phase (`first_contacts` on one pair: the C filter, exact "
           "arithmetic if it abstains; Python call overhead included) on random candidate pairs of a moving set (packing fraction "
           "0.3); 'in a batch' is the CPU time per pair of one call on all of them.\n", t2 + "\n"]

    n = args.n or (20_000 if args.quick else 100_000)
    rows = []
    lg = []
    for rotate in (True, False):
        r = large(n, rotate, 20 if args.quick else 60)
        lg.append(r)
        rows.append([f"{n:,}", "yes" if rotate else "no", f"{r['read_s']:.2f}", f"{r['broad_s']:.2f}", f"{r['narrow_s']:.2f}", f"{r['total']:.2f}", f"{r['cpu']:.2f}",
                     f"{r['broad']:,}", f"{r['candidates']:,}", f"{r['contacts']:,}", f"{r['at_start']:,}", f"{r['float']:,}", f"{r['exact']:,}",
                     f"{r['check_failures']} / {r['checked']}"])
        print(f"  large: {r}", flush=True)
    t3 = _table(["N", "rotation", "read s", "broad s", "narrow s", "total s", "CPU s (all threads)", "swept balls meet", "candidates", "meet", "at t = 0", "float", "exact",
                 "wrong in sample"], rows)
    print("\n" + t3 + "\n", flush=True)
    md += [f"### {n:,} moving ellipsoids, end to end\n", "Random ellipsoids (bench/bodies_data.py: packing fraction 0.3, axis ratio up to 2, "
           "largest semi-axis 1), each moving by up to its own size (uniform in [0, 1] times its largest semi-axis) in a random "
           "direction; with rotation each turns to an independent random orientation (q1 on q0's side). Every core. The last "
           "column compares a random sample of reported pairs and of candidate pairs not reported with the exact analysis.\n", t3 + "\n"]

    sets = [("grazing 3D + near misses", concat(grazing_pairs(30, seed=5), grazing_pairs(30, offset=2.0**-40, seed=8))),
            ("rotation 3D pairs", random_pairs(40, rotate=True, seed=3)),
            (f"{2_000 if args.quick else 10_000:,} moving ellipsoids", moving_bodies(2_000 if args.quick else 10_000, seed=4))]
    counts = (10, 100) if args.quick else (10, 100, 1000)
    rows = []
    for name, m in sets:
        s = sampling(m, counts)
        for r in s["rows"]:
            rows.append([name, f"{s['contacts']:,}", f"{s['sweep_seconds']:.2f}", f"{r['samples']}", f"{r['missed']:,}", f"{r['extra']:,}", f"{r['seconds']:.2f}"])
        print(f"  sampling {name}: {s}", flush=True)
    t4 = _table(["set", "contacts (sweep)", "sweep s", "samples", "missed by sampling", "extra", "sampling s"], rows)
    print("\n" + t4 + "\n", flush=True)
    md += ["### Against uniform sampling\n", "Sampling = the bodies' float matrices at S uniform times (`bodies_from_axes` of the "
           "interpolated centre and quaternion) and the certified static `contacts` at each; a pair is found when some sample "
           "classifies it tangent or overlapping. 'missed' = pairs that meet (the sweep) and no sample sees; 'extra' = pairs a "
           "sample sees that the sweep says never meet (float rounding of the sampled matrices).\n", t4 + "\n"]

    rot = next(r for r in pp if r["rotate"])
    tr = next(r for r in pp if not r["rotate"])
    big = next(r for r in lg if r["rotate"])
    verdict = [
        f"* correctness: {bad} missed / extra / outside / wrong over all pair sets (target 0)",
        f"* one candidate pair: median {tr['median_us']:.0f} us translation only (target <= 100), {rot['median_us']:.0f} us with rotation (target <= 1000); "
        f"exact arithmetic for {tr['exact'] + rot['exact']} of {tr['pairs'] + rot['pairs']}",
        f"* {n:,} moving ellipsoids with rotation: {big['total']:.1f} s end to end (target <= 10 s for 100,000)",
    ]
    print("\n".join(verdict))
    elapsed = time.perf_counter() - started
    if args.report:
        from bench.render import publish

        command = f"python bench/bench_sweep.py{' --quick' if args.quick else ''} --report"
        print(f"wrote {publish('sweep', command=command, markdown=chr(10).join([*md, '', *verdict]), load_average=f'{load[0]:.1f} at the start, {os.getloadavg()[0]:.1f} at the end')} in {elapsed:.0f} s")
    return 0 if bad == 0 else 1


def write_section(text: str) -> None:
    """Replace (or append) the sweep section of bench/REPORT.md, between its markers."""
    old = REPORT.read_text() if REPORT.exists() else ""
    pattern = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END) + "\n?", re.S)
    new = pattern.sub(lambda _: text, old) if pattern.search(old) else old.rstrip("\n") + "\n\n" + text
    REPORT.write_text(new)


if __name__ == "__main__":
    raise SystemExit(main())
