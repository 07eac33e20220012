"""Many bodies as a value: :class:`Bodies` (centres, semi-axes, orientations, ids, box).

What the file readers return and what :func:`core.contacts`, :class:`core.BodyIndex` and
:func:`core.sweep_contacts` take besides bare arrays: the parameters of N ellipses (d = 2) or
ellipsoids (d = 3), the bodies' own ids when the source has them (a LAMMPS ``id`` column, a CSV
``id`` column) so that answers can name them, and the periodic :class:`~core.Box` they live in.
The matrices are built from the parameters once, when first asked for, by
:func:`core.bodies_from_axes` (bit for bit what one shape gives), and the parameters checked once
with them (:func:`core.bodies.build.matrices_and_errors`); a row whose parameters are no shape
becomes a NaN matrix with the reason in :attr:`Bodies.errors`. Sources that store matrices
rather than parameters use :meth:`Bodies.from_matrices`.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Any, Self

import numpy as np

from ..shapes.quadrics import axes_row_errors
from .box import Box
from .build import matrices_and_errors

__all__ = ["Bodies"]


@dataclass
class Bodies:
    """N ellipses or ellipsoids: parameters (or matrices), optional ids, optional periodic box.

    Examples:
        >>> b = Bodies([[0, 0], [1, 0]], [[0.5, 0.5], [0.5, 0.5]], ids=[10, 11], box=(4, 4))
        >>> len(b), b.dimensions, b.box
        (2, 2, Box(Lx=4.0, Ly=4.0, Lz=None, xy=0.0, xz=0.0, yz=0.0))
        >>> b.matrices.shape
        (2, 3, 3)
        >>> Bodies([[0, 0]], [[1, -1]]).errors
        {0: 'semi-axes must be positive, got [1.0, -1.0]'}
    """

    centers: Any
    """(N, d) float64 centres (None only for :meth:`from_matrices`)."""
    semi_axes: Any = None
    """(N, d) float64 semi-axes (None only for :meth:`from_matrices`)."""
    orientations: Any = None
    """3D: (N, 4) quaternions wxyz; 2D: (N,) angles in radians; None: axis-aligned."""
    ids: Any = None
    """(N,) int64 ids of the bodies in their source, or None (then rows are their names)."""
    box: Any = None
    """The periodic :class:`~core.Box` (any form :meth:`core.Box.from_any` reads), or None."""
    _matrices: np.ndarray | None = field(default=None, init=False, repr=False, compare=False)
    _errors: dict[int, str] | None = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.centers is not None:
            try:
                self.centers = np.asarray(self.centers, dtype=np.float64)
                self.semi_axes = np.asarray(self.semi_axes, dtype=np.float64)
                if self.orientations is not None:
                    self.orientations = np.asarray(self.orientations, dtype=np.float64)
            except (TypeError, ValueError) as e:
                raise ValueError(f"bodies: centres, semi-axes and orientations must be arrays of numbers ({e})") from None
            c, r = self.centers, self.semi_axes
            if c.ndim != 2 or c.shape[1] not in (2, 3) or r.shape != c.shape:
                raise ValueError(f"bodies: centers and semi_axes must be (N, 2) or (N, 3) arrays of one shape, got {c.shape} and {r.shape}")
            n = c.shape[0]
        else:
            assert self._matrices is not None
            n = self._matrices.shape[0]
        if self.ids is not None:
            ids = np.asarray(self.ids)
            if ids.shape != (n,) or not np.issubdtype(ids.dtype, np.integer):
                raise ValueError(f"bodies: ids must be {n} integers, got an array of shape {ids.shape} and type {ids.dtype}")
            self.ids = ids.astype(np.int64, copy=False)
        self.box = Box.from_any(self.box, self.dimensions)

    @classmethod
    def from_matrices(cls, matrices: Any, *, ids: Any = None, box: Any = None) -> Bodies:
        """Bodies given by their (N, d+1, d+1) float matrices (no parameters).

        Raises:
            ValueError: not an (N, 3, 3) or (N, 4, 4) array.
        """
        Q = np.asarray(matrices, dtype=np.float64)
        if Q.ndim != 3 or Q.shape[1] != Q.shape[2] or Q.shape[1] not in (3, 4):
            raise ValueError(f"bodies: expected (N, 3, 3) or (N, 4, 4) matrices, got shape {Q.shape}")
        out = cls.__new__(cls)
        out.centers = out.semi_axes = out.orientations = None
        out.ids, out.box = ids, box
        out._matrices, out._errors = Q, {}
        out.__post_init__()
        return out

    @property
    def dimensions(self) -> int:
        """2 (ellipses) or 3 (ellipsoids)."""
        if self._matrices is not None:
            return int(self._matrices.shape[-1] - 1)
        return int(self.centers.shape[1])

    def __len__(self) -> int:
        return int(self._matrices.shape[0] if self._matrices is not None else self.centers.shape[0])

    @property
    def has_parameters(self) -> bool:
        """Whether centres and semi-axes are known (else only the matrices)."""
        return self.centers is not None

    @property
    def matrices(self) -> np.ndarray:
        """(N, d+1, d+1) float64 matrices (NaN rows: parameters that are no shape, see :attr:`errors`)."""
        if self._matrices is None:
            self._matrices, self._errors = matrices_and_errors(self.centers, self.semi_axes, self.orientations)
        return self._matrices

    @property
    def errors(self) -> dict[int, str]:
        """Row -> why its parameters are no ellipse/ellipsoid (those matrices are NaN)."""
        if self._errors is None:
            _ = self.matrices  # checked once, with the matrices (matrices_and_errors)
        assert self._errors is not None
        return self._errors

    @property
    def parameter_errors(self) -> dict[int, str]:
        """Row -> why its parameters are no shape, without the float matrices' own limit (what the sweep reads)."""
        if not self.has_parameters:
            return {}
        return axes_row_errors(self.centers, self.semi_axes, self.orientations, matrices=False)

    def name(self, k: int) -> str:
        """How messages name body k: "body 7" or, with ids, "body 7 (id 12)"."""
        return f"body {k}" if self.ids is None else f"body {k} (id {int(self.ids[k])})"

    def ordered_like(self, other: Bodies) -> Self:
        """These bodies in the order of ``other``'s ids (two frames of one trajectory); self when already so.

        Raises:
            ValueError: the two do not hold the same ids (or one has none while the counts differ).
        """
        if self.ids is None or other.ids is None or np.array_equal(self.ids, other.ids):
            if len(self) != len(other):
                raise ValueError(f"bodies: {len(other)} bodies at the start and {len(self)} at the end")
            return self
        order = np.argsort(self.ids, kind="stable")
        where = np.searchsorted(self.ids, other.ids, sorter=order)
        where = np.clip(where, 0, len(self) - 1)
        rows = order[where]
        if len(self) != len(other) or not np.array_equal(self.ids[rows], other.ids) or np.unique(self.ids).size != len(self):
            raise ValueError("bodies: the two frames do not hold the same ids (each body once): a body appeared or left")
        out = copy.copy(self)  # a subclass keeps its own fields (a file's name, its frame)
        if self.has_parameters:
            out.centers = np.asarray(self.centers)[rows]
            out.semi_axes = np.asarray(self.semi_axes)[rows]
            out.orientations = None if self.orientations is None else np.asarray(self.orientations)[rows]
            out._matrices = out._errors = None
        else:
            assert self._matrices is not None
            out._matrices = self._matrices[rows]
        out.ids = self.ids[rows]
        return out


def unpack(bodies: Any, box: Any) -> tuple[Any, Any, np.ndarray | None]:
    """(matrices or the array given, the box to use, ids): a :class:`Bodies` opened for the searches.

    An explicit ``box`` wins over the bodies' own box; bare arrays pass through unchanged.
    """
    if isinstance(bodies, Bodies):
        return bodies.matrices, bodies.box if box is None else box, bodies.ids
    return bodies, box, None
