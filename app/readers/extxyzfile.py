"""Extended XYZ files as OVITO writes them, read with ``extxyz`` (libAtoms' reference parser).

A frame (default: the last) whose comment line names the columns, e.g.::

    2
    Lattice="10 0 0 0 10 0 0 0 10" Properties=species:S:1:pos:R:3:orientation:R:4:aspherical_shape:R:3
    A 1 2 3 0 0 0 1 1 0.5 0.25
    ...

Columns by the names OVITO's XYZ exporter gives its particle properties: ``pos`` (Position),
``aspherical_shape`` (Aspherical Shape: the three **semi-axes**), ``orientation``
(Orientation, OVITO's order **x y z w**: reordered to wxyz here; identity when absent),
``radius`` (spheres, when there is no ``aspherical_shape``), ``id`` (the particles' own ids:
the outputs name them). Other columns (``species``, ...) are ignored. The cell: ``Lattice``
(three box vectors) with ``pbc`` (OVITO writes none: periodic, as the format's default); no
``Lattice``: open space. A periodic cell must be in HOOMD's orientation (a1 along x, a2 in the
xy plane) to become a box (:mod:`app.readers.bodyset`); an ``Origin`` is irrelevant (only
differences of positions matter). A cell periodic on some axes only has its open axes padded
(:func:`app.readers.bodyset.cell_box`); ``pbc="T T F"`` with every body at z = 0 is a 2D
system (ellipses in the periodic plane, :meth:`app.readers.bodyset.BodySet.in_plane`).
"""

from __future__ import annotations

import mmap
import os
import re
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from .bodyset import BodySet, cell_box, from_parameters
from .gsdfile import _frame_index
from .guard import clip, one_line

__all__ = ["read_extxyz", "extxyz_frames", "COMMENT_CHARS"]

COMMENT_CHARS = 1 << 20
"""Longest comment line read (1 Mi characters); a longer one is refused."""

_COUNT_CHARS = 4096
"""Longest atom-count line read."""

_MOST_ATOMS = 2**31 - 1
"""Most atoms the C parser counts (a C int)."""

_LATTICE = re.compile(rb"""(?:^|\s)["']?lattice["']?\s*=""", re.IGNORECASE)
_PROPERTIES = re.compile(r"""["']?properties["']?\s*=\s*(?:"([^"]*)"|'([^']*)'|\{([^}]*)\}|(\S+))""", re.IGNORECASE)


@dataclass(frozen=True)
class _Frame:
    """Where a frame is in the file: its bytes [start, end), the line of its atom count, its atoms."""

    start: int
    end: int
    line: int
    natoms: int
    lattice: bool = True
    """Whether the comment line gives a ``Lattice`` (without one the frame is in open space)."""


def read_extxyz(path: str, name: str, *, frame: int | None = None, planar: bool | None = None) -> BodySet:
    """Bodies of one frame of an extended XYZ file (module docstring).

    Every frame's atom count, comment line and lines are checked first (:func:`_frames`), so
    the C parser is only handed a frame whose claims the file backs: it does not check its
    allocations (a 173-byte file claiming 10^8 atoms crashed it) and it crashes on a frame of
    0 atoms. Only the wanted frame is parsed (copied to a temporary file when it is not the first).

    Raises:
        ValueError: extxyz missing, a malformed file (one line naming the file, the frame or
            line, and what is wrong), no such frame, missing columns, a cell that is periodic on
            some axes only or not in HOOMD's orientation.
    """
    frames = _frames(path, name)
    k = _frame_index(frame, len(frames), name)
    return _read_frame(path, name, frames[k], k, planar)


def extxyz_frames(path: str, name: str, select: slice = slice(None), *, planar: bool | None = None) -> tuple[range, Iterator[BodySet]]:
    """(the frames ``select`` picks, an iterator over them as :class:`BodySet`): the file checked once.

    Every frame is checked first (:func:`_frames`), then each wanted one is parsed alone, as
    :func:`read_extxyz` parses one (``python -m app audit``: memory of one frame).
    """
    frames = _frames(path, name)
    wanted = range(*select.indices(len(frames)))
    return wanted, (_read_frame(path, name, frames[k], k, planar) for k in wanted)


def _read_frame(path: str, name: str, fr: _Frame, k: int, planar: bool | None) -> BodySet:
    """Frame k (checked: :func:`_frames`) parsed by the C parser, alone."""
    try:
        import extxyz
    except ImportError:
        raise ValueError(f"{name}: reading extended XYZ needs extxyz: pip install 'ellipsoid-interference[formats]'") from None
    if fr.natoms == 0:  # nothing to parse (and the C parser would crash on it)
        return from_parameters(np.zeros((0, 3)), np.zeros((0, 3)), None, name, frame=k)
    with tempfile.TemporaryDirectory(prefix="xyz-") as tmp:
        source = path
        if fr.start > 0:  # the frame alone: the parser reads no frame before it
            source = os.path.join(tmp, "frame.xyz")
            with open(path, "rb") as src, open(source, "wb") as dst:
                src.seek(fr.start)
                _copy(src, dst, fr.end - fr.start)
        try:
            f = next(iter(extxyz.iread_dicts(source, index=0)), None)
        except Exception as e:  # noqa: BLE001 - the parser raises its own error kinds
            raise ValueError(f"{name}: frame {k}: {_parser_said(e, fr)}") from None
    if f is None:
        raise ValueError(f"{name}: frame {k} (line {fr.line}) cannot be read")
    return _bodies(f, name, k, fr.lattice, planar)


def _copy(src: Any, dst: Any, n: int) -> None:
    """Copy ``n`` bytes from one open file to another, in blocks."""
    while n > 0:
        block = src.read(min(n, 1 << 22))
        if not block:
            return
        dst.write(block)
        n -= len(block)


def _parser_said(e: BaseException, fr: _Frame) -> str:
    """The C parser's message, its "atom line i" as the file's line."""
    text = one_line(e, 10_000).removeprefix("ERROR:").strip()
    m = re.search(r"\s*on atom line (\d+)", text)
    if m:
        return f"line {fr.line + 2 + int(m.group(1))}: {clip(text[: m.start()] + text[m.end() :])}"
    return f"not a readable extended XYZ frame (line {fr.line}): {clip(text)}"


def _frames(path: str, name: str) -> list[_Frame]:
    """Every frame of the file, each checked before any parser sees it.

    A frame is an atom count (a non-negative integer, at most a C int), a comment line (at most
    :data:`COMMENT_CHARS` characters; its ``Properties`` name:type:count triplets with types R,
    I, S, L and positive counts), then that many lines, which must be in the file and must be
    able to hold the columns the Properties name (a small file claiming 10^8 atoms or 10^8
    columns is refused here, never allocated); no line may be so long that holding every atom's
    strings at its width would take far more memory than the frame's bytes. Blank lines may end
    the file.

    Raises:
        ValueError: the first thing wrong, naming the line and the frame.
    """
    try:
        with open(path, "rb") as file:
            size = os.fstat(file.fileno()).st_size
            if size == 0:
                return []
            with mmap.mmap(file.fileno(), 0, access=mmap.ACCESS_READ) as m:
                return _scan(m, size, name)
    except OSError as e:
        raise ValueError(f"cannot read {name}: {e.strerror}") from None


def _scan(m: mmap.mmap, size: int, name: str) -> list[_Frame]:
    frames: list[_Frame] = []
    pos, line = 0, 1
    visible = re.compile(rb"\S")
    while pos < size:
        k = len(frames)
        start = pos
        first, pos = _line(m, pos, size, _COUNT_CHARS, f"{name}: line {line}: the atom count of frame {k} is not a short line")
        if not first.strip():
            if visible.search(m, pos) is None:  # blank lines end the file
                break
            raise ValueError(f"{name}: line {line}: a blank line where frame {k} should start with its atom count")
        token = first.split()[0]
        if not token.lstrip(b"+-").isdigit() or len(token) - len(token.lstrip(b"+-")) > 1:
            raise ValueError(f"{name}: line {line}: the atom count of frame {k} is {clip(token.decode('utf-8', 'replace'), 60)!r}, not a number")
        natoms = int(token)
        if natoms < 0:
            raise ValueError(f"{name}: line {line}: frame {k} announces {natoms} atoms")
        if pos >= size:
            raise ValueError(f"{name}: frame {k} is truncated: {natoms} atoms announced (line {line}), no comment line follows")
        comment, pos = _line(m, pos, size, COMMENT_CHARS, f"{name}: line {line + 1}: the comment line of frame {k} is longer than {COMMENT_CHARS:,} characters")
        if b"\0" in comment:
            raise ValueError(f"{name}: line {line + 1} holds NUL bytes: not an extended XYZ file")
        columns = _columns(comment.decode("utf-8", "replace"), f"{name}: line {line + 1}: frame {k}")
        got, pos, longest, at = _skip_lines(m, pos, natoms, size)
        if got < natoms:
            raise ValueError(f"{name}: frame {k} is truncated: {natoms} atoms announced (line {line}), {got} lines follow")
        if natoms > _MOST_ATOMS:
            raise ValueError(f"{name}: frame {k}: {natoms} atoms announced (line {line}), more than the parser counts ({_MOST_ATOMS:,})")
        data = pos - (start + len(first) + len(comment) + 2)
        if natoms * columns > data:  # each value takes a character and a separator: half of this in a real file
            raise ValueError(f"{name}: line {line + 1}: frame {k}'s Properties name {columns:,} columns per atom, more than its {natoms:,} lines hold")
        if natoms * longest > 8 * data + (1 << 20):
            raise ValueError(
                f"{name}: line {line + 2 + at}: {longest:,} characters in frame {k} of {natoms:,} atoms whose lines are far shorter "
                "(its strings would be held at that width for every atom)"
            )
        frames.append(_Frame(start, pos, line, natoms, _LATTICE.search(comment) is not None))
        line += 2 + natoms
    return frames


def _line(m: mmap.mmap, pos: int, size: int, limit: int, too_long: str) -> tuple[bytes, int]:
    """(the line at ``pos`` without its newline, the position after it); ``too_long`` past ``limit`` characters."""
    end = m.find(b"\n", pos, min(size, pos + limit + 1))
    if end < 0:
        if size - pos > limit:
            raise ValueError(too_long)
        end = size
    return m[pos:end], end + 1


def _columns(comment: str, where: str) -> int:
    """Columns per atom the comment's ``Properties`` name (the most, if it names several; 4 by default)."""
    widest = 4  # the parser's default: species:S:1:pos:R:3
    for match in _PROPERTIES.finditer(comment):
        value = next(g for g in match.groups() if g is not None)
        parts = value.split(":")
        if len(parts) % 3:
            raise ValueError(f"{where}: Properties={clip(value, 80)!r} is not name:type:count triplets")
        total = 0
        for i in range(0, len(parts), 3):
            column, kind, count = parts[i : i + 3]
            if kind not in ("R", "I", "S", "L"):
                raise ValueError(f"{where}: Properties: the column {clip(column, 40)!r} has the type {clip(kind, 20)!r}, not R, I, S or L")
            if not count.isdigit() or int(count) < 1:
                raise ValueError(f"{where}: Properties: the column {clip(column, 40)!r} has {clip(count, 20)!r} values, not a positive count")
            total += int(count)
        widest = max(widest, total)
    return widest


def _skip_lines(m: mmap.mmap, pos: int, n: int, size: int) -> tuple[int, int, int, int]:
    """(lines found, up to ``n``; the position after them; the longest one's length; its index) from ``pos``.

    Newlines are found by numpy in blocks of the mapped file (no copy; the block grows with the
    lines still wanted), so a frame of a million atoms is skipped in milliseconds.
    """
    got = longest = at = 0
    line_start = pos
    while got < n and pos < size:
        stop = min(size, pos + max(1 << 12, min(1 << 22, (n - got) * 256)))
        view = np.frombuffer(m, np.uint8, count=stop - pos, offset=pos)
        ends = np.flatnonzero(view == 10)[: n - got] + pos
        del view
        if ends.size:
            lengths = ends - np.concatenate(([line_start], ends[:-1] + 1)) + 1
            j = int(np.argmax(lengths))
            if lengths[j] > longest:
                longest, at = int(lengths[j]), got + j
            got += int(ends.size)
            line_start = int(ends[-1]) + 1
            pos = line_start if got == n else stop
        else:
            pos = stop
    if got < n and line_start < size:  # a last line without its newline
        if size - line_start > longest:
            longest, at = size - line_start, got
        got += 1
        line_start = size
    return got, line_start, longest, at


def _bodies(f: Any, name: str, k: int, lattice: bool = True, planar: bool | None = None) -> BodySet:
    a = {key.lower(): v for key, v in f.arrays.items()}
    N = int(f.natoms)
    if "pos" not in a:
        raise ValueError(f"{name}: frame {k} has no pos column (Properties=...:pos:R:3:...)")
    pos = _real(a["pos"], "pos", 3, N, name)
    if "aspherical_shape" in a:
        semi = _real(a["aspherical_shape"], "aspherical_shape", 3, N, name)
    elif "radius" in a:
        semi = np.repeat(_real(a["radius"], "radius", 1, N, name).reshape(N, 1), 3, axis=1)
    else:
        raise ValueError(
            f"{name}: frame {k} has neither an aspherical_shape column (semi-axes) nor a radius column; "
            f"columns: {', '.join(f.arrays)}"
        )
    quat = None
    if "orientation" in a:
        xyzw = _real(a["orientation"], "orientation", 4, N, name)
        quat = xyzw[:, [3, 0, 1, 2]]
    ids = None
    if "id" in a:
        ids = np.asarray(a["id"]).reshape(-1)
        if ids.dtype.kind not in "iu" or ids.size != N:
            raise ValueError(f"{name}: frame {k}: column id holds {ids.dtype} values, not one integer per atom")
    pbc = np.asarray(f.pbc, dtype=bool).reshape(-1) if lattice else np.zeros(3, dtype=bool)
    box = _box(f, name, k, pbc, pos, semi)
    out = from_parameters(pos, semi, quat, name, box=box, ids=ids, frame=k)
    if planar is None:  # a 2D system: periodic in x and y, open in z, every body at z = 0
        planar = bool(lattice and pbc[0] and pbc[1] and not pbc[2] and not pos[:, 2].any())
    return out.in_plane() if planar else out


def _real(values: Any, column: str, width: int, N: int, name: str) -> np.ndarray:
    v = np.asarray(values)
    if v.dtype.kind not in "fiu":
        raise ValueError(f"{name}: column {column} holds {v.dtype}, not numbers")
    if v.size != N * width:
        raise ValueError(f"{name}: column {column} has {v.size // max(N, 1)} values per atom, not {width}")
    return v.astype(np.float64).reshape(N, width)


def _box(f: Any, name: str, k: int, pbc: np.ndarray, pos: np.ndarray, semi: np.ndarray) -> tuple[float, ...] | None:
    """The frame's box: None without a Lattice or with no periodic axis; open axes padded (:func:`cell_box`)."""
    if not pbc.any():
        return None
    cell = np.asarray(f.cell, dtype=np.float64)  # columns are the box vectors a1, a2, a3
    a1, a2, a3 = cell[:, 0], cell[:, 1], cell[:, 2]
    if a1[1] != 0 or a1[2] != 0 or a2[2] != 0:
        raise ValueError(
            f"{name}: frame {k}: the periodic cell is not in HOOMD's orientation (a1 along x, a2 in the xy plane): "
            f"Lattice vectors {a1.tolist()}, {a2.tolist()}, {a3.tolist()}"
        )
    Lx, Ly, Lz = a1[0], a2[1], a3[2]
    sides = [Lx, Ly, Lz]
    if not all(sides[a] > 0 for a in range(3) if pbc[a]):
        raise ValueError(f"{name}: frame {k}: the cell has no volume along a periodic axis: Lattice diagonal {Lx}, {Ly}, {Lz}")
    sides = [v if v > 0 else 1.0 for v in sides]  # an open axis' side is replaced (cell_box)
    return cell_box(sides, (a2[0] / sides[1], a3[0] / sides[2], a3[1] / sides[2]), pbc, pos, semi, name=f"{name}: frame {k}")
