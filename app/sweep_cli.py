"""The ``sweep`` sub-command of ``python -m app``: first contact times among moving bodies.

``python -m app sweep START END --out EVENTS.csv [--box Lx,Ly,Lz[,xy,xz,yz]] [--frame K] [--end-frame K]
[--format F] [--method exact] [--on-invalid mark] [--quiet]``

START and END are files of bodies as for ``contacts`` (any format of :mod:`app.readers`: CSV
with the columns ``x,y,z,a,b,c,qw,qx,qy,qz`` or ``x,y,a,b,angle``, Parquet, NPZ, HOOMD GSD,
LAMMPS dump, extended XYZ): row k of START is body k at t = 0, row k of END the same body at
t = 1 (same semi-axes, row by row). They may be two frames of one trajectory (``--frame``,
``--end-frame``). Each body moves on the straight line between its centres and turns along
q(t) = (1 - t) q0 + t q1 (:func:`core.sweep_contacts`). The box is ``--box``, else START's
(orthogonal, or tilted in HOOMD's convention); in a box, a body whose end centre is more than half
a box vector away along one (a wrapped trajectory: it crossed a face) is taken at the nearest
image of its end centre (:func:`unwrapped`).

EVENTS is CSV ``i,j,t_lo,t_hi,relation,certified_by,image_x,image_y,image_z`` (or ``-``: standard
output), then ``id_i,id_j`` when the files give the bodies ids: every pair that touches or
overlaps during the step, t_lo <= t* <= t_hi (floats written so that they read back exactly),
the relation at t* (``tangent``, or ``overlap`` when they already overlap at t = 0), which
arithmetic certified it (``float`` or ``exact``) and the image k of body j (j's path moved by
v(k)), sorted by (i, j) (one writer: :meth:`core.PairTable.to_csv`). It is written whole or not at all (:mod:`app.output`). Messages and the progress bar go
to standard error.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from core.options import ON_INVALID, SWEEP_METHODS

if TYPE_CHECKING:
    from core import Box

    from .readers import BodySet

__all__ = ["add_parser", "run_sweep", "MovingBodies", "read_moving_bodies", "unwrapped", "read_events_csv", "EVENTS_HEADER"]

EVENTS_HEADER = "i,j,t_lo,t_hi,relation,certified_by,image_x,image_y,image_z"


def add_parser(sub: Any) -> None:
    """Add ``sweep`` to the sub-command parsers of :func:`app.cli.build_parser`."""
    from .bodies_cli import add_body_file_options, box_argument, frame_argument

    s = sub.add_parser("sweep", help="certified first contact times among moving bodies (START, END files in, CSV out)")
    s.add_argument("start", help="bodies at t = 0 (any format of app.readers: CSV, Parquet, NPZ, GSD, LAMMPS, XYZ), or - for stdin")
    s.add_argument("end", help="the same bodies at t = 1 (same rows, same semi-axes)")
    s.add_argument("--out", required=True, help=f"output CSV {EVENTS_HEADER}, or - for stdout")
    s.add_argument("--box", type=box_argument, default=None, help="periodic box sides Lx,Ly[,Lz], or a tilted box Lx,Ly,Lz,xy,xz,yz (2D: Lx,Ly,xy) (minimum image over the step); default: START's box")
    add_body_file_options(s, dim=True)
    s.add_argument("--end-frame", type=frame_argument, default=None, help="frame of END when it is a trajectory (default: --frame)")
    s.add_argument(
        "--method", choices=SWEEP_METHODS, default="adaptive",
        help="adaptive: the certified float filter, exact arithmetic where it abstains; exact: every candidate pair exactly (slow)",
    )
    s.add_argument("--on-invalid", choices=ON_INVALID, default="raise", help="mark: report bad bodies and go on")
    s.add_argument("--quiet", action="store_true", help="no progress bar and no summary (errors only)")


@dataclass
class MovingBodies:
    """START and END read and checked for a sweep: what :func:`core.sweep_contacts` takes, and from where."""

    start: BodySet
    """The bodies at t = 0 (their parameters)."""
    end: BodySet
    """The same bodies at t = 1."""
    centers1: np.ndarray
    """END's centres, in a box taken at the nearest image of START's (:func:`unwrapped`)."""
    box: Box | None
    """The periodic :class:`core.Box` (``--box``, else START's), or None."""
    errors: dict[int, str]
    """Row -> why START or END describes no body there (the files' reasons)."""
    names: tuple[str, str]
    """How START and END are named in messages."""
    moved: int = 0
    """Bodies whose END centre was moved to its nearest image (they crossed a face of the box)."""

    @property
    def dim(self) -> int:
        """2 or 3."""
        return self.start.dim

    def arguments(self) -> tuple[Any, Any, Any, Any, Any]:
        """(centers0, centers1, semi_axes, orientations0, orientations1) for :func:`core.sweep_contacts`."""
        return self.start.centers, self.centers1, self.start.semi_axes, self.start.orientations, self.end.orientations


def read_moving_bodies(
    start: str,
    end: str,
    *,
    frame: int | None = None,
    end_frame: int | None = None,
    format: str | None = None,
    box: Any = None,
    on_invalid: str = "raise",
    dim: int | None = None,
) -> MovingBodies:
    """Read START and END (files of the same bodies at t = 0 and t = 1) and check that they match.

    The one reader of a sweep's files: ``python -m app sweep`` and the scene
    (``serve --bodies START --to END``) both use it.

    Args:
        start: file of bodies at t = 0 (any format of :mod:`app.readers`; ``-`` for stdin).
        end: the same bodies at t = 1.
        frame: frame of START when it is a trajectory (None: the last).
        end_frame: frame of END (None: ``frame``).
        format: reader (None: from the name, else the first bytes).
        box: periodic box (any form of :meth:`core.Box.from_any`; None: START's box, if any).
        on_invalid: "raise" a ValueError for the first row that is no body, or "mark" (the
            reasons are in :attr:`MovingBodies.errors`).
        dim: 2 reads 3D files of a 2D system as ellipses (:func:`app.readers.read_bodies`).

    Raises:
        ValueError: unreadable files, matrices instead of parameters, different numbers of
            bodies or semi-axes, a bad row (``on_invalid="raise"``), a box that does not fit.
    """
    from .readers import read_bodies

    if start == "-" and end == "-":
        raise ValueError("START and END cannot both be standard input")
    s = read_bodies(start, frame=frame, format=format, dim=dim)
    e = read_bodies(end, frame=end_frame if end_frame is not None else frame, format=format, dim=dim)
    if s.ids is not None and e.ids is not None and len(s) == len(e):
        e = e.ordered_like(s)  # LAMMPS writes atoms in any order; ids pair them
    names = ("<stdin>" if start == "-" else start, "<stdin>" if end == "-" else end)
    for b, name in zip((s, e), names, strict=True):
        if b.centers is None or b.semi_axes is None:
            raise ValueError(f"{name}: sweep needs the bodies' parameters (centres, semi-axes, orientations), not matrices Q")
    assert s.centers is not None and e.centers is not None and s.semi_axes is not None and e.semi_axes is not None
    if s.centers.shape != e.centers.shape:
        raise ValueError(
            f"{names[0]} has {len(s)} {s.dim}D bodies but {names[1]} has {len(e)} {e.dim}D bodies: "
            "END must hold the same bodies, row by row"
        )
    same = (s.semi_axes == e.semi_axes) | (np.isnan(s.semi_axes) & np.isnan(e.semi_axes))
    bad = np.flatnonzero(~same.all(axis=1))
    if bad.size:
        k = int(bad[0])
        raise ValueError(
            f"{s.where(k)}: the semi-axes differ between {names[0]} ({s.semi_axes[k].tolist()}) and "
            f"{names[1]} ({e.semi_axes[k].tolist()}): a body keeps its shape during the step"
        )
    errors = {k: f"{names[0]}: {why}" for k, why in s.parameter_errors.items()}  # no float matrix is built
    errors.update({k: f"{names[1]}: {why}" for k, why in e.parameter_errors.items() if k not in errors})
    if errors and on_invalid == "raise":
        k, why = min(errors.items())
        raise ValueError(f"{s.where(k)}: {why}")
    from .bodies_cli import command_box

    box = command_box(box, s)
    centers1, moved = e.centers, 0
    if box is not None:
        centers1, moved = unwrapped(s.centers, e.centers, box)
    return MovingBodies(s, e, centers1, box, errors, names, moved)


def run_sweep(args: argparse.Namespace) -> int:
    """``python -m app sweep``: read both files, sweep, write EVENTS, summarise. Returns the exit status."""
    from core import sweep_contacts

    from .bodies_cli import ProgressBar, say, warn_invalid
    from .output import Output

    if args.start == "-" and args.end == "-":
        raise ValueError("START and END cannot both be standard input")
    out = Output(args.out)  # checked (and its temporary file made) before any work
    with out as f:
        t0 = time.perf_counter()
        moving = read_moving_bodies(
            args.start, args.end, frame=args.frame, end_frame=args.end_frame, format=args.format, box=args.box,
            on_invalid=args.on_invalid, dim=args.dim,
        )
        start, names, box, errors = moving.start, moving.names, moving.box, moving.errors
        t1 = time.perf_counter()
        kind = "ellipsoids" if start.dim == 3 else "ellipses"
        say(args, f"read {len(start):,} moving {kind} from {names[0]} and {names[1]} in {t1 - t0:.1f} s" + (f"; periodic box {box.describe()}" if box is not None else ""))
        if moving.moved:
            say(args, f"{moving.moved:,} bodies crossed a face of the box between START and END: END taken at the nearest image")
        progress = None if args.quiet else ProgressBar(sys.stderr, "first contacts", min_total=50_000)
        res = sweep_contacts(
            *moving.arguments(), box=box, on_invalid=args.on_invalid, method=args.method, progress=progress,
        )
        res.ids = moving.start.ids
        t2 = time.perf_counter()
        res.to_csv(f)
    t3 = time.perf_counter()
    invalid = dict(res.invalid)
    invalid.update(errors)  # the reason from the files' parameters, not the stand-in's
    say(args, f"wrote {len(res):,} first contacts to {'<stdout>' if args.out == '-' else args.out}")
    say(args, res.summary())
    phases = ", ".join(f"{k} {v:.2f} s" for k, v in res.seconds.items() if k != "total")
    say(args, f"time: read files {t1 - t0:.2f} s, sweep ({phases}), write {t3 - t2:.2f} s, total {t3 - t0:.2f} s")
    warn_invalid(invalid, start.where)
    return 0


def unwrapped(c0: np.ndarray, c1: np.ndarray, box: Box) -> tuple[np.ndarray, int]:
    """END's centres moved by whole lattice vectors so that each body moves by its minimum image.

    Trajectories in a periodic box store wrapped positions: a body that crosses a face between
    two frames jumps by about one box vector. Its end centre is taken as c1 - v(k), k the
    rounded difference of the fractional coordinates (:meth:`core.Box.unwrap`, which checks that
    the subtraction is exact). Rows that are not bodies (NaN) are left as they are, for the
    reader's message. Returns (centres, how many moved).

    Examples:
        >>> from core import Box
        >>> c, n = unwrapped(np.array([[9.5, 5.0]]), np.array([[0.25, 5.0]]), Box(10, 10))
        >>> c.tolist(), n
        ([[10.25, 5.0]], 1)
        >>> c, n = unwrapped(np.array([[5.0, 9.5]]), np.array([[0.0, 0.25]]), Box(10, 10, xy=0.5))   # a2 = (5, 10)
        >>> c.tolist(), n
        ([[5.0, 10.25]], 1)
    """
    ok = np.isfinite(c0).all(axis=1) & np.isfinite(c1).all(axis=1)
    out = c1.copy()
    if not ok.any():
        return out, 0
    ends, k = box.unwrap(c0[ok], c1[ok])
    out[ok] = ends
    return out, int(np.count_nonzero(k.any(axis=1)))


def read_events_csv(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Read the first columns of an EVENTS file (module docstring): (i, j, t_lo, t_hi, int8 Relation codes)."""
    from core import Relation

    lines = Path(path).read_text().splitlines()
    if not lines or not lines[0].strip().startswith("i,j,t_lo,t_hi,relation"):
        raise ValueError(f"{path}: expected a header starting with {EVENTS_HEADER}")
    rows = [ln.split(",") for ln in lines[1:] if ln.strip()]
    return (
        np.array([int(r[0]) for r in rows], dtype=np.int64),
        np.array([int(r[1]) for r in rows], dtype=np.int64),
        np.array([float(r[2]) for r in rows], dtype=np.float64),
        np.array([float(r[3]) for r in rows], dtype=np.float64),
        np.array([int(Relation.parse(r[4])) for r in rows], dtype=np.int8),
    )
