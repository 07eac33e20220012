"""Pydantic models of moving shapes (the JSON format of :mod:`core.moving.motions`), /api/analyse and presets.

A motion is a bare matrix of expressions in t, ``{"matrix": ...}``, or ``{"shape": ...,
"translation": ..., "rotation": ..., "scale": ...}``; expressions are parsed exactly by
core.moving.expressions (never evaluated by Python). Response models mirror
``core.moving.analysis.MotionAnalysis.to_dict()``.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    PlainValidator,
    Tag,
    WithJsonSchema,
)

from .schemas import AlgebraicOut, RelationName, checked_number

__all__ = ["Expr", "Motion", "AnalyseIn", "AnalyseOut", "PresetOut"]

# --- motions (the JSON format of core.moving.motions, shared with the scene and the presets) ---------

MAX_EXPRESSION_SCHEMA_CHARS = 100_000
"""Static cap in the schema; the real limit is ApiSettings.max_expression_chars (checked per request)."""


def _expression(v: Any) -> int | float | str:
    """A number (kept as given) or an expression string in t (parsed by core.moving.expressions)."""
    if isinstance(v, str):
        if len(v) > MAX_EXPRESSION_SCHEMA_CHARS:
            raise ValueError(f"expression too long ({len(v)} characters)")
        return v
    return checked_number(v)


Expr = Annotated[
    int | float | str,
    PlainValidator(_expression),
    WithJsonSchema(
        {
            "anyOf": [
                {"type": "number"},
                {
                    "type": "string",
                    "maxLength": MAX_EXPRESSION_SCHEMA_CHARS,
                    "description": "expression in t: + - * / ^ ( ) numbers t sqrt(c), e.g. '(12*t - 11)/2', 'sqrt(2)*t'",
                    "examples": ["4*t - 2", "2*(t^2 - 1)/(t^2 + 1)"],
                },
            ]
        }
    ),
]
"""A number or an expression string in t (exact; never evaluated by Python)."""

ExprMatrix = Annotated[list[Annotated[list[Expr], Field(min_length=3, max_length=4)]], Field(min_length=3, max_length=4)]


class MotionShapeIn(BaseModel):
    """Body shape of a moving ellipse/ellipsoid; every number may be an expression in t."""

    model_config = ConfigDict(extra="forbid")

    center: Annotated[list[Expr], Field(min_length=2, max_length=3)]
    semi_axes: Annotated[list[Expr], Field(min_length=2, max_length=3)]
    orientation: Expr | Annotated[list[Expr], Field(min_length=2, max_length=4)] | None = Field(
        default=None, description="2D: angle (float radians) or [w, z]; 3D: quaternion [w, x, y, z]"
    )


class QuaternionRotation(BaseModel):
    """Rotation by a quaternion of expressions (divided by |q|^2: a rational rotation)."""

    model_config = ConfigDict(extra="forbid")

    quaternion: Annotated[list[Expr], Field(min_length=2, max_length=4)]
    """3D: [w, x, y, z]; 2D: [w, z]."""


class MatrixRotation(BaseModel):
    """Rotation by an explicit (orthogonal) matrix of expressions."""

    model_config = ConfigDict(extra="forbid")

    matrix: Annotated[list[Annotated[list[Expr], Field(min_length=2, max_length=3)]], Field(min_length=2, max_length=3)]


def _rotation_kind(v: Any) -> str:
    return "quaternion" if isinstance(v, dict) and "quaternion" in v or isinstance(v, QuaternionRotation) else "matrix"


Rotation = Annotated[
    Annotated[QuaternionRotation, Tag("quaternion")] | Annotated[MatrixRotation, Tag("matrix")],
    Discriminator(_rotation_kind),
]


class MotionByShape(BaseModel):
    """x_world = R(t) diag(scale(t)) x_body + translation(t)."""

    model_config = ConfigDict(extra="forbid")

    shape: MotionShapeIn
    translation: Annotated[list[Expr], Field(min_length=2, max_length=3)] | None = None
    rotation: Rotation | None = None
    scale: Annotated[list[Expr], Field(min_length=2, max_length=3)] | None = None


class MotionByMatrix(BaseModel):
    """The symmetric matrix A(t) itself, entries expressions in t."""

    model_config = ConfigDict(extra="forbid")

    matrix: ExprMatrix


def _motion_kind(v: Any) -> str:
    if isinstance(v, list):
        return "rows"
    if isinstance(v, MotionByMatrix) or isinstance(v, dict) and "matrix" in v:
        return "matrix"
    return "shape"


Motion = Annotated[
    Annotated[ExprMatrix, Tag("rows")] | Annotated[MotionByMatrix, Tag("matrix")] | Annotated[MotionByShape, Tag("shape")],
    Discriminator(_motion_kind),
]
"""A moving shape: a bare matrix of expressions, ``{"matrix": ...}`` or ``{"shape": ..., ...}``."""

IntervalEnd = Expr | None


class AnalyseIn(BaseModel):
    """Two motions and the time interval to analyse (a preset can be posted as it is)."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {
                    "a": {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["t", "0"]},
                    "b": {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["-t", "0"]},
                    "interval": ["-2", "2"],
                    "digits": 20,
                }
            ]
        },
    )

    a: Motion
    b: Motion
    interval: Annotated[list[IntervalEnd], Field(min_length=2, max_length=2)] = Field(
        default=[None, None], description="[lo, hi]: numbers, exact strings, or null for an infinite end"
    )
    digits: Annotated[int, Field(ge=1, le=100_000)] = Field(default=20, description="decimal digits of event values")
    polynomials: bool = Field(default=True, description="include a_i(t), s0, s1, s1,0 as strings")
    name: str | None = Field(default=None, description="ignored (lets a preset be posted unchanged)")
    description: str | None = Field(default=None, description="ignored")


class EventOut(AlgebraicOut):
    """A tangency instant (or, under ``roots``, another candidate) and what happens there."""

    relation: RelationName
    kind: str
    """change, touch or endpoint (events); root (other candidates)."""
    before: RelationName | None
    after: RelationName | None
    rule: str


class IntervalOut(BaseModel):
    """An open interval of constant relation (lo/hi None = infinite)."""

    lo: AlgebraicOut | None
    hi: AlgebraicOut | None
    relation: RelationName
    sample: str
    """Rational point where the relation was decided exactly."""


class SignRowOut(BaseModel):
    """One row of the sign table: at a candidate ("point") or an interval's sample."""

    where: Literal["point", "interval"]
    t: str
    a: list[Literal["+", "0", "-"]]
    """Signs of a_n .. a_0 (descending, as Var is written)."""
    s0: Literal["+", "0", "-"]
    s1: Literal["+", "0", "-"]
    s10: Literal["+", "0", "-"]
    var: int
    relation: RelationName
    rule: str


class PolynomialsOut(BaseModel):
    """a_i(t), ŝ0, ŝ1, ŝ1,0 (same signs as s0, s1, s1,0) as strings in t, with degrees."""

    a: list[str]
    s0: str
    s1: str
    s10: str
    degrees: dict[str, int | list[int]]


class AnalyseOut(BaseModel):
    """Exact interference analysis of two moving shapes over the interval."""

    dimension: Literal[2, 3]
    interval: list[str | None]
    case: Literal["s0", "s1", "none"]
    """Which polynomial gave the candidates (paper 4.4.1 / 4.4.2 / 4.4.3)."""
    sqrt_d: int
    digits: int
    events: list[EventOut]
    roots: list[EventOut]
    intervals: list[IntervalOut]
    sign_table: list[SignRowOut]
    rules: dict[str, str]
    a: Motion
    b: Motion
    polynomials: PolynomialsOut | None = None


class PresetOut(BaseModel):
    """A built-in moving pair, in the input format of /api/analyse."""

    name: str
    description: str
    a: Motion
    b: Motion
    interval: list[IntervalEnd]
