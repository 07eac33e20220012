"""LAMMPS dump files with ellipsoid columns (``dump custom``), read with ``lammpsio``.

A frame (default: the last) of a text dump such as ``dump 1 all custom 100 out.dump id type x y
z shapex shapey shapez quatw quati quatj quatk``:

* ``lammpsio`` reads the frame's box (``ITEM: BOX BOUNDS``, tilted ``xy xz yz`` included), the
  particle ids and the positions ``x y z``, and orders the particles by id.
* ``lammpsio`` does not read per-atom columns beyond its fixed set, so the ellipsoid columns of
  the same frame are read by name with numpy and put in the same id order: ``shapex shapey
  shapez`` are the three **diameters** of the ellipsoid (LAMMPS writes diameters since July
  2020), halved here (exact in binary); ``quatw quati quatj quatk`` the orientation (wxyz;
  identity when absent). A row with shape 0 0 0 (a point particle) is an invalid body.

The box becomes HOOMD's convention (:mod:`app.readers.bodyset`): Lx = xhi - xlo, ...; a tilted
box's tilt *lengths* xy, xz, yz become the factors xy / Ly, xz / Lz, yz / Lz (one rounding
each). Boundaries ``pp pp pp`` are a periodic box, fixed or shrink-wrapped ones (``ff``, ``ss``,
``fs``, ``fm``...) on every axis open space; a mix (a slab, ``pp pp ff``) has its open axes
padded (:func:`app.readers.bodyset.cell_box`). A 2D run (``dimension 2``: z bounds -0.5 0.5,
every atom at z = 0, quaternions about z) is read as ellipses (semi-axes shapex / 2, shapey / 2;
``--dim 2`` says so for other 2D dumps).

The frame's items are checked before lammpsio reads it (:func:`_check_items`): the step and the
count are integers, the count is not negative and its rows are in the file (a small file
claiming 10^8 atoms is refused, not allocated), the box bounds are three lines of numbers.
"""

from __future__ import annotations

import math
import mmap
import os
import tempfile
from collections.abc import Iterator

import numpy as np

from .bodyset import BodySet, cell_box, from_parameters
from .gsdfile import _frame_index
from .guard import GZIP_MAGIC, clip, one_line

__all__ = ["read_lammps_dump", "lammps_frames", "SHAPE_COLUMNS", "QUAT_COLUMNS"]

SHAPE_COLUMNS = ("shapex", "shapey", "shapez")
"""Diameters of the ellipsoid along its body axes."""
QUAT_COLUMNS = ("quatw", "quati", "quatj", "quatk")
"""Orientation quaternion, w first."""


def read_lammps_dump(path: str, name: str, *, frame: int | None = None, planar: bool | None = None) -> BodySet:
    """Bodies of one frame of a LAMMPS text dump (module docstring).

    Args:
        path: the file (text; a compressed dump must be decompressed first).
        name: its name, for messages.
        frame: frame number from 0 (negative: from the end); None: the last frame.
        planar: True: a 2D run (ellipses); False: 3D; None: 2D when the frame looks like
            LAMMPS' ``dimension 2`` (module docstring).

    Raises:
        ValueError: lammpsio missing, not a dump, no such frame, missing columns, bad numbers,
            a tilt along an open axis, a 2D run whose bodies leave the plane.
    """
    k, data = _frame_text(path, name, frame)
    return _parse_frame(data, k, name, planar)


def lammps_frames(path: str, name: str, select: slice = slice(None), *, planar: bool | None = None) -> tuple[range, Iterator[BodySet]]:
    """(the frames ``select`` picks, an iterator over them as :class:`BodySet`): one pass over the file.

    The file is scanned once for its frames, then each wanted frame is parsed as
    :func:`read_lammps_dump` parses one (``python -m app audit``: memory of one frame).
    """
    starts, size = _frame_starts(path, name)
    wanted = range(*select.indices(len(starts)))

    def frames() -> Iterator[BodySet]:
        with open(path, "rb") as f:
            for k in wanted:
                end = starts[k + 1] if k + 1 < len(starts) else size
                f.seek(starts[k])
                yield _parse_frame(f.read(end - starts[k]), k, name, planar)

    return wanted, frames()


def _parse_frame(data: bytes, k: int, name: str, planar: bool | None) -> BodySet:
    """The bodies of frame k, from its bytes (``ITEM: TIMESTEP`` to the next frame)."""
    try:
        import lammpsio
    except ImportError:
        raise ValueError(f"{name}: reading LAMMPS dumps needs lammpsio: pip install 'ellipsoid-interference[formats]'") from None
    lines = data.split(b"\n")
    atoms = next((i for i, ln in enumerate(lines) if ln.startswith(b"ITEM: ATOMS")), None)
    bounds = next((i for i, ln in enumerate(lines) if ln.startswith(b"ITEM: BOX BOUNDS")), None)
    if atoms is None or bounds is None:
        raise ValueError(f"{name}: frame {k} has no ITEM: BOX BOUNDS / ITEM: ATOMS section")
    _check_items(lines, bounds, atoms, k, name)
    columns = lines[atoms].decode("ascii", "replace").split()[2:]
    for need in (("x", "y", "z"), SHAPE_COLUMNS):
        missing = [c for c in need if c not in columns]
        if missing:
            raise ValueError(
                f"{name}: the dump has no column {', '.join(missing)} (columns: {' '.join(columns)}); "
                "write it with e.g. dump custom ... id type x y z shapex shapey shapez quatw quati quatj quatk"
            )
    periodic = _periodic(lines[bounds].decode("ascii", "replace").split()[3:], name)
    z_bounds = lines[bounds + 3].split()[:2]
    with tempfile.NamedTemporaryFile(suffix=".dump") as tmp:  # lammpsio reads a file by name
        tmp.write(data)
        tmp.flush()
        try:
            snap = next(iter(lammpsio.DumpFile(tmp.name, sort_ids=True)))
        except Exception as e:  # noqa: BLE001 - lammpsio raises IOError/ValueError/IndexError kinds
            raise ValueError(f"{name}: frame {k} cannot be read ({one_line(e)})") from None
    N = int(snap.N)
    use = [columns.index(c) for c in (*SHAPE_COLUMNS, *(QUAT_COLUMNS if "quatw" in columns else ()))]
    rows = lines[atoms + 1 : atoms + 1 + N]
    if len(rows) < N or (N and not rows[-1].strip()):
        raise ValueError(f"{name}: frame {k} is truncated: {N} atoms announced")
    try:
        table = np.loadtxt(rows, dtype=np.float64, ndmin=2, usecols=use) if N else np.zeros((0, len(use)))
    except ValueError as e:
        raise ValueError(f"{name}: frame {k}: {one_line(e, 300)}") from None
    ids = np.asarray(snap.id, dtype=np.int64)
    if "id" in columns and N:
        file_ids = np.loadtxt(rows, dtype=np.int64, usecols=[columns.index("id")], ndmin=1)
        table = table[np.argsort(file_ids, kind="stable")]  # lammpsio's order: sorted by id
    has_quat = "quatw" in columns
    if has_quat and any(c not in columns for c in QUAT_COLUMNS):
        raise ValueError(f"{name}: give all of {' '.join(QUAT_COLUMNS)} or none")
    centers, semi = np.asarray(snap.position, np.float64), table[:, :3] / 2
    box = None
    if any(periodic):
        lo, hi = np.asarray(snap.box.low, np.float64), np.asarray(snap.box.high, np.float64)
        L = hi - lo
        tilt = np.zeros(3) if snap.box.tilt is None else np.asarray(snap.box.tilt, np.float64)
        box = cell_box(L, (tilt[0] / L[1], tilt[1] / L[2], tilt[2] / L[2]), periodic, centers, semi, name=f"{name}: frame {k}")
    out = from_parameters(centers, semi, table[:, 3:7] if has_quat else None, name, box=box, ids=ids, frame=k)
    if planar is None:  # LAMMPS' dimension 2: z bounds -0.5 0.5, every atom at z = 0, turned about z
        flat = not centers[:, 2].any() and (not has_quat or not table[:, 4:6].any())
        planar = flat and [float(b) for b in z_bounds] == [-0.5, 0.5]
    return out.in_plane() if planar else out


def _check_items(lines: list[bytes], bounds: int, atoms: int, k: int, name: str) -> None:
    """Check what frame k's items claim before lammpsio reads them (module docstring).

    Raises:
        ValueError: a step or count that is no integer, a negative count, fewer rows than the
            count, box bounds that are not three lines of two or three numbers.
    """
    where = f"{name}: frame {k}"
    step = lines[1].strip() if len(lines) > 1 else b""
    if not _integer(step):
        raise ValueError(f"{where}: ITEM: TIMESTEP is followed by {_shown(step)}, not a step number")
    item = next((i for i, ln in enumerate(lines) if ln.startswith(b"ITEM: NUMBER OF ATOMS")), None)
    if item is None:
        raise ValueError(f"{where} has no ITEM: NUMBER OF ATOMS")
    count = lines[item + 1].strip() if item + 1 < len(lines) else b""
    if not _integer(count):
        raise ValueError(f"{where}: NUMBER OF ATOMS is {_shown(count)}, not a count")
    N = int(count)
    if N < 0:
        raise ValueError(f"{where}: NUMBER OF ATOMS is {N}")
    follow = len(lines) - atoms - 1 - (lines[-1].strip() == b"")  # the frame's text ends with a newline
    if N > follow:
        raise ValueError(f"{where} is truncated: {N} atoms announced, {max(follow, 0)} lines follow ITEM: ATOMS")
    for ln in lines[bounds + 1 : bounds + 4]:
        values = ln.split()
        try:
            ok = len(values) in (2, 3) and all(math.isfinite(float(v)) for v in values)
        except ValueError:
            ok = False
        if not ok:
            raise ValueError(f"{where}: ITEM: BOX BOUNDS needs three lines 'lo hi' (or 'lo hi tilt'), got {_shown(ln)}")


def _integer(text: bytes) -> bool:
    """Whether ``text`` is a decimal integer (an optional sign, then digits)."""
    return text.lstrip(b"+-").isdigit() and len(text) - len(text.lstrip(b"+-")) <= 1


def _shown(text: bytes) -> str:
    """A line of the file, quoted for a message (cut when long)."""
    return repr(clip(text.decode("utf-8", "replace"), 60)) if text else "nothing"


def _frame_starts(path: str, name: str) -> tuple[list[int], int]:
    """(the byte offset of every frame's ``ITEM: TIMESTEP`` line, the file's size)."""
    try:
        with open(path, "rb") as f:
            if f.read(2) == GZIP_MAGIC:
                raise ValueError(f"{name}: a gzip-compressed dump: decompress it first (gunzip)")
            size = os.fstat(f.fileno()).st_size
            if size == 0:
                raise ValueError(f"{name}: empty file")
            with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as m:
                starts = []
                at = m.find(b"ITEM: TIMESTEP")
                while at >= 0:
                    if at == 0 or m[at - 1 : at] == b"\n":
                        starts.append(at)
                    at = m.find(b"ITEM: TIMESTEP", at + 1)
    except OSError as e:
        raise ValueError(f"cannot read {name}: {e.strerror}") from None
    if not starts:
        raise ValueError(f"{name}: not a LAMMPS dump file (no ITEM: TIMESTEP line)")
    return starts, size


def _frame_text(path: str, name: str, frame: int | None) -> tuple[int, bytes]:
    """(frame number, the bytes of that frame) of a dump file."""
    starts, size = _frame_starts(path, name)
    k = _frame_index(frame, len(starts), name)
    end = starts[k + 1] if k + 1 < len(starts) else size
    try:
        with open(path, "rb") as f:
            f.seek(starts[k])
            return k, f.read(end - starts[k])
    except OSError as e:
        raise ValueError(f"cannot read {name}: {e.strerror}") from None


def _periodic(flags: list[str], name: str) -> tuple[bool, bool, bool]:
    """Which axes are periodic (``pp`` after ITEM: BOX BOUNDS; fixed or shrink-wrapped ``f s m``: open)."""
    flags = [f for f in flags if f not in ("xy", "xz", "yz")]
    if not flags:
        return (True, True, True)  # old dumps name no boundaries: LAMMPS's default is periodic
    if len(flags) != 3:
        raise ValueError(f"{name}: ITEM: BOX BOUNDS names {len(flags)} boundaries, not 3: {' '.join(flags)}")
    return (flags[0] == "pp", flags[1] == "pp", flags[2] == "pp")
