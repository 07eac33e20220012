"""The ``audit`` sub-command of ``python -m app``: a certified check of a hard-particle trajectory.

``python -m app audit TRAJECTORY --out REPORT.csv [--frames A:B] [--between] [--box ...]
[--scheduler ADDR] [--jobs N] [--format F] [--dim 2] [--on-invalid mark] [--quiet]``

TRAJECTORY is a GSD, LAMMPS dump or extended XYZ file (every frame), or a folder or glob of frame
files (``run/*.csv``: one frame per file, in natural order). For every frame picked by
``--frames`` (a Python slice: ``A:B`` from frame A to frame B - 1, ``A:``, ``:B``, ``K``), every
pair that is not separate is listed, with its certified relation for the bodies the file's
numbers describe, read exactly: centre, semi-axes and the rotation of the quaternion (of any
length), with no float matrix in between (:func:`core.sweep_contacts` at t = 0). So a gap of
1e-12 between two bodies far from the origin is a gap, whatever a float matrix of them would
round to (a file of matrices is classified as those matrices, :func:`core.contacts`).
With ``--between``, every pair that meets during the straight-line step from each frame to the
next is listed too (:func:`core.sweep_contacts`: centres on the minimum-image displacement,
orientations along q(t) = (1 - t) q0 + t q1; the bodies' own parameters, read exactly), with
its first contact t* in [t_lo, t_hi]. Bodies are matched between frames by the file's ids when it
has them (a LAMMPS dump lists atoms in any order), else by row.

REPORT.csv (or ``-``: standard output), written whole or not at all (:mod:`app.output`):
``frame,i,j,relation,certified_by,image_x,image_y,image_z,t_lo,t_hi`` (2D: no ``image_z``),
then ``id_i,id_j`` when the file gives ids. A frame's rows have empty ``t_lo,t_hi``; a step's
rows are under the frame the step starts from, with its bracket. Rows come in frame order, each
frame's pairs sorted by (i, j), then its step's.

Exit status: 0 when no pair overlaps; **3** when a pair overlaps in a frame, or already overlaps
at the start of a step (tangent pairs are listed but are no violation: hard particles may touch;
a step row that says ``tangent`` is the first contact of a straight-line path, which a real move
need not follow); 2 for bad input (the message names the file, the frame and the body). A
summary goes to standard error, with a progress bar on a terminal.

The frames are read one at a time and checked by worker processes (``--jobs``, default: every
core) or on a Dask cluster (``--scheduler``), a few at a time: memory of a few frames, however
long the trajectory.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from core.options import ON_INVALID

if TYPE_CHECKING:
    from core import Contacts, SweepContacts
    from core.options import OnInvalid

__all__ = ["add_parser", "run_audit", "frames_argument", "audit_frame", "FrameReport", "EXIT_OVERLAP"]

EXIT_OVERLAP = 3
"""Exit status when some pair overlaps."""


def frames_argument(text: str) -> slice:
    """``--frames A:B`` (or ``A:``, ``:B``, ``K``) as a slice (argparse type).

    Examples:
        >>> frames_argument("3:10"), frames_argument("-5:"), frames_argument("7")
        (slice(3, 10, None), slice(-5, None, None), slice(7, 8, None))
    """
    try:
        if ":" not in text:
            k = int(text)
            return slice(k, k + 1 if k != -1 else None)
        parts = text.split(":")
        if len(parts) > 3:
            raise ValueError
        values = [int(p) if p.strip() else None for p in parts]
        if len(values) == 3 and values[2] is not None and values[2] <= 0:
            raise ValueError
        return slice(*values)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--frames takes A:B (a Python slice of frame numbers: A:, :B, K), got {text!r}") from None


def add_parser(sub: Any) -> None:
    """Add ``audit`` to the sub-command parsers of :func:`app.cli.build_parser`."""
    from .bodies_cli import box_argument, scheduler_argument
    from .readers import FORMATS

    a = sub.add_parser("audit", help="certified check of a hard-particle trajectory: every pair that is not separate, per frame (and per step)")
    a.add_argument("trajectory", help="GSD, LAMMPS dump or extended XYZ file; or a folder or glob of frame files")
    a.add_argument("--out", required=True, help="output CSV frame,i,j,relation,certified_by,image_x,image_y[,image_z],t_lo,t_hi[,id_i,id_j]; - for stdout")
    a.add_argument("--frames", type=frames_argument, default=slice(None), help="frames A:B (a Python slice: A first, B not included; A:, :B, K); default: all")
    a.add_argument("--between", action="store_true", help="also every pair that meets during the straight-line step to the next frame")
    a.add_argument("--box", type=box_argument, default=None, help="periodic box Lx,Ly[,Lz] or Lx,Ly,Lz,xy,xz,yz (2D: Lx,Ly,xy); default: each frame's box")
    a.add_argument("--scheduler", type=scheduler_argument, default=None, help="a Dask scheduler's address: frames are checked on the cluster")
    a.add_argument("--jobs", type=_jobs_argument, default=None, help="worker processes on this machine (default: every core)")
    a.add_argument("--format", choices=FORMATS, default=None, help="file format (default: from the name, else the first bytes)")
    a.add_argument("--dim", type=int, choices=(2, 3), default=None, help="2: read 3D files of a 2D system (z = 0) as ellipses")
    a.add_argument("--on-invalid", choices=ON_INVALID, default="raise", help="mark: report bodies that are no ellipsoid and go on")
    a.add_argument("--quiet", action="store_true", help="no progress bar and no summary (errors only)")


def _jobs_argument(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"--jobs takes a positive number of processes, got {text!r}")
    return n


@dataclass
class FrameReport:
    """What one frame (and its step to the next) contributes to the report: CSV text and counts."""

    frame: int
    """The frame's number in the file."""
    text: str
    """Its CSV rows (no header)."""
    dimensions: int
    """2 or 3."""
    has_ids: bool
    """Whether its bodies have ids (the report's id columns)."""
    bodies: int
    """How many bodies."""
    counts: dict[str, int] = field(default_factory=dict)
    """``tangent``, ``overlap`` (in the frame), ``step_tangent``, ``step_overlap`` (its step), ``invalid``."""
    overlaps: list[str] = field(default_factory=list)
    """The first few overlapping pairs, as text for the summary."""
    seconds: float = 0.0
    """Time the check took in its worker."""


def header(dimensions: int, has_ids: bool) -> str:
    """The report's header line.

    Examples:
        >>> header(2, True)
        'frame,i,j,relation,certified_by,image_x,image_y,t_lo,t_hi,id_i,id_j'
    """
    images = ["image_x", "image_y", "image_z"][:dimensions]
    return ",".join(["frame", "i", "j", "relation", "certified_by", *images, "t_lo", "t_hi", *(["id_i", "id_j"] if has_ids else [])])


def _rows(frame: int, table: Any, d: int, has_ids: bool, *, bracket: bool = True) -> str:
    """CSV rows of a pair table (:class:`core.PairTable`) under ``frame``, in the report's column order.

    ``bracket=False``: the frame's own rows (empty ``t_lo, t_hi``) even from a sweep's table.
    """
    cols = table.columns(image_dims=d)
    n = len(table)
    parts: list[list[str]] = [[str(frame)] * n, [str(v) for v in cols["i"]], [str(v) for v in cols["j"]],
                              cols["relation"], cols["certified_by"]]
    parts += [[str(v) for v in cols[f"image_{'xyz'[a]}"]] for a in range(d)]
    parts += [[repr(v) for v in cols[name]] if bracket and name in cols else [""] * n for name in ("t_lo", "t_hi")]
    if has_ids:
        parts += [[str(v) for v in cols["id_i"]], [str(v) for v in cols["id_j"]]] if "id_i" in cols else [[""] * n] * 2
    return "".join(",".join(row) + "\n" for row in zip(*parts, strict=True))


def audit_frame(frame: int, bodies: Any, box: Any, following: Any = None, *, on_invalid: OnInvalid = "raise",
                threads: int | None = None) -> FrameReport:
    """The check of one frame, and of its step to the ``following`` frame when given (a worker's task).

    Args:
        frame: the frame's number (for the rows and the messages).
        bodies: its :class:`app.readers.BodySet`.
        box: the box to use (None: the frame's own).
        following: the next frame's bodies (``--between``), or None.
        on_invalid: "raise" a ValueError naming the first body that is no ellipsoid, or "mark".
        threads: the float filter's threads in this process (None: as set).

    Raises:
        ValueError: a bad body (``on_invalid="raise"``), a box the bodies do not fit, frames
            that do not hold the same bodies, a box that changes between the frames.
    """
    from core import Relation, contacts, set_threads, sweep_contacts

    t0 = time.perf_counter()
    if threads is not None:
        set_threads(threads)
    where = f"{bodies.source}: frame {frame}"
    use_box = box if box is not None else bodies.box
    errors = bodies.parameter_errors if bodies.has_parameters else bodies.errors
    if errors and on_invalid == "raise":
        k, why = next(iter(errors.items()))
        raise ValueError(f"{where}: {bodies.where(k)}: {why}")
    found: Contacts | SweepContacts
    try:
        if bodies.has_parameters:  # the bodies the file's numbers describe, read exactly (as --between does)
            found = sweep_contacts(bodies, bodies, box=use_box, on_invalid=on_invalid)
        else:  # a file of matrices: the matrices
            found = contacts(bodies, box=use_box, on_invalid=on_invalid)
    except ValueError as e:
        raise ValueError(f"{where}: {e}") from None
    d, has_ids = bodies.dimensions, bodies.ids is not None
    text = _rows(frame, found, d, has_ids, bracket=False)
    counts = {"tangent": int(np.count_nonzero(found.relation == Relation.TANGENT)),
              "overlap": int(np.count_nonzero(found.relation == Relation.OVERLAP)),
              "invalid": len(set(found.invalid) | set(errors))}
    overlaps = [f"frame {frame}: {_pair_name(bodies, int(a), int(b))}" for a, b in
                zip(found.i[found.relation == Relation.OVERLAP][:5], found.j[found.relation == Relation.OVERLAP][:5], strict=True)]
    if following is not None:
        step_box = use_box if box is not None else _same_box(bodies, following, frame)
        try:
            step = sweep_contacts(bodies, following, box=step_box, on_invalid=on_invalid)
        except ValueError as e:
            raise ValueError(f"{where} to frame {frame + 1}: {e}") from None
        text += _rows(frame, step, d, has_ids)
        counts["step_tangent"] = int(np.count_nonzero(step.relation == Relation.TANGENT))
        counts["step_overlap"] = int(np.count_nonzero(step.relation == Relation.OVERLAP))
    return FrameReport(frame, text, d, has_ids, len(bodies), counts, overlaps, time.perf_counter() - t0)


def _pair_name(bodies: Any, i: int, j: int) -> str:
    if bodies.ids is None:
        return f"bodies {i} and {j}"
    return f"bodies {i} (id {int(bodies.ids[i])}) and {j} (id {int(bodies.ids[j])})"


def _same_box(a: Any, b: Any, frame: int) -> Any:
    """The box of a step: both frames' box, which must be the same (a changing box has no straight-line step)."""
    if a.box != b.box:
        raise ValueError(
            f"{a.source}: the box changes from frame {frame} ({_box_text(a.box)}) to frame {frame + 1} ({_box_text(b.box)}): "
            "--between sweeps a step in one box; give --box to choose one"
        )
    return a.box


def _box_text(box: Any) -> str:
    return "open space" if box is None else box.describe()


class _Local:
    """Frames checked by worker processes on this machine (spawned: no state shared with the reader)."""

    def __init__(self, jobs: int) -> None:
        import multiprocessing

        self.jobs = jobs
        self.pool = ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn")) if jobs > 1 else None

    def submit(self, *args: Any, **kwargs: Any) -> Future[FrameReport]:
        if self.pool is None:
            f: Future[FrameReport] = Future()
            try:
                f.set_result(audit_frame(*args, **kwargs))
            except BaseException as e:  # noqa: BLE001 - handed to the caller as a failed future
                f.set_exception(e)
            return f
        return self.pool.submit(audit_frame, *args, threads=1, **kwargs)

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown(wait=False, cancel_futures=True)


class _Dask:
    """Frames checked on a Dask cluster (each frame's bodies scattered, then one task per frame)."""

    def __init__(self, address: str) -> None:
        from .bodies_cli import _connect

        self.client = _connect(address)
        workers = len(self.client.scheduler_info().get("workers", {})) or 1
        self.jobs = workers

    def submit(self, frame: int, bodies: Any, box: Any, following: Any = None, **kwargs: Any) -> Any:
        data = self.client.scatter([bodies] if following is None else [bodies, following])
        return self.client.submit(audit_frame, frame, data[0], box, data[1] if following is not None else None,
                                  threads=1, retries=2, pure=False, **kwargs)

    def close(self) -> None:
        self.client.close()


def _tasks(frames: Iterator[Any], between: bool) -> Iterator[tuple[int, Any, Any]]:
    """(frame number, its bodies, the next frame's bodies or None) for each frame picked."""
    previous: Any = None
    for bodies in frames:
        if previous is not None:
            yield int(previous.frame), previous, bodies if between else None
        previous = bodies
    if previous is not None:
        yield int(previous.frame), previous, None


def run_audit(args: argparse.Namespace) -> int:
    """``python -m app audit``: read the frames, check them, write the report, summarise. Returns the exit status."""
    from core import Box

    from .bodies_cli import ProgressBar, say
    from .output import Output
    from .readers import read_frames

    t0 = time.perf_counter()
    names, frames = read_frames(args.trajectory, frames=args.frames, format=args.format, dim=args.dim)
    if not names:
        raise ValueError(f"{args.trajectory}: --frames picks no frame")
    out = Output(args.out)  # checked (and its temporary file made) before any work
    runner: Any = _Dask(args.scheduler) if args.scheduler else _Local(args.jobs or len(os.sched_getaffinity(0)))
    progress = None if args.quiet else ProgressBar(sys.stderr, "audit", min_total=0, delay=1.0, unit="frames")
    reports: list[FrameReport] = []
    try:
        with out as f:
            window: dict[int, Any] = {}
            order: list[int] = []
            written = 0
            first: FrameReport | None = None
            box_of_run: Any = None

            def write(report: FrameReport) -> None:
                nonlocal first, written
                if first is None:
                    first = report
                    f.write(header(report.dimensions, report.has_ids) + "\n")
                elif (report.dimensions, report.has_ids) != (first.dimensions, first.has_ids):
                    raise ValueError(f"{args.trajectory}: frame {report.frame} has {report.dimensions}D bodies"
                                     f"{' with ids' if report.has_ids else ' without ids'}, unlike frame {first.frame}")
                f.write(report.text)
                report.text = ""
                reports.append(report)
                written += 1
                if progress is not None:
                    progress(written, len(names))

            def drain(limit: int) -> None:
                while len(order) > limit:  # in frame order: the oldest task first
                    write(window.pop(order.pop(0)).result())

            for number, bodies, following in _tasks(frames, args.between):
                if box_of_run is None and args.box is not None:
                    box_of_run = Box.from_any(args.box, bodies.dimensions)
                window[number] = runner.submit(number, bodies, box_of_run, following, on_invalid=args.on_invalid)
                order.append(number)
                drain(2 * runner.jobs)
            drain(0)
    finally:
        runner.close()
    elapsed = time.perf_counter() - t0
    total = {key: sum(r.counts.get(key, 0) for r in reports) for key in ("tangent", "overlap", "step_tangent", "step_overlap", "invalid")}
    violations = total["overlap"] + total["step_overlap"]
    if not args.quiet:
        kind = "ellipsoids" if reports[0].dimensions == 3 else "ellipses"
        say(args, f"audited {len(reports):,} frames of {reports[0].bodies:,} {kind} ({args.trajectory}) in {elapsed:.1f} s"
                  f" ({elapsed / len(reports):.2f} s per frame{', with the steps between' if args.between else ''})")
        text = f"pairs in the frames: {total['tangent']:,} tangent, {total['overlap']:,} overlapping"
        if args.between:
            text += f"; in the steps: {total['step_tangent']:,} first contacts, {total['step_overlap']:,} overlapping at the start"
        say(args, text)
        if total["invalid"]:
            say(args, f"{total['invalid']:,} bodies are no ellipsoid (--on-invalid mark): they are in no pair")
        say(args, f"wrote the report to {'<stdout>' if args.out == '-' else args.out}")
    if violations:
        first_overlaps = [o for r in reports for o in r.overlaps][:5]
        print(f"OVERLAP: {violations:,} overlapping pairs; first: " + "; ".join(first_overlaps), file=sys.stderr)
        return EXIT_OVERLAP
    if not args.quiet:
        say(args, "no pair overlaps")
    return 0
