"""What every reader of bodies returns: :class:`BodySet` (parameters, matrices, box).

Every file format (:mod:`app.readers`) gives the same arrays: centres (N, d), semi-axes (N, d),
orientations ((N, 4) quaternions wxyz in 3D, (N,) angles in radians in 2D, or None) and the
periodic box of the file, if it has one, in HOOMD's convention: ``(Lx, Ly[, Lz])`` for a box
whose sides are orthogonal, ``(Lx, Ly, Lz, xy, xz, yz)`` for a tilted (triclinic) one (tilt
*factors*: the box vectors are a1 = (Lx, 0, 0), a2 = (xy Ly, Ly, 0), a3 = (xz Lz, yz Lz, Lz)).
The matrices are built from the parameters exactly as :func:`core.quadric_from_axes` builds one
shape (:func:`core.bodies_from_axes`); a row whose parameters are no shape is kept as a NaN
matrix with the reason in :attr:`BodySet.errors`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from core import bodies_from_axes
from core.shapes.quadrics import axes_row_errors

from .guard import one_line

__all__ = ["BodySet", "from_parameters", "file_box"]


@dataclass
class BodySet:
    """Bodies read from a file: their matrices and, when the file had them, their parameters."""

    Q: np.ndarray
    """(N, d+1, d+1) float64 matrices (NaN rows: bodies whose parameters are no shape)."""
    centers: np.ndarray | None = None
    semi_axes: np.ndarray | None = None
    orientations: np.ndarray | None = None
    """(N, 4) quaternions wxyz (3D) or (N,) angles (2D); None with matrices only or no column."""
    errors: dict[int, str] = field(default_factory=dict)
    """Body -> why its parameters are no shape (those rows of Q are NaN)."""
    source: str = ""
    """File name, for messages."""
    box: tuple[float, ...] | None = None
    """The file's periodic box (module docstring), or None (open space, or no box in the file)."""
    first_line: int | None = None
    """Text tables: the line of the file that holds body 0 (messages say "line ...")."""
    ids: np.ndarray | None = None
    """Particle ids of the file (LAMMPS ``id``), if it has them (messages name them)."""
    frame: int | None = None
    """The frame read (trajectory files), counted from 0."""

    @property
    def dim(self) -> int:
        """2 or 3."""
        return int(self.Q.shape[-1] - 1)

    def __len__(self) -> int:
        return int(self.Q.shape[0])

    def where(self, k: int) -> str:
        """Where body k is in the file: "body 7 (line 9)", "body 7 (id 12)" or "body 7"."""
        if self.first_line is not None:
            return f"body {k} (line {k + self.first_line})"
        if self.ids is not None:
            return f"body {k} (id {int(self.ids[k])})"
        return f"body {k}"


def from_parameters(centers: Any, semi_axes: Any, orientations: Any, name: str, **extra: Any) -> BodySet:
    """A :class:`BodySet` from parameters (bad rows kept as errors; bad array shapes raise).

    Raises:
        ValueError: arrays of the wrong shapes, or values that are not numbers.
    """
    try:
        c = np.asarray(centers, dtype=np.float64)
        r = np.asarray(semi_axes, dtype=np.float64)
        o = None if orientations is None else np.asarray(orientations, dtype=np.float64)
        errors = axes_row_errors(c, r, o)
        Q = bodies_from_axes(c, r, o, on_invalid="mark")
    except (ValueError, TypeError) as e:
        raise ValueError(f"{name}: {one_line(e, 300)}") from None
    return BodySet(Q, c, r, o, errors, name, **extra)


def file_box(sides: Any, tilts: Any = (0.0, 0.0, 0.0), *, dim: int) -> tuple[float, ...]:
    """A file's periodic box in the convention of the module docstring.

    Args:
        sides: (Lx, Ly, Lz) (2D: Lz is ignored).
        tilts: HOOMD tilt factors (xy, xz, yz).
        dim: 2 or 3.

    Returns:
        ``(Lx, Ly[, Lz])`` when every tilt is 0, else ``(Lx, Ly, Lz, xy, xz, yz)`` unchanged.

    Examples:
        >>> file_box([10, 10, 10], dim=3)
        (10.0, 10.0, 10.0)
        >>> file_box([10, 8, 0], [0.5, 0, 0], dim=2)
        (10.0, 8.0, 0.0, 0.5, 0.0, 0.0)
    """
    L = [float(v) for v in np.asarray(sides, dtype=np.float64).reshape(-1)[:3]]
    t = [float(v) for v in np.asarray(tilts, dtype=np.float64).reshape(-1)[:3]]
    if not any(t):
        return tuple(L[:dim])
    return (*L, *t)


def usable_box(box: tuple[float, ...] | None, dim: int, source: str = "") -> tuple[float, ...] | None:
    """The box to hand to :func:`core.contacts`: the six numbers of a tilted box flow through.

    :func:`core.contacts` takes ``box=(Lx, Ly, Lz, xy, xz, yz)`` (the library's box reader is
    asked), so a tilted box is passed on unchanged, never silently made orthogonal (which
    would change which bodies touch). Should the reader ever refuse tilted boxes, such a box
    is refused here with a message.

    Raises:
        ValueError: a tilted box the library's box reader does not take.
    """
    if box is None or len(box) != 6 or _tilted_boxes(dim):
        return box
    where = f"{source}: " if source else ""
    raise ValueError(
        f"{where}the periodic box is tilted (triclinic): [Lx, Ly, Lz, xy, xz, yz] = "
        f"[{', '.join(f'{v:g}' for v in box)}]; tilted boxes are not supported yet "
        "(orthogonal boxes are: give --box Lx,Ly,Lz to use one instead)"
    )


def _tilted_boxes(dim: int) -> bool:
    """Whether :func:`core.contacts` takes a tilted box (asks its box reader)."""
    from core.bodies.periodic import read_box

    try:
        read_box((1.0, 1.0, 1.0 if dim == 3 else 0.0, 0.25, 0.0, 0.0), dim)
    except (ValueError, TypeError):
        return False
    return True
