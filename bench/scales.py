"""Bodies at any float scale: which arithmetic certifies them, and how long it takes.

The same random ellipsoid pairs (centres in a box of side 10, semi-axes 0.5 to 1.5, random
orientations) built with ``bodies_from_axes`` at scale s (centres and semi-axes times s), from
2^-1000 to 2^1000. ``classify`` (adaptive) certifies each pair with the float filter or exact
arithmetic; the table counts both, times the call and checks every label against
``method="exact"``::

    python -m bench.scales                 # 1,000 pairs per scale
    python -m bench.scales --pairs 5000

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
from core import Certifier, classify_detailed

__all__ = ["SCALES", "run_scales", "format_scales"]

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


def main(argv: list[str] | None = None) -> int:
    """Print the table."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--pairs", type=int, default=1000)
    args = p.parse_args(argv)
    print(f"# {args.pairs:,} random ellipsoid pairs per scale, bodies_from_axes(c * s, r * s, q), classify (adaptive)")
    print(format_scales(run_scales(args.pairs)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
