"""What :class:`~core.Contacts` and :class:`~core.SweepContacts` share: a table of pairs of bodies.

One pair per row: bodies ``i < j``, the certified ``relation``, which arithmetic certified it
(``certified_by``), in a periodic box the image ``k`` of body j (j moved by the lattice vector
v(k)), and, when the bodies had ids (a simulation file's own particle ids), ``id_i, id_j``.
The tables write themselves as CSV and as JSON-ready rows in one column order, so that the
command line, the HTTP API and the scene say the same thing:

    i, j, <the table's own columns>, relation, certified_by, image_x, image_y[, image_z], id_i, id_j

(``image_z`` in 3D, and in every ``contacts`` CSV for compatibility; ``id_i, id_j`` only when the
bodies have ids.) Floats are written with ``repr`` (the shortest text that reads back to the same
float), so certified brackets stay certified after a round trip.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import IO, Any, ClassVar

import numpy as np

from ..fixed.classify import Certifier
from ..relation import Relation
from .box import Box

__all__ = ["PairTable", "RELATION_NAMES", "CERTIFIER_NAMES"]

RELATION_NAMES: dict[int, str] = {int(r): str(r) for r in Relation}
"""int8 Relation code -> its name ("separate", "tangent", "overlap", ...)."""
CERTIFIER_NAMES: dict[int, str] = {int(Certifier.FLOAT): "float", int(Certifier.EXACT): "exact", int(Certifier.NONE): "none"}
"""int8 Certifier code -> "float" | "exact" | "none" (the CSV and JSON word)."""


class PairTable:
    """Shared behaviour of the pair tables (module docstring).

    Subclasses are dataclasses with at least these attributes; :attr:`OWN_COLUMNS` names the
    float columns a table adds between ``j`` and ``relation``.
    """

    OWN_COLUMNS: ClassVar[tuple[str, ...]] = ()
    """Float columns of the subclass written between ``j`` and ``relation`` (the sweep: t_lo, t_hi)."""

    i: np.ndarray
    j: np.ndarray
    relation: np.ndarray
    certified_by: np.ndarray
    n_bodies: int
    box: Box | None
    image: np.ndarray | None
    ids: np.ndarray | None
    invalid: dict[int, str]
    counts: dict[str, int]

    def __len__(self) -> int:
        return int(self.i.size)

    @property
    def dimensions(self) -> int | None:
        """2 or 3 when known from the box or the images; None in open space without pairs."""
        if self.box is not None:
            return self.box.dimensions
        if self.image is not None:
            return int(self.image.shape[1])
        return None

    def shifts(self) -> np.ndarray | None:
        """(M, d) float64: the lattice vector v(k) body j of each pair was moved by; None in open space.

        The float vectors the computation moved j by (:meth:`core.Box.shifts`): k L in an
        orthogonal box; in a tilted one k1 a1 + k2 a2 + k3 a3 rounded to the nearest float per
        component.
        """
        if self.image is None or self.box is None:
            return None
        return self.box.shifts(self.image)

    def pairs_of(self, body: int) -> np.ndarray:
        """Indices (into i, j, relation, ...) of the pairs that contain ``body``."""
        return np.flatnonzero((self.i == body) | (self.j == body))

    def certified_counts(self) -> dict[str, int]:
        """Reported pairs per certifier: ``{"float": ..., "exact": ...}``."""
        return Certifier.counts(self.certified_by)

    def images(self, d: int = 3) -> np.ndarray:
        """(M, d) int64 images of j (zeros in open space; a 2D image padded with 0 when d = 3)."""
        out = np.zeros((len(self), d), dtype=np.int64)
        if self.image is not None:
            w = min(d, self.image.shape[1])
            out[:, :w] = self.image[:, :w]
        return out

    def pair_ids(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The bodies' own ids of each pair ``(id_i, id_j)``, or None when the bodies have no ids."""
        if self.ids is None:
            return None
        ids = np.asarray(self.ids)
        return ids[self.i], ids[self.j]

    def columns(self, *, image_dims: int | None = None, extra: dict[str, Any] | None = None) -> dict[str, list[Any]]:
        """The table's columns in the CSV order (module docstring), as lists of Python values.

        Args:
            image_dims: how many image columns: 3 (the default: ``image_z`` is 0 in 2D, as every
                pairs CSV has it) or the dimension (2 in 2D).
            extra: more columns, written after the images and before the ids (e.g. the contact
                scale of ``python -m app contacts --with scale``).
        """
        d = 3 if image_dims is None else image_dims
        cols: dict[str, list[Any]] = {"i": self.i.tolist(), "j": self.j.tolist()}
        for name in self.OWN_COLUMNS:
            cols[name] = np.asarray(getattr(self, name), dtype=np.float64).tolist()
        cols["relation"] = [RELATION_NAMES[int(r)] for r in self.relation.tolist()]
        cols["certified_by"] = [CERTIFIER_NAMES.get(int(c), "none") for c in self.certified_by.tolist()]
        im = self.images(d)
        for a in range(d):
            cols[f"image_{'xyz'[a]}"] = im[:, a].tolist()
        for name, values in (extra or {}).items():
            cols[name] = list(values)
        ids = self.pair_ids()
        if ids is not None:
            cols["id_i"], cols["id_j"] = ids[0].tolist(), ids[1].tolist()
        return cols

    def to_csv(self, out: IO[str], *, image_dims: int | None = None, extra: dict[str, Any] | None = None) -> None:
        """Write the table as CSV (header first) to a text file; floats with ``repr`` (exact round trip)."""
        cols = self.columns(image_dims=image_dims, extra=extra)
        out.write(",".join(cols) + "\n")
        values = [[repr(v) if isinstance(v, float) else str(v) for v in col] for col in cols.values()]
        step = 1 << 16
        for s in range(0, len(self), step):
            out.write("".join(",".join(row) + "\n" for row in zip(*(v[s : s + step] for v in values), strict=True)))

    def rows(self, *, image_dims: int | None = None) -> Iterator[dict[str, Any]]:
        """One dict per pair (the JSON form): the CSV's columns, and ``image`` as d integers (None in open space)."""
        cols = self.columns(image_dims=image_dims)
        names = list(cols)
        images = None if self.image is None else self.image.tolist()
        for k, values in enumerate(zip(*cols.values(), strict=True)):
            row = dict(zip(names, values, strict=True))
            row["image"] = None if images is None else images[k]
            yield row
