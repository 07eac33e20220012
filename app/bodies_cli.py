"""The ``contacts`` and ``classify`` sub-commands of ``python -m app`` (files in, files out).

* ``python -m app contacts BODIES --out PAIRS.csv [--box Lx,Ly,Lz] [--frame K] [--format F]
  [--method M] [--on-invalid mark] [--with scale] [--scheduler ADDRESS] [--quiet]``: every
  pair of bodies that is not separate (:func:`core.contacts`). BODIES is any file of
  :mod:`app.readers` (CSV, Parquet, NPZ, HOOMD GSD, LAMMPS dump, extended XYZ) or ``-`` for
  standard input; PAIRS is CSV (or NPZ for a ``.npz`` name) or ``-`` for standard output
  (:mod:`app.bodyfiles`). The box of the file (GSD, LAMMPS, XYZ, NPZ ``box``) is used unless
  ``--box`` is given.
* ``python -m app classify PAIRS.npz --out LABELS.npy [--method M]``: the relations of the pairs
  of stacks ``A``, ``B`` in an .npz file, saved as int8 Relation codes (:func:`core.classify`);
  the .npy file is written at exactly the path given.

Standard output carries only the data (``--out -``); the progress bar, the summary and every
message go to standard error (``--quiet``: errors only). Output files are written whole or not
at all (:mod:`app.output`).
"""

from __future__ import annotations

import argparse
import io
import math
import sys
import time
from typing import Any, TextIO

import numpy as np

from core.options import METHODS, ON_INVALID

from .interrupt import check as check_stop

__all__ = ["add_parsers", "box_argument", "run_contacts", "run_classify", "COMMANDS", "ProgressBar"]

COMMANDS = ("contacts", "classify")


def box_argument(text: str) -> tuple[float, ...]:
    """``--box Lx,Ly[,Lz]`` (or ``Lx,Ly,Lz,xy,xz,yz``, a tilted box) as a tuple of floats (argparse type).

    Checked before any work: finite numbers, the sides Lx, Ly (and Lz of six) positive; whether
    a third number is Lz or a 2D tilt, and the rest, the library checks against the bodies.
    """
    try:
        sides = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--box takes Lx,Ly[,Lz] (numbers), got {text!r}") from None
    if len(sides) not in (2, 3, 6):
        raise argparse.ArgumentTypeError(f"--box takes 2 or 3 sides (or Lx,Ly,Lz,xy,xz,yz), got {text!r}")
    if not all(map(math.isfinite, sides)):
        raise argparse.ArgumentTypeError(f"--box takes finite numbers, got {text!r}")
    if not all(v > 0 for v in sides[: 3 if len(sides) == 6 else 2]):
        raise argparse.ArgumentTypeError(f"--box: the sides must be positive, got {text!r}")
    return sides


def scheduler_argument(text: str) -> str:
    """``--scheduler ADDRESS``: a Dask scheduler's address (argparse type; checked as Dask reads it, when installed)."""
    try:
        from distributed.comm.addressing import parse_address, parse_host_port
    except ImportError:  # run_contacts says what to install
        return text
    try:
        scheme, location = parse_address(text)
        if scheme in ("tcp", "tls"):
            parse_host_port(location)
    except ValueError as e:
        raise argparse.ArgumentTypeError(f"not a scheduler address ({e}), e.g. tcp://HOST:8786: {text!r}") from None
    return text


def frame_argument(text: str) -> int:
    """``--frame K``: an integer, from 0 (negative: from the end)."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--frame takes a frame number (0 first, -1 last), got {text!r}") from None


def add_body_file_options(parser: argparse.ArgumentParser, *, dim: bool = False) -> None:
    """``--frame`` and ``--format``: which frame of a trajectory, and which reader (:mod:`app.readers`); ``--dim`` too if asked."""
    from .readers import FORMATS

    parser.add_argument("--frame", type=frame_argument, default=None, help="frame of a trajectory (GSD, LAMMPS, XYZ): 0 first, -1 last (default)")
    parser.add_argument("--format", choices=FORMATS, default=None, help="file format (default: from the name, else the first bytes)")
    if dim:
        parser.add_argument("--dim", type=int, choices=(2, 3), default=None,
                            help="2: read a 3D file of a 2D system (z = 0, turned about z) as ellipses; default: the file says")


def add_parsers(sub: Any) -> None:
    """Add ``contacts`` and ``classify`` to the sub-command parsers of :func:`app.cli.build_parser`."""
    c = sub.add_parser("contacts", help="certified contacts among many bodies (CSV/Parquet/NPZ/GSD/LAMMPS/XYZ in, CSV/NPZ out)")
    c.add_argument("bodies", help="file of bodies (app.readers: CSV, Parquet, NPZ, HOOMD GSD, LAMMPS dump, extended XYZ), or - for stdin")
    c.add_argument(
        "--out", required=True,
        help="output: CSV i,j,relation,certified_by,image_x,image_y,image_z (NPZ for a .npz name), or - for stdout",
    )
    c.add_argument("--box", type=box_argument, default=None, help="periodic box sides Lx,Ly[,Lz], or a tilted box Lx,Ly,Lz,xy,xz,yz (2D: Lx,Ly,xy) (minimum image); default: the file's box")
    add_body_file_options(c, dim=True)
    c.add_argument("--method", choices=METHODS, default="adaptive")
    c.add_argument("--on-invalid", choices=ON_INVALID, default="raise", help="mark: report bad bodies and go on")
    c.add_argument(
        "--with", dest="extras", action="append", choices=("scale",), default=[],
        help="scale: add a certified contact-scale bracket scale_lo,scale_hi and a containment flag per pair",
    )
    c.add_argument("--scheduler", type=scheduler_argument, default=None, help="run on Dask: scheduler address tcp://host:8786 (pip install 'ellipsoid-interference[dask]')")
    c.add_argument("--quiet", action="store_true", help="no progress bar and no summary (errors only)")

    k = sub.add_parser("classify", help="certified relations of a file of pairs (NPZ with stacks A, B)")
    k.add_argument("pairs", help="NPZ with arrays A and B, stacks (N, n, n) that broadcast; - for stdin")
    k.add_argument("--out", required=True, help="output .npy of int8 codes (0 separate, 1 tangent, 2 overlap, -2 invalid), exactly this path; - for stdout")
    k.add_argument("--method", choices=METHODS, default="adaptive")
    k.add_argument("--on-invalid", choices=ON_INVALID, default="raise")
    k.add_argument("--quiet", action="store_true", help="no summary (errors only)")


class ProgressBar:
    """A one-line progress bar on a terminal (plain lines at most every 10 % otherwise).

    It appears once the work is large (``min_total`` pairs) or has run for ``delay`` seconds,
    so short runs stay quiet and long ones always say how far they are.

    Args:
        stream: where to draw (stderr).
        label: text before the bar.
        min_total: totals from this many pairs draw from the start.
        delay: any run draws once it has taken this many seconds.
    """

    def __init__(self, stream: TextIO, label: str, *, min_total: int = 1_000_000, delay: float = 1.0, unit: str = "pairs") -> None:
        self.unit = unit
        self.stream = stream
        self.label = label
        self.min_total = min_total
        self.delay = delay
        self.tty = bool(getattr(stream, "isatty", lambda: False)())
        self.start = time.perf_counter()
        self.last = -100

    def __call__(self, done: int, total: int) -> None:
        """Show ``done`` of ``total``; a stop signal that was swallowed on its way is raised here again."""
        check_stop()
        elapsed = time.perf_counter() - self.start
        if total < self.min_total and elapsed < self.delay:
            return
        pct = int(100 * done / total) if total else 100
        if not self.tty and pct // 10 == self.last // 10 and done < total:
            return
        self.last = pct
        bar = "#" * (pct * 30 // 100)
        line = f"{self.label} [{bar:<30}] {pct:3d}% {done:,}/{total:,} {self.unit}, {elapsed:.1f} s"
        self.stream.write(("\r" + line) if self.tty else line + "\n")
        if self.tty and done >= total:
            self.stream.write("\n")
        self.stream.flush()


def say(args: argparse.Namespace, text: str) -> None:
    """A message for the user: stderr (stdout carries only data), unless --quiet."""
    if not getattr(args, "quiet", False):
        print(text, file=sys.stderr, flush=True)


def warn_invalid(invalid: dict[int, str], where: Any) -> None:
    """The first ten invalid bodies and why (``where(k)`` names body k in its file), on stderr.

    Warnings about the answer: shown even with --quiet.
    """
    for k in sorted(invalid)[:10]:
        print(f"invalid {where(k)}: {invalid[k]}", file=sys.stderr)
    if len(invalid) > 10:
        print(f"... and {len(invalid) - 10} more invalid bodies", file=sys.stderr)


def _connect(address: str) -> Any:
    """A ``distributed.Client`` on ``address`` (checked by :func:`scheduler_argument`), or a one-line RuntimeError within seconds."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise RuntimeError("--scheduler needs Dask: pip install 'ellipsoid-interference[dask]'") from None
    import logging

    from core.bodies.distributed import connect

    logging.getLogger("distributed").setLevel(logging.CRITICAL)  # its retries are not the user's business
    return connect(address)


def command_box(given: Any, bodies: Any) -> Any:
    """The box of a command: ``--box`` (any form :meth:`core.Box.from_any` reads), else the file's.

    Raises:
        ValueError: a ``--box`` that is no box for the bodies' dimension, saying what was expected.
    """
    from core import Box

    if given is None:
        return bodies.box
    try:
        return Box.from_any(given, bodies.dimensions)
    except ValueError as e:
        raise ValueError(f"--box: {str(e).removeprefix('box: ')}") from None


def run_contacts(args: argparse.Namespace) -> int:
    """``python -m app contacts``: read, search, write, summarise. Returns the exit status."""
    from core import contacts

    from .bodyfiles import write_pairs_csv, write_pairs_npz
    from .output import Output
    from .readers import read_bodies

    as_npz = args.out.lower().endswith(".npz")
    out = Output(args.out, binary=as_npz)  # checked (and its temporary file made) before any work
    with out as f:
        t0 = time.perf_counter()
        bodies = read_bodies(args.bodies, frame=args.frame, format=args.format, dim=args.dim)
        source = "<stdin>" if args.bodies == "-" else args.bodies
        if bodies.errors and args.on_invalid == "raise":
            k, why = next(iter(bodies.errors.items()))
            raise ValueError(f"{source}: {bodies.where(k)}: {why}")
        box = command_box(args.box, bodies)
        t1 = time.perf_counter()
        what = "ellipsoids" if bodies.dim == 3 else "ellipses"
        frame = f" (frame {bodies.frame})" if bodies.frame is not None else ""
        say(args, f"read {len(bodies):,} {what} from {source}{frame} in {t1 - t0:.1f} s" + (f"; periodic box {box.describe()}" if box is not None else ""))
        scheduler = _connect(args.scheduler) if args.scheduler else None
        try:
            progress = None if args.quiet else (True if scheduler is not None else ProgressBar(sys.stderr, "classifying"))
            chunk = 10_000 if args.method == "exact" else None  # exact: ~1 ms of work per 10 pairs, progress every second or so
            res = contacts(
                bodies, box=box, method=args.method, on_invalid=args.on_invalid, scheduler=scheduler, progress=progress,
                **({"chunk": chunk} if chunk else {}),
            )
        finally:
            if scheduler is not None:
                scheduler.close()
        details: dict[str, np.ndarray] | None = None
        if "scale" in args.extras:
            from core.bodies.details import pair_details

            ts = time.perf_counter()
            d = pair_details(bodies.Q, res)
            details = {"scale_lo": d.scale_lo, "scale_hi": d.scale_hi, "contained": np.array(d.contained_names())}
            say(args, f"contact scales and containment of {len(res):,} pairs in {time.perf_counter() - ts:.1f} s")
        t2 = time.perf_counter()
        if as_npz:
            write_pairs_npz(f, res, details)
        else:
            write_pairs_csv(f, res, details)
    t3 = time.perf_counter()
    invalid = dict(res.invalid)
    invalid.update(bodies.errors)  # the reason from the file's parameters, not "NaN"
    say(args, f"wrote {len(res):,} pairs to {'<stdout>' if args.out == '-' else args.out}")
    say(args, res.summary())
    phases = ", ".join(f"{k} {v:.2f} s" for k, v in res.seconds.items() if k != "total")
    say(args, f"time: read {t1 - t0:.2f} s, {phases}, write {t3 - t2:.2f} s, total {t3 - t0:.2f} s")
    warn_invalid(invalid, bodies.where)
    return 0


def run_classify(args: argparse.Namespace) -> int:
    """``python -m app classify``: relations of the pairs of an .npz file, saved as .npy (exactly at ``--out``)."""
    from core import Relation, classify_detailed

    from .output import Output
    from .readers.npzfile import npz_arrays

    out = Output(args.out, binary=True)
    with out as f:
        if args.pairs == "-":
            source: Any = sys.stdin.buffer.read()
            name = "<stdin>"
        else:
            source, name = args.pairs, args.pairs
        arrays = npz_arrays(source, name, ("A", "B"), required=("A", "B"))
        A, B = arrays["A"], arrays["B"]
        t0 = time.perf_counter()
        res = classify_detailed(A, B, method=args.method, on_invalid=args.on_invalid)
        codes = np.asarray(res.relation, dtype=np.int8)
        buf = io.BytesIO()
        np.save(buf, codes)  # to a file object: numpy adds no ".npy" to the name
        f.write(buf.getvalue())
    counts = {str(r): int(np.count_nonzero(codes == r)) for r in Relation if np.count_nonzero(codes == r)}
    exact = int(np.count_nonzero(res.certified_by == 2))
    where = "<stdout>" if args.out == "-" else args.out
    say(args, f"wrote {codes.size:,} labels to {where} in {time.perf_counter() - t0:.2f} s: {counts}; {exact} certified by exact arithmetic")
    for k in sorted(res.errors)[:10]:
        print(f"invalid pair {k}: {res.errors[k]}", file=sys.stderr)
    return 0
