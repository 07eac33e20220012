"""Files of many bodies and of their contacts: CSV and NPZ in, CSV out.

Bodies (``python -m app contacts BODIES``, ``serve --bodies``, the scene's upload):

* CSV with a header row: 3D columns ``x,y,z,a,b,c,qw,qx,qy,qz`` (centre, semi-axes, unit or
  non-unit quaternion wxyz), 2D columns ``x,y,a,b,angle`` (radians); any column order, nothing
  else. Body k is data row k (line k + 2 of the file).
* NPZ with arrays ``centers`` (N, d), ``semi_axes`` (N, d), ``orientations`` ((N, 4) or (N,)),
  or ``Q`` (N, d + 1, d + 1) matrices.

Numbers are read as float64 (the matrices are then built exactly as
:func:`core.quadric_from_axes` builds one shape: :func:`core.bodies_from_axes`). Pairs out:
CSV ``i,j,relation`` with relation in ``separate|tangent|overlap``.
"""

from __future__ import annotations

import io
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from core import Relation, bodies_from_axes
from core.shapes.quadrics import axes_row_errors

__all__ = ["BodySet", "COLUMNS", "read_bodies", "read_bodies_bytes", "write_bodies_csv", "write_pairs_csv", "read_pairs_csv"]

COLUMNS = {3: ("x", "y", "z", "a", "b", "c", "qw", "qx", "qy", "qz"), 2: ("x", "y", "a", "b", "angle")}
"""CSV columns of a body, by dimension."""


@dataclass
class BodySet:
    """Bodies read from a file: their matrices and, when the file had them, their parameters."""

    Q: np.ndarray
    """(N, d+1, d+1) float64 matrices (NaN rows: bodies whose parameters are no shape)."""
    centers: np.ndarray | None = None
    semi_axes: np.ndarray | None = None
    orientations: np.ndarray | None = None
    """(N, 4) quaternions (3D) or (N,) angles (2D); None with matrices only."""
    errors: dict[int, str] = field(default_factory=dict)
    """Body -> why its parameters are no shape (those rows of Q are NaN)."""
    source: str = ""
    """File name, for messages."""

    @property
    def dim(self) -> int:
        """2 or 3."""
        return int(self.Q.shape[-1] - 1)

    def __len__(self) -> int:
        return int(self.Q.shape[0])

    def where(self, k: int) -> str:
        """Where body k is in the file ("body 7 (line 9)" for CSV)."""
        return f"body {k} (line {k + 2})" if self.source.lower().endswith(".csv") else f"body {k}"


def read_bodies(path: str | Path) -> BodySet:
    """Read a CSV or NPZ file of bodies (module docstring); bad parameters are kept as errors.

    Raises:
        ValueError: unreadable file, unknown or missing columns/arrays, a value that is not a
            number (the message names the line), inconsistent shapes.
    """
    p = Path(path)
    try:
        data = p.read_bytes()
    except OSError as e:
        raise ValueError(f"cannot read {path}: {e.strerror}") from None
    return read_bodies_bytes(data, p.name)


def read_bodies_bytes(data: bytes, name: str) -> BodySet:
    """:func:`read_bodies` from the bytes of a file called ``name`` (.csv or .npz)."""
    if name.lower().endswith(".npz") or data[:2] == b"PK":
        return _read_npz(data, name)
    return _read_csv(data, name)


def _read_csv(data: bytes, name: str) -> BodySet:
    text = data.decode("utf-8-sig", errors="replace")
    first, _, rest = text.partition("\n")
    header = [h.strip().lower() for h in first.strip().split(",")]
    dim = next((d for d, cols in COLUMNS.items() if sorted(header) == sorted(cols)), None)
    if dim is None:
        raise ValueError(
            f"{name}: the header must name the columns {','.join(COLUMNS[3])} (ellipsoids) or "
            f"{','.join(COLUMNS[2])} (ellipses), in any order; got {first.strip()[:200]!r}"
        )
    try:
        table = np.loadtxt(io.StringIO(rest), delimiter=",", dtype=np.float64, ndmin=2)
    except ValueError as e:
        raise ValueError(f"{name}: {_line_of(str(e))}") from None
    if table.size == 0:
        table = np.zeros((0, len(header)))
    if table.shape[1] != len(header):
        raise ValueError(f"{name}: {table.shape[1]} values per row but {len(header)} columns in the header")
    col = {h: table[:, k] for k, h in enumerate(header)}
    names = COLUMNS[dim]
    centers = np.stack([col[c] for c in names[:dim]], axis=1)
    axes = np.stack([col[c] for c in names[dim : 2 * dim]], axis=1)
    orient = np.stack([col[c] for c in names[2 * dim :]], axis=1) if dim == 3 else col["angle"]
    return _from_parameters(centers, axes, orient, name)


def _line_of(message: str) -> str:
    """The line of the file in numpy's "... at row 12, column 3" (the header is line 1)."""
    import re

    m = re.search(r"at row (\d+), column (\d+)", message)
    if not m:
        return message
    row = int(m.group(1))
    return f"line {row + 2}, column {m.group(2)}: {message.split(' at row')[0]}"


def _read_npz(data: bytes, name: str) -> BodySet:
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except (ValueError, OSError, zipfile.BadZipFile) as e:
        raise ValueError(f"{name}: not a readable .npz file ({e})") from None
    if "Q" in arrays:
        Q = np.asarray(arrays["Q"])
        if Q.ndim != 3 or Q.shape[1] != Q.shape[2] or Q.shape[1] not in (3, 4):
            raise ValueError(f"{name}: Q must be (N, 3, 3) or (N, 4, 4), got shape {Q.shape}")
        if Q.dtype.kind not in "fiu":
            raise ValueError(f"{name}: Q must hold numbers, got dtype {Q.dtype}")
        return BodySet(Q.astype(np.float64), source=name)
    missing = {"centers", "semi_axes"} - set(arrays)
    if missing:
        raise ValueError(f"{name}: expected arrays centers, semi_axes, orientations (or Q); missing {sorted(missing)}")
    return _from_parameters(arrays["centers"], arrays["semi_axes"], arrays.get("orientations"), name)


def _from_parameters(centers: Any, axes: Any, orient: Any, name: str) -> BodySet:
    try:
        c = np.asarray(centers, dtype=np.float64)
        r = np.asarray(axes, dtype=np.float64)
        o = None if orient is None else np.asarray(orient, dtype=np.float64)
        errors = axes_row_errors(c, r, o)
        Q = bodies_from_axes(c, r, o, on_invalid="mark")
    except (ValueError, TypeError) as e:
        raise ValueError(f"{name}: {e}") from None
    return BodySet(Q, c, r, o, errors, name)


def write_bodies_csv(path: str | Path, centers: Any, semi_axes: Any, orientations: Any) -> None:
    """Write bodies as CSV (3D: x,y,z,a,b,c,qw,qx,qy,qz; 2D: x,y,a,b,angle), floats round-trip exactly."""
    c = np.asarray(centers, dtype=np.float64)
    dim = c.shape[1]
    o = np.asarray(orientations, dtype=np.float64).reshape(len(c), -1)
    rows = np.concatenate([c, np.asarray(semi_axes, dtype=np.float64), o], axis=1)
    with open(path, "w", newline="") as f:
        f.write(",".join(COLUMNS[dim]) + "\n")
        f.write("".join(",".join(repr(v) for v in row) + "\n" for row in rows.tolist()))


def write_pairs_csv(path: str | Path, i: np.ndarray, j: np.ndarray, relation: np.ndarray) -> None:
    """Write ``i,j,relation`` rows (relation as ``separate|tangent|overlap``; header first)."""
    names = np.array([str(Relation(k)) for k in range(-2, 3)], dtype=object)  # codes -2 .. 2
    text = names[relation.astype(np.int64) + 2]
    with open(path, "w", newline="") as f:
        f.write("i,j,relation\n")
        step = 1 << 18
        for s in range(0, len(i), step):
            f.write("".join(f"{a},{b},{t}\n" for a, b, t in zip(i[s : s + step].tolist(), j[s : s + step].tolist(), text[s : s + step], strict=True)))


def read_pairs_csv(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read a file written by :func:`write_pairs_csv`: (i, j, int8 Relation codes)."""
    lines = Path(path).read_text().splitlines()
    if not lines or lines[0].strip() != "i,j,relation":
        raise ValueError(f"{path}: expected the header i,j,relation")
    rows = [ln.split(",") for ln in lines[1:] if ln.strip()]
    i = np.array([int(r[0]) for r in rows], dtype=np.int64)
    j = np.array([int(r[1]) for r in rows], dtype=np.int64)
    rel = np.array([int(Relation.parse(r[2])) for r in rows], dtype=np.int8)
    return i, j, rel
