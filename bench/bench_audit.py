"""Benchmark of ``python -m app audit`` against the float check a user would write.

    python -m bench.bench_audit              # 100 frames of 100,000 ellipsoids (~3 min with the anchor)
    python -m bench.bench_audit --quick      # 10 frames of 20,000 (seconds)

Speed: a HOOMD GSD trajectory of nearly aligned ellipsoids at packing fraction 0.5
(:func:`bench.trajectory_data.fcc_trajectory`: no pair overlaps, many bounding spheres meet) is
audited by the command (certified, every core) and by the anchor: per frame, scipy's
``cKDTree.query_pairs`` on the centres (periodic) and the Perram-Wertheim contact function in
numpy float64 (:func:`pw_overlap`), on one core as a user's script runs. Both answer "does any
pair overlap?" for every frame.

Accuracy near contact: pairs of axis-aligned ellipsoids of different shapes that touch exactly,
a quarter of them moved by +-2^-40 (overlaps and gaps of ~1e-12, 40 to 1,000 from the origin:
:func:`bench.trajectory_data.touching_pairs`), written as one frame and audited by the command.
The certified labels and the float check's (with no tolerance, and with a tolerance of 1e-10 on
the contact function) are compared with that truth.

Writes ``bench/results/audit.json`` (the command, the machine, the numbers) and prints a table.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.machine import RESULTS, cores, cpu_model
from bench.render import write_report
from bench.trajectory_data import FCC_AXES, fcc_trajectory, touching_pairs, write_gsd


def rotations(q: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotation matrices of unit quaternions wxyz."""
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def _inv3(m: np.ndarray) -> np.ndarray:
    """Inverses of (M, 3, 3) symmetric matrices by their adjugates."""
    a, b, c, d, e, f = m[:, 0, 0], m[:, 0, 1], m[:, 0, 2], m[:, 1, 1], m[:, 1, 2], m[:, 2, 2]
    A, B, C = d * f - e * e, c * e - b * f, b * e - c * d
    det = a * A + b * B + c * C
    D, E, F = a * f - c * c, b * c - a * e, a * d - b * b
    return np.stack([np.stack([A, B, C], -1), np.stack([B, D, E], -1), np.stack([C, E, F], -1)], -2) / det[:, None, None]


def pw_function(r: np.ndarray, Ai: np.ndarray, Aj: np.ndarray, iterations: int = 40) -> np.ndarray:
    """max over lambda in [0, 1] of lambda (1 - lambda) r^T [(1 - lambda) Ai + lambda Aj]^-1 r (golden section).

    Ai, Aj: the inverse shape matrices R diag(a^2) R^T; < 1: the ellipsoids overlap, 1: they touch.
    """
    g = (math.sqrt(5) - 1) / 2
    lo, hi = np.zeros(len(r)), np.ones(len(r))

    def F(lam: np.ndarray) -> np.ndarray:
        C = (1 - lam)[:, None, None] * Ai + lam[:, None, None] * Aj
        return lam * (1 - lam) * np.einsum("ni,nij,nj->n", r, _inv3(C), r)

    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1, f2 = F(x1), F(x2)
    for _ in range(iterations):
        left = f1 < f2
        lo = np.where(left, x1, lo)
        hi = np.where(left, hi, x2)
        x1n = np.where(left, x2, hi - g * (hi - lo))
        x2n = np.where(left, lo + g * (hi - lo), x1)
        f1n = np.where(left, f2, F(x1n))  # (computes both; a user's vectorised script does the same)
        f2n = np.where(left, F(x2n), f1)
        x1, x2, f1, f2 = x1n, x2n, f1n, f2n
    return np.maximum(f1, f2)


def pw_overlap(centers: np.ndarray, axes: np.ndarray, quats: np.ndarray, box: tuple[float, ...] | None,
               tol: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The user's float check: cKDTree pairs within 2 max(a), then the Perram-Wertheim function.

    Returns (i, j, F) of the candidate pairs; the pair overlaps when F < 1 - tol.
    """
    from scipy.spatial import cKDTree

    L = None if box is None else np.asarray(box, dtype=np.float64)
    c = centers if L is None else centers - L * np.floor(centers / L)  # cKDTree wants [0, L)
    if L is not None:
        c = np.where(c >= L, 0.0, c)
    tree = cKDTree(c, boxsize=L)
    pairs = tree.query_pairs(2 * float(axes.max()), output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    d = centers[j] - centers[i]
    if L is not None:
        d -= L * np.round(d / L)
    R = rotations(quats)
    Ainv = np.einsum("nij,nj,nkj->nik", R, axes**2, R)
    return i, j, pw_function(d, Ainv[i], Ainv[j])


def speed(cells: tuple[int, int, int], frames: int, folder: Path, jobs: int | None, *, anchor: bool = True) -> dict[str, object]:
    """Audit the GSD trajectory with the command and (``anchor``) with the float anchor; timings and answers."""
    traj = fcc_trajectory(cells, frames, seed=1)
    path = folder / "run.gsd"
    write_gsd(str(path), traj)
    n = len(traj.semi_axes)
    del traj
    cmd = [sys.executable, "-m", "app", "audit", str(path), "--out", str(folder / "report.csv"), "--quiet"]
    if jobs:
        cmd += ["--jobs", str(jobs)]
    t = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    certified = time.perf_counter() - t
    if done.returncode not in (0, 3):
        raise RuntimeError(done.stderr)
    rows = sum(1 for _ in open(folder / "report.csv")) - 1
    if not anchor:
        return {"bodies": n, "frames": frames, "fraction": 0.5, "certified_s": certified, "certified_overlaps": rows,
                "certified_exit": done.returncode, "jobs": jobs or cores()}
    import gsd.hoomd

    t = time.perf_counter()
    flagged = candidates = 0
    with gsd.hoomd.open(str(path), "r") as f:
        for frame in f:
            c = np.asarray(frame.particles.position, np.float64)
            q = np.asarray(frame.particles.orientation, np.float64)
            q /= np.linalg.norm(q, axis=1)[:, None]
            axes = np.tile(FCC_AXES, (len(c), 1))
            i, _, F = pw_overlap(c, axes, q, tuple(frame.configuration.box[:3]))
            candidates += len(i)
            flagged += int(np.count_nonzero(F < 1))
    anchor_s = time.perf_counter() - t
    return {"bodies": n, "frames": frames, "fraction": 0.5, "certified_s": certified, "certified_overlaps": rows,
            "certified_exit": done.returncode, "anchor_s": anchor_s, "anchor_candidates": candidates, "anchor_overlaps": flagged,
            "jobs": jobs or cores()}


def accuracy(m: int) -> dict[str, object]:
    """Touching pairs: the command's labels and the float check's against the construction's truth."""
    pairs = touching_pairs(m, seed=3)
    truth = pairs.truth
    with tempfile.TemporaryDirectory(prefix="audit-pairs-") as d:  # the command, on one frame of the pairs
        frame = Path(d) / "pairs.csv"
        rows = np.concatenate([pairs.centers, pairs.semi_axes, np.tile([1.0, 0, 0, 0], (len(pairs.centers), 1))], axis=1)
        frame.write_text("x,y,z,a,b,c,qw,qx,qy,qz\n" + "".join(",".join(repr(v) for v in r) + "\n" for r in rows.tolist()))
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "app", "audit", str(frame), "--out", str(Path(d) / "r.csv"), "--quiet", "--jobs", "1"],
                       check=False, capture_output=True)
        certified_s = time.perf_counter() - t
        import csv

        got = {(int(r["i"]), int(r["j"])): r["relation"] for r in csv.DictReader(open(Path(d) / "r.csv"))}
    keys = set(got) | set(truth)
    out: dict[str, object] = {
        "pairs": m, "tangent": sum(v == "tangent" for v in truth.values()), "overlap": sum(v == "overlap" for v in truth.values()),
        "certified": {"wrong": sum(1 for k in keys if got.get(k) != truth.get(k)),
                      "false_overlaps": sum(1 for k in keys if got.get(k) == "overlap" and truth.get(k) != "overlap"),
                      "missed_overlaps": sum(1 for k in keys if truth.get(k) == "overlap" and got.get(k) != "overlap"),
                      "seconds": certified_s},
    }
    quats = np.tile([1.0, 0, 0, 0], (len(pairs.centers), 1))
    t = time.perf_counter()
    i, j, F = pw_overlap(pairs.centers, pairs.semi_axes, quats, None)
    float_s = time.perf_counter() - t
    for tol in (0.0, 1e-10):
        labels = np.where(F < 1 - tol, "overlap", np.where(F <= 1 + tol, "tangent", ""))
        float_got = {(int(a), int(b_)): str(v) for a, b_, v in zip(i, j, labels, strict=True) if v}
        keys = set(float_got) | set(truth)
        out[f"float_tol_{tol:g}"] = {
            "wrong": sum(1 for k in keys if float_got.get(k) != truth.get(k)),
            "false_overlaps": sum(1 for k in keys if float_got.get(k) == "overlap" and truth.get(k) != "overlap"),
            "missed_overlaps": sum(1 for k in keys if truth.get(k) == "overlap" and float_got.get(k) != "overlap"),
            "seconds": float_s,
        }
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; print the table; write bench/results/audit.json."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="10 frames of 20,000 bodies, a 12^3 lattice")
    ap.add_argument("--jobs", type=int, default=None, help="the command's worker processes (default: every core)")
    ap.add_argument("--command-only", action="store_true",
                    help="time only the command on the trajectory (no float anchor, no accuracy): bench/results/audit-command.json")
    args = ap.parse_args(argv)
    load_before = os.getloadavg()[0]  # a shared machine: the figures depend on what else runs
    cells, frames, m = ((10, 20, 25), 10, 20_000) if args.quick else ((25, 40, 25), 100, 100_000)
    with tempfile.TemporaryDirectory(prefix="audit-bench-") as d:
        sp = speed(cells, frames, Path(d), args.jobs, anchor=not args.command_only)
    if args.command_only:
        name = "audit-command-quick" if args.quick else "audit-command"
        result = {"command": "python -m bench.bench_audit --command-only" + (" --quick" if args.quick else ""),
                  "cpu": cpu_model(), "cores": cores(),
                  "load_average": f"{load_before:.1f} at the start, {os.getloadavg()[0]:.1f} at the end", "speed": sp}
        RESULTS.mkdir(exist_ok=True)
        (RESULTS / f"{name}.json").write_text(json.dumps(result, indent=2) + "\n")
        write_report()
        print(f"python -m app audit of {sp['frames']} frames x {sp['bodies']:,} ellipsoids: {sp['certified_s']:.1f} s "
              f"({sp['jobs']} processes), {sp['certified_overlaps']} rows; load {result['load_average']}")
        return 0
    acc = accuracy(m)
    command = "python -m bench.bench_audit" + (" --quick" if args.quick else "")
    result = {"command": command, "cpu": cpu_model(), "cores": cores(),
              "load_average": f"{load_before:.1f} at the start, {os.getloadavg()[0]:.1f} at the end",
              "speed": sp, "accuracy": acc}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / ("audit-quick.json" if args.quick else "audit.json")).write_text(json.dumps(result, indent=2) + "\n")
    write_report()  # bench/REPORT.md: the rendering of every result file
    print(f"| audit of {sp['frames']} frames x {sp['bodies']:,} ellipsoids (fraction 0.5) | seconds | overlaps found |")
    print("|---|---:|---:|")
    print(f"| python -m app audit (certified, {sp['jobs']} processes) | {sp['certified_s']:.1f} | {sp['certified_overlaps']} |")
    print(f"| cKDTree + Perram-Wertheim in numpy (float, 1 process) | {sp['anchor_s']:.1f} | {sp['anchor_overlaps']} |")
    print()
    print(f"| {acc['pairs']:,} pairs: {acc['tangent']:,} touch exactly, {acc['overlap']:,} overlap by 2^-40 | wrong labels | false overlaps | missed overlaps |")
    print("|---|---:|---:|---:|")
    for name, key in (("certified (python -m app audit)", "certified"), ("float Perram-Wertheim, tolerance 0", "float_tol_0"),
                      ("float Perram-Wertheim, tolerance 1e-10", "float_tol_1e-10")):
        r = acc[key]
        print(f"| {name} | {r['wrong']:,} | {r['false_overlaps']:,} | {r['missed_overlaps']:,} |")
    return 0



if __name__ == "__main__":
    raise SystemExit(main())
