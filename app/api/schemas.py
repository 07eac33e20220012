"""Pydantic models at the boundary of the HTTP API (requests in, responses out).

Numbers: a JSON number is taken as the binary float (or integer) it is; a string is an exact
decimal or fraction ("0.1" is 1/10, "3/7"). NaN and infinity (``NaN``/``Infinity`` tokens that
Python's JSON reader accepts) are rejected with 422. A shape is a 3x3 / 4x4 matrix (nested
lists) or ``{"center", "semi_axes", "orientation"}``; see :func:`app.api.convert.quadric_input`
for when that shape is built exactly.
"""

from __future__ import annotations

import math
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

from core.rationals import MAX_NUMBER_CHARS, to_fmpq

__all__ = [
    "Number",
    "Matrix",
    "ShapeIn",
    "Quadric",
    "PairIn",
    "PairItem",
    "BatchIn",
    "ClassifyIn",
    "ClassifyOut",
    "QuantityOut",
    "ExplainOut",
    "HealthOut",
    "Expr",
    "Motion",
    "AnalyseIn",
    "PresetOut",
    "AnalyseOut",
    "ErrorItem",
    "ErrorOut",
    "ERROR_RESPONSES",
]

MAX_INT_DIGITS = MAX_NUMBER_CHARS
"""Largest integer accepted as a JSON number, in decimal digits (as for number strings)."""


def _number(v: Any) -> int | float | str:
    """Check one JSON number or number string (value kept as given; core converts it exactly)."""
    if isinstance(v, bool):
        raise ValueError(f"a boolean is not a number: {v!r}")
    if isinstance(v, int):
        if v and math.log10(abs(v)) >= MAX_INT_DIGITS:
            raise ValueError(f"integer too large (more than {MAX_INT_DIGITS} digits); send it as a string fraction")
        return v
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"not a finite number: {v!r} (NaN and infinity are not accepted)")
        return v
    if isinstance(v, str):
        to_fmpq(v)  # raises ValueError saying what is wrong with the string
        return v
    raise ValueError(f"expected a number or a number string like '3/7', got {type(v).__name__}")


Number = Annotated[
    int | float | str,
    PlainValidator(_number),
    WithJsonSchema(
        {
            "anyOf": [
                {"type": "number"},
                {
                    "type": "string",
                    "maxLength": MAX_NUMBER_CHARS,
                    "description": "exact decimal or fraction: '0.1', '-3/7', '1e-9'",
                    "examples": ["3/7", "0.1"],
                },
            ]
        }
    ),
]
"""A finite JSON number (the binary value it is) or an exact number string."""

Row = Annotated[list[Number], Field(min_length=3, max_length=4)]
Matrix = Annotated[
    list[Row],
    Field(
        min_length=3,
        max_length=4,
        description="symmetric 3x3 (ellipse, on (x, y, 1)) or 4x4 (ellipsoid) matrix, interior X^T A X < 0",
        examples=[[[1, 0, 0], [0, 1, 0], [0, 0, -1]]],
    ),
]


class ShapeIn(BaseModel):
    """An ellipse or ellipsoid by centre, semi-axes and orientation."""

    model_config = ConfigDict(extra="forbid")

    center: Annotated[list[Number], Field(min_length=2, max_length=3)]
    """(x, y) or (x, y, z)."""
    semi_axes: Annotated[list[Number], Field(min_length=2, max_length=3)]
    """Positive lengths along the body axes, as many as centre coordinates."""
    orientation: Number | Annotated[list[Number], Field(min_length=4, max_length=4)] | None = Field(
        default=None,
        description="2D: angle in radians (float) or quaternion [w, 0, 0, z]; 3D: quaternion [w, x, y, z] "
        "(need not be unit). Omitted: axis-aligned.",
    )


def _quadric_kind(v: Any) -> str:
    return "shape" if isinstance(v, dict | ShapeIn) else "matrix"


Quadric = Annotated[
    Annotated[Matrix, Tag("matrix")] | Annotated[ShapeIn, Tag("shape")],
    Discriminator(_quadric_kind),
]
"""A matrix (nested lists) or a shape object."""

MethodName = Literal["adaptive", "exact", "float"]


class PairItem(BaseModel):
    """One pair of a batch."""

    model_config = ConfigDict(extra="forbid")

    a: Quadric
    b: Quadric


class PairIn(PairItem):
    """One pair to classify."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {"a": [[1, 0, 0], [0, 1, 0], [0, 0, -1]], "b": [[1, 0, -2], [0, 1, 0], [-2, 0, 3]]},
                {"a": {"center": [0, 0], "semi_axes": [1, 1]}, "b": {"center": ["2.000000001", 0], "semi_axes": [1, 1]}},
            ]
        },
    )

    method: MethodName = Field(
        default="adaptive",
        description="adaptive: float filter, exact rationals where it abstains; exact: rationals only; "
        "float: filter only (may answer 'undecided')",
    )


class BatchIn(BaseModel):
    """Several pairs at once; the answer is a list in the same order."""

    model_config = ConfigDict(extra="forbid")

    pairs: Annotated[list[PairItem], Field(min_length=1)]
    method: MethodName = "adaptive"


def _classify_kind(v: Any) -> str:
    return "batch" if isinstance(v, dict) and "pairs" in v or isinstance(v, BatchIn) else "pair"


ClassifyIn = Annotated[
    Annotated[PairIn, Tag("pair")] | Annotated[BatchIn, Tag("batch")],
    Discriminator(_classify_kind),
]

RelationName = Literal["separate", "tangent", "overlap", "undecided"]


class ClassifyOut(BaseModel):
    """The certified relation of one pair."""

    relation: RelationName
    """'undecided' only with method 'float'."""
    certified_by: Literal["float", "exact"] | None
    """Arithmetic that certified the relation: the float filter (with its proven error bound)
    or exact rationals; None when undecided."""
    kind: Literal["ellipse", "ellipsoid"]
    method: MethodName


class QuantityOut(BaseModel):
    """One number of the decision (see core.explain.Quantity)."""

    name: str
    approx: float | None
    """Float value (None if it overflows a double); display only."""
    exact: str | None = None
    """Exact rational 'p/q' when the exact path computed it."""
    bound: float | None = None
    """|exact - approx| <= bound when the float filter computed it."""
    sign: int | None = None
    """Certified sign -1, 0, 1 (None when not certified)."""


class ExplainOut(BaseModel):
    """Everything behind one decision."""

    n: Literal[3, 4]
    relation: RelationName
    certified_by: Literal["float", "exact"]
    rule: str
    rule_text: str
    var: int
    coefficients: list[QuantityOut]
    """a_0 .. a_n of P(T) = det(T A + B), ascending."""
    s0: QuantityOut | None = None
    s1: QuantityOut | None = None
    s10: QuantityOut | None = None
    subresultants_needed: list[str]


# --- motions (the JSON format of core.motions, shared with the scene and the presets) ---------

MAX_EXPRESSION_SCHEMA_CHARS = 100_000
"""Static cap in the schema; the real limit is ApiSettings.max_expression_chars (checked per request)."""


def _expression(v: Any) -> int | float | str:
    """A number (kept as given) or an expression string in t (parsed by core.expressions)."""
    if isinstance(v, str):
        if len(v) > MAX_EXPRESSION_SCHEMA_CHARS:
            raise ValueError(f"expression too long ({len(v)} characters)")
        return v
    return _number(v)


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


class AlgebraicOut(BaseModel):
    """An exact real time: decimal value, isolating interval with rational ends, exact value if rational."""

    value: str
    """Decimal to the requested digits."""
    approx: float | None
    exact: str | None
    """"p/q" when the time is rational, else None."""
    isolating: list[str]
    """[lo, hi] rational ends of an interval that holds this time and no other candidate."""


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


class ErrorItem(BaseModel):
    """One validation error: where (``loc``), what (``msg``), which kind (``type``)."""

    loc: list[str | int]
    msg: str
    type: str


class ErrorOut(BaseModel):
    """Every 4xx/503 body: a message saying what is wrong, or a list of located errors."""

    detail: str | list[ErrorItem]


ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    400: {"model": ErrorOut, "description": "Unreadable body (e.g. JSON nested too deeply)"},
    413: {"model": ErrorOut, "description": "Body over the size limit"},
    422: {"model": ErrorOut, "description": "Invalid input: the message says what is wrong"},
}
"""Error responses documented on every API route."""


class HealthOut(BaseModel):
    """Liveness and load."""

    status: Literal["ok"]
    analyses_running: int
    max_concurrent_analyses: int
