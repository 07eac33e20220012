"""Benchmark of the moving-shape analysis (core.moving.analysis.analyse).

Prints a table: analyse time for each paper example and for random rational motions of growing
degree (translation degree 1..4, rotation quaternion degree 0..4, i.e. rotation matrix entries of
degree 0..8), with deg s0, the number of events, the certified digits, the time to refine all
events to 50 digits, and the time of one relation_at call.

Run: ``python bench/bench_motion.py [--quick] [--repeat N]``.
"""

from __future__ import annotations

import argparse
import random
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from core import analyse  # noqa: E402
from core.moving.presets import preset_arguments  # noqa: E402


def _poly(rng: random.Random, deg: int) -> str:
    coeffs = [rng.randint(-3, 3) for _ in range(deg + 1)]
    if coeffs[-1] == 0:
        coeffs[-1] = rng.choice([-2, -1, 1, 2])
    return " + ".join(f"({c})*t^{k}" for k, c in enumerate(coeffs))


def random_pair(rng: random.Random, trans_deg: int, rot_deg: int) -> dict:
    """Two ellipsoids with integer semi-axes, polynomial translations and quaternion rotations."""

    def motion() -> dict:
        m = {
            "shape": {"center": [0, 0, 0], "semi_axes": [rng.randint(1, 4) for _ in range(3)]},
            "translation": [_poly(rng, trans_deg) for _ in range(3)],
        }
        if rot_deg > 0:
            m["rotation"] = {"quaternion": ["1 + " + _poly(rng, rot_deg)] + [_poly(rng, rot_deg) for _ in range(3)]}
        return m

    return {"A_t": motion(), "B_t": motion(), "interval": ("-1", "1")}


def measure(args: dict, repeat: int) -> dict:
    best = float("inf")
    res = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = analyse(**args)
        best = min(best, time.perf_counter() - t0)
    assert res is not None
    t0 = time.perf_counter()
    for e in res.events:
        e.decimal(50)
    refine50 = time.perf_counter() - t0
    lo, hi = res.interval
    lo_f = float(lo) if lo is not None else -1.0
    hi_f = float(hi) if hi is not None else 1.0
    ts = [lo_f + (hi_f - lo_f) * k / 999 for k in range(1000)]
    t0 = time.perf_counter()
    for t in ts:
        res.relation_at(t)
    rel_at = (time.perf_counter() - t0) / len(ts)
    return {
        "time": best,
        "deg_s0": res.s0.degree() if not res.s0.is_zero() else -1,
        "deg_s1": res.s1.degree() if not res.s1.is_zero() else -1,
        "events": len(res.events),
        "roots": len(res.roots),
        "digits": res.digits,
        "refine50": refine50,
        "relation_at": rel_at,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="fewer random cases")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    rows = []
    for name in ["example-29", "example-30", "example-31", "example-32", "example-33"]:
        rows.append((name, measure(preset_arguments(name), a.repeat)))
    rng = random.Random(a.seed)
    grid = [(1, 0), (2, 0), (1, 1), (2, 1)] if a.quick else [(td, rd) for rd in range(0, 5) for td in range(1, 5)]
    for td, rd in grid:
        args = random_pair(rng, td, rd)
        t0 = time.perf_counter()
        try:
            rows.append((f"random trans {td} rot {rd}", measure(args, 1)))
        except ValueError as e:  # e.g. a random quaternion vanishing in I
            rows.append((f"random trans {td} rot {rd}", {"error": str(e)[:60]}))
        if time.perf_counter() - t0 > 120:
            print(f"# stopping the grid after {td}, {rd}: too slow", file=sys.stderr)
            break
    head = f"{'case':26s} {'analyse':>10s} {'deg s0':>7s} {'deg s1':>7s} {'events':>6s} {'roots':>5s} {'digits':>6s} {'50 digits':>10s} {'relation_at':>12s}"
    print(head)
    print("-" * len(head))
    for name, r in rows:
        if "error" in r:
            print(f"{name:26s} error: {r['error']}")
            continue
        print(
            f"{name:26s} {r['time'] * 1e3:8.1f}ms {r['deg_s0']:7d} {r['deg_s1']:7d} {r['events']:6d} {r['roots']:5d} "
            f"{r['digits']:6d} {r['refine50'] * 1e3:8.2f}ms {r['relation_at'] * 1e6:10.1f}us"
        )


if __name__ == "__main__":
    main()
