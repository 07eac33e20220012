"""What a contact search returns: :class:`Contacts`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..relation import Relation
from .box import Box
from .pairs import PairTable

__all__ = ["Contacts"]


@dataclass
class Contacts(PairTable):
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
    box: Box | None = None
    """Periodic box (:class:`core.Box`); None in open space."""
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
    ids: np.ndarray | None = None
    """(N,) the bodies' own ids (a file's particle ids, :class:`core.Bodies`), or None: the CSV and
    JSON then carry ``id_i, id_j``."""

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
