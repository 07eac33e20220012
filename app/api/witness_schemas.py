"""Pydantic models of the witness endpoints: contact scale, separating plane, contact point.

Exact values travel as strings ("p/q"); an irrational value as an algebraic number: a decimal to
the requested digits, the integer polynomial it is a root of (ascending coefficients) and an
isolating interval with rational ends. Floats are approximations for display.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field
from pydantic.config import JsonValue

from .schemas import AlgebraicOut, PairItem

__all__ = [
    "WitnessIn",
    "ContactScaleIn",
    "ContactScaleOut",
    "PlaneOut",
    "ContactPointOut",
    "WitnessOut",
]

Kind = Literal["ellipse", "ellipsoid"]
CertifiedBy = Literal["float", "exact"]
"""Which arithmetic certified a witness: floats with directed rounding, or exact rationals."""
Decided = Literal["separate", "tangent", "overlap"]
"""The relation of a pair that has a witness (never undecided)."""

_EXAMPLES: list[JsonValue] = [
    {"a": [[1, 0, 0], [0, 1, 0], [0, 0, -1]], "b": [[1, 0, -3], [0, 1, 0], [-3, 0, 8]]},
    {"a": {"center": [0, 0, 0], "semi_axes": [2, 1, 1]}, "b": {"center": [3, 0, 0], "semi_axes": [1, 1, 1]}},
]


class WitnessIn(PairItem):
    """One pair, and how many decimal digits to print exact irrational values with."""

    model_config = ConfigDict(extra="forbid", json_schema_extra={"examples": _EXAMPLES})

    digits: Annotated[int, Field(ge=1, le=100_000)] = Field(
        default=20, description="significant digits of the decimals of exact values (server limit applies)"
    )


class ContactScaleIn(WitnessIn):
    """One pair; the relative width asked of the bracket; whether to compute the exact value."""

    model_config = ConfigDict(extra="forbid", json_schema_extra={"examples": _EXAMPLES})

    rtol: Annotated[float, Field(gt=0, le=1)] = Field(
        default=1e-12, description="relative width of the bracket: hi - lo <= rtol * hi"
    )
    exact: bool = Field(default=False, description="also give mu* exactly (polynomial, isolating interval, decimals)")


class ContactScaleOut(BaseModel):
    """Certified bracket lo <= mu* <= hi of the contact scale.

    Scale both shapes about their centres by mu* and they touch: mu* > 1 separate, = 1 tangent,
    < 1 overlap.
    """

    relation: Decided
    kind: Kind
    lo: str
    """Exact rational lower bound."""
    hi: str
    """Exact rational upper bound (equal to lo when mu* is known exactly)."""
    approx: float | None
    margin: float | None
    """mu* - 1 (approximate): > 0 apart, 0 touching, < 0 overlapping."""
    margin_text: str
    """"1.8 % apart", "touching", "overlapping by 3 %"."""
    exact: AlgebraicOut | None = None
    """mu* exactly, when asked for."""
    certified_by: CertifiedBy = "exact"
    """Which arithmetic proved the bracket (the bounds are exact rationals either way)."""


class PlaneOut(BaseModel):
    """A plane n.x = d with a strictly in n.x < d and b strictly in n.x > d, verified exactly."""

    relation: Literal["separate"]
    sentence: str
    normal: list[str]
    """n, exact rationals (not unit length)."""
    offset: str
    """d, exact rational."""
    unit_normal_approx: list[float]
    offset_approx: float | None
    """d / |n| (float), the offset of the unit normal (None if it overflows a double)."""
    support_a: str
    """An upper bound of max n.x over a (< d)."""
    support_b: str
    """A lower bound of min n.x over b (> d)."""
    gap_lower_bound: float | None
    """A lower bound of the Euclidean distance between the shapes (support_b - support_a) / |n|."""
    certified_by: CertifiedBy = "exact"
    """Which arithmetic proved that the plane separates (its numbers are exact either way)."""


class ContactPointOut(BaseModel):
    """Tangent: the exact contact point and common normal. Overlap: a rational point inside both."""

    relation: Literal["tangent", "overlap"]
    sentence: str
    point: list[AlgebraicOut]
    normal: list[AlgebraicOut] | None = None
    """Tangent: n = (upper rows of a) X, the common normal out of a into b (not unit length)."""
    pencil_root: AlgebraicOut | None = None
    """Tangent: the positive double root T* of det(T a + b) (a, b with negative interiors)."""
    certified_by: CertifiedBy = "exact"
    """Which arithmetic proved the point (a tangent pair's is always exact)."""


class WitnessOut(BaseModel):
    """The certified relation, the sentence that explains it and the object that proves it."""

    relation: Decided
    sentence: str
    margin_text: str
    contact_scale: ContactScaleOut
    plane: PlaneOut | None = None
    point: ContactPointOut | None = None
