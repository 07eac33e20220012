"""Static benchmark: run time against error for two ellipses / ellipsoids (issues 2 and 6).

For every data set of :mod:`bench.datasets` (labels from the independent exact oracle) and every
method, one core:

* ``float``: ``classify(A, B, method="float")`` (certified filter; may abstain: "undecided").
* ``adaptive``: ``classify(A, B)`` (float filter, exact rationals for the abstentions; the
  escalation rate comes from :class:`core.Stats`).
* ``exact``: ``classify(A, B, method="exact")``, one pair per call.
* ``numpy-eig``: batched ``eigvals(solve(A, B))`` with the root criterion and a float tolerance
  (what users write; see :func:`classify_eig`).
* ``coal-gjk`` / ``coal-gjk-tight`` / ``fcl-gjk`` / ``fcl-gjk-indep`` (3D only, when the packages
  are installed): GJK collide on the ellipsoid primitives (default tolerance 1e-6 and 1e-12 for
  coal; fcl's libccd and its own GJK solver). A boolean answer: collide -> overlap, else
  separate; on a tangent pair either answer counts as right.

Measured per method and data set: pairs/s (throughput on the stack tiled to a fixed size; one
call per pair for exact and GJK), wrong labels and undecided on the data set itself, the
escalation rate, and the worst (max) and median time of single-pair calls.

Run: ``python -m bench.static [--quick]`` (prints the table).
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from core import Stats, classify

from . import datasets as D

__all__ = ["MethodResult", "classify_eig", "gjk_methods", "build_datasets", "run_method", "run_static", "METHODS", "format_table"]

METHODS = ("float", "adaptive", "exact", "numpy-eig")
"""Methods that always run; GJK methods are added by :func:`gjk_methods` when installed."""

EIG_TOL = 1e-9
"""Relative tolerance of the eigenvalue baseline (typical user choice)."""


def classify_eig(A: np.ndarray, B: np.ndarray, *, tol: float = EIG_TOL) -> np.ndarray:
    """Baseline: Relation codes from the eigenvalues of A^-1 B with a float tolerance.

    det(A^-1 B - lam I) = 0  <=>  det(B - lam A) = 0  <=>  P(-lam) = 0 with P(T) = det(T A + B):
    the eigenvalues are the negated roots of P. By Theorems 7 / 19 (and NOTES.md), P has at least
    one (2D) / two (3D) negative roots, and the shapes are separate iff P has two distinct positive
    roots, externally tangent iff P has a positive double root, overlapping iff P has no positive
    root. Hence: two distinct negative real eigenvalues -> separate; a negative double eigenvalue
    -> tangent; no negative real eigenvalue -> overlap. With floats, "real" means
    |Im lam| <= tol * max(1, |lam|) and "double" means |lam1 - lam2| <= tol * max(|lam1|, |lam2|).

    Args:
        A, B: (N, n, n) float64 stacks.
        tol: relative tolerance.

    Returns:
        (N,) int8 codes (0 separate, 1 tangent, 2 overlap), -1 where numpy raised LinAlgError
        (singular A, no convergence); may be wrong.

    Examples:
        >>> c = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> A, B = np.array([c(0), c(0), c(0)], float), np.array([c(3), c(2), c(1)], float)
        >>> classify_eig(A, B).tolist()     # the tangent pair: its double eigenvalue -1 splits by 4e-8
        [0, 0, 2]
        >>> classify_eig(A, B, tol=1e-6).tolist()
        [0, 1, 2]
    """
    try:
        lam = np.linalg.eigvals(np.linalg.solve(A, B))
    except np.linalg.LinAlgError:  # singular A or no convergence somewhere in the batch
        if len(A) == 1:
            return np.array([-1], dtype=np.int8)  # the baseline raises: counted as undecided
        return np.concatenate([classify_eig(A[i : i + 1], B[i : i + 1], tol=tol) for i in range(len(A))])
    mag = np.abs(lam)
    neg = (np.abs(lam.imag) <= tol * np.maximum(1.0, mag)) & (lam.real < 0)
    k = neg.sum(axis=1)
    vals = np.where(neg, lam.real, np.inf)
    vals.sort(axis=1)
    l1, l2 = vals[:, 0], vals[:, 1]
    with np.errstate(invalid="ignore"):
        double = np.abs(l1 - l2) <= tol * np.maximum(np.abs(l1), np.abs(l2))
    out = np.full(len(A), 2, dtype=np.int8)
    out[(k >= 2) & ~double] = 0
    out[(k >= 2) & double] = 1
    return out


# ------------------------------------------------------------------------------------ GJK
def _gjk_coal(tol: float) -> Callable[[Any], Callable[[], list[bool]]] | None:
    try:
        import coal
    except ImportError:
        return None

    def prepare(ds: D.Dataset) -> Callable[[], list[bool]]:
        req = coal.CollisionRequest()
        req.gjk_tolerance = tol
        if tol < 1e-6:
            req.gjk_max_iterations = 1000
        items = []
        for cA, aA, RA, cB, aB, RB in ds.shapes:
            items.append(
                (
                    coal.Ellipsoid(*map(float, aA)),
                    coal.Transform3s(np.asarray(RA, float), np.asarray(cA, float)),
                    coal.Ellipsoid(*map(float, aB)),
                    coal.Transform3s(np.asarray(RB, float), np.asarray(cB, float)),
                )
            )

        def run() -> list[bool]:
            out = []
            for gA, tA, gB, tB in items:
                res = coal.CollisionResult()
                coal.collide(gA, tA, gB, tB, req, res)
                out.append(res.isCollision())
            return out

        return run

    return prepare


def _gjk_fcl(solver: int | None) -> Callable[[Any], Callable[[], list[bool]]] | None:
    try:
        import fcl
    except ImportError:
        return None

    def prepare(ds: D.Dataset) -> Callable[[], list[bool]]:
        req = fcl.CollisionRequest() if solver is None else fcl.CollisionRequest(gjk_solver_type=solver)
        items = []
        for cA, aA, RA, cB, aB, RB in ds.shapes:
            items.append(
                (
                    fcl.CollisionObject(fcl.Ellipsoid(*map(float, aA)), fcl.Transform(np.asarray(RA, float), np.asarray(cA, float))),
                    fcl.CollisionObject(fcl.Ellipsoid(*map(float, aB)), fcl.Transform(np.asarray(RB, float), np.asarray(cB, float))),
                )
            )

        def run() -> list[bool]:
            out = []
            for oA, oB in items:
                res = fcl.CollisionResult()
                fcl.collide(oA, oB, req, res)
                out.append(bool(res.is_collision))
            return out

        return run

    return prepare


def gjk_methods() -> dict[str, Callable[[Any], Callable[[], list[bool]]]]:
    """Installed GJK baselines: name -> prepare(dataset) -> run() -> collide flags."""
    out = {}
    for name, prep in (
        ("coal-gjk", _gjk_coal(1e-6)),
        ("coal-gjk-tight", _gjk_coal(1e-12)),
        ("fcl-gjk", _gjk_fcl(None)),
        ("fcl-gjk-indep", _gjk_fcl(1)),
    ):
        if prep is not None:
            out[name] = prep
    return out


# ------------------------------------------------------------------------------------ measuring
@dataclass
class MethodResult:
    """One cell of the benchmark: a method on a data set."""

    dataset: str
    family: str
    dim: int
    method: str
    n: int
    """Pairs labelled (the data set, or the part of it the method ran on)."""
    pairs_per_s: float
    wrong: int
    """Decided labels that differ from the oracle."""
    undecided: int
    escalated: int | None = None
    """Pairs sent to exact (adaptive) or left undecided (float)."""
    worst_us: float = math.nan
    """Max time of a single-pair call (over the sampled pairs)."""
    median_us: float = math.nan
    timed_pairs: int = 0
    """Pairs in the throughput measurement (tiled stack)."""
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def error_rate(self) -> float:
        return self.wrong / self.n if self.n else math.nan


def _best(fn: Callable[[], Any], repeat: int) -> float:
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _tile(x: np.ndarray, total: int) -> np.ndarray:
    reps = max(1, -(-total // len(x)))
    return np.ascontiguousarray(np.tile(x, (reps, 1, 1))[: max(total, len(x))])


def _single_times(call: Callable[[int], Any], idx: np.ndarray) -> tuple[float, float]:
    ts = []
    for i in idx:
        t0 = time.perf_counter()
        call(int(i))
        ts.append(time.perf_counter() - t0)
    return (max(ts) * 1e6, float(np.median(ts)) * 1e6) if ts else (math.nan, math.nan)


def _wrong(codes: np.ndarray, truth: np.ndarray) -> int:
    return int(((codes != -1) & (codes != truth)).sum())


def run_method(method: str, ds: D.Dataset, *, quick: bool, gjk: dict[str, Any] | None = None) -> MethodResult | None:
    """Measure one method on one data set (None if the method does not apply, e.g. GJK in 2D)."""
    A, B, truth = ds.A, ds.B, ds.truth
    N = len(ds)
    repeat = 1 if quick else 3
    target = (100_000 if ds.family == "random" else 20_000) if quick else (1_000_000 if ds.family == "random" else 200_000)
    singles = 30 if quick else 200
    base = dict(dataset=ds.name, family=ds.family, dim=ds.dim, method=method)
    if method == "float":
        codes = classify(A, B, method="float")
        At, Bt = _tile(A, target), _tile(B, target)
        dt = _best(lambda: classify(At, Bt, method="float"), repeat)
        worst, med = _single_times(lambda i: classify(A[i], B[i], method="float"), np.arange(min(N, singles)))
        und = int((codes == -1).sum())
        return MethodResult(**base, n=N, pairs_per_s=len(At) / dt, wrong=_wrong(codes, truth), undecided=und,
                            escalated=und, worst_us=worst, median_us=med, timed_pairs=len(At))
    if method == "adaptive":
        st = Stats()
        codes = classify(A, B, stats=st)
        rate = st.escalated / N
        budget = 0.2 if quick else 1.0  # seconds of exact work in one timed call
        total = target if rate == 0 else int(min(target, max(N, budget / (rate * 5e-4))))
        At, Bt = _tile(A, total), _tile(B, total)
        dt = _best(lambda: classify(At, Bt), repeat)
        esc = np.flatnonzero(classify(A, B, method="float") == -1)
        idx = np.concatenate([esc[:singles], np.arange(min(N, singles))])  # worst case: escalated pairs
        worst, med = _single_times(lambda i: classify(A[i], B[i]), idx)
        return MethodResult(**base, n=N, pairs_per_s=len(At) / dt, wrong=_wrong(codes, truth), undecided=int((codes == -1).sum()),
                            escalated=st.escalated, worst_us=worst, median_us=med, timed_pairs=len(At))
    if method == "exact":
        cap = (200 if ds.family == "random" else 60) if quick else (2000 if ds.family == "random" else 300)
        m = min(N, cap)
        codes = np.empty(m, dtype=np.int8)
        ts = np.empty(m)
        for i in range(m):
            t0 = time.perf_counter()
            codes[i] = classify(A[i], B[i], method="exact")
            ts[i] = time.perf_counter() - t0
        return MethodResult(**base, n=m, pairs_per_s=m / ts.sum(), wrong=_wrong(codes, truth[:m]), undecided=0,
                            worst_us=ts.max() * 1e6, median_us=float(np.median(ts)) * 1e6, timed_pairs=m)
    if method == "numpy-eig":
        codes = classify_eig(A, B)
        total = (5_000 if quick else 50_000) if ds.family == "random" else (2_000 if quick else 20_000)
        At, Bt = _tile(A, total), _tile(B, total)
        dt = _best(lambda: classify_eig(At, Bt), repeat)
        worst, med = _single_times(lambda i: classify_eig(A[i : i + 1], B[i : i + 1]), np.arange(min(N, singles)))
        return MethodResult(**base, n=N, pairs_per_s=len(At) / dt, wrong=_wrong(codes, truth), undecided=int((codes == -1).sum()),
                            worst_us=worst, median_us=med, timed_pairs=len(At))
    if gjk is not None and method in gjk:
        if ds.dim != 3 or not ds.shapes:
            return None
        run = gjk[method](ds)
        hit = np.array(run(), dtype=bool)
        dt = _best(run, repeat)
        # collide: right unless (separate and hit) or (overlap and no hit); tangent: either
        wrong = int(((truth == 0) & hit).sum() + ((truth == 2) & ~hit).sum())
        return MethodResult(**base, n=N, pairs_per_s=N / dt, wrong=wrong, undecided=0,
                            worst_us=math.nan, median_us=dt / N * 1e6, timed_pairs=N,
                            extra={"tangent_pairs": int((truth == 1).sum())})
    raise ValueError(f"unknown method {method!r}")


def build_datasets(*, quick: bool, seed: int = 0, log: Callable[[str], None] = print) -> list[D.Dataset]:
    """All static data sets, labelled by the oracle (the slow part: ~1 ms per pair)."""
    n_random, n_tan, n_near, n_ext = (500, 40, 20, 60) if quick else (20000, 300, 200, 500)
    out: list[D.Dataset] = []
    t0 = time.perf_counter()
    for dim in (2, 3):
        out.append(D.random_pairs(dim, n_random, seed=seed))
        out.append(D.tangent_pairs(dim, n_tan, seed=seed))
        for e in D.GAP_EXPONENTS:
            for sign in (1, -1):
                out.append(D.near_tangent_pairs(dim, n_near, gap=10.0**-e, sign=sign, seed=seed))
        for kind in D.EXTREME_KINDS:
            out.append(D.extreme_pairs(dim, n_ext, kind=kind, seed=seed))
    log(f"# {len(out)} data sets, {sum(len(d) for d in out)} pairs labelled by the oracle in {time.perf_counter() - t0:.1f} s")
    return out


def warm_up() -> None:
    """Build / load the compiled kernels before timing, and pin the static rows to one thread."""
    import core

    core.warm_up(wait=True)
    core.set_threads(1)
    for dim in (2, 3):
        ds = D.random_pairs(dim, 8, seed=99)
        classify(ds.A, ds.B, method="float")
        classify(ds.A, ds.B)
        classify(ds.A[0], ds.B[0])


def run_static(*, quick: bool = False, seed: int = 0, log: Callable[[str], None] = print,
               datasets: list[D.Dataset] | None = None) -> dict[str, Any]:
    """Run every method on every data set.

    Returns:
        {"results": [MethodResult...], "datasets": [{name, family, dim, n, counts, dropped}],
         "methods": [...], "missing": {method: reason}, "seconds": wall time}.
    """
    t0 = time.perf_counter()
    warm_up()
    dsets = datasets if datasets is not None else build_datasets(quick=quick, seed=seed, log=log)
    gjk = gjk_methods()
    missing = {m: "package not installed" for m in ("coal-gjk", "coal-gjk-tight", "fcl-gjk", "fcl-gjk-indep") if m not in gjk}
    methods = [*METHODS, *gjk]
    results: list[MethodResult] = []
    for ds in dsets:
        for m in methods:
            r = run_method(m, ds, quick=quick, gjk=gjk)
            if r is not None:
                results.append(r)
        log(f"#   {ds.name:24s} done ({time.perf_counter() - t0:.0f} s)")
    info = [dict(name=d.name, family=d.family, dim=d.dim, n=len(d), counts=d.counts(), dropped=d.dropped) for d in dsets]
    return {"results": results, "datasets": info, "methods": methods, "missing": missing, "seconds": time.perf_counter() - t0}


def _fmt_rate(x: float) -> str:
    if x >= 1e6:
        return f"{x / 1e6:.2f} M"
    if x >= 1e3:
        return f"{x / 1e3:.1f} k"
    return f"{x:.0f}"


def format_table(results: list[MethodResult], *, families: tuple[str, ...] = ("random", "tangent", "extreme", "near")) -> str:
    """Markdown table, one row per data set and method; near-tangent sets merged per sign and dim."""
    rows = []
    merged: dict[tuple[str, int, str, str], list[MethodResult]] = {}
    for r in results:
        if r.family not in families:
            continue
        if r.family == "near":
            sign = r.dataset.split()[1][0]
            merged.setdefault((f"near {sign} (all gaps) {r.dim}D", r.dim, r.method, "near"), []).append(r)
        else:
            rows.append(r)
    for (name, dim, method, fam), rs in merged.items():
        n = sum(r.n for r in rs)
        tp = sum(r.timed_pairs for r in rs)
        time_total = sum(r.timed_pairs / r.pairs_per_s for r in rs)
        esc = None if rs[0].escalated is None else sum(r.escalated or 0 for r in rs)
        rows.append(MethodResult(name, fam, dim, method, n, tp / time_total, sum(r.wrong for r in rs), sum(r.undecided for r in rs),
                                 esc, max(r.worst_us for r in rs), float(np.median([r.median_us for r in rs])), tp))
    head = "| data set | method | pairs | pairs/s | wrong | undecided | escalated | median us/pair | worst us/pair |"
    lines = [head, "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        esc = "" if r.escalated is None else f"{r.escalated} ({100 * r.escalated / r.n:.2f} %)"
        worst = "" if math.isnan(r.worst_us) else f"{r.worst_us:.0f}"
        med = "" if math.isnan(r.median_us) else f"{r.median_us:.1f}"
        lines.append(f"| {r.dataset} | {r.method} | {r.n} | {_fmt_rate(r.pairs_per_s)} | {r.wrong} | {r.undecided} | {esc} | {med} | {worst} |")
    return "\n".join(lines)


def format_gap_table(results: list[MethodResult], dim: int) -> str:
    """Markdown: per gap decade and side, wrong labels of each method and the escalation rate."""
    near = [r for r in results if r.family == "near" and r.dim == dim]
    methods = list(dict.fromkeys(r.method for r in near))
    names = list(dict.fromkeys(r.dataset for r in near))
    cell = {(r.dataset, r.method): r for r in near}
    head = "| gap | " + " | ".join(f"{m} wrong" for m in methods) + " | float undecided | adaptive escalated |"
    lines = [head, "|---|" + "---:|" * (len(methods) + 2)]
    for nm in names:
        ws = [f"{cell[(nm, m)].wrong}/{cell[(nm, m)].n}" if (nm, m) in cell else "" for m in methods]
        fl = cell.get((nm, "float"))
        ad = cell.get((nm, "adaptive"))
        und = f"{100 * fl.undecided / fl.n:.0f} %" if fl else ""
        esc = f"{100 * (ad.escalated or 0) / ad.n:.0f} %" if ad else ""
        lines.append(f"| {nm.split()[1]} | " + " | ".join(ws) + f" | {und} | {esc} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description="Static benchmark: run time against error (prints markdown tables).")
    ap.add_argument("--quick", action="store_true", help="small data sets (well under a minute)")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    out = run_static(quick=a.quick, seed=a.seed)
    print(format_table(out["results"]))
    for dim in (2, 3):
        print(f"\nNear-tangent pairs, {dim}D\n")
        print(format_gap_table(out["results"], dim))
    if out["missing"]:
        print("\nnot installed:", ", ".join(out["missing"]))


if __name__ == "__main__":
    main()
