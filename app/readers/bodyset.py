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

from dataclasses import dataclass
from typing import Any

import numpy as np

from core import Bodies

__all__ = ["BodySet", "from_parameters", "file_box", "cell_box"]


@dataclass
class BodySet(Bodies):
    """Bodies read from a file (:class:`core.Bodies`: parameters or matrices, ids, box) and where they came from.

    ``box`` is a :class:`core.Box` (or None: open space, or no box in the file); ``ids`` the
    file's own particle ids (a LAMMPS ``id`` column, a CSV or XYZ ``id`` column), if it has them.
    """

    source: str = ""
    """File name, for messages."""
    first_line: int | None = None
    """Text tables: the line of the file that holds body 0 (messages say "line ...")."""
    frame: int | None = None
    """The frame read (trajectory files), counted from 0."""

    @classmethod
    def of_matrices(cls, Q: Any, *, source: str = "", box: Any = None, ids: Any = None) -> BodySet:
        """Bodies given by their matrices only (an NPZ of matrices)."""
        out = cls.from_matrices(Q, ids=ids, box=box)
        assert isinstance(out, BodySet)
        out.source, out.first_line, out.frame = source, None, None
        return out

    @property
    def Q(self) -> np.ndarray:
        """(N, d+1, d+1) float64 matrices (NaN rows: bodies whose parameters are no shape)."""
        return self.matrices

    @property
    def dim(self) -> int:
        """2 or 3."""
        return self.dimensions

    def in_plane(self) -> BodySet:
        """These 3D bodies as 2D ones (ellipses in the plane z = 0): a 2D system stored as 3D.

        LAMMPS (``dimension 2``) and extended XYZ store 2D systems with z = 0 and orientations
        about z; the ellipses are the bodies' sections by that plane: semi-axes a, b; the box
        Lx, Ly, xy.

        Raises:
            ValueError: a body off the plane, turned out of it, or a box tilted along z.
        """
        if self.dimensions == 2:
            return self
        if not self.has_parameters:
            raise ValueError(f"{self.source}: 2D bodies need centres and semi-axes (this file has matrices)")
        c = np.asarray(self.centers)
        off = np.flatnonzero(c[:, 2] != 0)
        if off.size:
            k = int(off[0])
            raise ValueError(f"{self.source}: {self.where(k)} has z = {c[k, 2]:g}: 2D bodies lie in the plane z = 0")
        q = None if self.orientations is None else np.asarray(self.orientations, dtype=np.float64)
        if q is not None:
            turned = np.flatnonzero((q[:, 1] != 0) | (q[:, 2] != 0))
            if turned.size:
                k = int(turned[0])
                raise ValueError(f"{self.source}: {self.where(k)} is turned out of the plane (quaternion {q[k].tolist()}): "
                                 "2D bodies turn about z, (w, 0, 0, z)")
        box = None
        if self.box is not None:
            if self.box.xz or self.box.yz:
                raise ValueError(f"{self.source}: the box is tilted along z (xz, yz = {self.box.xz:g}, {self.box.yz:g}): not a 2D box")
            box = (self.box.Lx, self.box.Ly, self.box.xy)
        return BodySet(c[:, :2].copy(), np.asarray(self.semi_axes)[:, :2].copy(), q, self.ids, box,
                       source=self.source, first_line=self.first_line, frame=self.frame)

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
        out = BodySet(centers, semi_axes, orientations, source=name, **extra)
    except (ValueError, TypeError) as e:
        raise ValueError(f"{name}: {e}") from None
    return out


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


def cell_box(sides: Any, tilts: Any, periodic: Any, centers: Any, semi_axes: Any, *, name: str) -> tuple[float, ...] | None:
    """A 3D file's box when its cell may be periodic on some axes only (LAMMPS ``pp pp ff``, XYZ ``pbc``).

    Every axis periodic: the box (:func:`file_box`); none: None (open space). A mix: each open
    axis gets a side longer than the bodies' extent along it plus four times the largest
    semi-axis, so that no image across it can touch a body (the answer is that of open space
    along that axis, exactly); a tilt that couples an open axis with another is refused.

    Raises:
        ValueError: a tilt along an open axis.

    Examples:
        >>> cell_box((10, 10, 10), (0, 0, 0), (True, True, False), [[0, 0, 1], [0, 0, 4]], [[1, 1, 1]] * 2, name="f")
        (10.0, 10.0, 8.0)
    """
    per = [bool(v) for v in periodic]
    if all(per):
        return file_box(sides, tilts, dim=3)
    if not any(per):
        return None
    L = [float(v) for v in np.asarray(sides, dtype=np.float64).reshape(-1)[:3]]
    t = [float(v) for v in np.asarray(tilts, dtype=np.float64).reshape(-1)[:3]]
    for k, (a, b) in enumerate(((0, 1), (0, 2), (1, 2))):
        if t[k] and not (per[a] and per[b]):
            raise ValueError(f"{name}: the cell is tilted ({('xy', 'xz', 'yz')[k]} = {t[k]:g}) along an open axis: not supported")
    c = np.asarray(centers, dtype=np.float64).reshape(-1, 3)
    r = np.asarray(semi_axes, dtype=np.float64).reshape(-1, 3)
    reach = 4 * float(np.nanmax(r)) if r.size and np.isfinite(r).any() else 1.0
    for a in range(3):
        if not per[a]:
            extent = float(np.nanmax(c[:, a]) - np.nanmin(c[:, a])) if c.size and np.isfinite(c[:, a]).any() else 0.0
            L[a] = extent + reach + 1.0  # 4 R where 2 R would do: room for every rounding
    return file_box(L, t, dim=3)


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
