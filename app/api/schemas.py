"""Pydantic models at the boundary of the HTTP API (requests in, responses out).

Numbers: a JSON number is taken as the binary float (or integer) it is; a string is an exact
decimal or fraction ("0.1" is 1/10, "3/7"). NaN and infinity (``NaN``/``Infinity`` tokens that
Python's JSON reader accepts) are rejected with 422. A shape is a 3x3 / 4x4 matrix (nested
lists) or ``{"center", "semi_axes", "orientation"}``; see :func:`app.api.convert.quadric_input`
for when that shape is built exactly. Motion models live in :mod:`app.api.motion_schemas`.
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

from core.options import Method
from core.shapes.limits import SERVER
from core.shapes.numbers import parse_number

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
    "AlgebraicOut",
    "HealthOut",
    "ErrorItem",
    "ErrorOut",
    "ERROR_RESPONSES",
]


class OutOfRange:
    """A JSON number that cannot be read as given: ``message`` says why and what to send instead."""

    __slots__ = ("text", "message")

    def __init__(self, text: str, message: str) -> None:
        self.text = text
        self.message = message

    def __repr__(self) -> str:
        return f"OutOfRange({self.text[:40]!r})"


assert SERVER.number_chars is not None  # the server caps number strings (core.shapes.limits.SERVER)
MAX_NUMBER_CHARS: int = SERVER.number_chars
"""Longest number string accepted by the API (:data:`core.shapes.limits.SERVER`; the library has none)."""
MAX_INT_DIGITS = MAX_NUMBER_CHARS
"""Largest integer accepted as a JSON number, in decimal digits (as for number strings)."""


def checked_number(v: Any) -> int | float | str:
    """Check one JSON number or number string (value kept as given; core converts it exactly)."""
    if isinstance(v, bool):
        raise ValueError(f"a boolean is not a number: {v!r}")
    if isinstance(v, OutOfRange):  # a JSON number a float cannot hold (app.api.json_body)
        raise ValueError(v.message)
    if isinstance(v, int):
        if v and math.log10(abs(v)) >= MAX_INT_DIGITS:
            raise ValueError(f"integer too large (more than {MAX_INT_DIGITS} digits); send it as a string fraction")
        return v
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"not a finite number: {v!r} (NaN and infinity are not accepted)")
        return v
    if isinstance(v, str):
        parse_number(v, SERVER)  # raises ValueError saying what is wrong with the string
        return v
    raise ValueError(f"expected a number or a number string like '3/7', got {type(v).__name__}")


Number = Annotated[
    int | float | str,
    PlainValidator(checked_number),
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

MethodName = Method
"""core's methods (:data:`core.options.Method`): one list for the library, the CLI and the API."""


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
CertifiedBy = Literal["float", "exact"]


class ClassifyOut(BaseModel):
    """The certified relation of one pair."""

    relation: RelationName
    """'undecided' only with method 'float'."""
    certified_by: CertifiedBy | None
    """Arithmetic that certified the relation: the float filter (with its proven error bound)
    or exact rationals; None when undecided."""
    kind: Literal["ellipse", "ellipsoid"]
    method: MethodName


class QuantityOut(BaseModel):
    """One number of the decision (see core.fixed.explain.Quantity)."""

    name: str
    approx: float | None
    """Float value (None if it overflows a double); display only."""
    exact: str | None = None
    """Exact rational 'p/q' when the exact path computed it."""
    bound: float | None = None
    """|exact - approx| <= bound when the float filter computed it."""
    sign: int | None = None
    """Certified sign -1, 0, 1 (None when not certified)."""
    text: str = ""
    """The value in scientific notation at any size ("-1.23457e+612"), computed exactly: short
    even where ``approx`` is None and ``exact`` runs to thousands of digits."""


class ExplainOut(BaseModel):
    """Everything behind one decision."""

    n: Literal[3, 4]
    relation: RelationName
    certified_by: CertifiedBy
    rule: str
    rule_text: str
    var: int
    coefficients: list[QuantityOut]
    """a_0 .. a_n of P(T) = det(T A + B), ascending."""
    s0: QuantityOut | None = None
    s1: QuantityOut | None = None
    s10: QuantityOut | None = None
    subresultants_needed: list[str]


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
    408: {"model": ErrorOut, "description": "Body stalled or too slow to arrive (ApiSettings.body_stall_s, body_read_s); the connection is closed"},
    413: {"model": ErrorOut, "description": "Body over the size limit"},
    415: {"model": ErrorOut, "description": "Body not sent as JSON (content-type: application/json)"},
    422: {"model": ErrorOut, "description": "Invalid input: the message says what is wrong"},
}
"""Error responses documented on every API route."""


class AlgebraicOut(BaseModel):
    """A real algebraic number: rational ('exact'), or a root of 'polynomial' in 'isolating'.

    The one JSON form of an exact irrational value (:meth:`core.algebra.algebraic.RealAlgebraic.to_dict`):
    witness values, the times of motion events and the ends of motion intervals.
    """

    value: str
    """Decimal to the requested significant digits (error below one unit in the last place)."""
    approx: float | None
    """Float approximation (None if it overflows a double)."""
    exact: str | None
    """'p/q' when the number is rational."""
    isolating: list[str]
    """[lo, hi] rational ends of an interval that holds this root of the polynomial and no other."""
    polynomial: list[str] | None = None
    """Integer coefficients, ascending, of a polynomial it is a root of (None when rational)."""


class HealthOut(BaseModel):
    """Liveness and load."""

    status: Literal["ok"]
    analyses_running: int
    """Jobs running in the worker processes (analyses, explanations, witnesses, contacts...)."""
    max_concurrent_analyses: int
    analyses_waiting: int = 0
    """Requests waiting in the queue for a worker."""
    max_queued_analyses: int = 0
    large_bodies: int = 0
    """Requests with a body over 64 kB in the server (received, read, waiting for a worker or running)."""
    max_large_bodies: int = 0
