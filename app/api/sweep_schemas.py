"""Pydantic models of ``POST /api/sweep``: bodies at t = 0 and t = 1 in, first contact times out.

Bodies are float64 numbers (JSON numbers only, as for ``/api/contacts``: :data:`FloatNumber`),
one row per body like a CSV row of ``python -m app sweep``: ``start`` row k is body k at t = 0
(3D ``[x, y, z, a, b, c, qw, qx, qy, qz]``, 2D ``[x, y, a, b, angle]``), ``end`` row k the same
body at t = 1, with the same semi-axes; the end orientation may be left out (``[x, y, z, a, b,
c]``, 2D ``[x, y, a, b]``: the body keeps its orientation). Each body moves as
:func:`core.sweep_contacts` says: its centre on the straight line, its quaternion (2D: its
half-angle number) along q(t) = (1 - t) q0 + t q1. At most
``ApiSettings.max_contacts_bodies`` bodies (10,000 by default) per request, as for
``/api/contacts``.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from core import Box
from core.options import OnInvalid, SweepMethod

from .contacts_schemas import FloatNumber
from .schemas import AlgebraicOut, CertifiedBy

__all__ = ["SweepIn", "SweepOut", "SweepPairOut", "SweepArguments", "sweep_arguments", "in_api_words"]

StartRow = Annotated[list[FloatNumber], Field(min_length=5, max_length=10)]
EndRow = Annotated[list[FloatNumber], Field(min_length=4, max_length=10)]

_ROW_3D = "[x, y, z, a, b, c, qw, qx, qy, qz]"
_ROW_2D = "[x, y, a, b, angle]"


class SweepIn(BaseModel):
    """Bodies at t = 0 and at t = 1 (row by row), an optional periodic box, what to answer."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {"start": [[0, 0, 1, 1, 0], [3, 0, 1, 1, 0], [0, 5, 1, 1, 0]],
                 "end": [[0, 0, 1, 1, 0], [1, 0, 1, 1, 0], [0, 5, 1, 1, 0]], "exact_times": True},
                {"start": [[0, 0, 0, 1, 1, 1, 1, 0, 0, 0], [3, 0, 0, 1, 0.5, 0.5, 1, 0, 0, 0]],
                 "end": [[0, 0, 0, 1, 1, 1], [1, 0, 0, 1, 0.5, 0.5, 0, 0, 0, 1]]},
            ]
        },
    )

    start: list[StartRow] = Field(
        description=f"one row per body at t = 0: 3D {_ROW_3D} (centre, semi-axes, quaternion wxyz of any non-zero "
        f"length), 2D {_ROW_2D} (radians)",
    )
    end: list[EndRow] = Field(
        description="the same bodies at t = 1, row by row, with the same semi-axes: 3D [x, y, z, a, b, c, qw, qx, qy, qz] "
        "or [x, y, z, a, b, c] (orientation kept), 2D [x, y, a, b, angle] or [x, y, a, b]. The centre moves on the "
        "straight line; the orientation along q(t) = (1 - t) q0 + t q1 (2D: the angle turns from angle0 to angle1). "
        "In a periodic box give the end unwrapped (the start plus the displacement)",
    )
    box: Annotated[list[FloatNumber], Field(min_length=2, max_length=6)] | None = Field(
        default=None,
        description="periodic box: sides [Lx, Ly(, Lz)], or a tilted box in HOOMD's convention [Lx, Ly, Lz, xy, xz, yz] "
        "(2D: [Lx, Ly, xy]): minimum image over the whole step",
    )
    method: SweepMethod = Field(
        default="adaptive",
        description="adaptive: the certified float filter, exact arithmetic where it abstains; exact: every candidate "
        "pair exactly (slow)",
    )
    on_invalid: OnInvalid = Field(
        default="raise", description="raise: 422 naming the first bad row; mark: list bad rows in 'invalid' and sweep the rest"
    )
    ids: list[Annotated[int, Field(ge=-(2**63), lt=2**63)]] | None = Field(
        default=None, description="the bodies' own ids, one per row (a simulation's particle ids): each pair then "
        "carries id_i and id_j"
    )
    exact_times: bool = Field(
        default=False,
        description="also give each pair's t* exactly ('time': a real algebraic number); costly (exact arithmetic per "
        "pair), so at most ApiSettings.max_sweep_exact_times pairs (100) per answer",
    )
    digits: Annotated[int, Field(ge=1, le=100_000)] = Field(
        default=20, description="significant digits of the decimal 'value' of exact times (at most ApiSettings.max_digits)"
    )


PairRelation = Literal["tangent", "overlap"]
"""The relation at t* (separate pairs are not listed): tangent, or overlap when they overlap at t = 0."""


class SweepPairOut(BaseModel):
    """One pair of bodies that touches or overlaps during the step, with its first contact t*."""

    i: int
    j: int
    """i < j; in a periodic box, j's image (j moved by the lattice vector of ``image``: image * box in an orthogonal box) during the whole step."""
    t_lo: float
    """t_lo <= t* (certified; the float reads back exactly)."""
    t_hi: float
    """t* <= t_hi, t_hi - t_lo <= 1e-9 (certified); t_lo = t_hi = 0 when they already meet at t = 0."""
    relation: PairRelation
    certified_by: CertifiedBy
    """Which arithmetic certified the bracket: "float" (the filter) or "exact"."""
    time: AlgebraicOut | None = None
    """t* exactly (only with ``exact_times``): the one JSON form of a real algebraic number."""
    image: list[int] | None = None
    """Lattice image of j (periodic box only)."""
    image_x: int = 0
    image_y: int = 0
    image_z: int = 0
    """The lattice image k of j as three numbers (all 0 in open space, image_z 0 in 2D)."""
    id_i: int | None = None
    """The id of body i (only when the request gave ``ids``)."""
    id_j: int | None = None
    """The id of body j (only when the request gave ``ids``)."""


class SweepOut(BaseModel):
    """Every pair that touches or overlaps during t in [0, 1], with its first contact, sorted by (i, j)."""

    bodies: int
    pairs: list[SweepPairOut]
    counts: dict[str, int]
    """bodies, invalid, broad (pairs whose swept balls meet), candidates (after the relative-motion
    test), float / exact (how the candidates were certified), contacts, tangent, overlap, at_start
    (t* = 0)."""
    invalid: dict[int, str]
    """Row -> why it describes no moving body (on_invalid 'mark')."""
    summary: str


SweepArguments = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None, Box | None]
"""(centers0, centers1, semi_axes, orientations0, orientations1, box) for :func:`core.sweep_contacts`."""


def sweep_arguments(body: SweepIn) -> SweepArguments:
    """The request as the arguments of :func:`core.sweep_contacts` (ValueError naming what is wrong).

    The count limit is the route's (checked before this runs in a worker).

    Examples:
        >>> c0, c1, r, o0, o1, box = sweep_arguments(SweepIn(start=[[0, 0, 1, 1, 0.5]], end=[[2, 0, 1, 1]]))
        >>> c1.tolist(), r.tolist(), o0.tolist(), o1, box
        ([[2.0, 0.0]], [[1.0, 1.0]], [0.5], None, None)
    """
    n = len(body.start)
    if len(body.end) != n:
        raise ValueError(f"start has {n} rows but end has {len(body.end)}: end holds the same bodies at t = 1, row by row")
    widths = {len(r) for r in body.start}
    if widths not in ({10}, {5}, set()):
        raise ValueError(f"start: every row must be {_ROW_3D} (3D) or every row {_ROW_2D} (2D)")
    d = 3 if widths == {10} or not widths else 2
    full, bare = (10, 6) if d == 3 else (5, 4)
    for k, row in enumerate(body.end):
        if len(row) not in (full, bare):
            want = f"{_ROW_3D} or [x, y, z, a, b, c]" if d == 3 else f"{_ROW_2D} or [x, y, a, b]"
            raise ValueError(f"end row {k}: expected {want} (the start rows are {d}D), got {len(row)} numbers")
    box = Box.from_any(body.box, d)  # what a box is, core's to say (as /api/contacts)
    s = np.array(body.start, dtype=np.float64).reshape(n, full)
    c0, r = s[:, :d], s[:, d : 2 * d]
    o0 = s[:, 2 * d :] if d == 3 else s[:, 2 * d]
    c1 = np.array([row[:d] for row in body.end], dtype=np.float64).reshape(n, d)
    r1 = np.array([row[d : 2 * d] for row in body.end], dtype=np.float64).reshape(n, d)
    differ = np.flatnonzero((r1 != r).any(axis=1))
    if differ.size:
        k = int(differ[0])
        raise ValueError(
            f"end row {k}: semi-axes {r1[k].tolist()} differ from start's {r[k].tolist()}: a body keeps its shape during the step"
        )
    turning = [k for k, row in enumerate(body.end) if len(row) == full]
    o1: np.ndarray | None = None
    if turning:
        o1 = o0.copy()
        o1[turning] = np.array([body.end[k][2 * d :] if d == 3 else body.end[k][2 * d] for k in turning], dtype=np.float64)
    return c0, c1, r, o0, o1, box


_WORDS = (
    ("orientations0", "start's orientation"),
    ("orientations1", "end's orientation"),
    ("q1 = -lambda q0 (lambda > 0); flip the sign of q1", "end's = -lambda start's (lambda > 0); flip the sign of end's quaternion"),
)


def in_api_words(message: Any) -> str:
    """A message of :func:`core.sweep_contacts` in the request's terms (``start``, ``end``).

    Examples:
        >>> in_api_words("row 0: orientations0: the quaternion is zero")
        "row 0: start's orientation: the quaternion is zero"
    """
    text = str(message)
    for core_word, api_word in _WORDS:
        text = text.replace(core_word, api_word)
    return text
