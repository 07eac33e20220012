"""Pydantic models of ``POST /api/contacts``: many bodies in, the pairs that are not separate out.

Bodies are float64 numbers (the contact search builds float matrices, as ``python -m app
contacts`` does from a file): JSON numbers only, no number strings. One body is a row like a CSV
row of :mod:`app.bodyfiles` (3D ``[x, y, z, a, b, c, qw, qx, qy, qz]``, 2D
``[x, y, a, b, angle]``), or a matrix. At most ``ApiSettings.max_contacts_bodies`` bodies
(10,000 by default) per request.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, PlainValidator, WithJsonSchema

from core.options import OnInvalid
from core.shapes.numbers import binary64

from .schemas import CertifiedBy, MethodName, OutOfRange

__all__ = ["ContactsIn", "ContactsOut", "PairOut", "FloatNumber"]


def checked_float(v: Any) -> float:
    """A finite JSON number as the float64 it is exactly.

    Strings, booleans and integers that a float64 cannot hold (2^53 + 1) are refused; 2^60 is a
    float64 and is taken.
    """
    if isinstance(v, bool):
        raise ValueError(f"a boolean is not a number: {v!r}")
    if isinstance(v, OutOfRange):
        raise ValueError(v.message.split(";")[0] + ": bodies are float64 numbers")
    if not isinstance(v, int | float):
        raise ValueError(f"expected a JSON number (bodies are float64 numbers), got {type(v).__name__}")
    f = binary64(v, typed=True)  # the one "exactly a float64" test (core.shapes.numbers)
    if f is None and isinstance(v, int):  # beyond 2^53 with low bits, or beyond the float64 range
        digits = f"{len(str(abs(v)))}" if v.bit_length() < 14000 else f"about {v.bit_length() * 30103 // 100000 + 1}"
        raise ValueError(f"an integer of {digits} digits that is not exactly a float64: bodies are float64 numbers")
    if f is None or not math.isfinite(f):  # (a float is always its own float64: None never comes here)
        raise ValueError(f"not a finite number: {v!r}")
    return f


FloatNumber = Annotated[float, PlainValidator(checked_float), WithJsonSchema({"type": "number"})]
"""A finite JSON number, read as the float64 it is."""

BodyRow = Annotated[list[FloatNumber], Field(min_length=5, max_length=10)]
BodyMatrix = Annotated[list[Annotated[list[FloatNumber], Field(min_length=3, max_length=4)]], Field(min_length=3, max_length=4)]


class ContactsIn(BaseModel):
    """Bodies (rows of parameters, or matrices), an optional periodic box and the method."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {"bodies": [[0, 0, 0.5, 0.5, 0], [1, 0, 0.5, 0.5, 0], [1.5, 0, 0.5, 0.5, 0]]},
                {"bodies": [[0.5, 0.5, 0.5, 1, 1, 1, 1, 0, 0, 0], [3.5, 0.5, 0.5, 1, 1, 1, 1, 0, 0, 0]], "box": [4, 4, 4]},
            ]
        },
    )

    bodies: list[BodyRow] | None = Field(
        default=None,
        description="one row per body: 3D [x, y, z, a, b, c, qw, qx, qy, qz] (centre, semi-axes, quaternion wxyz), "
        "2D [x, y, a, b, angle] (radians)",
    )
    matrices: list[BodyMatrix] | None = Field(
        default=None, description="or one symmetric 4x4 (3x3) matrix per body, interior X^T A X < 0"
    )
    box: Annotated[list[FloatNumber], Field(min_length=2, max_length=6)] | None = Field(
        default=None,
        description="periodic box: sides [Lx, Ly(, Lz)], or a tilted box in HOOMD's convention [Lx, Ly, Lz, xy, xz, yz] "
        "(2D: [Lx, Ly, xy]): minimum image convention",
    )
    method: MethodName = "adaptive"
    on_invalid: OnInvalid = Field(
        default="raise", description="raise: 422 naming the first bad body; mark: list bad bodies in 'invalid'"
    )
    ids: list[Annotated[int, Field(ge=-(2**63), lt=2**63)]] | None = Field(
        default=None, description="the bodies' own ids, one per body in row order (a simulation's particle ids): "
        "each pair then carries id_i and id_j"
    )


PairRelation = Literal["tangent", "overlap", "undecided"]
"""The relation of a listed pair (separate pairs are not listed)."""


class PairOut(BaseModel):
    """One pair of bodies that is not separate."""

    i: int
    j: int
    """i < j; in a periodic box, j's nearest image (j moved by the lattice vector of ``image``)."""
    relation: PairRelation
    certified_by: CertifiedBy | None
    """Which arithmetic certified the relation: "float" (the filter) or "exact"."""
    image: list[int] | None = None
    """Lattice image of j (periodic box only)."""
    image_x: int = 0
    image_y: int = 0
    image_z: int = 0
    """The lattice image k of j as three numbers (j stands at c_j + k L, or c_j + k1 a1 + k2 a2 + k3 a3 in a tilted box; all 0 in open space, image_z 0 in 2D)."""
    id_i: int | None = None
    """The id of body i (only when the request gave ``ids``)."""
    id_j: int | None = None
    """The id of body j (only when the request gave ``ids``)."""


class ContactsOut(BaseModel):
    """Every pair that touches or overlaps, certified, sorted by (i, j)."""

    bodies: int
    pairs: list[PairOut]
    counts: dict[str, int]
    """bodies, invalid, candidates (pairs whose bounding spheres meet), float / exact (how the
    candidates were certified), separate, tangent, overlap, undecided."""
    invalid: dict[int, str]
    """Body -> why it is not an ellipse/ellipsoid (on_invalid 'mark')."""
    summary: str
