"""Cycles per pair in each stage of the compiled filter, by data set (where the time goes).

The block driver (``core/fixed/_blocks.h``) is compiled once more into a small program with a
time-stamp read (``rdtsc``) between its stages (:data:`MARKS`):
transpose, the unscaled first pass, the scaled and full first passes again (with the subsets'
bookkeeping), the semi-static s0 test, the certificates, the running-error s0 test and the
output. The program runs the chosen SIMD variant (by default the one the extension runs on this
CPU; compiled from the extension's own ``_filter_<variant>.c``) on one core over ``--pairs`` pairs (each data
set tiled) and keeps the fastest of ``--rounds`` runs: on a shared machine, the run least
disturbed. The same driver built without the time stamps gives the last columns.

Where the time goes, not whether a change is faster: the time stamps cost cycles and change the
code GCC writes for the whole driver (its register allocation and scheduling), and a change to
one stage can move the others' speed in the extension as built while this table shows them
unchanged (seen 2026-12-04: a split of the certificates measured 3-5 % faster here, while the
extension ran random pairs 28 % slower). Judge a change by the kernel as built, interleaved
with the old one (``bench.throughput``, or the two .so files called through ctypes). x86-64 with
gcc only.

    python -m bench.stage_cycles [--dim 3] [--pairs 1000000] [--rounds 7] [--variant avx2] [--define CHUNK4=16]
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from bench import datasets as D
from bench.render import published

ROOT = Path(__file__).resolve().parent.parent
FIXED = ROOT / "core" / "fixed"
FLAGS = ["-fwrapv", "-fPIC", "-O3", "-std=c99", "-ffp-contract=off", "-fno-fast-math", "-fno-math-errno", "-fno-trapping-math"]
"""The extension's flags: Python's (sysconfig CFLAGS: -fwrapv, -fPIC change the code GCC writes) and setup.py's."""
STAGES = ("transpose", "first pass", "scaled / full again", "s0 semi-static", "certificates", "s0 radius + output")
MARKS = ("PREFETCH(0)", "PREFETCH(1)", "/* stage 1 again with the scaling", "PREFETCH(4)", "PREFETCH(5)", "PREFETCH(6)", "PREFETCH(7)")
"""Where the time stamps go in _blocks.h (before each, at the start of its line)."""

_DRIVER = r"""
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <x86intrin.h>
uint64_t stage_acc[8], stage_last;
#ifdef STAMPS
#define TICK(i) do { uint64_t t_ = __rdtsc(); if (i) stage_acc[i] += t_ - stage_last; stage_last = t_; } while (0)
#else
#define TICK(i) do { } while (0)
#endif
@VARIANT@
"""
"""The timed block driver, a unit of its own as in the extension (with the caller in the same
unit GCC would specialise it: the table pointer is a constant there)."""

_MAIN = r"""
#define _GNU_SOURCE /* madvise, posix_memalign under -std=c99 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <x86intrin.h>
extern uint64_t stage_acc[8];
int64_t @CLASSIFY@(const double *A, const double *B, signed char *out, int64_t count, const signed char *table);
/* An input array on huge pages where the kernel offers them, as numpy allocates large arrays (its
 * madvise): on 4 KB pages the stream from memory measured ~4 cycles per pair slower (TLB misses, and
 * the hardware prefetchers stop at each page). */
static double *big(size_t bytes) {
    const size_t huge = (size_t)2 << 20, size = (bytes + huge - 1) / huge * huge;
    void *p = NULL;
    if (posix_memalign(&p, huge, size) != 0) return malloc(bytes);
    madvise(p, size, MADV_HUGEPAGE);
    return p;
}
int main(int argc, char **argv) {
    const int64_t n = atoll(argv[3]), rounds = atoll(argv[4]), e = @E@;
    FILE *fa = fopen(argv[1], "rb"), *fb = fopen(argv[2], "rb");
    fseek(fa, 0, SEEK_END);
    const int64_t m = ftell(fa) / (8 * e);
    rewind(fa);
    double *A0 = malloc(m * e * 8), *B0 = malloc(m * e * 8), *A = big(n * e * 8), *B = big(n * e * 8);
    if (fread(A0, 8, m * e, fa) != (size_t)(m * e) || fread(B0, 8, m * e, fb) != (size_t)(m * e)) return 1;
    for (int64_t i = 0; i < n; i++) {
        memcpy(A + e * i, A0 + e * (i % m), 8 * e);
        memcpy(B + e * i, B0 + e * (i % m), 8 * e);
    }
    signed char *out = malloc(n);
    uint64_t best[8] = {0}, best_total = UINT64_MAX;
    for (int64_t r = 0; r < rounds; r++) {
        memset(stage_acc, 0, sizeof stage_acc);
        const uint64_t t0 = __rdtsc();
        @CLASSIFY@(A, B, out, n, NULL);
        const uint64_t t1 = __rdtsc();
        if (t1 - t0 < best_total) {
            best_total = t1 - t0;
            memcpy(best, stage_acc, sizeof stage_acc);
        }
    }
    printf("%.2f", (double)best_total / n);
    for (int i = 1; i <= 6; i++) printf(" %.2f", (double)best[i] / n);
    printf("\n");
    return 0;
}
"""

VARIANT_FILES = {"baseline": "_filter_base.c", "avx2": "_filter_avx2.c", "avx512": "_filter_avx512.c"}
"""The extension's own source of each SIMD variant (its target pragmas and settings), read as it is."""


def default_variant() -> str:
    """The variant the extension runs on this CPU (baseline when the extension is not built)."""
    from core.fixed import compiled

    v = compiled.variant()
    return v if v in VARIANT_FILES else "baseline"


def build(variant: str, dim: int, work: Path, defines: tuple[str, ...] = ()) -> tuple[Path, Path]:
    """The timed programs: _blocks.h with a TICK at each mark, the variant's settings, our main;
    built with the time stamps (``-DSTAMPS``) and without."""
    blocks = (FIXED / "_blocks.h").read_text()
    for i, mark in enumerate(MARKS):
        if "        " + mark not in blocks:
            raise RuntimeError(f"_blocks.h changed: no {mark!r} to time")
        blocks = blocks.replace("        " + mark, f"        TICK({i}); " + mark, 1)
    (work / "blocks.h").write_text(blocks)
    text = (FIXED / "_variant.h").read_text()
    text = text.replace('"_blocks.h"', '"blocks.h"').replace('"_kernels.h"', f'"{FIXED / "_kernels.h"}"')
    (work / "variant.h").write_text(text)
    n = dim + 1
    source = (FIXED / VARIANT_FILES[variant]).read_text().replace('"_variant.h"', '"variant.h"')
    (work / "driver.c").write_text(_DRIVER.replace("@VARIANT@", source))
    (work / "main.c").write_text(_MAIN.replace("@E@", str(n * n)).replace("@CLASSIFY@", f"classify{n}_f64_{variant}"))
    exes = []
    for stamps in (True, False):
        cc = ["gcc", *FLAGS, *(f"-D{d}" for d in defines), *(["-DSTAMPS"] if stamps else []), "-I", str(work)]
        obj, exe = work / f"driver_{int(stamps)}.o", work / f"stages_{variant}_{dim}_{int(stamps)}"
        subprocess.run([*cc, "-c", "-o", str(obj), str(work / "driver.c")], check=True, capture_output=True)
        subprocess.run([*cc, "-o", str(exe), str(work / "main.c"), str(obj), "-lm"], check=True, capture_output=True)
        exes.append(exe)
    return exes[0], exes[1]


def run(dim: int = 3, pairs: int = 1_000_000, rounds: int = 7, variant: str | None = None, labelled: int = 400,
        defines: tuple[str, ...] = ()) -> list[dict[str, object]]:
    """Cycles per pair by stage, one row per data set (random, then the structured kinds)."""
    work = Path(tempfile.mkdtemp(prefix="stages-"))
    try:
        exe, plain = build(variant or default_variant(), dim, work, defines)
        cpu = ["taskset", "-c", str(min(os.sched_getaffinity(0)))] if shutil.which("taskset") else []
        fa, fb = work / "a.bin", work / "b.bin"

        def timed(prog: Path) -> list[float]:
            """The program's output on the pairs in fa, fb: total cycles per pair, then the stages'."""
            cmd = [*cpu, str(prog), str(fa), str(fb), str(pairs), str(rounds)]
            return [float(v) for v in subprocess.run(cmd, check=True, capture_output=True, text=True).stdout.split()]

        sets = [D.random_pairs(dim, labelled, seed=11)] + [D.structured_pairs(dim, labelled, kind=k, seed=12) for k in D.STRUCTURED_KINDS]
        rows = []
        for ds in sets:
            np.ascontiguousarray(ds.A, dtype=np.float64).tofile(fa)
            np.ascontiguousarray(ds.B, dtype=np.float64).tofile(fb)
            total, *stages = timed(exe)
            plain_total = timed(plain)[0]
            rows.append({"name": ds.name, "total": total, "plain": plain_total, **dict(zip(STAGES, stages, strict=True))})
        return rows
    finally:
        shutil.rmtree(work, ignore_errors=True)


def format_rows(rows: list[dict[str, object]]) -> str:
    """A markdown table: cycles per pair, then each row's total as a fraction of the random row's."""
    head = "| data | " + " | ".join(STAGES) + " | total | without time stamps | random / this (without) |"
    lines = [head, "|---|" + "---:|" * (len(STAGES) + 3)]
    base = float(rows[0]["plain"])  # type: ignore[arg-type]
    for r in rows:
        cells = " | ".join(f"{float(r[s]):.1f}" for s in STAGES)  # type: ignore[arg-type]
        lines.append(f"| {r['name']} | {cells} | {float(r['total']):.1f} | {float(r['plain']):.1f} | "  # type: ignore[arg-type]
                     f"{base / float(r['plain']):.2f}x |")  # type: ignore[arg-type]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--dim", type=int, default=3, choices=(2, 3))
    p.add_argument("--pairs", type=int, default=1_000_000)
    p.add_argument("--rounds", type=int, default=7)
    p.add_argument("--variant", default=None, choices=tuple(VARIANT_FILES), help="default: the variant the extension runs on this CPU")
    p.add_argument("--define", action="append", default=[], metavar="NAME=VALUE",
                   help="a macro of core/fixed/_variant.h for an experiment (CHUNK4=16, PF_DIST=4, ...)")
    p.add_argument("--write", action="store_true", help="write bench/results/stages.json and render bench/REPORT.md")
    a = p.parse_args(argv)
    if platform.machine() not in ("x86_64", "AMD64") or shutil.which("gcc") is None:
        print("needs x86-64 and gcc")
        return 1
    a.variant = a.variant or default_variant()
    extra = f", {' '.join(a.define)}" if a.define else ""
    command = f"python -m bench.stage_cycles --dim {a.dim} --pairs {a.pairs} --variant {a.variant}{''.join(' --define ' + d for d in a.define)} --write"
    with published("stages", command=command, write=a.write):
        print(f"**cycles per pair (rdtsc), {a.variant}, {a.dim}D, {a.pairs:,} pairs, fastest of {a.rounds} runs, one core{extra}**\n")
        print(format_rows(run(a.dim, a.pairs, a.rounds, a.variant, defines=tuple(a.define))))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
