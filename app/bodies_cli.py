"""The ``contacts`` and ``classify`` sub-commands of ``python -m app`` (files in, files out).

* ``python -m app contacts BODIES --out PAIRS.csv [--box Lx,Ly,Lz] [--method M]
  [--on-invalid mark] [--scheduler ADDRESS]``: every pair of bodies that is not separate
  (:func:`core.contacts`); BODIES is CSV or NPZ (:mod:`app.bodyfiles`). A progress bar on
  stderr while pairs are classified (long runs), a summary at the end.
* ``python -m app classify PAIRS.npz --out LABELS.npy [--method M]``: the relations of the pairs
  of stacks ``A``, ``B`` in an .npz file, saved as int8 Relation codes (:func:`core.classify`).
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any, TextIO

import numpy as np

__all__ = ["add_parsers", "box_argument", "run_contacts", "run_classify", "COMMANDS", "ProgressBar"]

COMMANDS = ("contacts", "classify")


def box_argument(text: str) -> tuple[float, ...]:
    """``--box Lx,Ly[,Lz]`` as a tuple of floats (argparse type)."""
    try:
        sides = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--box takes Lx,Ly[,Lz] (numbers), got {text!r}") from None
    if len(sides) not in (2, 3):
        raise argparse.ArgumentTypeError(f"--box takes 2 or 3 sides, got {text!r}")
    return sides


def add_parsers(sub: Any) -> None:
    """Add ``contacts`` and ``classify`` to the sub-command parsers of :func:`app.cli.build_parser`."""
    c = sub.add_parser("contacts", help="certified contacts among many bodies (CSV/NPZ in, CSV out)")
    c.add_argument("bodies", help="CSV (x,y,z,a,b,c,qw,qx,qy,qz or x,y,a,b,angle) or NPZ (centers, semi_axes, orientations | Q)")
    c.add_argument("--out", required=True, help="output CSV: i,j,relation (relation: separate|tangent|overlap)")
    c.add_argument("--box", type=box_argument, default=None, help="periodic box sides Lx,Ly[,Lz] (minimum image)")
    c.add_argument("--method", choices=("adaptive", "float", "exact"), default="adaptive")
    c.add_argument("--on-invalid", choices=("raise", "mark"), default="raise", help="mark: report bad bodies and go on")
    c.add_argument("--scheduler", default=None, help="run on Dask: scheduler address tcp://host:8786 (pip install -e .[dask])")
    c.add_argument("--quiet", action="store_true", help="no progress bar")

    k = sub.add_parser("classify", help="certified relations of a file of pairs (NPZ with stacks A, B)")
    k.add_argument("pairs", help="NPZ with arrays A and B, stacks (N, n, n) that broadcast")
    k.add_argument("--out", required=True, help="output .npy of int8 codes (0 separate, 1 tangent, 2 overlap, -2 invalid)")
    k.add_argument("--method", choices=("adaptive", "float", "exact"), default="adaptive")
    k.add_argument("--on-invalid", choices=("raise", "mark"), default="raise")


class ProgressBar:
    """A one-line progress bar on a terminal (plain lines, at most every 10 %, otherwise).

    Args:
        stream: where to draw (stderr).
        label: text before the bar.
        min_total: totals below this draw nothing (short runs stay quiet).
    """

    def __init__(self, stream: TextIO, label: str, *, min_total: int = 1_000_000) -> None:
        self.stream = stream
        self.label = label
        self.min_total = min_total
        self.tty = bool(getattr(stream, "isatty", lambda: False)())
        self.start = time.perf_counter()
        self.last = -1

    def __call__(self, done: int, total: int) -> None:
        """Show ``done`` of ``total``."""
        if total < self.min_total:
            return
        pct = int(100 * done / total) if total else 100
        if not self.tty and pct // 10 == self.last // 10 and done < total:
            return
        self.last = pct
        bar = "#" * (pct * 30 // 100)
        line = f"{self.label} [{bar:<30}] {pct:3d}% {done:,}/{total:,} pairs, {time.perf_counter() - self.start:.1f} s"
        self.stream.write(("\r" + line) if self.tty else line + "\n")
        if self.tty and done >= total:
            self.stream.write("\n")
        self.stream.flush()


def run_contacts(args: argparse.Namespace) -> int:
    """``python -m app contacts``: read, search, write, summarise. Returns the exit status."""
    from core import contacts

    from .bodyfiles import read_bodies, write_pairs_csv

    t0 = time.perf_counter()
    bodies = read_bodies(args.bodies)
    if bodies.errors and args.on_invalid == "raise":
        k, why = next(iter(bodies.errors.items()))
        raise ValueError(f"{args.bodies}: {bodies.where(k)}: {why}")
    if args.box is not None and len(args.box) != bodies.dim:
        raise ValueError(f"--box has {len(args.box)} sides but the bodies are {bodies.dim}D")
    t1 = time.perf_counter()
    err = sys.stderr
    if not args.quiet:
        err.write(f"read {len(bodies):,} {'ellipsoids' if bodies.dim == 3 else 'ellipses'} from {args.bodies} in {t1 - t0:.1f} s\n")
    progress = None if args.quiet else ProgressBar(err, "classifying")
    res = contacts(
        bodies.Q, box=args.box, method=args.method, on_invalid=args.on_invalid, scheduler=args.scheduler, progress=progress
    )
    invalid = dict(res.invalid)
    for k, why in bodies.errors.items():  # the reason from the file's parameters, not "NaN"
        invalid[k] = why
    t2 = time.perf_counter()
    write_pairs_csv(args.out, res.i, res.j, res.relation)
    t3 = time.perf_counter()
    print(f"wrote {len(res):,} pairs to {args.out}")
    print(res.summary())
    phases = ", ".join(f"{k} {v:.2f} s" for k, v in res.seconds.items() if k != "total")
    print(f"time: read {t1 - t0:.2f} s, {phases}, write {t3 - t2:.2f} s, total {t3 - t0:.2f} s")
    for k in sorted(invalid)[:10]:
        print(f"invalid {bodies.where(k)}: {invalid[k]}")
    if len(invalid) > 10:
        print(f"... and {len(invalid) - 10} more invalid bodies")
    return 0


def run_classify(args: argparse.Namespace) -> int:
    """``python -m app classify``: relations of the pairs of an .npz file, saved as .npy."""
    from core import Relation, classify_detailed

    try:
        with np.load(args.pairs, allow_pickle=False) as z:
            if "A" not in z.files or "B" not in z.files:
                raise ValueError(f"{args.pairs}: expected arrays A and B, found {sorted(z.files)}")
            A, B = z["A"], z["B"]
    except (OSError, EOFError) as e:
        raise ValueError(f"cannot read {args.pairs}: {e}") from None
    t0 = time.perf_counter()
    res = classify_detailed(A, B, method=args.method, on_invalid=args.on_invalid)
    codes = np.asarray(res.relation, dtype=np.int8)
    np.save(args.out, codes)
    counts = {str(r): int(np.count_nonzero(codes == r)) for r in Relation if np.count_nonzero(codes == r)}
    exact = int(np.count_nonzero(res.certified_by == 2))
    print(f"wrote {codes.size:,} labels to {args.out} in {time.perf_counter() - t0:.2f} s: {counts}; {exact} certified by exact arithmetic")
    for k in sorted(res.errors)[:10]:
        print(f"invalid pair {k}: {res.errors[k]}")
    return 0
