"""One command for the whole benchmark: static pairs, moving shapes, scene cost -> bench/REPORT.md.

Run from the repository root::

    python -m bench.report            # full run (about 5-10 minutes on 2 cores; the HTTP API rows: bench/api_load.py)
    python -m bench.report --quick    # small sizes, under a minute

Writes the tables of each section into ``bench/results/<name>.json`` (targets, throughput, static,
near-tangent, moving, scene, api: :func:`publish_sections`), renders ``bench/REPORT.md`` from every
result file (:mod:`bench.render`), and draws ``bench/figures/*.png`` (matplotlib, the ``bench``
extra). ``--out DIR`` writes the full Markdown report into DIR instead and no data (the smoke test
uses a temporary directory).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import os
import platform
import re
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

if __package__ in (None, ""):  # python bench/report.py
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    __package__ = "bench"  # noqa: A001

import numpy as np  # noqa: E402

import bench  # noqa: E402,F401  (pins BLAS threads before numpy)

from . import api_load, bodies_browser, moving, scene_browser, scene_cost, static, throughput  # noqa: E402

__all__ = ["main", "machine_info", "write_report", "targets"]

HERE = Path(__file__).resolve().parent


def machine_info() -> dict[str, str]:
    """Cores, CPU model, load and library versions."""
    info = {"cores (os.cpu_count)": str(os.cpu_count()), "python": platform.python_version(), "platform": platform.platform()}
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
    except OSError:
        info["cpu"] = platform.processor() or "unknown"
    try:
        info["load average (1, 5, 15 min) at start"] = " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        pass
    import flint

    info["numpy"] = np.__version__
    info["python-flint"] = flint.__version__
    for mod, key in (("viser", "viser"), ("coal", "coal"), ("fcl", "python-fcl"), ("matplotlib", "matplotlib")):
        try:
            m = __import__(mod)
            info[key] = getattr(m, "__version__", "installed")
        except ImportError:
            info[key] = "not installed"
    if info.get("python-fcl") == "installed":
        try:
            from importlib.metadata import version

            info["python-fcl"] = version("python-fcl")
        except Exception:  # noqa: BLE001
            pass
    return info


# ------------------------------------------------------------------------------------ targets
def _cell(results: list[Any], dataset: str, method: str) -> Any:
    for r in results:
        if r.dataset == dataset and r.method == method:
            return r
    return None


def targets(st: dict[str, Any], sc: dict[str, Any] | None, api: dict[str, Any] | None = None) -> list[tuple[str, str, str, bool | None]]:
    """(target, measured, verdict text, met) rows."""
    res = st["results"]
    rows: list[tuple[str, str, str, bool | None]] = []
    for dim, goal in ((3, 3e6), (2, 10e6)):
        r = _cell(res, f"random {dim}D", "adaptive")
        if r:
            ok = r.pairs_per_s >= goal
            rows.append((f"adaptive >= {goal / 1e6:g} M {'ellipsoid' if dim == 3 else 'ellipse'} pairs/s (random {dim}D, one core)",
                         f"{r.pairs_per_s / 1e6:.2f} M/s", "met" if ok else f"short by {100 * (1 - r.pairs_per_s / goal):.0f} %", ok))
    for dim in (3, 2):
        r = _cell(res, f"random {dim}D", "adaptive")
        if r:
            rate = (r.escalated or 0) / r.n
            rows.append((f"escalation < 0.1 % on random {dim}D pairs", f"{100 * rate:.3f} % ({r.escalated}/{r.n})", "met" if rate < 1e-3 else "missed", rate < 1e-3))
    wrong = {m: sum(r.wrong for r in res if r.method == m) for m in ("float", "adaptive", "exact")}
    n_lab = {m: sum(r.n for r in res if r.method == m) for m in ("float", "adaptive", "exact")}
    ok = all(v == 0 for v in wrong.values())
    rows.append(("zero wrong labels everywhere (float, adaptive, exact; all data sets)",
                 ", ".join(f"{m}: {wrong[m]} / {n_lab[m]}" for m in wrong), "met" if ok else "**VIOLATED**", ok))
    r = _cell(res, "random 3D", "exact")
    if r:
        ok = r.median_us <= 200
        mean = 1e6 / r.pairs_per_s
        rows.append(("exact path <= 200 us per ellipsoid pair (random 3D, one call per pair)",
                     f"median {r.median_us:.0f} us, mean {mean:.0f} us, worst {r.worst_us:.0f} us",
                     "met (median)" if ok else f"missed: median {r.median_us / 200:.1f}x the target", ok))
    if sc:
        for kind, name_part in (("drag", "drag (3D"), ("t-step", "slider (panels at 20 Hz), plots on")):
            rs = [x for x in sc["rows"] if x["kind"] == kind and name_part in x["name"]]
            goal = scene_cost.TARGETS_MS[kind]
            if rs:
                worst = max(x["median_ms"] for x in rs)
                ok = worst < goal
                rows.append((f"one {kind} < {goal:g} ms server time ({'3D static drag' if kind == 'drag' else 'slider step, examples 29 and 30'})",
                             ", ".join(f"{x['median_ms']:.2f} ms" for x in rs) + " (median)", "met" if ok else "missed", ok))
    if sc and sc.get("browser"):
        br = sc["browser"]
        worst = max(r["ms"] for r in br["presets"])
        goal = scene_browser.TARGETS_MS["preset to screen"]
        server = [r.get("server_ms", 0.0) for r in br["presets"]]
        medians = [r.get("ms_median", r["ms"]) for r in br["presets"]]
        rows.append((f"a preset on screen < {goal:g} ms (pick in the dropdown -> shapes drawn in the certified colour; headless "
                     "Chromium, software WebGL)", f"median {min(medians):.0f}-{max(medians):.0f} ms, worst {worst:.0f} ms over "
                     f"{len(br['presets'])} presets x {max(r.get('rounds', 1) for r in br['presets'])} picks; of it the server, "
                     "choice -> certified picture sent: "
                     f"{min(server):.0f}-{max(server):.0f} ms (analysed at server start: {min(r['analysis_ms'] for r in br['presets']):.0f}-"
                     f"{max(r['analysis_ms'] for r in br['presets']):.0f} ms)", "met" if worst < goal else "missed", worst < goal))
        sh = br["screenshots"]
        ok = sh["further_ms_max"] < scene_browser.TARGETS_MS["further screenshot"]
        rows.append(("screenshots: one browser for many images, each further image well under 1 s",
                     f"first {sh['first_s']:.1f} s, further {sh['further_t_ms_median']:.0f} ms (another t) / "
                     f"{sh['further_config_ms_median']:.0f} ms (another configuration), slowest {sh['further_ms_max']:.0f} ms",
                     "met" if ok else "missed", ok))
    if sc and sc.get("bodies_browser"):
        rows += bodies_browser.target_rows(sc["bodies_browser"])
    if api:
        b2, b3 = api.get("batch_2d"), api.get("batch_3d")
        if b2 and b3:
            rows.append((f"API batch of {b2['pairs']:,} pairs (one POST /api/classify, one vectorised classify call)",
                         f"ellipses {b2['best_ms']:.0f} ms, ellipsoids {b3['best_ms']:.0f} ms (best; median {b2['median_ms']:.0f} / {b3['median_ms']:.0f} ms)",
                         "reported", None))
        c = api.get("concurrency")
        if c:
            ok = c["p99_ms"] < api_load.TARGET_P99_MS
            rows.append((f"single-pair classify at concurrency {c['concurrency']}: p99 < {api_load.TARGET_P99_MS:g} ms",
                         f"p50 {c['p50_ms']:.0f} ms, p99 {c['p99_ms']:.0f} ms ({c['requests_per_s']:.0f} requests/s)",
                         "met" if ok else "missed", ok))
    return rows


# ------------------------------------------------------------------------------------ figures
def make_figures(st: dict[str, Any], mv: dict[str, Any] | None, sc: dict[str, Any] | None, outdir: Path) -> list[str]:
    """PNG plots; returns the file names written ([] without matplotlib)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    outdir.mkdir(parents=True, exist_ok=True)
    written = []
    res = st["results"]
    methods = list(dict.fromkeys(r.method for r in res))
    colours = dict(zip(methods, plt.get_cmap("tab10").colors, strict=False))
    markers = {"random": "o", "tangent": "*", "near": ".", "extreme": "s"}

    # 1. pairs/s against wrong-label rate, one point per method and data set
    fig, ax = plt.subplots(figsize=(9, 5.5))
    for m in methods:
        for fam, mk in markers.items():
            pts = [(r.pairs_per_s, r.error_rate) for r in res if r.method == m and r.family == fam]
            if pts:
                x, y = zip(*pts, strict=False)
                ax.scatter(x, y, c=[colours[m]], marker=mk, s=40 if mk != "." else 60, alpha=0.75,
                           label=m if fam == "random" else None, edgecolors="none")
    ax.set_xscale("log")
    ax.set_yscale("symlog", linthresh=1e-3)
    ax.set_ylim(-1e-4, 1.2)
    ax.set_xlabel("pairs per second (one core, log)")
    ax.set_ylabel("wrong-label rate (symlog; 0 = no wrong label)")
    ax.set_title("Run time against error: one point per method and data set")
    h1 = ax.legend(loc="upper left", fontsize=8, title="method")
    ax.add_artist(h1)
    fam_handles = [plt.Line2D([], [], color="grey", marker=mk, linestyle="", label=fam) for fam, mk in markers.items()]
    ax.legend(handles=fam_handles, loc="center left", fontsize=8, title="data set family")
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(outdir / "static_tradeoff.png", dpi=110)
    plt.close(fig)
    written.append("static_tradeoff.png")

    # 2. near-tangent: escalation and wrong labels per gap decade
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, dim in zip(axes, (2, 3), strict=False):
        for m in methods:
            xs, ys = [], []
            for sign in ("+", "-"):
                pts = sorted((int(r.dataset.split()[1][-2:]) * (1 if sign == "+" else -1), r.error_rate) for r in res
                             if r.family == "near" and r.dim == dim and r.method == m and r.dataset.split()[1][0] == sign)
                xs += [p[0] for p in pts]
                ys += [p[1] for p in pts]
            if xs and m != "exact":
                order = np.argsort(xs)
                ax.plot(np.array(xs)[order], np.array(ys)[order], marker="o", ms=3, color=colours[m], label=f"{m} wrong")
        esc = sorted((int(r.dataset.split()[1][-2:]) * (1 if r.dataset.split()[1][0] == "+" else -1), (r.escalated or 0) / r.n)
                     for r in res if r.family == "near" and r.dim == dim and r.method == "adaptive")
        if esc:
            ax.plot([e[0] for e in esc], [e[1] for e in esc], "k--", label="adaptive escalated to exact")
        ax.set_title(f"near-tangent pairs {dim}D (x = ±k: gap 1e-k apart / into)")
        ax.set_xlabel("gap exponent k (negative: overlapping side)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("fraction of pairs")
    if axes[1].get_legend_handles_labels()[0]:  # a run without near-tangent 3D rows has nothing to name
        axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(outdir / "near_tangent.png", dpi=110)
    plt.close(fig)
    written.append("near_tangent.png")

    if mv and [c for c in mv["cases"] if "error" not in c]:
        ok = [c for c in mv["cases"] if "error" not in c]
        sizes = mv["sizes"]
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
        tot = sum(len(c["events"]) for c in ok)
        found = [sum(c["sampling"][k]["found"] for c in ok) / max(tot, 1) for k in range(len(sizes))]
        errs = [max([c["sampling"][k]["max_err"] for c in ok if not math.isnan(c["sampling"][k]["max_err"])] or [math.nan]) for k in range(len(sizes))]
        t_s = [sum(c["sampling"][k]["time"] for c in ok) for k in range(len(sizes))]
        t_exact = sum(c["time"] for c in ok)
        axes[0].semilogx(sizes, found, "o-", label="sampling: events found")
        axes[0].axhline(1.0, color="k", ls="--", label="exact analysis (all, certified)")
        axes[0].set_xlabel("samples N")
        axes[0].set_ylabel("fraction of events found")
        axes[0].set_ylim(0, 1.05)
        ax2 = axes[0].twinx()
        ax2.loglog(sizes, errs, "s:", color="tab:red", label="worst event-time error")
        ax2.set_ylabel("worst event-time error", color="tab:red")
        axes[0].legend(loc="lower right", fontsize=8)
        axes[0].set_title(f"{len(ok)} moving cases, {tot} events")
        axes[1].loglog(sizes, t_s, "o-", label="sampling (float eval + classify)")
        axes[1].axhline(t_exact, color="k", ls="--", label="exact analysis")
        axes[1].set_xlabel("samples N")
        axes[1].set_ylabel("total time over all cases (s)")
        axes[1].legend(fontsize=8)
        axes[1].grid(alpha=0.3, which="both")
        fig.tight_layout()
        fig.savefig(outdir / "moving_sampling.png", dpi=110)
        plt.close(fig)
        written.append("moving_sampling.png")

        fig, ax = plt.subplots(figsize=(6.5, 4.2))
        pts = [(c["deg_s0"], c["time"]) for c in ok if c["deg_s0"] > 0]
        pts += [(r["deg_s0"], r["time"]) for r in mv["degree"] if "time" in r and r["deg_s0"] > 0]
        if pts:
            x, y = zip(*pts, strict=False)
            ax.loglog(x, y, "o")
            ax.set_xlabel("degree of s0 in t")
            ax.set_ylabel("analyse time (s)")
            ax.set_title("Exact analysis time against deg s0")
            ax.grid(alpha=0.3, which="both")
            fig.tight_layout()
            fig.savefig(outdir / "degree.png", dpi=110)
            written.append("degree.png")
        plt.close(fig)

    if sc and sc.get("rows"):
        fig, ax = plt.subplots(figsize=(9, 4.2))
        names = [r["name"].replace(", ", "\n", 1) for r in sc["rows"]]
        med = [r["median_ms"] for r in sc["rows"]]
        p95 = [r["p95_ms"] for r in sc["rows"]]
        y = np.arange(len(names))
        ax.barh(y, p95, color="lightgrey", label="p95")
        ax.barh(y, med, color="tab:blue", label="median")
        for r, yy in zip(sc["rows"], y, strict=False):
            ax.plot([scene_cost.TARGETS_MS[r["kind"]]] * 2, [yy - 0.4, yy + 0.4], "r-")
        ax.set_yticks(y, names, fontsize=6)
        ax.set_xlabel("server time per update (ms); red: target")
        ax.legend(fontsize=8)
        ax.invert_yaxis()
        fig.tight_layout()
        fig.savefig(outdir / "scene_cost.png", dpi=110)
        plt.close(fig)
        written.append("scene_cost.png")
    return written


# ------------------------------------------------------------------------------------ profiles
def profile_exact(n: int = 100) -> str:
    """Top functions (own time) of ``classify(..., method="exact")`` on random ellipsoid pairs."""
    import cProfile
    import io
    import pstats

    from core import classify

    from . import datasets as D

    ds = D.random_pairs(3, n, seed=7)
    pr = cProfile.Profile()
    pr.enable()
    for i in range(n):
        classify(ds.A[i], ds.B[i], method="exact")
    pr.disable()
    buf = io.StringIO()
    pstats.Stats(pr, stream=buf).sort_stats("tottime").print_stats(12)
    text = buf.getvalue()
    return text[text.find("ncalls") :] if "ncalls" in text else text


def profile_t_step(n: int = 200) -> str:
    """Top functions (cumulative) of n jump t-steps of example-30 (readout, bar, t box at once)."""
    import cProfile
    import io
    import pstats

    import viser

    from app.scene.common.state import SceneConfig
    from app.scene.pair import session as S

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        s = S.Session(server, SceneConfig(preset="example-30"))
        s.ready.wait(120)
        lo, hi = s.state.analysis.window if s.state.analysis else (0.0, 1.0)
        pr = cProfile.Profile()
        pr.enable()
        for i in range(n):
            s.set_t(lo + (hi - lo) * (i + 0.5) / n)
        pr.disable()
        buf = io.StringIO()
        pstats.Stats(pr, stream=buf).sort_stats("cumulative").print_stats(14)
        text = buf.getvalue()
        return text[text.find("ncalls") :] if "ncalls" in text else text
    finally:
        server.stop()


# ------------------------------------------------------------------------------------ report
def _md_table(d: dict[str, str]) -> str:
    return "\n".join(["| | |", "|---|---|", *[f"| {k} | {v} |" for k, v in d.items()]])


def _reading(st: dict[str, Any], mv: dict[str, Any] | None, sc: dict[str, Any] | None, tg: list[Any]) -> list[str]:
    """Short reading of the numbers, computed from them (no claim without its number)."""
    res = st["results"]
    out = []
    met = [t for t in tg if t[3]]
    missed = [t for t in tg if t[3] is False]
    out.append(f"Targets met: {len(met)} of {len([t for t in tg if t[3] is not None])}." + (" Missed: " + "; ".join(f"{t[0]} ({t[1]})" for t in missed) + "." if missed else ""))
    w = {m: sum(r.wrong for r in res if r.method == m) for m in st["methods"]}
    n = {m: sum(r.n for r in res if r.method == m) for m in st["methods"]}
    out.append("Wrong labels over all static data sets: " + ", ".join(f"{m} {w[m]}/{n[m]}" for m in st["methods"]) + ".")
    tan = [r for r in res if r.family == "tangent" and r.method == "numpy-eig"]
    if tan:
        out.append(f"The eigenvalue baseline (tolerance {static.EIG_TOL:g}) mislabels {sum(r.wrong for r in tan)} of {sum(r.n for r in tan)} "
                   "exactly tangent pairs (a double eigenvalue splits in floats) and fails on the tiniest near-tangent gaps; "
                   "GJK answers a boolean (no tangency) and its default tolerance decides wrongly from gaps around its tolerance down.")
    near_fl = [r for r in res if r.family == "near" and r.method == "adaptive"]
    if near_fl:
        first = None
        for e in static.D.GAP_EXPONENTS:
            rs = [r for r in near_fl if r.dataset.split()[1][-2:] == f"{e:02d}"]
            if rs and sum(r.escalated or 0 for r in rs) > 0:
                first = e
                break
        if first:
            out.append(f"The float filter abstains first at relative gaps around 1e-{first:02d}; the adaptive method escalates those pairs "
                       "to exact arithmetic, so its throughput drops where the pairs are nearly degenerate, never its correctness.")
    ext = [r for r in res if r.family == "extreme" and r.method == "adaptive" and r.n and (r.escalated or 0) / r.n > 0.5]
    if ext:
        out.append("Extreme inputs where the float filter abstains on most pairs (everything goes to exact): "
                   + ", ".join(f"{r.dataset} ({100 * (r.escalated or 0) / r.n:.0f} %)" for r in ext)
                   + ". The bound is relative to the largest entry (centres at 1e6 make c^T Q c dominate; aspect 1e6 spreads entries over 12 decades).")
    if mv:
        ok = [c for c in mv["cases"] if "error" not in c]
        fails = sum(len(c["check"]["failures"]) for c in ok)
        pts = sum(c["check"]["checked"] for c in ok)
        out.append(f"Moving shapes: {len(ok)} cases analysed, {pts} rational times checked against the oracle, {fails} failures.")
        big = mv["sizes"][-1]
        k = len(mv["sizes"]) - 1
        missed_big = [f"{c['name']}: {', '.join(c['sampling'][k]['missed'])}" for c in ok if c["sampling"][k]["missed"]]
        slow = [c for c in ok if c["deg_s0"] == -1 and c["sampling"][k]["time"] > 10 * c["time"]]
        if slow:
            out.append("Sampling is slowest where s0 vanishes identically (" + ", ".join(c["name"] for c in slow)
                       + "): the float filter can never certify a sign there, so every sample goes to exact arithmetic "
                       f"(N = {big:g}: " + ", ".join(f"{c['sampling'][k]['time']:.1f} s" for c in slow)
                       + ", against " + ", ".join(f"{c['time'] * 1e3:.0f} ms" for c in slow) + " for the exact analysis).")
        if missed_big:
            out.append(f"Even with N = {big:g} samples, uniform sampling misses: " + "; ".join(missed_big[:8]) + (" …" if len(missed_big) > 8 else "") + ".")
    if sc:
        out.append("Scene: no exact analysis and no static explain() runs during t-steps (columns 'analyses run', 'explain() calls'); "
                   "closing the plots panel removes the plot-cursor updates (coalesced to 20 Hz in every mode).")
    out.append("Noise: the machine has 2 cores shared with other jobs during the run (load average above); throughputs are best-of-3 "
               "and single-pair worst cases are maxima, which scheduler pauses inflate.")
    return out


def write_report(st: dict[str, Any], mv: dict[str, Any] | None, sc: dict[str, Any] | None, *, outdir: Path, command: str,
                 info: dict[str, str], profiles: dict[str, str], seconds: float, api: dict[str, Any] | None = None,
                 tp: dict[str, Any] | None = None) -> Path:
    """Write REPORT.md (and the figures) into outdir; returns the report path."""
    outdir.mkdir(parents=True, exist_ok=True)
    figs = make_figures(st, mv, sc, outdir / "figures")
    tg = targets(st, sc, api) + (throughput.throughput_targets(tp) if tp else [])
    L: list[str] = []
    L.append("# Benchmark report: run time against error, numerical stress, scene cost\n")
    L.append(f"Generated by `{command}` in {seconds:.0f} s on {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}. "
             "Rerun it to reproduce; `--quick` gives a smaller run in under a minute.\n")
    L.append("## Machine\n")
    L.append(_md_table(info) + "\n")
    L.append("Timings of the static rows on one core (`core.set_threads(1)`; the scaling section uses every core), BLAS pools pinned to one thread. "
             "Ground truth: `tests/oracle.py` (exact characteristic polynomial with flint `fmpq_mat`, certified root isolation), "
             "never the code under test.\n")
    L.append("## Targets\n")
    L.append("| target | measured | verdict |\n|---|---|---|")
    for t in tg:
        L.append(f"| {t[0]} | {t[1]} | {t[2]} |")
    L.append("\n## Reading\n")
    L.extend(f"- {x}" for x in _reading(st, mv, sc, tg))
    if tp:
        L.append("\n## Throughput on every core, on the inputs users bring\n")
        L.append("Certified = `core.classify(A, B)` (adaptive: compiled float filter, exact arithmetic for what it leaves) on "
                 "float64 stacks; the uncertified baseline is the paper's tree in plain C (`bench/baseline_tree.c`, built at "
                 "benchmark time with `gcc -O3 -march=native`, no error bound, no validation); the memory read sums both input "
                 "arrays once. Structured data: s0 vanishes identically for spheres and translated or homothetic copies, so the "
                 "filter decides them by its certificates that do not need s0 (rules `sep-witness`, `common-point`).\n")
        L.append(throughput.format_throughput(tp) + "\n")
    L.append("\n## Static pairs\n")
    L.append("Methods: `float` (certified filter, may abstain), `adaptive` (filter + exact for abstentions; the default), `exact` "
             "(rationals, one call per pair), `numpy-eig` (batched `eigvals(solve(A, B))` with a tolerance), GJK collide from "
             "coal and python-fcl on their ellipsoid primitives when installed (3D only; boolean, so on tangent pairs either answer counts as right; "
             "GJK receives the centre / semi-axes / rotation the float matrices were built from, so below gaps of about 1e-15 the rounding of "
             "the matrices alone can make its input differ from the labelled pair).\n")
    L.append("**Root criterion of the eigenvalue baseline.** det(A^-1 B - lam I) = 0 iff det(T A + B) = 0 with T = -lam, so the "
             "eigenvalues of A^-1 B are the negated roots of P. By Theorems 7 / 19, P has at least one (2D) or two (3D) negative "
             "roots, and the shapes are separate iff P has two distinct positive roots, externally tangent iff it has a positive "
             f"double root, overlapping iff none. Hence: two distinct negative real eigenvalues -> separate, a negative double "
             f"eigenvalue -> tangent, none -> overlap; 'real' is |Im| <= {static.EIG_TOL:g} max(1, |lam|), 'double' is a relative "
             f"difference <= {static.EIG_TOL:g}.\n")
    if st["missing"]:
        L.append("Not installed (skipped): " + ", ".join(f"{k} ({v})" for k, v in st["missing"].items()) + ".\n")
    if "static_tradeoff.png" in figs:
        L.append("![pairs/s against error](figures/static_tradeoff.png)\n")
    L.append("Columns: pairs/s from the batch call on the data set tiled to a fixed size (exact and GJK: one call per pair); "
             "wrong = decided labels that differ from the oracle; escalated = pairs the float filter left undecided (sent to exact "
             "by adaptive); median / worst us = single-pair calls (`classify(A[i], B[i])`: the scene's path; for adaptive the "
             "escalated pairs are included in the sample). Near-tangent rows merge the 14 gap decades of one side.\n")
    ds_lines = ["| data set | pairs | separate | tangent | overlap | dropped (rounded to invalid) |", "|---|---:|---:|---:|---:|---:|"]
    for d in st["datasets"]:
        if d["family"] != "near":
            c = d["counts"]
            ds_lines.append(f"| {d['name']} | {d['n']} | {c['separate']} | {c['tangent']} | {c['overlap']} | {d['dropped']} |")
    L.append(static.format_table(st["results"]) + "\n")
    L.append("<details><summary>Data sets (labels from the oracle)</summary>\n\n" + "\n".join(ds_lines) + "\n\n</details>\n")
    L.append("### Near-tangent pairs per gap decade\n")
    if "near_tangent.png" in figs:
        L.append("![near-tangent](figures/near_tangent.png)\n")
    for dim in (2, 3):
        L.append(f"**{dim}D** (wrong / pairs per method; gap = relative translation along the common normal, + apart, - into)\n")
        L.append(static.format_gap_table(st["results"], dim) + "\n")
    if mv:
        L.append("## Moving shapes: exact analysis against uniform sampling\n")
        L.append("Sampling = evaluate A(t), B(t) in floats at N uniform times of a window and classify each pair with the certified "
                 "static classifier; an event is 'found' when a grid cell containing it changes label (estimate: cell midpoint) or a "
                 "sample is labelled tangent. 'spurious' = label changes in a cell without an exact event. 'wrong sampled labels' "
                 "compares sampled labels with `relation_at(t)` at the same float t (up to 2000 samples per case). Infinite intervals "
                 "use a window around the events (ends not aligned with them).\n")
        if "moving_sampling.png" in figs:
            L.append("![moving](figures/moving_sampling.png)\n")
        L.append(moving.format_summary(mv) + "\n")
        L.append("Per case (check = the independent oracle and `classify(method=\"exact\")` on the exact A(q), B(q) against "
                 "`relation_at(q)` at rational times inside every interval, random times, and just before/after each event "
                 "(isolating interval refined below 1e-12); 'n/a' where sqrt(d) makes A(q) irrational):\n")
        L.append(moving.format_cases(mv) + "\n")
        fails = [(c["name"], f) for c in mv["cases"] if "check" in c for f in c["check"]["failures"]]
        L.append(f"**Failures: {len(fails)}**" + ("" if not fails else ":\n" + "\n".join(f"- {n}: {f}" for n, f in fails)) + "\n")
        L.append("### Time against the degree of s0 (random 3D motions)\n")
        if "degree.png" in figs:
            L.append("![degree](figures/degree.png)\n")
        L.append(moving.format_degree(mv["degree"]) + "\n")
    if sc:
        L.append("## Scene: server cost of one update\n")
        L.append("Measured without a browser on a private viser server (compute + queueing the websocket messages; `app.scene.pair.session.Session`). "
                 "'slider' = `set_t(t, defer_panels=True)` (what the slider and playback run: shapes and colours at once, panels "
                 "coalesced to 20 Hz, their messages counted); 'jump' = `set_t(t)` (what an event button or a typed t runs: the readout, "
                 "intervals bar and t box at once; the plot cursor follows within 50 ms in every mode). 'analyses run' = calls of "
                 "`core.moving.analysis.analyse` during the steps; 'explain() calls' = static explanations during the steps. "
                 "Each row is the best of 3 runs on fresh servers (lowest median), as throughputs are best-of-3: the machine is shared.\n")
        if "scene_cost.png" in figs:
            L.append("![scene](figures/scene_cost.png)\n")
        L.append(scene_cost.format_scene(sc) + "\n")
        if sc.get("cross_check"):
            cc = {k: round(v, 3) if isinstance(v, float) else v for k, v in sc["cross_check"].items()}
            L.append(f"Cross-check with the scene helper's `measure_update_costs()`: `{cc}`\n")
        if sc.get("browser"):
            L.append("## Scene in a browser: presets to screen, screenshots\n")
            L.append("Headless Debian Chromium (software WebGL, SwiftShader) on this machine, `bench/scene_browser.py` (in a "
                     "subprocess). 'On screen' = from the click on a preset in the dropdown to three.js holding both shapes at "
                     "their poses in the certified colour (the presets are analysed once when the server starts, in its worker pool: "
                     "the analysis column is that worker time, not part of the pick); "
                     "'panel complete' adds the readout, timeline and plots. Screenshots: one browser and one server for all "
                     "images (`app.screenshot.screenshots`).\n")
            L.append(scene_browser.format_browser(sc["browser"]) + "\n")
        if sc.get("bodies_browser"):
            L.append("## Many bodies in a browser: orbit, open pair, screenshots\n")
            L.append("`bench/bodies_browser.py` (in a subprocess): random ellipsoids (packing fraction 0.3) in "
                     "`serve --bodies`'s view, headless Chromium at 1200 x 800, software WebGL. Each body is a point; the "
                     "largest on screen are solids within a triangle budget, chosen for the tab's camera.\n")
            L.append(bodies_browser.format_bodies_browser(sc["bodies_browser"]) + "\n")
    if api:
        L.append("## HTTP API: batch and concurrent requests\n")
        L.append("The real server (`python -m app serve --api-only`) in a subprocess, driven over keep-alive HTTP/1.1 from the "
                 "benchmark process (`bench/api_load.py`, a minimal asyncio client); client-side wall times. The batch is one "
                 "`POST /api/classify` of 1,000 random float pairs (the route makes one vectorised `core.classify(method=\"float\")` "
                 "call per matrix size, exact arithmetic only for the pairs the filter leaves undecided); the concurrency row is "
                 "32 connections each sending single random ellipsoid pairs back to back (after a warm-up round). Client and "
                 "server share the 2 cores.\n")
        L.append(api_load.format_api(api) + "\n")
    if profiles:
        L.append("## Where the time goes (profiles of what is over its target)\n")
        for name, text in profiles.items():
            L.append(f"**{name}**\n\n```\n{text.strip()}\n```\n")
    if not figs:
        L.append("_matplotlib is not installed (`pip install -e .[bench]`): no figures._\n")
    path = outdir / "REPORT.md"
    # sections written by other scripts (bench_sweep.py --report) are kept as they are
    blocks = re.findall(r"<!-- \w+:begin -->.*?<!-- \w+:end -->", path.read_text(), re.S) if path.exists() else []
    path.write_text("\n".join(L) + "\n" + "".join("\n" + b + "\n" for b in blocks))
    return path


SECTIONS = {"Targets": "targets", "Throughput": "throughput", "Static pairs": "static", "Moving shapes": "moving",
            "Scene": "scene", "Many bodies in a browser": "scene", "HTTP API": "api"}
"""The result file (bench/results/<name>.json) each section of the report's Markdown goes to, by title prefix."""


def publish_sections(text: str, command: str, results: Path | None = None) -> list[Path]:
    """Write the tables of a report's sections into bench/results/*.json and render bench/REPORT.md."""
    from . import render

    folder = results or render.RESULTS
    parts: dict[str, list[str]] = {}
    for section in re.split(r"^(?=## )", text, flags=re.M):
        title = section.splitlines()[0].removeprefix("## ").strip() if section.startswith("## ") else ""
        name = next((v for k, v in SECTIONS.items() if title.startswith(k)), None)
        own, _, near = section.partition("### Near-tangent")
        if name == "static":  # its near-tangent subsection is a question of its own
            parts.setdefault("near-tangent", []).append("### Near-tangent" + near)
        if name is not None:
            parts.setdefault(name, []).append(own if name == "static" else section)
    paths = [render.publish(name, command=command, markdown="\n".join(md), results=folder, report=None) for name, md in parts.items()]
    render.write_report(folder, render.REPORT if results is None else folder / "REPORT.md")
    return paths


def main(argv: list[str] | None = None) -> Path:
    ap = argparse.ArgumentParser(description="Run the static, moving and scene benchmarks; write bench/REPORT.md and figures.")
    ap.add_argument("--quick", action="store_true", help="small sizes (under a minute)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=HERE, help="directory for REPORT.md and figures/ (default: bench/, where "
                    "the numbers go to bench/results/*.json and REPORT.md is rendered from them)")
    ap.add_argument("--skip", nargs="*", default=[], choices=["moving", "scene", "browser", "api", "profiles", "throughput"], help="parts to leave out")
    ap.add_argument("--allow-missing-peers", action="store_true", help="run even if a peer (coal, python-fcl, scipy) is missing")
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    log: Callable[[str], None] = lambda s: print(s, file=sys.stderr, flush=True)
    missing = [name for name, module in (("coal", "coal"), ("python-fcl", "fcl"), ("scipy", "scipy")) if importlib.util.find_spec(module) is None]
    if missing and not a.allow_missing_peers:  # the GJK rows must not be empty again (issue 24)
        ap.error(f"the benchmark's peers are not installed: {', '.join(missing)}. Fix: pip install -e \".[bench]\" "
                 "(or --allow-missing-peers to run without them)")
    info = machine_info()
    tp = None
    if "throughput" not in a.skip:
        log("# throughput (every core, baseline, structured data, cold start)")
        tp = throughput.run_throughput(quick=a.quick, log=log)
    log("# static benchmark")
    st = static.run_static(quick=a.quick, seed=a.seed, log=log)
    mv = None
    if "moving" not in a.skip:
        log("# moving shapes")
        mv = moving.run_moving(quick=a.quick, seed=a.seed, log=log)
    sc = None
    if "scene" not in a.skip:
        log("# scene cost")
        try:
            sc = scene_cost.run_scene_cost(quick=a.quick, log=log)
        except ImportError as e:  # viser / app missing
            log(f"# scene cost skipped: {e}")
        if sc is not None and "browser" not in a.skip:
            log("# scene in a browser (presets to screen, screenshots)")
            try:
                sc["browser"] = scene_browser.run_in_subprocess(quick=a.quick)
            except (RuntimeError, OSError, ValueError) as e:  # no chromium, or it failed
                log(f"# scene in a browser skipped: {e}")
            log("# many bodies in a browser (orbit, open pair)")
            try:
                sc["bodies_browser"] = bodies_browser.run_in_subprocess(quick=a.quick)
            except (RuntimeError, OSError, ValueError) as e:  # no chromium, or it failed
                log(f"# many bodies in a browser skipped: {e}")
    api = None
    if "api" not in a.skip:
        log("# HTTP API")
        try:
            api = api_load.run_api_load(quick=a.quick, seed=a.seed, log=log)
        except (ImportError, RuntimeError) as e:  # app missing, or the server did not start
            log(f"# HTTP API skipped: {e}")
    profiles: dict[str, str] = {}
    if "profiles" not in a.skip:
        tg = targets(st, sc, api)
        for t in tg:
            if t[3] is False and "exact path" in t[0]:
                profiles["exact path, 100 random ellipsoid pairs (cProfile, own time)"] = profile_exact(30 if a.quick else 100)
        full = [r for r in (sc or {}).get("rows", []) if r["kind"] == "t-step" and r["median_ms"] >= scene_cost.TARGETS_MS["t-step"]]
        if full:
            profiles["jump t-step (event button / typed t: readout, bar, t box at once), example-30, over 1 ms (cProfile, cumulative)"] = profile_t_step(50 if a.quick else 200)
    command = "python -m bench.report" + (" --quick" if a.quick else "") + (f" --seed {a.seed}" if a.seed else "")
    path = write_report(st, mv, sc, outdir=a.out, command=command, info=info, profiles=profiles, seconds=time.perf_counter() - t0,
                        api=api, tp=tp)
    if a.out.resolve() == HERE.resolve():  # the repository's report: its numbers become data, REPORT.md their rendering
        for p in publish_sections(path.read_text(), command):
            log(f"# wrote {p}")
        path = HERE / "REPORT.md"
    log(f"# wrote {path} in {time.perf_counter() - t0:.0f} s")
    return path


if __name__ == "__main__":
    main()
