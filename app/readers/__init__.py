"""Readers of files of many bodies: every format gives the same :class:`BodySet`.

One reader per format, each with the format's own library where one exists; all return the
same arrays (centres, semi-axes, orientations wxyz, and the file's periodic box in HOOMD's
convention ``(Lx, Ly, Lz)`` or ``(Lx, Ly, Lz, xy, xz, yz)``: :mod:`app.readers.bodyset`).
They serve ``python -m app contacts``, ``serve --bodies``, ``screenshot --bodies`` and the
scene's upload.

=========  =====================================  ==============================================
format     file names                             read with
=========  =====================================  ==============================================
csv        ``*.csv`` (anything else: CSV)         numpy, block by block (:mod:`.table`)
parquet    ``*.parquet``, ``*.pq``                pyarrow (:mod:`.table`)
npz        ``*.npz``                              numpy, never unpickling (:mod:`.npzfile`)
gsd        ``*.gsd``                              gsd, HOOMD-blue's (:mod:`.gsdfile`)
lammps     ``*.dump``, ``*.lammpstrj``            lammpsio + the ellipsoid columns (:mod:`.lammpsdump`)
xyz        ``*.xyz``, ``*.extxyz``                extxyz, libAtoms' (:mod:`.extxyzfile`)
=========  =====================================  ==============================================

The format comes from ``format=`` (``--format``), else the file name, else the first bytes.
``-`` reads standard input (CSV is streamed; other formats are read whole first).

Hostile files (issue 52): every reader checks a file's claims (counts in a header, shapes,
sizes in an archive's directory) against the file's size before it makes an array, and a
text format's file that is no text (gzip, UTF-16, NUL bytes) is refused before it is parsed
(:mod:`.guard`); a malformed file of any format is one ValueError line naming the file, and the
frame or line, never another exception (``tests/test_hostile_files.py``).
"""

from __future__ import annotations

import os
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from .bodyset import BodySet, file_box, usable_box
from .table import COLUMNS

__all__ = ["BodySet", "COLUMNS", "FORMATS", "format_of", "read_bodies", "read_frames", "read_bodies_bytes", "file_box", "usable_box"]

FORMATS = ("csv", "parquet", "npz", "gsd", "lammps", "xyz")
"""The formats read, by name (``--format``)."""

_SUFFIXES = {
    ".csv": "csv", ".txt": "csv", ".parquet": "parquet", ".pq": "parquet", ".npz": "npz", ".gsd": "gsd",
    ".dump": "lammps", ".lammpstrj": "lammps", ".lammps": "lammps", ".xyz": "xyz", ".extxyz": "xyz",
}
_TRAJECTORIES = ("gsd", "lammps", "xyz")
_TEXT = {"csv": "text table", "lammps": "LAMMPS dump", "xyz": "extended XYZ file"}
"""Formats read as text, and what to call them in messages."""


def format_of(name: str, head: bytes = b"") -> str:
    r"""The format of a file from its name, else from its first bytes ("csv" when unsure).

    Examples:
        >>> format_of("run.lammpstrj"), format_of("x.bin", b"PK\x03\x04"), format_of("-", b"x,y,a")
        ('lammps', 'npz', 'csv')
    """
    suffix = Path(name).suffix.lower()
    if suffix in _SUFFIXES:
        return _SUFFIXES[suffix]
    if head.startswith(b"PK"):
        return "npz"
    if head.startswith(b"PAR1"):
        return "parquet"
    if head.startswith(b"\xdf\x65\xdf\x65"):
        return "gsd"
    if head.lstrip().startswith(b"ITEM: TIMESTEP"):
        return "lammps"
    lines = head.split(b"\n")
    if len(lines) > 1 and lines[0].strip().isdigit() and (b"Properties=" in lines[1] or b"Lattice=" in lines[1]):
        return "xyz"
    return "csv"


def read_bodies(path: str | os.PathLike[str], *, frame: int | None = None, format: str | None = None,
                dim: int | None = None) -> BodySet:
    """Read a file of bodies (``-``: standard input) in any format of :data:`FORMATS`.

    Args:
        path: the file, or ``-``.
        frame: trajectories (GSD, LAMMPS, XYZ): the frame from 0 (negative: from the end);
            None: the last one. Other formats have one frame: only None, 0 or -1.
        format: one of :data:`FORMATS`, or None to tell from the name and the first bytes.
        dim: 2 reads a file that stores a 2D system as 3D (z = 0, turned about z) as ellipses;
            3 keeps 3D; None: the file says (GSD's dimensions, LAMMPS' 2D bounds, XYZ's pbc).

    Raises:
        ValueError: unreadable file, unknown format, a format's own errors (missing columns,
            bad numbers...: the message names the line or body).
    """
    name = str(path)
    if dim not in (None, 2, 3):
        raise ValueError(f"dim must be 2 or 3, got {dim!r}")
    if name == "-":
        return _in_dimension(_read_stream(sys.stdin.buffer, "<stdin>", frame, format, dim), dim)
    try:
        with open(path, "rb") as f:
            head = f.read(512)
            fmt = _checked_format(format, name, head, frame)
            if fmt == "csv":
                f.seek(0)
                from .table import read_csv

                return _in_dimension(read_csv(f, Path(name).name), dim)
    except IsADirectoryError:
        raise ValueError(f"cannot read {name}: it is a folder") from None
    except OSError as e:
        raise ValueError(f"cannot read {name}: {e.strerror}") from None
    return _in_dimension(_read_file(name, Path(name).name, fmt, frame, dim), dim)


def read_frames(path: str | os.PathLike[str], *, frames: slice = slice(None), format: str | None = None,
                dim: int | None = None) -> tuple[list[str], Iterator[BodySet]]:
    """The frames of a trajectory, one at a time: (a name for each frame picked, an iterator of them).

    ``path`` is a trajectory file (GSD, LAMMPS dump, extended XYZ: its frames, read in one pass),
    another file of bodies (one frame), a folder of frame files or a glob pattern (``run/*.csv``:
    one frame per file, the last one of a trajectory, files in natural order: ``f2`` before
    ``f10``). ``frames`` picks frames as a Python slice does. Nothing but the frame at hand is held.

    Raises:
        ValueError: no such file or no file matches, an unknown format; a frame's own errors
            surface when the iterator reaches it.
    """
    import glob as globbing

    name = str(path)
    if os.path.isdir(name) or any(ch in name for ch in "*?["):
        files = sorted((f for f in (globbing.glob(os.path.join(name, "*")) if os.path.isdir(name) else globbing.glob(name))
                        if os.path.isfile(f)), key=_natural)
        if not files:
            raise ValueError(f"{name}: no files of frames there")
        numbers = list(range(len(files)))[frames]

        def each_file() -> Iterator[BodySet]:
            for k in numbers:
                b = read_bodies(files[k], format=format, dim=dim)
                b.frame = k  # the frame's number: its place among the files
                yield b

        return [files[k] for k in numbers], each_file()
    try:
        with open(name, "rb") as f:
            head = f.read(512)
    except IsADirectoryError:
        raise ValueError(f"cannot read {name}: it is a folder") from None
    except OSError as e:
        raise ValueError(f"cannot read {name}: {e.strerror}") from None
    fmt = _checked_format(format, name, head, None)
    short = Path(name).name
    planar = None if dim is None else dim == 2
    if fmt == "gsd":
        from .gsdfile import gsd_frames

        wanted, it = gsd_frames(name, short, frames)
    elif fmt == "lammps":
        from .lammpsdump import lammps_frames

        wanted, it = lammps_frames(name, short, frames, planar=planar)
    elif fmt == "xyz":
        from .extxyzfile import extxyz_frames

        wanted, it = extxyz_frames(name, short, frames, planar=planar)
    else:
        wanted = range(*frames.indices(1))

        def one() -> Iterator[BodySet]:
            for k in wanted:
                b = read_bodies(name, format=fmt, dim=dim)
                b.frame = k
                yield b

        it = one()
    return [f"{short} frame {k}" for k in wanted], (_in_dimension(b, dim) for b in it)


def _natural(name: str) -> list[Any]:
    """Sort key: digits as numbers (``frame2`` before ``frame10``)."""
    import re

    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name)]


def read_bodies_bytes(data: bytes, name: str, *, frame: int | None = None, format: str | None = None,
                      dim: int | None = None) -> BodySet:
    """:func:`read_bodies` from the bytes of a file called ``name`` (the scene's upload)."""
    import io

    return _in_dimension(_read_stream(io.BytesIO(data), name, frame, format, dim), dim)


def _in_dimension(bodies: BodySet, dim: int | None) -> BodySet:
    """The bodies in the dimension asked for (``--dim``): a 3D file of a 2D system made 2D."""
    if dim == 2 and bodies.dimensions == 3:
        return bodies.in_plane()
    if dim == 3 and bodies.dimensions == 2:
        raise ValueError(f"{bodies.source}: --dim 3, but the file holds 2D bodies")
    return bodies


def _read_stream(stream: IO[bytes], name: str, frame: int | None, format: str | None, dim: int | None = None) -> BodySet:
    """A stream (stdin, an upload): CSV is parsed as it comes, other formats via a temporary file."""
    head = stream.peek(512)[:512] if hasattr(stream, "peek") else b""
    if not head and hasattr(stream, "getvalue"):
        head = stream.getvalue()[:512]
    fmt = _checked_format(format, name, head, frame)
    if fmt == "csv":
        from .table import read_csv

        return read_csv(stream, name)
    data = stream.read()
    if fmt == "npz":
        from .npzfile import read_npz

        return read_npz(data, name)
    with tempfile.TemporaryDirectory(prefix="bodies-") as d:  # the libraries read files by name
        tmp = os.path.join(d, "bodies" + {"gsd": ".gsd", "lammps": ".dump", "xyz": ".xyz", "parquet": ".parquet"}[fmt])
        with open(tmp, "wb") as f:
            f.write(data)
        return _read_file(tmp, name, fmt, frame, dim)


def _checked_format(format: str | None, name: str, head: bytes, frame: int | None) -> str:
    """The format to read (``format``, else from the name and the first bytes), its first bytes checked."""
    if format is not None and format not in FORMATS:
        raise ValueError(f"unknown format {format!r}; formats: {', '.join(FORMATS)}")
    fmt = format or format_of(name, head)
    if frame not in (None, 0, -1) and fmt not in _TRAJECTORIES:
        raise ValueError(f"{name}: --frame {frame}: a {fmt} file holds one frame (frames: GSD, LAMMPS dump, XYZ)")
    if fmt in _TEXT:
        from .guard import refuse_non_text

        refuse_non_text(head, Path(name).name, _TEXT[fmt])
    return fmt


def _read_file(path: str, name: str, fmt: str, frame: int | None, dim: int | None = None) -> BodySet:
    if fmt == "npz":
        from .npzfile import read_npz

        return read_npz(path, name)
    if fmt == "parquet":
        from .table import read_parquet

        return read_parquet(path, name)
    if fmt == "gsd":
        from .gsdfile import read_gsd

        return read_gsd(path, name, frame=frame)
    if fmt == "lammps":
        from .lammpsdump import read_lammps_dump

        return read_lammps_dump(path, name, frame=frame, planar=None if dim is None else dim == 2)
    from .extxyzfile import read_extxyz

    return read_extxyz(path, name, frame=frame, planar=None if dim is None else dim == 2)
