"""Moving shapes: the exact analysis (core.analyse) against sampling t on a uniform grid (issue 6).

What users do instead of an exact analysis: evaluate A(t), B(t) in floats at N uniform times and
classify each pair with the static classifier (here the certified ``classify``, so every sampled
label is the true label of the rounded matrices). From the label sequence, an event is seen in a
grid cell where the label changes (estimated at the cell midpoint) or at a sample labelled
tangent. For each case and N this module reports the sampling time, the events found and missed
(short touches are missed unless a sample lands exactly on them), the worst error in the event
times, spurious changes (cells without an exact event: rounding near a degenerate motion), and
sampled labels that differ from the exact relation at the same (float, exact binary) time.

Stress (failures must be none): for every analysed case, rational times inside each reported
interval, random rational times, and the two ends of each event's refined isolating interval
(just before / just after), each checked on the exact matrices A(q), B(q) with the independent
oracle (``tests/oracle.py``) and with ``classify(method="exact")`` against ``relation_at(q)``;
rational events are checked to be tangent.
Known patterns are asserted too (a graze is one "touch" event at t = 0, a near miss has none).
Cases with sqrt(d) in their entries cannot be evaluated at rational times exactly and are
marked "n/a" in the check.

Run: ``python -m bench.moving [--quick]``.
"""

from __future__ import annotations

import argparse
import math
import random
import signal
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
from flint import fmpq

from core import analyse, classify
from core.moving.motions import as_motion, matrix_at_exact
from core.moving.presets import preset_arguments, preset_names

from . import datasets as D

__all__ = ["float_matrices", "sample_labels", "compare_sampling", "check_analysis", "run_moving", "SAMPLE_SIZES"]

SAMPLE_SIZES = (10, 100, 1000, 10_000, 100_000)
_TANGENT = 1


def _polyval(coeffs: list[Any], ts: np.ndarray) -> np.ndarray:
    if not coeffs:
        return np.zeros_like(ts)
    return np.polynomial.polynomial.polyval(ts, [float(c) for c in coeffs])


def float_matrices(motion: Any, ts: np.ndarray) -> np.ndarray:
    """(N, n, n) float64 A(t) at every t (entries p(t) + q(t) sqrt(d) over den(t), in floats).

    Examples:
        >>> m = {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["t", "0"]}
        >>> float_matrices(m, np.array([2.0]))[0].tolist()
        [[1.0, 0.0, -2.0], [0.0, 1.0, 0.0], [-2.0, 0.0, 3.0]]
    """
    M = as_motion(motion).matrix()
    n = len(M)
    out = np.empty((len(ts), n, n))
    for i in range(n):
        for j in range(i, n):
            e = M[i][j]
            v = _polyval(e.num.p.coeffs(), ts)
            if not e.num.q.is_zero():
                v = v + math.sqrt(e.num.d) * _polyval(e.num.q.coeffs(), ts)
            v = v / _polyval(e.den.coeffs(), ts)
            out[:, i, j] = out[:, j, i] = v
    return out


def window(res: Any) -> tuple[float, float]:
    """Finite float window of the analysed interval (infinite ends: around the events)."""
    lo, hi = res.interval
    ev = [float(e) for e in res.events]
    span = (max(ev) - min(ev)) if ev else 0.0
    w = max(1.0, 0.5 * span)
    flo = float(lo) if lo is not None else (min(ev) - w if ev else -3.0)
    fhi = float(hi) if hi is not None else (max(ev) + 1.37 * w if ev else 3.0 * 1.37)
    return flo, fhi


def sample_labels(args: dict[str, Any], ts: np.ndarray) -> np.ndarray:
    """Static classification at every sampled time (float matrices, certified labels)."""
    return classify(float_matrices(args["A_t"], ts), float_matrices(args["B_t"], ts))


def compare_sampling(args: dict[str, Any], res: Any, N: int, *, wrong_check: int = 2000) -> dict[str, Any]:
    """Sampling with N uniform times against the exact analysis ``res``.

    Returns:
        {"N", "time", "found", "events", "missed": [event kinds/times missed], "max_err",
         "spurious", "wrong", "checked"}.
    """
    lo, hi = window(res)
    ts = np.linspace(lo, hi, N)
    t0 = time.perf_counter()
    labels = sample_labels(args, ts)
    dt = time.perf_counter() - t0
    h = (hi - lo) / (N - 1)
    change = np.flatnonzero(labels[:-1] != labels[1:])
    tangent = np.flatnonzero(labels == _TANGENT)
    ev = [(float(e), e.kind) for e in res.events if lo <= float(e) <= hi]
    change_set = set(change.tolist())
    found, errs, missed = 0, [], []
    for tau, kind in ev:
        k = int(np.clip(np.searchsorted(ts, tau, side="right") - 1, 0, N - 2))  # ts[k] <= tau
        near = tangent[np.abs(ts[tangent] - tau) <= h] if tangent.size else tangent
        cands = [abs(ts[i] - tau) for i in near]
        cands += [abs((ts[c] + ts[c + 1]) / 2 - tau) for c in (k - 1, k) if c in change_set and ts[c] <= tau <= ts[c + 1]]
        if cands:
            found += 1
            errs.append(min(cands))
        else:
            missed.append(f"{kind} at {tau:.6g}")
    taus = np.array(sorted(t for t, _ in ev))
    spurious = 0
    for c in change:  # a change cell with no event inside
        spurious += not (taus.size and ((taus >= ts[c]) & (taus <= ts[c + 1])).any())
    idx = np.unique(np.linspace(0, N - 1, min(N, wrong_check)).astype(int))
    wrong = sum(int(labels[i]) != int(res.relation_at(float(ts[i]))) for i in idx)
    return {"N": N, "time": dt, "found": found, "events": len(ev), "missed": missed, "max_err": max(errs) if errs else math.nan,
            "spurious": spurious, "wrong": wrong, "checked": len(idx), "h": h}


# ------------------------------------------------------------------------------------ checks
def _oracle_code(args: dict[str, Any], q: fmpq) -> tuple[int, int]:
    """(oracle code, classify(method="exact") code) of the exact matrices at rational time q."""
    A = matrix_at_exact(args["A_t"], q)
    B = matrix_at_exact(args["B_t"], q)
    return int(D.label(np.array([A], dtype=object), np.array([B], dtype=object))[0]), int(classify(A, B, method="exact"))


def _rational_between(a: float, b: float, rng: random.Random) -> fmpq:
    x = a + (b - a) * rng.uniform(0.1, 0.9)
    return fmpq(*x.as_integer_ratio())


def check_analysis(args: dict[str, Any], res: Any, *, points: int = 12, seed: int = 0) -> dict[str, Any]:
    """Independent check of an analysis at rational times (see the module docstring).

    Returns:
        {"checked": number of rational times, "failures": [descriptions], "na": reason or None}.
    """
    if as_motion(args["A_t"]).sqrt_d() != 1 or as_motion(args["B_t"]).sqrt_d() != 1:
        return {"checked": 0, "failures": [], "na": "sqrt(d) in the entries"}
    rng = random.Random(seed)
    lo, hi = window(res)
    I_lo, I_hi = res.interval
    qs: list[tuple[fmpq, str]] = []
    for iv in res.intervals:
        a = float(iv.lo) if iv.lo is not None else lo - 1.0
        b = float(iv.hi) if iv.hi is not None else hi + 1.0
        for _ in range(2):
            q = _rational_between(a, b, rng)
            if (iv.lo is None or iv.lo.compare(q) < 0) and (iv.hi is None or iv.hi.compare(q) > 0):
                qs.append((q, "inside an interval"))
    for _ in range(points):
        q = _rational_between(lo, hi, rng)
        if (I_lo is None or q >= I_lo) and (I_hi is None or q <= I_hi):
            qs.append((q, "random time"))
    failures = []
    for e in res.events:
        e.time.try_rational()
        e.time.refine_to(fmpq(1, 10**12))
        if e.time.is_rational:
            qs.append((e.time.lo, f"event {e.kind}"))
            continue
        for q, where in ((e.lo, "just before"), (e.hi, "just after")):
            if (I_lo is None or q >= I_lo) and (I_hi is None or q <= I_hi):
                qs.append((q, f"{where} {e.kind} event"))
    for q, where in qs:
        try:
            truth, static_code = _oracle_code(args, q)
        except ValueError as err:  # e.g. a denominator vanishing at q
            failures.append(f"t = {q}: cannot evaluate ({err})")
            continue
        got = int(res.relation_at(q))
        if truth != got or static_code != got:
            failures.append(f"{where} t = {q}: analysis says {got}, oracle {truth}, classify {static_code}")
    expect = args.get("expect")
    kinds = [(e.kind, float(e)) for e in res.events]
    if expect == "touch at 0" and kinds != [("touch", 0.0)]:
        failures.append(f"expected one touch at t = 0, got {kinds}")
    if expect == "none" and kinds:
        failures.append(f"expected no event, got {kinds}")
    return {"checked": len(qs), "failures": failures, "na": None}


@contextmanager
def _time_limit(seconds: float) -> Iterator[None]:
    """Raise TimeoutError after ``seconds`` (main thread only; no limit elsewhere)."""
    try:
        old = signal.signal(signal.SIGALRM, lambda *_: (_ for _ in ()).throw(TimeoutError()))
    except ValueError:  # not the main thread
        yield
        return
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def _analyse(args: dict[str, Any], repeat: int) -> tuple[Any, float]:
    best, res = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = analyse(args["A_t"], args["B_t"], args["interval"])
        best = min(best, time.perf_counter() - t0)
    return res, best


def _deg(p: Any) -> int:
    return -1 if p.is_zero() else int(p.degree())


# ------------------------------------------------------------------------------------ cases
def cases(*, quick: bool, seed: int = 0) -> dict[str, list[dict[str, Any]]]:
    """The moving cases: paper examples and 2D presets; random motions; stress cases."""
    presets = []
    for name in preset_names():
        a = preset_arguments(name)
        a["name"] = name
        presets.append(a)
    rnd = [D.random_motion(dim, td, rd, seed=seed) for dim in (2, 3) for td, rd in ([(1, 0), (2, 1)] if quick else [(1, 0), (2, 0), (1, 1), (2, 1), (3, 1)])]
    stress = []
    for dim in (2, 3):
        for s in range(1 if quick else 3):
            stress.append(D.grazing_motion(dim, seed=seed + s))
        for k in ((3, 9) if quick else (3, 6, 9, 12)):
            stress.append(D.grazing_motion(dim, depth=fmpq(1, 10**k), seed=seed))
            stress.append(D.grazing_motion(dim, depth=-fmpq(1, 10**k), seed=seed))
    for k in ((3, 9) if quick else (3, 6, 9, 12)):
        for sgn in (1, -1):
            stress.append(D.almost_tangent_motion(sgn * fmpq(1, 10**k)))
    return {"paper and presets": presets, "random": rnd, "stress": stress}


def degree_sweep(*, quick: bool, seed: int = 0, budget: float = 60.0, log: Callable[[str], None] = print) -> list[dict[str, Any]]:
    """Time of analyse against deg s0 for random 3D motions of growing degree (stops at budget)."""
    grid = [(1, 0), (2, 0), (3, 0), (1, 1), (2, 1)] if quick else [(1, 0), (2, 0), (3, 0), (4, 0), (1, 1), (2, 1), (3, 1), (1, 2), (2, 2), (3, 2), (1, 3), (2, 3), (3, 3), (1, 4), (2, 4), (4, 4)]
    rows, t_start = [], time.perf_counter()
    for td, rd in grid:
        left = budget - (time.perf_counter() - t_start)
        if left <= 1:
            rows.append({"trans": td, "rot": rd, "skipped": "time budget"})
            continue
        args = D.random_motion(3, td, rd, seed=seed)
        try:
            with _time_limit(left):
                res, dt = _analyse(args, 1)
        except TimeoutError:
            rows.append({"trans": td, "rot": rd, "skipped": f"over {left:.0f} s"})
            continue
        except ValueError as e:  # e.g. a random quaternion vanishing in I
            rows.append({"trans": td, "rot": rd, "skipped": str(e)[:60]})
            continue
        rows.append({"trans": td, "rot": rd, "time": dt, "deg_s0": _deg(res.s0), "deg_s1": _deg(res.s1), "events": len(res.events)})
        log(f"#   degree sweep trans {td} rot {rd}: deg s0 {_deg(res.s0)}, {dt:.3f} s")
    return rows


def run_moving(*, quick: bool = False, seed: int = 0, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Run every case: exact analysis, sampling for each N, independent check; and the degree sweep."""
    t0 = time.perf_counter()
    classify(np.eye(4)[None] * [1, 1, 1, -1], np.eye(4)[None] * [1, 1, 1, -1])  # warm the kernels
    sizes = SAMPLE_SIZES[:4] if quick else SAMPLE_SIZES
    out: dict[str, Any] = {"cases": [], "sizes": list(sizes)}
    for group, items in cases(quick=quick, seed=seed).items():
        for args in items:
            try:
                with _time_limit(60):
                    res, dt = _analyse(args, 1 if quick else 3)
            except (TimeoutError, ValueError) as e:
                out["cases"].append({"group": group, "name": args["name"], "error": str(e)[:80] or "timeout"})
                continue
            row: dict[str, Any] = {
                "group": group, "name": args["name"], "n": res.n, "time": dt, "deg_s0": _deg(res.s0),
                "events": [(float(e), e.kind) for e in res.events], "window": window(res),
            }
            row["sampling"] = [compare_sampling(args, res, N, wrong_check=300 if quick else 2000) for N in sizes]
            row["check"] = check_analysis(args, res, points=4 if quick else 12, seed=seed)
            out["cases"].append(row)
            log(f"#   {args['name']:28s} analyse {dt * 1e3:7.1f} ms, {len(res.events)} events, check {row['check']['checked']} points, "
                f"{len(row['check']['failures'])} failures")
    out["degree"] = degree_sweep(quick=quick, seed=seed, budget=20 if quick else 120, log=log)
    out["seconds"] = time.perf_counter() - t0
    return out


# ------------------------------------------------------------------------------------ tables
def format_cases(out: dict[str, Any]) -> str:
    """Markdown: per case, the exact analysis and sampling at each N (found/events, error)."""
    sizes = out["sizes"]
    head = "| case | deg s0 | exact analyse | events | " + " | ".join(f"N={N:g}: found, max err, time" for N in sizes) + " | check |"
    lines = [head, "|---|---:|---:|---:|" + "---|" * len(sizes) + "---|"]
    for c in out["cases"]:
        if "error" in c:
            lines.append(f"| {c['name']} | | error: {c['error']} | |" + " |" * len(sizes) + " |")
            continue
        cells = []
        for s in c["sampling"]:
            err = "" if math.isnan(s["max_err"]) else f", {s['max_err']:.1e}"
            extra = f", {s['spurious']} spurious" if s["spurious"] else ""
            extra += f", {s['wrong']}/{s['checked']} wrong labels" if s["wrong"] else ""
            cells.append(f"{s['found']}/{s['events']}{err}{extra}, {s['time'] * 1e3:.1f} ms")
        ch = c["check"]
        chk = ch["na"] or (f"{ch['checked']} pts, **{len(ch['failures'])} failures**" if ch["failures"] else f"{ch['checked']} pts, ok")
        kinds = ", ".join(sorted({k for _, k in c["events"]}))
        lines.append(f"| {c['name']} | {c['deg_s0']} | {c['time'] * 1e3:.1f} ms | {len(c['events'])} {('(' + kinds + ')') if kinds else ''} | " + " | ".join(cells) + f" | {chk} |")
    return "\n".join(lines)


def format_summary(out: dict[str, Any]) -> str:
    """Markdown: per N, totals over all cases (events missed, worst error, spurious, time)."""
    sizes = out["sizes"]
    ok = [c for c in out["cases"] if "error" not in c]
    lines = ["| method | events found / total | touches found | worst event-time error | spurious changes | wrong sampled labels | total time |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    n_ev = sum(len(c["events"]) for c in ok)
    n_touch = sum(1 for c in ok for _, k in c["events"] if k == "touch")
    lines.append(f"| exact analysis (core.analyse) | {n_ev} / {n_ev} | {n_touch} / {n_touch} | 0 (certified, 20 digits) | 0 | 0 | {sum(c['time'] for c in ok) * 1e3:.0f} ms |")
    for k, N in enumerate(sizes):
        ss = [(c, c["sampling"][k]) for c in ok]
        found = sum(s["found"] for _, s in ss)
        tot = sum(s["events"] for _, s in ss)
        touch_found = 0
        for c, s in ss:
            missed_touch = sum(1 for m in s["missed"] if m.startswith("touch"))
            touch_found += sum(1 for _, kk in c["events"] if kk == "touch") - missed_touch
        errs = [s["max_err"] for _, s in ss if not math.isnan(s["max_err"])]
        lines.append(f"| sampling N = {N:g} | {found} / {tot} | {touch_found} / {n_touch} | {max(errs) if errs else float('nan'):.1e} | "
                     f"{sum(s['spurious'] for _, s in ss)} | {sum(s['wrong'] for _, s in ss)} / {sum(s['checked'] for _, s in ss)} | {sum(s['time'] for _, s in ss) * 1e3:.0f} ms |")
    return "\n".join(lines)


def format_degree(rows: list[dict[str, Any]]) -> str:
    lines = ["| translation degree | rotation (quaternion) degree | deg s0 | deg s1 | events | analyse time |", "|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if "skipped" in r:
            lines.append(f"| {r['trans']} | {r['rot']} | | | | skipped: {r['skipped']} |")
        else:
            lines.append(f"| {r['trans']} | {r['rot']} | {r['deg_s0']} | {r['deg_s1']} | {r['events']} | {r['time'] * 1e3:.1f} ms |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description="Moving shapes: exact analysis against uniform sampling (markdown tables).")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    out = run_moving(quick=a.quick, seed=a.seed)
    print(format_summary(out))
    print()
    print(format_cases(out))
    print()
    print(format_degree(out["degree"]))


if __name__ == "__main__":
    main()
