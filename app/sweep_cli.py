"""The ``sweep`` sub-command of ``python -m app``: first contact times among moving bodies.

``python -m app sweep START.csv END.csv --out EVENTS.csv [--box Lx,Ly,Lz] [--on-invalid mark]``

START and END are body files as for ``contacts`` (:mod:`app.bodyfiles`: CSV with the columns
``x,y,z,a,b,c,qw,qx,qy,qz`` or ``x,y,a,b,angle``, or NPZ with ``centers``, ``semi_axes``,
``orientations``): row k of START is body k at t = 0, row k of END the same body at t = 1 (same
semi-axes, row by row). Each body moves on the straight line between its centres and turns along
q(t) = (1 - t) q0 + t q1 (:func:`core.sweep_contacts`). EVENTS is CSV ``i,j,t_lo,t_hi,relation``:
every pair that touches or overlaps during the step, t_lo <= t* <= t_hi (floats written so that
they read back exactly), relation at t* (``tangent``, or ``overlap`` when they already overlap
at t = 0), sorted by (i, j). The file is written to a temporary file next to EVENTS and renamed
into place (readers never see a partial file). A progress bar on stderr while pairs are checked.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["add_parser", "run_sweep", "write_events_csv", "read_events_csv"]


def add_parser(sub: Any) -> None:
    """Add ``sweep`` to the sub-command parsers of :func:`app.cli.build_parser`."""
    from .bodies_cli import box_argument

    s = sub.add_parser("sweep", help="certified first contact times among moving bodies (START, END files in, CSV out)")
    s.add_argument("start", help="bodies at t = 0 (CSV x,y,z,a,b,c,qw,qx,qy,qz or x,y,a,b,angle; or NPZ centers, semi_axes, orientations)")
    s.add_argument("end", help="the same bodies at t = 1 (same rows, same semi-axes)")
    s.add_argument("--out", required=True, help="output CSV: i,j,t_lo,t_hi,relation")
    s.add_argument("--box", type=box_argument, default=None, help="periodic box sides Lx,Ly[,Lz] (minimum image over the step)")
    s.add_argument("--on-invalid", choices=("raise", "mark"), default="raise", help="mark: report bad bodies and go on")
    s.add_argument("--quiet", action="store_true", help="no progress bar")


def run_sweep(args: argparse.Namespace) -> int:
    """``python -m app sweep``: read both files, sweep, write EVENTS, summarise. Returns the exit status."""
    from core import sweep_contacts

    from .bodies_cli import ProgressBar
    from .bodyfiles import read_bodies

    t0 = time.perf_counter()
    start, end = read_bodies(args.start), read_bodies(args.end)
    for b, name in ((start, args.start), (end, args.end)):
        if b.centers is None or b.semi_axes is None:
            raise ValueError(f"{name}: sweep needs the bodies' parameters (centres, semi-axes, orientations), not matrices Q")
    assert start.centers is not None and end.centers is not None and start.semi_axes is not None and end.semi_axes is not None
    if start.centers.shape != end.centers.shape:
        raise ValueError(
            f"{args.start} has {len(start)} {start.dim}D bodies but {args.end} has {len(end)} {end.dim}D bodies: "
            "END must hold the same bodies, row by row"
        )
    same = (start.semi_axes == end.semi_axes) | (np.isnan(start.semi_axes) & np.isnan(end.semi_axes))
    bad = np.flatnonzero(~same.all(axis=1))
    if bad.size:
        k = int(bad[0])
        raise ValueError(
            f"{start.where(k)}: the semi-axes differ between {args.start} ({start.semi_axes[k].tolist()}) and "
            f"{args.end} ({end.semi_axes[k].tolist()}): a body keeps its shape during the step"
        )
    errors = {k: f"{args.start}: {why}" for k, why in start.errors.items()}
    errors.update({k: f"{args.end}: {why}" for k, why in end.errors.items() if k not in errors})
    if errors and args.on_invalid == "raise":
        k, why = next(iter(sorted(errors.items())))
        raise ValueError(f"{start.where(k)}: {why}")
    if args.box is not None and len(args.box) != start.dim:
        raise ValueError(f"--box has {len(args.box)} sides but the bodies are {start.dim}D")
    t1 = time.perf_counter()
    err = sys.stderr
    if not args.quiet:
        kind = "ellipsoids" if start.dim == 3 else "ellipses"
        err.write(f"read {len(start):,} moving {kind} from {args.start} and {args.end} in {t1 - t0:.1f} s\n")
    progress = None if args.quiet else ProgressBar(err, "first contacts", min_total=50_000)
    res = sweep_contacts(
        start.centers, end.centers, start.semi_axes, start.orientations, end.orientations,
        box=args.box, on_invalid=args.on_invalid, progress=progress,
    )
    invalid = dict(res.invalid)
    invalid.update(errors)  # the reason from the files' parameters, not the stand-in's
    t2 = time.perf_counter()
    write_events_csv(args.out, res.i, res.j, res.t_lo, res.t_hi, res.relation)
    t3 = time.perf_counter()
    print(f"wrote {len(res):,} first contacts to {args.out}")
    print(res.summary())
    phases = ", ".join(f"{k} {v:.2f} s" for k, v in res.seconds.items() if k != "total")
    print(f"time: read files {t1 - t0:.2f} s, {phases}, write {t3 - t2:.2f} s, total {t3 - t0:.2f} s")
    for k in sorted(invalid)[:10]:
        print(f"invalid {start.where(k)}: {invalid[k]}")
    if len(invalid) > 10:
        print(f"... and {len(invalid) - 10} more invalid bodies")
    return 0


def write_events_csv(path: str | Path, i: np.ndarray, j: np.ndarray, t_lo: np.ndarray, t_hi: np.ndarray, relation: np.ndarray) -> None:
    """Write ``i,j,t_lo,t_hi,relation`` rows atomically (temporary file, then rename).

    Floats are written with ``repr`` (the shortest text that reads back to the same float), so
    the brackets stay certified after a round trip.
    """
    from core import Relation

    names = {int(r): str(r) for r in Relation}
    target = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent if str(target.parent) else ".")
    try:
        with os.fdopen(fd, "w", newline="") as f:
            f.write("i,j,t_lo,t_hi,relation\n")
            step = 1 << 16
            for s in range(0, len(i), step):
                f.write("".join(
                    f"{a},{b},{lo!r},{hi!r},{names[r]}\n"
                    for a, b, lo, hi, r in zip(
                        i[s : s + step].tolist(), j[s : s + step].tolist(), t_lo[s : s + step].tolist(),
                        t_hi[s : s + step].tolist(), relation[s : s + step].tolist(), strict=True,
                    )
                ))
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def read_events_csv(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Read a file written by :func:`write_events_csv`: (i, j, t_lo, t_hi, int8 Relation codes)."""
    from core import Relation

    lines = Path(path).read_text().splitlines()
    if not lines or lines[0].strip() != "i,j,t_lo,t_hi,relation":
        raise ValueError(f"{path}: expected the header i,j,t_lo,t_hi,relation")
    rows = [ln.split(",") for ln in lines[1:] if ln.strip()]
    return (
        np.array([int(r[0]) for r in rows], dtype=np.int64),
        np.array([int(r[1]) for r in rows], dtype=np.int64),
        np.array([float(r[2]) for r in rows], dtype=np.float64),
        np.array([float(r[3]) for r in rows], dtype=np.float64),
        np.array([int(Relation.parse(r[4])) for r in rows], dtype=np.int8),
    )
