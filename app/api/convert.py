"""Between the pydantic models and core: build matrices, call the classifier, map errors.

No mathematics here: shapes go to :func:`core.quadric_from_axes`, matrices to
:func:`core.validate_quadric` (so every bad matrix is named "a" or "b", as in the JSON), and the
relation comes from :func:`core.classify` (:func:`classify_items`: one vectorised call for a whole
batch). Bad input is one error, :class:`core.InvalidInput`: core's message prefixed with where in the
request the culprit is, its pair index and matrix name ("a" or "b") attached; the app's one
exception handler answers it 422. No FastAPI here: this runs in the worker processes too.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any, cast

import numpy as np

from core import (
    Box,
    Certifier,
    InvalidInput,
    Relation,
    bodies_from_axes,
    classify_detailed,
    quadric_from_axes,
    validate_quadric,
)
from core.shapes.numbers import binary64, to_fmpq

from ..jobs import Budget
from .contacts_schemas import ContactsIn
from .schemas import ClassifyOut, PairItem, RelationName, ShapeIn

__all__ = ["bad_input", "quadric_input", "checked_pair", "classify_items", "Plain", "plain_shapes", "is_plain_pair", "contacts_matrices"]


@contextmanager
def bad_input(where: str = "", *, pair: int | None = None, matrix: str | None = None) -> Iterator[None]:
    """A core ``ValueError`` as :class:`core.InvalidInput`, its message prefixed by ``where``.

    Args:
        where: where in the request the culprit is ("pairs[3]: b: ").
        pair: its index in the request's batch (None: not a batch).
        matrix: the request's name of the culprit ("a", "b"), when one shape is.
    """
    try:
        yield
    except (ValueError, ArithmeticError) as e:  # ArithmeticError: e.g. a number too big for a float
        inner = e if isinstance(e, InvalidInput) else None
        raise InvalidInput(
            f"{where}{e}", pair=pair, matrix=matrix or (inner.matrix if inner else None), reason=str(e)
        ) from None


_API_NAMES = {"A": "a", "B": "b"}
"""Core's names of the two matrices of a pair -> the request's fields."""


def _in_api_names(e: InvalidInput, where: str, pair: int | None) -> InvalidInput:
    """Core's error about matrix "A" or "B" of a pair, in the request's names ("a", "b") and place."""
    name = _API_NAMES.get(e.matrix or "", e.matrix)
    reason = e.reason
    if e.matrix and name and reason.startswith(e.matrix + " "):
        reason = name + reason[len(e.matrix):]
    return InvalidInput(f"{where}{reason}", pair=pair, matrix=name, reason=reason)


def _is_exact(v: Any) -> bool:
    return not isinstance(v, float)


def quadric_input(q: list[list[Any]] | ShapeIn) -> Any:
    """Core input for a matrix or a shape.

    A shape is built **exactly** (rational matrix) when no number in it is a JSON float and the
    orientation is absent or a quaternion; otherwise in float64 (number strings are rounded to
    the nearest double and a 2D angle is radians), and that float matrix is then taken as the
    exact binary rationals it holds, like any float input.
    """
    if not isinstance(q, ShapeIn):
        return q
    orientation = q.orientation
    if len(q.center) == 3 and orientation is not None and not isinstance(orientation, list):
        raise ValueError("a 3D orientation is a quaternion [w, x, y, z], not an angle")
    values = [*q.center, *q.semi_axes]
    if isinstance(orientation, list):
        values += orientation
    exact = all(_is_exact(v) for v in values) and (orientation is None or isinstance(orientation, list))
    if exact:
        return quadric_from_axes(q.center, q.semi_axes, orientation, exact=True)

    def fl(v: Any) -> float:
        try:
            return v if isinstance(v, float) else float(to_fmpq(v))
        except OverflowError:
            raise ValueError(f"{v!r} is too large for a float (this shape is built in floats)") from None

    if isinstance(orientation, list):
        orientation = [fl(v) for v in orientation]
    elif orientation is not None:
        orientation = fl(orientation)
    return quadric_from_axes([fl(v) for v in q.center], [fl(v) for v in q.semi_axes], orientation)


def _float_matrix(m: Any) -> Any:
    """A square matrix of JSON numbers as a float64 array (the same values: the float filter can run), else unchanged.

    Only for matrices :func:`plain_shapes` found plain: every entry is a binary64 value, so the
    conversion is exact and not tested again. A matrix that is not square stays as it is: the
    validation names the problem.
    """
    if isinstance(m, np.ndarray) or _size(m) is None:
        return m
    return np.array(m, dtype=np.float64)


def _size(m: Any) -> int | None:
    """N for an n x n matrix (3 or 4), else None."""
    try:
        n = len(m)
        return n if n in (3, 4) and all(len(row) == n for row in m) else None
    except TypeError:
        return None


def _converted(pair: PairItem, where: str, index: int | None = None, plain: Plain | None = None) -> tuple[Any, Any]:
    """Both shapes as core input (float64 arrays for plain matrices), not validated yet.

    ``plain``: the request's decision (:func:`plain_shapes`), made once by its route; None: made here.
    """
    flags = plain_shapes(pair) if plain is None else plain
    out = []
    for name, q, flat in (("a", pair.a, flags[0]), ("b", pair.b, flags[1])):
        with bad_input(f"{where}{name}: ", pair=index, matrix=name):
            m = quadric_input(q)
            out.append(_float_matrix(m) if flat and not isinstance(q, ShapeIn) else m)  # a shape builds its own
    return out[0], out[1]


def _validated(a: Any, b: Any, where: str, index: int | None = None) -> None:
    """InvalidInput naming "a" or "b" for an invalid matrix, or for an ellipse paired with an ellipsoid."""
    for name, m in (("a", a), ("b", b)):
        with bad_input(where, pair=index, matrix=name):
            validate_quadric(m, name=name)
    if len(a) != len(b):
        reason = f"a is {len(a)}x{len(a)} and b is {len(b)}x{len(b)}: both must be ellipses (3x3) or both ellipsoids (4x4)"
        raise InvalidInput(f"{where}{reason}", pair=index, reason=reason)


Plain = tuple[bool, bool]
"""Whether each shape of a pair (a, b) holds only JSON numbers that are binary64 values (:func:`plain_shapes`)."""


def plain_shapes(pair: PairItem) -> Plain:
    """Whether each shape of the pair holds only JSON numbers that are binary64 values: the request's one test.

    Matrices or shapes: classifying a pair of such shapes is bounded work (the float filter, at
    worst one exact classification of doubles), so it runs in a server thread; number strings
    (exact values of up to 400 characters and exponents up to 1000) go to the worker processes.
    The route decides this once per request (:func:`core.shapes.numbers.binary64`, once per
    number) and passes it down (:func:`classify_items`), which then builds the float matrices
    without testing the numbers again.
    """
    return _plain(pair.a), _plain(pair.b)


def _plain(q: list[list[Any]] | ShapeIn) -> bool:
    """Whether every number of one shape is a JSON float or a float-exact integer (strings are exact input)."""
    if isinstance(q, ShapeIn):
        o = q.orientation
        values = [*q.center, *q.semi_axes, *(o if isinstance(o, list) else [] if o is None else [o])]
    else:
        values = [v for row in q for v in row]
    return all(binary64(v, typed=True) is not None for v in values)


def is_plain_pair(pair: PairItem) -> bool:
    """True when every number of the pair is a JSON number (a binary64 value): :func:`plain_shapes` of both."""
    return all(plain_shapes(pair))


def checked_pair(pair: PairItem, where: str = "") -> tuple[Any, Any]:
    """Both shapes as core input, validated (:class:`core.InvalidInput` naming "a" or "b" otherwise)."""
    a, b = _converted(pair, where)
    _validated(a, b, where)
    return a, b


def classify_items(
    pairs: Sequence[PairItem], method: str, budget: Budget, *, batch: bool = True, plain: Sequence[Plain] | None = None
) -> list[ClassifyOut]:
    """Certified relation of each pair, with the arithmetic that certified it.

    One :func:`core.classify_detailed` call per matrix size and input kind (float matrices
    vectorised through the float filter; exact-valued ones read exactly), which reports per pair
    which arithmetic certified it; ``budget`` is checked before every pair that needs exact
    arithmetic. The first invalid pair in request order is named (``pairs[i]: b: ...``): a shape
    that cannot be built, or core's own reason (each group is classified with
    ``on_invalid="raise"``: core validates once, its error is renamed to the request's names).
    ``plain``: the route's :func:`plain_shapes` of each pair (None: decided here), not made again.

    Raises:
        InvalidInput: bad input (``pair``: its index in the request, ``matrix``: "a" or "b").
        BudgetExceeded, Cancelled: from ``budget`` (the route answers 503).
    """
    n = len(pairs)
    if plain is not None and len(plain) != n:
        raise ValueError(f"plain: {len(plain)} decisions for {n} pairs")
    where = [f"pairs[{i}]: " if batch else "" for i in range(n)]
    mats: list[tuple[Any, Any] | None] = [None] * n
    index = [i if batch else None for i in range(n)]
    errors: dict[int, InvalidInput] = {}
    for i, pair in enumerate(pairs):
        if i % 64 == 0:
            budget.check(f"while reading pair {i} of {n}")
        try:
            mats[i] = _converted(pair, where[i], index[i], None if plain is None else plain[i])
        except InvalidInput as e:
            errors[i] = e
    codes = np.full(n, int(Relation.INVALID), dtype=np.int8)
    by: list[str | None] = [None] * n
    groups: dict[tuple[int, bool], list[int]] = {}
    for i, m in enumerate(mats):
        if m is None:
            continue
        na, nb = _size(m[0]), _size(m[1])
        if na is None or na != nb:  # not square, or an ellipse with an ellipsoid: core cannot pair them
            try:
                _validated(m[0], m[1], where[i], index[i])
            except InvalidInput as e:
                errors[i] = e
            continue
        floats = isinstance(m[0], np.ndarray) and isinstance(m[1], np.ndarray)
        groups.setdefault((na, floats), []).append(i)
    for (size, floats), idx in groups.items():
        if errors and min(errors) < idx[0]:
            continue  # an earlier pair is already the answer
        if floats:
            A = np.stack([mats[i][0] for i in idx])  # type: ignore[index]
            B = np.stack([mats[i][1] for i in idx])  # type: ignore[index]
        else:
            A, B = np.empty((len(idx), size, size), dtype=object), np.empty((len(idx), size, size), dtype=object)
            for k, i in enumerate(idx):
                A[k], B[k] = mats[i]  # type: ignore[misc]
        budget.check(f"before the {len(idx)} pairs of {size}x{size} matrices")
        try:
            res = classify_detailed(
                A, B, method=method, on_invalid="raise",  # type: ignore[arg-type]
                progress=lambda k, m: budget.check(f"after {k} of the {m} pairs needing exact arithmetic ({n} pairs in the request)"),
            )
        except InvalidInput as e:  # the group's first invalid pair, validated once (by core)
            i = idx[e.pair or 0]
            errors[i] = _in_api_names(e, where[i], index[i])
            continue
        codes[idx] = res.relation
        for k, i in enumerate(idx):
            c = Certifier(int(res.certified_by[k]))
            by[i] = None if c == Certifier.NONE else str(c)
    if errors:  # the first bad pair, in request order, named with the API's names
        raise errors[min(errors)]
    return [
        ClassifyOut(
            relation=cast(RelationName, str(Relation(int(codes[i])))),  # no INVALID: raised above
            certified_by=by[i],  # type: ignore[arg-type]
            kind="ellipse" if len(mats[i][0]) == 3 else "ellipsoid",  # type: ignore[index]
            method=method,  # type: ignore[arg-type]
        )
        for i in range(n)
    ]


def contacts_matrices(body: ContactsIn) -> np.ndarray:
    """The bodies of a contacts request as float matrices (InvalidInput for mixed forms or bad rows).

    The count limit is the route's (checked before this runs in a worker).
    """
    if (body.bodies is None) == (body.matrices is None):
        raise InvalidInput("send either 'bodies' (rows of parameters) or 'matrices', not both or neither")
    if body.matrices is not None:
        sizes = {len(m) for m in body.matrices} | {len(r) for m in body.matrices for r in m}
        if len(sizes) > 1:
            raise InvalidInput("matrices: every matrix must be 3x3 (ellipses) or every one 4x4 (ellipsoids)")
        return np.array(body.matrices, dtype=np.float64).reshape(len(body.matrices), *(2 * (sizes.pop() if sizes else 4,)))
    widths = {len(r) for r in body.bodies or []}
    if not widths:
        return np.zeros((0, 4, 4))
    if widths not in ({10}, {5}):
        raise InvalidInput("bodies: every row must be [x, y, z, a, b, c, qw, qx, qy, qz] (3D) or every row [x, y, a, b, angle] (2D)")
    t = np.array(body.bodies, dtype=np.float64)
    d = 3 if t.shape[1] == 10 else 2
    with bad_input():
        Box.from_any(body.box, d)  # before any matrix is built: what a box is, core's to say
    with bad_input("bodies: "):
        if body.on_invalid == "mark":
            return bodies_from_axes(t[:, :d], t[:, d : 2 * d], t[:, 2 * d :] if d == 3 else t[:, 4], on_invalid="mark")
        return bodies_from_axes(t[:, :d], t[:, d : 2 * d], t[:, 2 * d :] if d == 3 else t[:, 4])
