"""What a sweep returns: :class:`SweepContacts`, the first contact of every pair that meets."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from flint import fmpq

from ..algebra.algebraic import RealAlgebraic
from ..moving.first_contact import first_contact
from ..moving.linear import LinearMotions
from ..relation import Relation
from .box import Box
from .pairs import PairTable

__all__ = ["SweepContacts"]


@dataclass
class SweepContacts(PairTable):
    """Every pair of moving bodies that is not separate somewhere in [0, 1], with its first contact.

    Pairs are (i, j) with i < j, sorted by (i, j). t* is the first t in [0, 1] at which the
    pair is not separate (0 when they already touch or overlap at t = 0); in a periodic box the
    pair is body i with the image of body j moved by the lattice vector of ``image`` during the
    whole step (:meth:`shifts`: ``image`` * L in an orthogonal box).
    """

    i: np.ndarray
    """int64 first body of each pair."""
    j: np.ndarray
    """int64 second body (i < j)."""
    t_lo: np.ndarray
    """float64: t_lo <= t* (certified)."""
    t_hi: np.ndarray
    """float64: t* <= t_hi, t_hi - t_lo <= 1e-9 (certified)."""
    relation: np.ndarray
    """int8 :class:`~core.Relation` at t*: TANGENT, or OVERLAP (only at t* = 0)."""
    certified_by: np.ndarray
    """int8 :class:`~core.Certifier`: the float filter (FLOAT) or exact arithmetic (EXACT)."""
    n_bodies: int
    """Number of bodies (valid or not)."""
    bodies: LinearMotions = field(repr=False)
    """The bodies, read exactly (what :meth:`time` computes with)."""
    box: Box | None = None
    """Periodic box (:class:`core.Box`); None in open space."""
    image: np.ndarray | None = None
    """(M, d) int8 lattice image of j for each pair (periodic box), else None."""
    invalid: dict[int, str] = field(default_factory=dict)
    """Row -> why it describes no moving body (``on_invalid="mark"``); such rows are in no pair."""
    counts: dict[str, int] = field(default_factory=dict)
    """``bodies``, ``invalid``, ``broad`` (pairs whose swept balls meet), ``candidates`` (after the
    relative-motion test), ``float`` / ``exact`` (candidates certified by the float filter /
    exact arithmetic), ``contacts``, ``tangent``, ``overlap``, ``at_start`` (t* = 0)."""
    seconds: dict[str, float] = field(default_factory=dict)
    """Wall-clock seconds: ``read``, ``broad``, ``narrow``, ``total``."""
    _times: dict[int, RealAlgebraic] = field(default_factory=dict, repr=False)
    ids: np.ndarray | None = None
    """(N,) the bodies' own ids (a file's particle ids, :class:`core.Bodies`), or None: the CSV and
    JSON then carry ``id_i, id_j``."""

    OWN_COLUMNS: ClassVar[tuple[str, ...]] = ("t_lo", "t_hi")

    def time(self, k: int) -> RealAlgebraic:
        """t* of pair k exactly: a real algebraic number with an isolating interval.

        Computed on first request (exact arithmetic on the pair's exact motions, searching
        only [t_lo, t_hi], :func:`core.moving.first_contact.first_contact`), then kept.

        Raises:
            IndexError: k is not a pair of the result.
        """
        k = int(k)
        if not 0 <= k < len(self):
            raise IndexError(f"pair {k} out of range (0..{len(self) - 1})")
        if k not in self._times:
            lo = fmpq(*float(self.t_lo[k]).as_integer_ratio())
            hi = fmpq(*float(self.t_hi[k]).as_integer_ratio())
            if lo == hi:
                self._times[k] = RealAlgebraic.rational(lo)
            else:
                shifts = self.shifts()
                shift = None if shifts is None else shifts[k]
                e = first_contact(self.bodies.motion(int(self.i[k])), self.bodies.motion(int(self.j[k]), shift), (lo, hi))
                if e is None:  # pragma: no cover - the bracket is certified
                    raise RuntimeError(f"pair {k}: no contact in its certified bracket [{lo}, {hi}]")
                self._times[k] = e.time
        return self._times[k]

    def first_time(self) -> np.ndarray:
        """(N,) float64: each body's earliest t_lo over its pairs (inf: it meets nothing)."""
        out = np.full(self.n_bodies, np.inf)
        np.minimum.at(out, self.i, self.t_lo)
        np.minimum.at(out, self.j, self.t_lo)
        return out

    def order(self) -> np.ndarray:
        """Pair indices in time order (by t_lo, then (i, j)): the event list of the step."""
        return np.lexsort((self.j, self.i, self.t_lo))

    def to_rows(self) -> list[tuple[int, int, float, float, str]]:
        """``[(i, j, t_lo, t_hi, "tangent" | "overlap"), ...]`` (the CSV rows)."""
        names = {int(r): str(r) for r in Relation}
        return [
            (int(a), int(b), float(lo), float(hi), names[int(r)])
            for a, b, lo, hi, r in zip(self.i, self.j, self.t_lo, self.t_hi, self.relation, strict=True)
        ]

    def summary(self) -> str:
        """One paragraph: bodies, candidates, contacts, how they were certified.

        Examples:
            >>> from core.moving.linear import read_linear_motions
            >>> z = np.zeros(0)
            >>> SweepContacts(z.astype(np.int64), z.astype(np.int64), z, z, z.astype(np.int8), z.astype(np.int8), 2,
            ...               read_linear_motions([[0, 0]] * 2, [[0, 0]] * 2, [[1, 1]] * 2)[0]).summary()
            '2 moving bodies, 0 candidate pairs, 0 meet (0 at t = 0)'
        """
        c = self.counts
        at_start = int(np.count_nonzero(self.t_hi == 0.0))
        text = f"{self.n_bodies} moving bodies, {c.get('candidates', 0)} candidate pairs, {len(self)} meet ({at_start} at t = 0)"
        if c.get("candidates"):
            text += f"; certified by the float filter {c.get('float', 0)}, by exact arithmetic {c.get('exact', 0)}"
        if self.invalid:
            text += f"; {len(self.invalid)} invalid bodies"
        return text
