"""Files of many bodies and of their contacts: bodies in (:mod:`app.readers`), pairs out.

Bodies are read by :func:`read_bodies` in any format of :mod:`app.readers` (CSV, Parquet, NPZ,
HOOMD GSD, LAMMPS dump, extended XYZ); this module re-exports it for the scene and the command
line, and writes bodies (CSV) and pairs.

Pairs out (``python -m app contacts --out PAIRS``), one row per pair that is not separate:

* CSV: ``i,j,relation,certified_by,image_x,image_y,image_z`` (relation ``tangent|overlap``;
  certified_by ``float|exact``: which arithmetic certified the relation; image: the periodic
  image k of body j, c_j + k L, all 0 in open space and image_z 0 in 2D), and with ``--with
  scale`` also ``scale_lo,scale_hi,contained`` (:mod:`core.bodies.details`).
* NPZ (``--out PAIRS.npz``): the same columns as arrays of the same names (relation and
  certified_by as int8 codes, image as one (M, 3) int8 array), plus ``relation_names``.
"""

from __future__ import annotations

from pathlib import Path
from typing import IO, Any

import numpy as np

from core import Certifier, Relation

from .readers import COLUMNS, BodySet, read_bodies, read_bodies_bytes

__all__ = [
    "BodySet", "COLUMNS", "PAIR_COLUMNS", "read_bodies", "read_bodies_bytes", "write_bodies_csv", "write_pairs_csv",
    "write_pairs_npz", "read_pairs_csv",
]

PAIR_COLUMNS = ("i", "j", "relation", "certified_by", "image_x", "image_y", "image_z")
"""Columns of a pairs CSV (``--with scale`` adds ``scale_lo, scale_hi, contained``)."""

_BY_NAME = {int(Certifier.FLOAT): "float", int(Certifier.EXACT): "exact"}


def write_bodies_csv(path: str | Path, centers: Any, semi_axes: Any, orientations: Any) -> None:
    """Write bodies as CSV (3D: x,y,z,a,b,c,qw,qx,qy,qz; 2D: x,y,a,b,angle), floats round-trip exactly."""
    c = np.asarray(centers, dtype=np.float64)
    dim = c.shape[1]
    o = np.asarray(orientations, dtype=np.float64).reshape(len(c), -1)
    rows = np.concatenate([c, np.asarray(semi_axes, dtype=np.float64), o], axis=1)
    with open(path, "w", newline="") as f:
        f.write(",".join(COLUMNS[dim]) + "\n")
        f.write("".join(",".join(repr(v) for v in row) + "\n" for row in rows.tolist()))


def _images(image: np.ndarray | None, m: int) -> np.ndarray:
    """(M, 3) int8 images (zeros in open space, z = 0 in 2D)."""
    out = np.zeros((m, 3), dtype=np.int8)
    if image is not None:
        out[:, : image.shape[1]] = image
    return out


def write_pairs_csv(
    out: str | Path | IO[str],
    i: np.ndarray,
    j: np.ndarray,
    relation: np.ndarray,
    certified_by: np.ndarray | None = None,
    image: np.ndarray | None = None,
    details: dict[str, np.ndarray] | None = None,
) -> None:
    """Write the pairs as CSV (module docstring): to a path or an open text file.

    Args:
        out: a path, or a text file open for writing (e.g. an :class:`app.output.Output`).
        i: first bodies.
        j: second bodies.
        relation: int8 Relation codes.
        certified_by: int8 Certifier codes (None: the column is left out, as in old files).
        image: (M, d) periodic images of j, or None (open space: zeros).
        details: ``--with scale`` columns (``scale_lo``, ``scale_hi`` floats, ``contained``
            strings), or None.
    """
    if not hasattr(out, "write"):
        with open(out, "w", newline="") as opened:  # type: ignore[arg-type]
            return write_pairs_csv(opened, i, j, relation, certified_by, image, details)
    f: Any = out
    names = np.array([str(Relation(k)) for k in range(-2, 3)], dtype=object)  # codes -2 .. 2
    rel = names[relation.astype(np.int64) + 2]
    cols: list[tuple[str, Any]] = [("i", i.tolist()), ("j", j.tolist()), ("relation", rel.tolist())]
    if certified_by is not None:
        cols.append(("certified_by", [_BY_NAME.get(int(c), "none") for c in certified_by.tolist()]))
        im = _images(image, len(i))
        cols += [("image_x", im[:, 0].tolist()), ("image_y", im[:, 1].tolist()), ("image_z", im[:, 2].tolist())]
    if details:
        cols += [("scale_lo", [repr(v) for v in details["scale_lo"].tolist()]),
                 ("scale_hi", [repr(v) for v in details["scale_hi"].tolist()]),
                 ("contained", list(details["contained"]))]
    f.write(",".join(name for name, _ in cols) + "\n")
    step = 1 << 16
    values = [v for _, v in cols]
    for s in range(0, len(i), step):
        f.write("".join(",".join(map(str, row)) + "\n" for row in zip(*(v[s : s + step] for v in values), strict=True)))


def write_pairs_npz(
    out: IO[bytes] | str | Path,
    i: np.ndarray,
    j: np.ndarray,
    relation: np.ndarray,
    certified_by: np.ndarray,
    image: np.ndarray | None = None,
    details: dict[str, np.ndarray] | None = None,
) -> None:
    """Write the pairs as NPZ arrays (module docstring) to a path or an open binary file."""
    arrays: dict[str, Any] = {
        "i": np.asarray(i, np.int64), "j": np.asarray(j, np.int64), "relation": np.asarray(relation, np.int8),
        "certified_by": np.asarray(certified_by, np.int8), "image": _images(image, len(i)),
        "relation_names": np.array([str(Relation(k)) for k in range(-2, 3)]),
    }
    if details:
        arrays.update(details)
        arrays["contained"] = np.asarray(details["contained"]).astype(str)
    np.savez(out, **arrays)


def read_pairs_csv(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read the ``i, j, relation`` of a file written by :func:`write_pairs_csv`: (i, j, int8 codes)."""
    lines = Path(path).read_text().splitlines()
    header = lines[0].strip().split(",") if lines else []
    if header[:3] != ["i", "j", "relation"]:
        raise ValueError(f"{path}: expected a header starting with i,j,relation")
    rows = [ln.split(",") for ln in lines[1:] if ln.strip()]
    i = np.array([int(r[0]) for r in rows], dtype=np.int64)
    j = np.array([int(r[1]) for r in rows], dtype=np.int64)
    rel = np.array([int(Relation.parse(r[2])) for r in rows], dtype=np.int8)
    return i, j, rel
