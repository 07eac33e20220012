"""The periodic box as a value: :class:`Box` (orthogonal or tilted, 2D or 3D), as freud's ``Box``.

One owner for what a box is. HOOMD-blue's convention: sides ``Lx, Ly[, Lz]`` and tilt *factors*
``xy, xz, yz``; the box vectors are the columns a1 = (Lx, 0, 0), a2 = (xy Ly, Ly, 0),
a3 = (xz Lz, yz Lz, Lz) (2D: a1 = (Lx, 0), a2 = (xy Ly, Ly)). ``Lz=None`` is a 2D box.
:meth:`Box.from_any` reads every form the library has accepted (d sides, six numbers, a 2D
``(Lx, Ly, xy)``, a HOOMD 2D frame's six numbers, another :class:`Box`), so nothing that passed a
tuple breaks. The arithmetic (correctly rounded lattice vectors, certified fractional
coordinates, the minimum-image checks) lives in :mod:`core.bodies.periodic` and works on
:attr:`Box.array`.

Wrapping follows freud and HOOMD: a wrapped point has fractional coordinates in [-1/2, 1/2)
(the cell centred on the origin).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .periodic import box_vectors, cell_heights, fractional, lattice_shifts, read_box

__all__ = ["Box"]


@dataclass(frozen=True, eq=False)
class Box:
    """A periodic box: sides and tilt factors (HOOMD's convention, module docstring).

    Examples:
        >>> b = Box(10, 8, xy=0.5)          # 2D, tilted
        >>> b.dimensions, b.tilted, b.vectors.tolist()
        (2, True, [[10.0, 4.0], [0.0, 8.0]])
        >>> Box.from_any((10, 10, 10), 3)
        Box(Lx=10.0, Ly=10.0, Lz=10.0, xy=0.0, xz=0.0, yz=0.0)
        >>> Box(10, 10, 10).wrap([[6.0, -7.0, 4.0]]).tolist()
        [[-4.0, 3.0, 4.0]]
        >>> Box(10, 10, -1)
        Traceback (most recent call last):
        ...
        ValueError: box: expected 3 positive finite sides (Lx, Ly, Lz) or (Lx, Ly, Lz, xy, xz, yz) (a tilted box, HOOMD's tilt factors), got [10.0, 10.0, -1.0]
    """

    Lx: float
    """Side along x (the length of a1)."""
    Ly: float
    """Side along y (the y component of a2)."""
    Lz: float | None = None
    """Side along z; None: a 2D box."""
    xy: float = 0.0
    """Tilt factor: a2 = (xy Ly, Ly[, 0])."""
    xz: float = 0.0
    """Tilt factor: a3 = (xz Lz, yz Lz, Lz) (3D only)."""
    yz: float = 0.0
    """Tilt factor (3D only)."""
    _array: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        d = 2 if self.Lz is None else 3
        numbers = [self.Lx, self.Ly, 0.0 if self.Lz is None else self.Lz, self.xy, self.xz, self.yz]
        for name, v in zip(("Lx", "Ly", "Lz", "xy", "xz", "yz"), numbers, strict=True):
            if isinstance(v, bool) or not isinstance(v, int | float | np.integer | np.floating):
                raise ValueError(f"box: {name} must be a real number, got {v!r}")
        if d == 2 and (self.xz or self.yz):
            raise ValueError(f"box: a 2D box has no tilt factors xz, yz; got xz = {self.xz}, yz = {self.yz}")
        arr = read_box(numbers if any(numbers[3:]) else numbers[:d], d)
        assert arr is not None
        arr.setflags(write=False)
        for name, v in zip(("Lx", "Ly", "Lz", "xy", "xz", "yz"), numbers, strict=True):  # plain floats
            object.__setattr__(self, name, None if (name == "Lz" and self.Lz is None) else float(v))
        object.__setattr__(self, "_array", arr)

    @classmethod
    def from_any(cls, box: Any, dim: int) -> Box | None:
        """A box from any accepted form, for bodies of dimension ``dim``; None stays None.

        Accepted: a :class:`Box` (of that dimension), d sides, ``(Lx, Ly, Lz, xy, xz, yz)`` (3D),
        ``(Lx, Ly, xy)`` or a HOOMD 2D frame's six numbers (2D), or an array of those.

        Raises:
            ValueError: anything else, saying what was expected.

        Examples:
            >>> Box.from_any((10, 8, 0.5), 2)
            Box(Lx=10.0, Ly=8.0, Lz=None, xy=0.5, xz=0.0, yz=0.0)
            >>> Box.from_any(None, 3) is None
            True
        """
        if box is None:
            return None
        if isinstance(box, Box):
            if box.dimensions != dim:
                raise ValueError(f"box: a {box.dimensions}D box for {dim}D bodies")
            return box
        arr = read_box(box, dim)
        assert arr is not None
        if arr.size == 6:
            Lx, Ly, Lz, xy, xz, yz = (float(v) for v in arr)
            return cls(Lx, Ly, Lz if dim == 3 else None, xy, xz, yz)
        return cls(float(arr[0]), float(arr[1]), float(arr[2]) if dim == 3 else None)

    @property
    def dimensions(self) -> int:
        """2 or 3."""
        return 2 if self.Lz is None else 3

    @property
    def tilted(self) -> bool:
        """Whether any tilt factor is nonzero."""
        return bool(self.xy or self.xz or self.yz)

    @property
    def array(self) -> np.ndarray:
        """The box as :mod:`core.bodies.periodic` takes it: d sides, or the six numbers when tilted (read-only)."""
        return self._array

    @property
    def vectors(self) -> np.ndarray:
        """(d, d) box vectors as columns (the tilt products rounded once: for drawing and estimates)."""
        return box_vectors(self._array, self.dimensions)

    @property
    def heights(self) -> np.ndarray:
        """(d,) lower bounds of the distances between opposite faces (the sides when orthogonal)."""
        return cell_heights(self._array, self.dimensions)

    @property
    def volume(self) -> float:
        """Area (2D) or volume (3D) of the cell: the product of the sides (tilt keeps it)."""
        return float(self.Lx * self.Ly * (self.Lz if self.Lz is not None else 1.0))

    def fractional(self, points: Any) -> np.ndarray:
        """(N, d) fractional coordinates f of the points (p = f1 a1 + f2 a2 [+ f3 a3]), in floats.

        Each is within a few roundings of the exact value
        (:func:`core.bodies.periodic.fractional` also returns that bound).
        """
        p = self._points(points)
        return fractional(p, self._array)[0]

    def shifts(self, images: Any) -> np.ndarray:
        """(M, d) float lattice vectors v(k) of integer images k, each component correctly rounded.

        Examples:
            >>> Box(10, 10, 10, xy=0.1).shifts([[1, 1, 0]]).tolist()
            [[11.0, 10.0, 0.0]]
        """
        k = np.asarray(images, dtype=np.int64).reshape(-1, self.dimensions)
        return lattice_shifts(self._array, k)

    def images(self, points: Any) -> np.ndarray:
        """(N, d) int64 images k such that p - v(k) lies in the cell around the origin (f in [-1/2, 1/2))."""
        f = self.fractional(points)
        return np.floor(f + 0.5).astype(np.int64)

    def wrap(self, points: Any) -> np.ndarray:
        """The points moved by whole lattice vectors into the cell centred on the origin.

        ``p - v(k)`` with k from :meth:`images`, in float64 (one rounding per component where
        the difference is not a float: the positions a simulation stores when it wraps).
        """
        p = self._points(points)
        k = self.images(p)
        moved = k.any(axis=1)
        out = p.copy()
        if moved.any():
            out[moved] = p[moved] - self.shifts(k[moved])
        return out

    def unwrap(self, c0: Any, c1: Any) -> tuple[np.ndarray, np.ndarray]:
        """``c1`` moved by whole lattice vectors to the image nearest ``c0``, and those images.

        Trajectories store wrapped positions: a body that crosses a face between two frames
        jumps by a box vector. The image k of each row is the rounded difference of the
        fractional coordinates; the end is ``c1 - v(k)`` (then ``c1 - v(k) - c0`` is the
        minimum-image displacement).

        Returns:
            (the unwrapped ends (N, d) float64, the images k (N, d) int64: c1 - v(k) is returned).

        Raises:
            ValueError: a row where ``c1 - v(k)`` is not a float (it would move the end by a
                rounding; only possible far from the cell, never for wrapped frames of a box
                whose sides are floats), naming the row.

        Examples:
            >>> ends, k = Box(10, 10).unwrap([[4.95, 0.0]], [[-4.85, 0.0]])
            >>> ends.tolist(), k.tolist()
            ([[5.15, 0.0]], [[-1, 0]])
        """
        p0, p1 = self._points(c0), self._points(c1)
        if p0.shape != p1.shape:
            raise ValueError(f"unwrap: c0 has shape {p0.shape} and c1 {p1.shape}")
        k = np.rint(self.fractional(p1) - self.fractional(p0)).astype(np.int64)
        moved = k.any(axis=1)
        out = p1.copy()
        if moved.any():
            v = self.shifts(k[moved])
            out[moved] = p1[moved] - v
            # the subtraction must be exact (TwoSum's error term 0), else the path would change
            s, a, b = out[moved], p1[moved], -v
            bb = s - a
            err = (a - (s - bb)) + (b - bb)
            bad = np.flatnonzero((err != 0).any(axis=1) | ~np.isfinite(s).all(axis=1))
            if bad.size:
                row = int(np.flatnonzero(moved)[bad[0]])
                raise ValueError(
                    f"row {row}: its end {p1[row].tolist()} moved to the image nearest its start is not a "
                    "float (the positions lie too far from the box): wrap the frames into the box first"
                )
        return out, k

    def to_tuple(self) -> tuple[float, ...]:
        """The box as the library's tuples: d sides, or ``(Lx, Ly, Lz, xy, xz, yz)`` when tilted (2D: Lz 0).

        Examples:
            >>> Box(10, 8, xy=0.5).to_tuple()
            (10.0, 8.0, 0.0, 0.5, 0.0, 0.0)
        """
        return tuple(float(v) for v in self._array)

    def tolist(self) -> list[float]:
        """:meth:`to_tuple` as a list (JSON)."""
        return list(self.to_tuple())

    def __eq__(self, other: object) -> bool:
        """Equal to another Box of the same numbers, or to the tuple :meth:`to_tuple` gives (the old form)."""
        if isinstance(other, Box):
            return self.to_tuple() == other.to_tuple() and self.dimensions == other.dimensions
        if isinstance(other, tuple | list):
            try:
                return self.to_tuple() == tuple(float(v) for v in other)
            except (TypeError, ValueError):
                return False
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self.to_tuple())

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        """``np.asarray(box)``: :attr:`array` (code that took the box as an array keeps working)."""
        return np.array(self._array, dtype=dtype)

    def __len__(self) -> int:
        return int(self._array.size)

    def __iter__(self) -> Any:
        return iter(self.to_tuple())

    def __getitem__(self, k: Any) -> Any:
        return self._array[k]

    def describe(self) -> str:
        """Short text: "10 x 10 x 10", with "tilted (xy, xz, yz) = (...)" when tilted.

        Examples:
            >>> Box(8, 8, xy=0.5).describe()
            '8 x 8 tilted (xy) = (0.5)'
        """
        d = self.dimensions
        text = " x ".join(f"{v:g}" for v in self._array[:d])
        if self.tilted:
            names, vals = (("xy",), (self.xy,)) if d == 2 else (("xy", "xz", "yz"), (self.xy, self.xz, self.yz))
            text += f" tilted ({', '.join(names)}) = ({', '.join(f'{v:g}' for v in vals)})"
        return text

    def _points(self, points: Any) -> np.ndarray:
        p = np.asarray(points, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != self.dimensions:
            raise ValueError(f"expected ({'N'}, {self.dimensions}) points for a {self.dimensions}D box, got shape {p.shape}")
        return p

