"""Files of many bodies and of their contacts: bodies in (:mod:`app.readers`), pairs out.

Bodies are read by :func:`read_bodies` in any format of :mod:`app.readers` (CSV, Parquet, NPZ,
HOOMD GSD, LAMMPS dump, extended XYZ); this module re-exports it for the scene and the command
line, and writes bodies (CSV) and pairs.

Pairs out (``python -m app contacts --out PAIRS``), one row per pair that is not separate:

* CSV: ``i,j,relation,certified_by,image_x,image_y,image_z`` (relation ``tangent|overlap``;
  certified_by ``float|exact``: which arithmetic certified the relation; image: the periodic
  image k of body j, c_j + k L, all 0 in open space and image_z 0 in 2D), and with ``--with
  scale`` also ``scale_lo,scale_hi,contained`` (:mod:`core.bodies.details`), then ``id_i,id_j``
  when the file gave the bodies ids (a LAMMPS, CSV or XYZ ``id`` column). One writer:
  :meth:`core.PairTable.to_csv`.
* NPZ (``--out PAIRS.npz``): the same columns as arrays of the same names (relation and
  certified_by as int8 codes, image as one (M, 3) int8 array), plus ``relation_names``.
"""

from __future__ import annotations

from pathlib import Path
from typing import IO, Any

import numpy as np

from core import PairTable, Relation

from .readers import COLUMNS, BodySet, read_bodies, read_bodies_bytes

__all__ = [
    "BodySet", "COLUMNS", "PAIR_COLUMNS", "read_bodies", "read_bodies_bytes", "write_bodies_csv", "write_pairs_csv",
    "write_pairs_npz", "read_pairs_csv",
]

PAIR_COLUMNS = ("i", "j", "relation", "certified_by", "image_x", "image_y", "image_z")
"""Columns of a pairs CSV (``--with scale`` adds ``scale_lo, scale_hi, contained``)."""

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


def write_pairs_csv(out: IO[str], pairs: PairTable, details: dict[str, np.ndarray] | None = None) -> None:
    """Write the pairs as CSV (module docstring) to an open text file (e.g. an :class:`app.output.Output`).

    Args:
        out: a text file open for writing.
        pairs: :class:`core.Contacts` (or any :class:`core.PairTable`): its columns in their order,
            ``id_i, id_j`` last when the bodies had ids.
        details: ``--with scale`` columns (``scale_lo``, ``scale_hi`` floats, ``contained``
            strings), written before the ids, or None.
    """
    extra = None
    if details:
        extra = {"scale_lo": details["scale_lo"].tolist(), "scale_hi": details["scale_hi"].tolist(),
                 "contained": list(details["contained"])}
    pairs.to_csv(out, extra=extra)


def write_pairs_npz(out: IO[bytes] | str | Path, pairs: PairTable, details: dict[str, np.ndarray] | None = None) -> None:
    """Write the pairs as NPZ arrays (module docstring) to a path or an open binary file."""
    arrays: dict[str, Any] = {
        "i": np.asarray(pairs.i, np.int64), "j": np.asarray(pairs.j, np.int64), "relation": np.asarray(pairs.relation, np.int8),
        "certified_by": np.asarray(pairs.certified_by, np.int8), "image": _images(pairs.image, len(pairs)),
        "relation_names": np.array([str(Relation(k)) for k in range(-2, 3)]),
    }
    if details:
        arrays.update(details)
        arrays["contained"] = np.asarray(details["contained"]).astype(str)
    ids = pairs.pair_ids()
    if ids is not None:
        arrays["id_i"], arrays["id_j"] = ids
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
