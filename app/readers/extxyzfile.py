"""Extended XYZ files as OVITO writes them, read with ``extxyz`` (libAtoms' reference parser).

A frame (default: the last) whose comment line names the columns, e.g.::

    2
    Lattice="10 0 0 0 10 0 0 0 10" Properties=species:S:1:pos:R:3:orientation:R:4:aspherical_shape:R:3
    A 1 2 3 0 0 0 1 1 0.5 0.25
    ...

Columns by the names OVITO's XYZ exporter gives its particle properties: ``pos`` (Position),
``aspherical_shape`` (Aspherical Shape: the three **semi-axes**), ``orientation``
(Orientation, OVITO's order **x y z w**: reordered to wxyz here; identity when absent),
``radius`` (spheres, when there is no ``aspherical_shape``). Other columns (``species``,
``id``, ...) are ignored. The cell: ``Lattice`` (three box vectors) with ``pbc`` (OVITO writes
none: periodic, as the format's default). A periodic cell must be in HOOMD's orientation
(a1 along x, a2 in the xy plane) to become a box (:mod:`app.readers.bodyset`); an ``Origin`` is
irrelevant (only differences of positions matter).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .bodyset import BodySet, file_box, from_parameters
from .gsdfile import _frame_index

__all__ = ["read_extxyz"]


def read_extxyz(path: str, name: str, *, frame: int | None = None) -> BodySet:
    """Bodies of one frame of an extended XYZ file (module docstring).

    Raises:
        ValueError: extxyz missing, a malformed file, no such frame, missing columns, a cell
            that is periodic on some axes only or not in HOOMD's orientation.
    """
    try:
        import extxyz
    except ImportError:
        raise ValueError(f"{name}: reading extended XYZ needs extxyz: pip install 'ellipsoid-interference[formats]'") from None
    f = None
    n = 0
    try:
        if frame is not None and frame >= 0:
            f = next(iter(extxyz.iread_dicts(path, index=frame)), None)
            n = frame + 1 if f is not None else sum(1 for _ in extxyz.iread_dicts(path))
        else:  # from the end: every frame is read once, the wanted one kept
            frames = list(extxyz.iread_dicts(path))
            n = len(frames)
            f = frames[_frame_index(frame, n, name)] if n else None
    except ValueError:
        raise
    except Exception as e:  # noqa: BLE001 - the parser raises its own error kinds
        raise ValueError(f"{name}: not a readable extended XYZ file ({e})") from None
    k = _frame_index(frame, n, name)
    assert f is not None
    return _bodies(f, name, k)


def _bodies(f: Any, name: str, k: int) -> BodySet:
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
    return from_parameters(pos, semi, quat, name, box=_box(f, name, k), frame=k)


def _real(values: Any, column: str, width: int, N: int, name: str) -> np.ndarray:
    v = np.asarray(values)
    if v.dtype.kind not in "fiu":
        raise ValueError(f"{name}: column {column} holds {v.dtype}, not numbers")
    return v.astype(np.float64).reshape(N, width)


def _box(f: Any, name: str, k: int) -> tuple[float, ...] | None:
    pbc = np.asarray(f.pbc, dtype=bool).reshape(-1)
    if not pbc.any():
        return None
    if not pbc.all():
        raise ValueError(f"{name}: frame {k}: pbc {pbc.tolist()} mixes periodic and open axes: not supported")
    cell = np.asarray(f.cell, dtype=np.float64)  # columns are the box vectors a1, a2, a3
    a1, a2, a3 = cell[:, 0], cell[:, 1], cell[:, 2]
    if a1[1] != 0 or a1[2] != 0 or a2[2] != 0:
        raise ValueError(
            f"{name}: frame {k}: the periodic cell is not in HOOMD's orientation (a1 along x, a2 in the xy plane): "
            f"Lattice vectors {a1.tolist()}, {a2.tolist()}, {a3.tolist()}"
        )
    Lx, Ly, Lz = a1[0], a2[1], a3[2]
    if not (Lx > 0 and Ly > 0 and Lz > 0):
        raise ValueError(f"{name}: frame {k}: the cell has no volume: Lattice diagonal {Lx}, {Ly}, {Lz}")
    return file_box((Lx, Ly, Lz), (a2[0] / Ly, a3[0] / Lz, a3[1] / Lz), dim=3)
