"""Certified throughput on every core, against the uncertified C tree, on the inputs users bring.

Rows (issue 13): adaptive ``classify`` on random pairs with every core and with one, the paper's
tree in plain C without any certification (``bench/baseline_tree.c``, ``-O3 -march=native``, one
thread) and the memory-read limit on the same arrays; spheres, translated copies, homothetic
copies and numpy-built matrices (their rate against random, escalation, wrong labels against
the oracle); a large ellipsoid beside a small sphere at relative gaps >= 1e-3; and the cold start
of the compiled kernels in a fresh process with an empty cache, then with a warm one.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from . import baseline
from . import datasets as D

__all__ = ["run_throughput", "format_throughput", "throughput_targets"]

ROOT = Path(__file__).resolve().parents[1]


def _tile(ds: D.Dataset, size: int) -> tuple[np.ndarray, np.ndarray]:
    reps = -(-size // len(ds))
    return np.ascontiguousarray(np.tile(ds.A, (reps, 1, 1))[:size]), np.ascontiguousarray(np.tile(ds.B, (reps, 1, 1))[:size])


def _cold_start() -> dict[str, float]:
    """Seconds from process start to compiled kernels ready: empty cache, then warm cache."""
    code = (
        "import time; t0 = time.perf_counter(); import core; t1 = time.perf_counter(); ok = core.warm_up(wait=True); "
        "t2 = time.perf_counter(); import numpy as np; from core.fixed import compiled; "
        "print(f'{t1 - t0} {t2 - t1} {ok}'); print(compiled.status())"
    )
    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, ELLIPSOID_KERNEL_CACHE=tmp)
        for key in ("empty cache", "warm cache"):
            t = time.perf_counter()
            res = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300, check=False)
            total = time.perf_counter() - t
            first = res.stdout.splitlines()[0].split() if res.stdout else ["nan", "nan", "False"]
            out[f"{key}: import core (s)"] = float(first[0])
            out[f"{key}: kernels ready after import (s)"] = float(first[1]) if first[2] == "True" else float("nan")
            out[f"{key}: whole process (s)"] = total
    return out


def run_throughput(*, quick: bool = False, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Measure every row; returns plain data for the report."""
    import core
    from core.fixed.classify import Certifier, classify_detailed

    core.warm_up(wait=True)
    baseline.build()
    size = 100_000 if quick else 1_000_000
    n_lab = 100 if quick else 400
    reps = 3 if quick else 5
    cores = os.cpu_count() or 1
    rows: list[dict[str, Any]] = []
    random_rate: dict[int, float] = {}
    for dim in (3, 2):
        ds = D.random_pairs(dim, n_lab, seed=11)
        A, B = _tile(ds, size)
        core.set_threads(None)
        all_cores = baseline.best_rate(lambda A=A, B=B: core.classify(A, B), size, reps)
        core.set_threads(1)
        one = baseline.best_rate(lambda A=A, B=B: core.classify(A, B), size, reps)
        core.set_threads(None)
        base = baseline.best_rate(lambda A=A, B=B: baseline.baseline_codes(A, B), size, reps)
        read = baseline.read_rate(A, B, reps)
        agree = float((baseline.baseline_codes(ds.A, ds.B) == ds.truth).mean())
        random_rate[dim] = all_cores
        rows.append({"kind": "random", "dim": dim, "all": all_cores, "one": one, "baseline": base, "read": read,
                     "baseline_right": agree, "cores": cores})
        log(f"# random {dim}D: {all_cores / 1e6:.1f} M/s all cores, {one / 1e6:.1f} one, baseline {base / 1e6:.1f}, read {read / 1e6:.0f}")
    structured: list[dict[str, Any]] = []
    for dim in (3, 2):
        for kind in D.STRUCTURED_KINDS:
            ds = D.structured_pairs(dim, n_lab, kind=kind, seed=12)
            res = classify_detailed(ds.A, ds.B)
            A, B = _tile(ds, size)
            rate = baseline.best_rate(lambda A=A, B=B: core.classify(A, B), size, reps)
            structured.append({
                "name": f"{kind} {dim}D", "dim": dim, "n": len(ds), "rate": rate, "ratio": rate / random_rate[dim],
                "escalated": int(np.count_nonzero(res.certified_by == Certifier.EXACT)),
                "wrong": int(np.count_nonzero(res.relation != ds.truth)),
            })
            log(f"# {kind} {dim}D: {rate / 1e6:.1f} M/s ({rate / random_rate[dim]:.2f}x random), escalated {structured[-1]['escalated']}")
    hard: list[dict[str, Any]] = []
    for dim in (3, 2):
        for gap in (1e-3, 1e-2, 1e-1):
            for sign in (1, -1):
                ds = D.big_small_pairs(dim, n_lab // 2, gap=gap, sign=sign, seed=13)
                res = classify_detailed(ds.A, ds.B, method="float")
                hard.append({
                    "name": ds.name, "n": len(ds),
                    "undecided": int(np.count_nonzero(res.relation == core.Relation.UNDECIDED)),
                    "wrong": int(np.count_nonzero((res.relation != core.Relation.UNDECIDED) & (res.relation != ds.truth))),
                })
    log("# cold start")
    cold = _cold_start()
    return {"rows": rows, "structured": structured, "hard": hard, "cold": cold, "size": size, "cores": cores}


def throughput_targets(tp: dict[str, Any]) -> list[tuple[str, str, str, bool]]:
    """(target, measured, verdict, met) rows of issue 13."""
    out = []
    r3 = next(r for r in tp["rows"] if r["dim"] == 3)
    ok = r3["all"] >= r3["baseline"]
    out.append((f"certified adaptive (random 3D, all {r3['cores']} cores) >= the uncertified C tree (one thread)",
                f"{r3['all'] / 1e6:.1f} M/s vs {r3['baseline'] / 1e6:.1f} M/s ({r3['all'] / r3['baseline']:.2f}x; one core {r3['one'] / 1e6:.1f} M/s)",
                "met" if ok else "missed", ok))
    worst = min(tp["structured"], key=lambda s: s["ratio"])
    ok = worst["ratio"] >= 0.5 and all(s["wrong"] == 0 for s in tp["structured"])
    out.append(("spheres, translated / homothetic copies, numpy-built: >= 0.5x random, 0 wrong",
                f"worst {worst['name']} {worst['ratio']:.2f}x; wrong {sum(s['wrong'] for s in tp['structured'])}; escalated "
                f"{sum(s['escalated'] for s in tp['structured'])} / {sum(s['n'] for s in tp['structured'])}", "met" if ok else "missed", ok))
    und = sum(h["undecided"] for h in tp["hard"])
    tot = sum(h["n"] for h in tp["hard"])
    wrong = sum(h["wrong"] for h in tp["hard"])
    ok = und <= 0.05 * tot and wrong == 0
    out.append(("large ellipsoid beside a small sphere, gaps >= 1e-3: <= 5 % undecided, 0 wrong",
                f"{100 * und / max(tot, 1):.1f} % undecided ({und}/{tot}), {wrong} wrong", "met" if ok else "missed", ok))
    c = tp["cold"]
    first = c["empty cache: kernels ready after import (s)"]
    warm = c["warm cache: kernels ready after import (s)"]
    ok = first <= 5.0 and warm < 1.0
    out.append(("cold start: kernels ready <= 5 s in a fresh process with an empty cache; a new process does not recompile",
                f"{first:.2f} s (empty cache), {warm:.2f} s (warm cache)", "met" if ok else "missed", ok))
    return out


def format_throughput(tp: dict[str, Any]) -> str:
    """Markdown tables of the throughput section."""
    L = [f"Batches of {tp['size']:,} pairs (a labelled data set tiled), best of several runs; 'all cores' = {tp['cores']} threads.\n",
         "| data | certified, all cores | certified, one core | uncertified C tree, one thread | memory read, one thread | C tree right (vs oracle) |",
         "|---|---:|---:|---:|---:|---:|"]
    for r in tp["rows"]:
        L.append(f"| random {r['dim']}D | {r['all'] / 1e6:.2f} M/s | {r['one'] / 1e6:.2f} M/s | {r['baseline'] / 1e6:.2f} M/s | "
                 f"{r['read'] / 1e6:.0f} M/s | {100 * r['baseline_right']:.1f} % |")
    L.append("\n| structured data | pairs/s (all cores) | vs random | escalated to exact | wrong |\n|---|---:|---:|---:|---:|")
    for s in tp["structured"]:
        L.append(f"| {s['name']} | {s['rate'] / 1e6:.2f} M/s | {s['ratio']:.2f}x | {s['escalated']} / {s['n']} | {s['wrong']} |")
    L.append("\n| hard but decidable (float filter alone) | pairs | undecided | wrong |\n|---|---:|---:|---:|")
    for h in tp["hard"]:
        L.append(f"| {h['name']} | {h['n']} | {h['undecided']} | {h['wrong']} |")
    L.append("\n| cold start | seconds |\n|---|---:|")
    for k, v in tp["cold"].items():
        L.append(f"| {k} | {v:.2f} |")
    return "\n".join(L)
