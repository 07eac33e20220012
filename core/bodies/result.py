"""What a contact search returns: :class:`Contacts`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..fixed.classify import Certifier
from ..relation import Relation

__all__ = ["Contacts"]


@dataclass
class Contacts:
    """Every pair of bodies that is not separate, with its certified relation.

    Pairs are (i, j) with i < j, sorted by (i, j). In a periodic box the pair is body i with the
    nearest image of body j: j moved by the lattice vector v(``image``) (:meth:`shifts`; k L in
    an orthogonal box, k1 a1 + k2 a2 + k3 a3 rounded to floats in a tilted one).
    """

    i: np.ndarray
    """int64 first body of each pair."""
    j: np.ndarray
    """int64 second body (i < j)."""
    relation: np.ndarray
    """int8 :class:`~core.Relation` codes: TANGENT or OVERLAP (UNDECIDED only with
    ``method="float"``)."""
    certified_by: np.ndarray
    """int8 :class:`~core.Certifier` code of each reported pair (float filter or exact)."""
    n_bodies: int
    """Number of bodies searched (valid or not)."""
    box: np.ndarray | None = None
    """Periodic box: its d sides, or the six numbers (Lx, Ly, Lz, xy, xz, yz) of a tilted box
    (:func:`core.bodies.periodic.read_box`); None in open space."""
    image: np.ndarray | None = None
    """(M, d) int8 lattice image k of j for each pair (periodic box), else None."""
    invalid: dict[int, str] = field(default_factory=dict)
    """Body -> why it is not an ellipse/ellipsoid (``on_invalid="mark"``); such bodies are in
    no pair."""
    counts: dict[str, int] = field(default_factory=dict)
    """How the search went: ``bodies``, ``invalid``, ``candidates`` (pairs whose bounding
    spheres meet), ``float`` and ``exact`` (candidates certified by the float filter / exact
    arithmetic), ``undecided`` (``method="float"`` only), ``separate``, ``tangent``,
    ``overlap``, and ``exact_bounds`` (bodies whose bounding sphere needed exact arithmetic)."""
    seconds: dict[str, float] = field(default_factory=dict)
    """Wall-clock seconds per phase: ``bounds``, ``broad``, ``narrow``, ``total``."""

    def __len__(self) -> int:
        return int(self.i.size)

    def per_body(self) -> np.ndarray:
        """(N,) int8: the worst relation of each body (SEPARATE if in no pair; INVALID).

        Examples:
            >>> c = Contacts(np.array([0]), np.array([2]), np.array([1], np.int8), np.array([2], np.int8), 4,
            ...              invalid={3: "body 3: ..."})
            >>> c.per_body().tolist()
            [1, 0, 1, -2]
        """
        worst = np.full(self.n_bodies, Relation.SEPARATE, dtype=np.int8)
        np.maximum.at(worst, self.i, self.relation)
        np.maximum.at(worst, self.j, self.relation)
        if self.invalid:
            worst[list(self.invalid)] = Relation.INVALID
        return worst

    def shifts(self) -> np.ndarray | None:
        """(M, d) float64: the vector v(k) body j of each pair was moved by; None in open space.

        The exact float vectors the search translated j's matrix by
        (:func:`core.bodies.periodic.lattice_shifts`): k L in an orthogonal box; in a tilted one
        k1 a1 + k2 a2 + k3 a3 rounded to the nearest float per component.

        Examples:
            >>> c = Contacts(np.array([0]), np.array([1]), np.array([1], np.int8), np.array([2], np.int8), 2,
            ...              box=np.array([10.0, 10.0, 0.0, 0.5, 0.0, 0.0]), image=np.array([[0, -1]], np.int8))
            >>> c.shifts().tolist()
            [[-5.0, -10.0]]
        """
        if self.image is None or self.box is None:
            return None
        from .periodic import lattice_shifts

        return lattice_shifts(self.box, self.image)

    def pairs_of(self, body: int) -> np.ndarray:
        """Indices (into i, j, relation) of the pairs that contain ``body``."""
        return np.flatnonzero((self.i == body) | (self.j == body))

    def to_rows(self) -> list[tuple[int, int, str]]:
        """``[(i, j, "tangent" | "overlap" | ...), ...]`` (the CSV rows)."""
        names = {int(r): str(r) for r in Relation}
        return [(int(a), int(b), names[int(r)]) for a, b, r in zip(self.i, self.j, self.relation, strict=True)]

    def summary(self) -> str:
        """One paragraph: bodies, candidates, contacts by relation, how they were certified.

        Examples:
            >>> Contacts(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int8),
            ...          np.zeros(0, np.int8), 3, counts={"candidates": 0}).summary()
            '3 bodies, 0 candidate pairs, 0 contacts (0 tangent, 0 overlap)'
        """
        c = self.counts
        rel = np.bincount(self.relation.astype(np.int64) + 2, minlength=5)
        text = (
            f"{self.n_bodies} bodies, {c.get('candidates', 0)} candidate pairs, {len(self)} contacts "
            f"({rel[Relation.TANGENT + 2]} tangent, {rel[Relation.OVERLAP + 2]} overlap)"
        )
        if rel[Relation.UNDECIDED + 2]:
            text += f", {rel[Relation.UNDECIDED + 2]} undecided (method='float')"
        if c.get("candidates"):
            text += f"; certified by the float filter {c.get('float', 0)}, by exact arithmetic {c.get('exact', 0)}"
        if self.invalid:
            text += f"; {len(self.invalid)} invalid bodies"
        return text

    def certified_counts(self) -> dict[str, int]:
        """Reported pairs per certifier: ``{"float": ..., "exact": ...}``."""
        return Certifier.counts(self.certified_by)
