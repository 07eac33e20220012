"""Benchmark of the witnesses (core.witness): contact scale, separating plane, contact point.

Prints a table of the time per pair (median over repeats) for:

* ``contact_scale`` one pair (adaptive: certified floats, exact where they cannot; and
  ``method="exact"``), float and rational input, 2D and 3D, and with the exact algebraic value
  (``.algebraic()``, 30 digits);
* stacks of 10 000 random float pairs (``contact_scale`` at rtol 1e-12 and 1e-9,
  ``separating_plane``), with how many pairs the floats certified;
* ``witness(..., method="float")`` (one float pair: the scene's drag path);
* ``separating_plane`` and ``contact_point`` (tangent: exact; overlap: a rational point), one pair;
* ``distance`` (certified bracket of the Euclidean distance), one separate pair;
* ``witness`` (everything for one pair);
* extreme scales (issue 21): every witness on valid pairs scaled by 10^+-150 (floats) and
  10^+-1000 (exact), near tangent at gaps 1e-7..1e-14, a needle, and contact_scale at rtol
  1e-200: the worst time of one call (target: <= 1 s).

Run: ``python bench/bench_witness.py [--quick]``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from fractions import Fraction as F
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.render import published  # noqa: E402
from core import (  # noqa: E402
    Certifier,  # noqa: E402
    classify,
    explain,
    quadric_from_axes,
    warm_up,
)
from core.witness import (  # noqa: E402
    NoWitness,
    contact_point,
    contact_scale,
    distance,
    separating_plane,
    witness,
)


def random_floats(rng: np.random.Generator, d: int, N: int) -> np.ndarray:
    out = []
    for _ in range(N):
        o = rng.uniform(0, 3) if d == 2 else rng.normal(size=4)
        out.append(quadric_from_axes(rng.uniform(-3, 3, d), rng.uniform(0.2, 3, d), o))
    return np.array(out)


def random_exact(rng: np.random.Generator, d: int) -> list[list[Any]]:
    c = [F(int(rng.integers(-30, 30)), 10) for _ in range(d)]
    r = [F(int(rng.integers(2, 30)), 10) for _ in range(d)]
    q = [int(v) for v in rng.integers(-3, 4, size=4)]
    if not any(q):
        q[0] = 1
    if d == 2:
        q = [q[0] or 1, 0, 0, q[3]]
    return quadric_from_axes(c, r, q, exact=True)


def tangent_pair(d: int, a: F, r: F) -> tuple[list[list[F]], list[list[F]]]:
    """Ellipsoid with first semi-axis a (others 1) and a ball of radius r touching its tip."""
    A = quadric_from_axes([0] * d, [a] + [1] * (d - 1), exact=True)
    B = quadric_from_axes([a + r] + [0] * (d - 1), [r] * d, exact=True)
    return A, B


def space_exact(M: list[list[Any]], L: F) -> list[list[F]]:
    """The shape seen through x -> L x (exact)."""
    n = len(M)
    return [[F(int(M[i][j].p), int(M[i][j].q)) / L ** ((i < n - 1) + (j < n - 1)) for j in range(n)] for i in range(n)]


def space_float(M: np.ndarray, L: float) -> np.ndarray:
    """The same for a float matrix (rounded)."""
    D = np.diag([1 / L] * (M.shape[0] - 1) + [1.0])
    return D @ M @ D


def extreme_pairs(rng: np.random.Generator, n: int) -> list[tuple[str, Any, Any]]:
    """Valid pairs at extreme scales (issue 21's classes), each labelled."""
    out: list[tuple[str, Any, Any]] = []
    fl = list(zip(random_floats(rng, 3, n), random_floats(rng, 3, n), strict=True))
    for L in (1e150, 1e-150, 1e100):
        out += [(f"float, space x {L:g}", space_float(a, L), space_float(b, L)) for a, b in fl]
    out += [("float, matrices x 2^-1000, 1e300", a * 2.0**-1000, b * 1e300) for a, b in fl]
    for k in (1000, -1000, 100):
        for g in (F(1, 10**7), F(1, 10**9), -F(1, 10**8)):
            A = quadric_from_axes([0, 0, 0], [2, 1, 1], exact=True)
            B = quadric_from_axes([3 + g, F(1, 1000), 0], [1, 1, 1], exact=True)
            out.append((f"exact, space x 10^{k}, near tangent", space_exact(A, F(10) ** k), space_exact(B, F(10) ** k)))
    needle = quadric_from_axes([0, 0, 0], [1000, F(1, 1000), F(1, 1000)], exact=True)
    for c in ([1001 + F(1, 10**14), 0, 0], [0, 1 + F(1, 1000) + F(1, 10**14), 0]):
        out.append(("exact, needle at gap 1e-14", needle, quadric_from_axes(c, [1, 1, 1], exact=True)))
    return out


def worst_call(fn: Callable[[Any, Any], Any], pairs: list[tuple[str, Any, Any]]) -> tuple[float, str]:
    """The slowest single call (seconds) and its pair's label."""
    worst, label = 0.0, ""
    for name, a, b in pairs:
        t0 = time.perf_counter()
        fn(a, b)
        dt = time.perf_counter() - t0
        if dt > worst:
            worst, label = dt, name
    return worst, label


def per_pair(fn: Callable[[Any, Any], Any], pairs: list[tuple[Any, Any]], repeat: int) -> float:
    """Median over ``repeat`` runs of the mean time per pair (microseconds)."""
    runs = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for a, b in pairs:
            fn(a, b)
        runs.append((time.perf_counter() - t0) / len(pairs))
    return statistics.median(runs) * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer pairs and repeats")
    ap.add_argument("--write", action="store_true", help="write bench/results/witness.json and render bench/REPORT.md")
    args = ap.parse_args()
    command = "python bench/bench_witness.py" + (" --quick" if args.quick else "") + " --write"
    with published("witness", command=command, write=args.write):
        _run(args)


def _run(args: argparse.Namespace) -> None:
    """Time every witness and print the tables."""
    n_one, n_batch, repeat = (30, 2000, 1) if args.quick else (200, 10000, 3)
    warm_up()
    rng = np.random.default_rng(15)
    rows: list[tuple[str, str, float, str]] = []

    for d in (2, 3):
        kind = "ellipses" if d == 2 else "ellipsoids"
        A, B = random_floats(rng, d, n_one), random_floats(rng, d, n_one)
        fl = list(zip(A, B, strict=True))
        ex = [(random_exact(rng, d), random_exact(rng, d)) for _ in range(n_one)]
        rows.append(("contact_scale, adaptive (rtol 1e-12)", f"float {kind}", per_pair(contact_scale, fl, repeat), ""))
        rows.append(("contact_scale, exact (rtol 1e-12)", f"float {kind}", per_pair(lambda a, b: contact_scale(a, b, method="exact"), fl, repeat), ""))
        rows.append(("contact_scale (rtol 1e-12)", f"rational {kind}", per_pair(contact_scale, ex, repeat), ""))
        rows.append(
            ("contact_scale + .algebraic() (30 digits)", f"float {kind}",
             per_pair(lambda a, b: contact_scale(a, b).algebraic().decimal(30), fl[: max(10, n_one // 5)], 1), "")
        )
        rows.append(("witness, method='float' (one pair, drag path)", f"float {kind}", per_pair(lambda a, b: witness(a, b, rtol=1e-6, method="float", on_invalid="mark"), fl, repeat), ""))
        sep = [(a, b) for a, b in fl if classify(a, b) == 0]
        ovl = [(a, b) for a, b in fl if classify(a, b) == 2]
        rows.append(("separating_plane (adaptive)", f"float {kind}, separate", per_pair(separating_plane, sep, repeat), ""))
        rows.append(("distance bracket (rtol 1e-12)", f"float {kind}, separate", per_pair(distance, sep, repeat), ""))
        rows.append(("contact_point, overlap (rational point)", f"float {kind}, overlap", per_pair(contact_point, ovl, repeat), ""))
        tan = [tangent_pair(d, F(int(a), 4), F(int(r), 3)) for a, r in zip(rng.integers(2, 12, n_one // 3), rng.integers(1, 9, n_one // 3), strict=True)]
        rows.append(("contact_point, tangent (exact point, normal)", f"rational {kind}, tangent", per_pair(contact_point, tan, repeat), ""))
        rows.append(("witness (scale + plane or point)", f"float {kind}", per_pair(witness, fl, repeat), ""))

        A, B = random_floats(rng, d, n_batch), random_floats(rng, d, n_batch)
        for rtol in (1e-12, 1e-9):
            t0 = time.perf_counter()
            r = contact_scale(A, B, rtol=rtol)
            dt = (time.perf_counter() - t0) / n_batch * 1e6
            by_float = sum(1 for c in r if c.certified_by == Certifier.FLOAT)
            rows.append((f"contact_scale stack (rtol {rtol:g}), {n_batch} pairs", f"float {kind}", dt, f"{by_float}/{n_batch} certified by floats"))
        t0 = time.perf_counter()
        p = separating_plane(A, B, on_invalid="mark")
        dt = (time.perf_counter() - t0) / n_batch * 1e6
        planes = [x for x in p if not isinstance(x, NoWitness)]
        by_float = sum(1 for x in planes if x.certified_by == Certifier.FLOAT)
        rows.append((f"separating_plane stack, {n_batch} pairs", f"float {kind}", dt, f"{len(planes)} separate pairs, {by_float} certified by floats"))

    print("| operation | input | us per pair | note |")
    print("|---|---|---:|---|")
    for op, inp, us, note in rows:
        print(f"| {op} | {inp} | {us:,.1f} | {note} |")

    pairs = extreme_pairs(rng, 3 if args.quick else 10)
    sep = [p for p in pairs if classify(p[1], p[2]) == 0]
    meet = [p for p in pairs if classify(p[1], p[2]) != 0]
    checks: list[tuple[str, Callable[[Any, Any], Any], list[tuple[str, Any, Any]]]] = [
        ("explain", explain, pairs),
        ("contact_scale (rtol 1e-12)", contact_scale, pairs),
        ("contact_scale (rtol 1e-200)", lambda a, b: contact_scale(a, b, rtol=1e-200), pairs),
        ("witness", witness, pairs),
        ("distance", distance, sep),
        ("separating_plane", separating_plane, sep),
        ("contact_point", contact_point, meet),
        ("contact_scale, as a stack of one", lambda a, b: contact_scale(np.asarray(a)[None], np.asarray(b)[None]), [p for p in pairs if isinstance(p[1], np.ndarray)]),
    ]
    print()
    print(f"Extreme scales ({len(pairs)} valid pairs: floats at 1e+-150, exact at 10^+-1000, near tangent, a needle):")
    print()
    print("| call | pairs | worst call (s) | worst pair | target |")
    print("|---|---:|---:|---|---|")
    for name, fn, ps in checks:
        worst, label = worst_call(fn, ps)
        print(f"| {name} | {len(ps)} | {worst:.3f} | {label} | {'met' if worst <= 1.0 else 'MISSED'} (<= 1 s) |")


if __name__ == "__main__":
    main()
