"""HOOMD-blue GSD files (read with the ``gsd`` package, ``pip install 'ellipsoid-interference[formats]'``).

One frame (default: the last) of a HOOMD trajectory: ``particles/position`` (centres),
``particles/orientation`` (quaternions wxyz), ``particles/typeid`` with the shape of each type
from ``particles/type_shapes`` (``{"type": "Ellipsoid", "a", "b", "c"}``: semi-axes, as HOOMD's
HPMC ``Ellipsoid`` integrator logs them; ``{"type": "Sphere", "diameter"}`` is a sphere of radius
diameter / 2), and ``configuration/box`` ``[Lx, Ly, Lz, xy, xz, yz]`` (HOOMD boxes are
periodic; tilted boxes included). With ``configuration/dimensions`` = 2 the bodies are ellipses
in the plane z = 0 (semi-axes a, b; the quaternion must rotate about z).

GSD stores float32 numbers; each is the float64 of the same value (widened exactly).

Before a frame is read, the counts it claims (``particles/N``, ``bonds/N``, ...; gsd.hoomd makes
arrays of that many rows, default values where a chunk is missing) are checked against the
file's size (:func:`_check_counts`), and every per-particle array read must have N rows.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from typing import Any

import numpy as np

from .bodyset import BodySet, file_box, from_parameters
from .guard import one_line

__all__ = ["read_gsd", "gsd_frames"]


def read_gsd(path: str, name: str, *, frame: int | None = None) -> BodySet:
    """Bodies of one frame of a GSD file (module docstring).

    Args:
        path: the file.
        name: its name, for messages.
        frame: frame number from 0 (negative: from the end); None: the last frame.

    Raises:
        ValueError: gsd missing, not a GSD file, no such frame, a type whose shape is not an
            ellipsoid, no shapes in the file.
    """
    traj = _open(path, name)
    with traj:
        return _frame(traj, _frame_index(frame, len(traj), name), path, name)


def gsd_frames(path: str, name: str, select: slice = slice(None)) -> tuple[range, Iterator[BodySet]]:
    """(the frames ``select`` picks, an iterator over them as :class:`BodySet`): the file opened once.

    Each frame is checked and read as :func:`read_gsd` reads one (``python -m app audit``:
    memory of one frame).
    """
    traj = _open(path, name)
    wanted = range(*select.indices(len(traj)))

    def frames() -> Iterator[BodySet]:
        with traj:
            for k in wanted:
                yield _frame(traj, k, path, name)

    return wanted, frames()


def _open(path: str, name: str) -> Any:
    """The file as a ``gsd.hoomd`` trajectory (a one-line ValueError if it is none)."""
    try:
        import gsd.hoomd
    except ImportError:
        raise ValueError(f"{name}: reading GSD files needs the gsd package: pip install 'ellipsoid-interference[formats]'") from None
    try:
        return gsd.hoomd.open(path, "r")
    except Exception as e:  # noqa: BLE001 - gsd raises RuntimeError/OSError kinds for bad files
        raise ValueError(f"{name}: not a readable GSD file ({_said(e, path)})") from None


def _frame(traj: Any, k: int, path: str, name: str) -> BodySet:
    """Frame k of an open trajectory, its counts checked against the file's size before it is read."""
    try:
        counts = _counts(traj.file, k)
    except Exception as e:  # noqa: BLE001
        raise ValueError(f"{name}: frame {k} cannot be read ({_said(e, path)})") from None
    _check_counts(counts, os.path.getsize(path), name)
    try:
        f = traj[k]
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise ValueError(f"{name}: frame {k}: particles/type_shapes holds no valid JSON ({one_line(e)})") from None
    except Exception as e:  # noqa: BLE001
        raise ValueError(f"{name}: frame {k} cannot be read ({_said(e, path)})") from None
    return _bodies(f, name, k)


_GROUPS = {"particles": ("bodies", 12), "bonds": ("bonds", 4), "angles": ("angles", 4), "dihedrals": ("dihedrals", 4),
           "impropers": ("impropers", 4), "constraints": ("constraints", 4), "pairs": ("pairs", 4)}
"""The groups gsd.hoomd reads with their counts: what they count, and the fewest bytes an item takes
in a file (a particle's position: 3 float32; any other item: one 4-byte value)."""


def _counts(file: Any, k: int) -> dict[tuple[int, str], np.ndarray]:
    """The ``GROUP/N`` chunks of frame k and frame 0 (whose chunks gsd.hoomd reads as defaults)."""
    return {
        (frame, group): np.asarray(file.read_chunk(frame=frame, name=f"{group}/N")).reshape(-1)
        for frame in sorted({0, k}) for group in _GROUPS if file.chunk_exists(frame=frame, name=f"{group}/N")
    }


def _check_counts(counts: dict[tuple[int, str], np.ndarray], size: int, name: str) -> None:
    """Refuse a count that is no count, or claims more items than the file's ``size`` bytes hold.

    Raises:
        ValueError: a count that is negative, not an integer, or beyond ``size`` / (bytes of an item).
    """
    for (frame, group), value in counts.items():
        what, least = _GROUPS[group]
        if value.size == 0:
            continue
        if value.dtype.kind not in "iu":
            raise ValueError(f"{name}: frame {frame}: {group}/N holds {value.dtype} values, not a count")
        count = int(value[0])
        if count < 0 or count * least > size:
            raise ValueError(
                f"{name}: frame {frame} claims {count} {what} ({group}/N) but the file's {size:,} bytes hold at most {size // least:,}"
            )


def _said(e: BaseException, path: str) -> str:
    """A library's error without the temporary or full path it repeats (the message names the file)."""
    return one_line(str(e).replace(f": {path}", "").replace(path, "the file"))


def _frame_index(frame: int | None, n: int, name: str) -> int:
    """The frame to read, counted from 0 (module docstring); a message for one out of range."""
    if n == 0:
        raise ValueError(f"{name}: the file has no frames")
    k = n - 1 if frame is None else frame
    if not -n <= k < n:
        raise ValueError(f"{name}: no frame {frame}: the file has {n} frame{'s' if n != 1 else ''} (0..{n - 1}; -1 is the last)")
    return k % n


def _bodies(f: Any, name: str, k: int) -> BodySet:
    p = f.particles
    N = int(p.N)
    dim = int(f.configuration.dimensions)
    types = list(p.types or [])
    shapes = list(p.type_shapes or [])
    if N and not shapes:
        raise ValueError(
            f"{name}: frame {k} has no particles/type_shapes: the shape of each type is needed "
            "(HOOMD writes it when the HPMC integrator's type_shapes are logged to the GSD file)"
        )
    semi = np.empty((len(shapes), 3))
    for t, shape in enumerate(shapes):
        semi[t] = _semi_axes(shape, types[t] if t < len(types) else str(t), name)
    for chunk, width in (("position", 3), ("orientation", 4), ("typeid", 1)):
        rows = np.asarray(getattr(p, chunk)).size // width
        if rows != N or np.asarray(getattr(p, chunk)).size % width:
            raise ValueError(f"{name}: frame {k}: particles/{chunk} holds {np.asarray(getattr(p, chunk)).size} values, not {N} x {width} (particles/N is {N})")
    typeid = np.asarray(p.typeid, dtype=np.int64)
    if typeid.size and (typeid.min() < 0 or typeid.max() >= len(shapes)):
        raise ValueError(f"{name}: frame {k}: a typeid has no entry in particles/type_shapes ({len(shapes)} shapes)")
    pos = np.asarray(p.position, dtype=np.float64).reshape(N, 3)
    q = np.asarray(p.orientation, dtype=np.float64).reshape(N, 4)
    box = np.asarray(f.configuration.box, dtype=np.float64)
    if dim == 2:
        bad = np.flatnonzero(pos[:, 2] != 0)
        if bad.size:
            raise ValueError(f"{name}: frame {k} is 2D but particle {int(bad[0])} has z = {pos[bad[0], 2]!r}")
        return from_parameters(pos[:, :2], semi[typeid][:, :2], q, name, box=file_box(box[:3], box[3:], dim=2), frame=k)
    return from_parameters(pos, semi[typeid], q, name, box=file_box(box[:3], box[3:], dim=3), frame=k)


def _semi_axes(shape: Any, type_name: str, name: str) -> tuple[float, float, float]:
    """Semi-axes of one type's shape (Ellipsoid a, b, c; Sphere diameter / 2)."""
    kind = shape.get("type") if isinstance(shape, dict) else None
    try:
        if kind == "Ellipsoid":
            return float(shape["a"]), float(shape["b"]), float(shape["c"])
        if kind == "Sphere":
            r = float(shape["diameter"]) / 2
            return r, r, r
    except (KeyError, TypeError, ValueError):
        raise ValueError(f"{name}: type {type_name!r}: incomplete {kind} shape {shape!r}") from None
    raise ValueError(f"{name}: type {type_name!r} has the shape {kind or shape!r}: only Ellipsoid and Sphere shapes are ellipsoids")
