"""The public witnesses: one function each, for one pair or broadcast stacks, shaped like ``classify``.

Every function takes one pair or stacks (..., n, n) that broadcast, and

* ``method``: "adaptive" (default: certified floats where they certify, exact rationals for the
  rest), "float" (floats only: a pair they cannot certify is a :class:`NoWitness` of kind
  "undecided", as ``classify`` answers UNDECIDED) or "exact" (rationals throughout);
* ``on_invalid``: "raise" (default) a ValueError for the first pair that is invalid or has no
  such witness (a plane of a pair that is not separate, a point of a separate pair), naming it in
  a stack; or "mark" it: that pair's answer is a :class:`NoWitness` saying why.

One pair gives one result (:class:`ContactScale`, :class:`SeparatingPlane`, ...); a stack gives an
object array of those results with the batch shape, so a stack of one gives what one pair gives,
in array form. All of them run through the one filtered evaluation of
:mod:`core.witness.filtered`. Results hold exact rationals whichever arithmetic certified them
(``certified_by`` says which).
"""

from __future__ import annotations

from typing import Literal, TypeAlias, overload

from ..filtered import predicate
from ..options import Method, OnInvalid, check_options
from ..relation import Relation
from ..shapes.quadrics import Matrix, Stack
from .distance import DistanceBracket, distance_exact, distance_float
from .filtered import NoWitness, Pairs, WitnessArray, filtered, finish, read_pairs
from .plane import SeparatingPlane, no_plane, plane_exact, plane_float
from .point import ContactPoint, no_point, point_exact, point_float
from .scale import ContactScale, check_rtol, scale_exact, scale_float
from .witness import Witness, compose

__all__ = ["contact_scale", "separating_plane", "contact_point", "distance", "witness", "Matrix", "Stack"]

Exact: TypeAlias = Literal["adaptive", "exact"]

# the filtered predicates of the witnesses (their counters: core.filter_stats())
_SCALE = predicate("contact_scale")
_PLANE = predicate("separating_plane")
_POINT = predicate("contact_point")
_DISTANCE = predicate("distance")


def _none(rel: Relation) -> str | None:
    return None


# ------------------------------------------------------------------ contact scale


@overload
def contact_scale(A: Matrix, B: Matrix, *, rtol: float = ..., method: Exact = ..., on_invalid: Literal["raise"] = ...) -> ContactScale: ...
@overload
def contact_scale(A: Matrix, B: Matrix, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> ContactScale | NoWitness: ...
@overload
def contact_scale(A: Stack, B: Stack | Matrix, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> WitnessArray: ...
@overload
def contact_scale(A: Matrix, B: Stack, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> WitnessArray: ...
@overload
def contact_scale(A: object, B: object, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> ContactScale | NoWitness | WitnessArray: ...
def contact_scale(
    A: object, B: object, *, rtol: float = 1e-12, method: Method = "adaptive", on_invalid: OnInvalid = "raise"
) -> ContactScale | NoWitness | WitnessArray:
    """Certified contact scale mu*: > 1 separate, = 1 tangent, < 1 overlap.

    Scale both shapes about their own centres by mu* and they touch; for two spheres
    mu* = |c1 - c2| / (r1 + r2).

    Args:
        A: one matrix, or a stack (..., n, n); any input form of :func:`core.classify`.
        B: the same for B (stacks broadcast).
        rtol: relative width asked of each bracket, > 0: hi - lo <= rtol * hi. Floats reach
            about 1e-14; tighter requests are met exactly (``method="float"``: undecided). The
            exact value is :meth:`ContactScale.algebraic`.
        method: "adaptive", "float" or "exact" (module docstring).
        on_invalid: "raise" or "mark" (module docstring).

    Returns:
        One pair: a :class:`ContactScale` (exact rationals ``lo <= mu* <= hi``, ``relation``,
        ``approx``, ``algebraic()``); a stack: an object array of them.

    Raises:
        ValueError: an invalid matrix (``on_invalid="raise"``), sizes that differ, a bad option.

    Examples:
        >>> from flint import fmpq
        >>> sphere = lambda x, r: [[1, 0, 0, -x], [0, 1, 0, 0], [0, 0, 1, 0], [-x, 0, 0, x * x - r * r]]
        >>> cs = contact_scale(sphere(0, 1), sphere(5, 1.5))      # mu = 5 / 2.5
        >>> cs.lo, cs.hi, str(cs.relation)
        (2, 2, 'separate')
        >>> contact_scale(sphere(0, 1), sphere(2, 1)).relation
        <Relation.TANGENT: 1>
        >>> cs = contact_scale(sphere(0, 1), sphere(1, fmpq(1, 3)), method="exact")    # mu = 1 / (4/3)
        >>> cs.lo, str(cs.relation), str(cs.certified_by)
        (3/4, 'overlap', 'exact')
        >>> [c.lo for c in contact_scale([sphere(0, 1)], [sphere(5, 1.5)])]   # a stack of one
        [2]
    """
    check_rtol(rtol)
    check_options(method, on_invalid)
    pairs = read_pairs(A, B, method)
    out = filtered(
        pairs,
        what="contact scale",
        missing=_none,
        float_stage=lambda p, todo: scale_float(p, todo, rtol),
        exact_stage=lambda p, i: scale_exact(p, i, rtol),
        counter=_SCALE,
    )
    return finish(out, pairs, on_invalid)


# ------------------------------------------------------------------ separating plane


@overload
def separating_plane(A: Matrix, B: Matrix, *, method: Exact = ..., on_invalid: Literal["raise"] = ...) -> SeparatingPlane: ...
@overload
def separating_plane(A: Matrix, B: Matrix, *, method: Method = ..., on_invalid: OnInvalid = ...) -> SeparatingPlane | NoWitness: ...
@overload
def separating_plane(A: Stack, B: Stack | Matrix, *, method: Method = ..., on_invalid: OnInvalid = ...) -> WitnessArray: ...
@overload
def separating_plane(A: Matrix, B: Stack, *, method: Method = ..., on_invalid: OnInvalid = ...) -> WitnessArray: ...
@overload
def separating_plane(A: object, B: object, *, method: Method = ..., on_invalid: OnInvalid = ...) -> SeparatingPlane | NoWitness | WitnessArray: ...
def separating_plane(
    A: object, B: object, *, method: Method = "adaptive", on_invalid: OnInvalid = "raise"
) -> SeparatingPlane | NoWitness | WitnessArray:
    """A plane n.x = d with A strictly in n.x < d and B strictly in n.x > d, certified.

    Args:
        A: one matrix, or a stack (..., n, n); any input form of :func:`core.classify`.
        B: the same for B (stacks broadcast).
        method: "adaptive", "float" or "exact" (module docstring).
        on_invalid: "raise" or "mark" (module docstring); a pair that is not separate has no
            separating plane.

    Returns:
        One pair: a :class:`SeparatingPlane` (exact rational ``normal``, ``offset``; ``unit()``
        floats for drawing); a stack: an object array of them.

    Raises:
        ValueError: the pair is not separate (tangent or overlapping: no plane separates it
            strictly) or a matrix is invalid (``on_invalid="raise"``), or a bad option.

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> p = separating_plane(circle(0), circle(3))
        >>> p.normal, p.offset
        ((1, 0), 3/2)
        >>> separating_plane(circle(0), circle(2))
        Traceback (most recent call last):
        ...
        ValueError: A and B are tangent: they touch, so no plane separates them strictly (contact_point gives where)
        >>> [type(p).__name__ for p in separating_plane([circle(0)] * 2, [circle(3), circle(2)], on_invalid="mark")]
        ['SeparatingPlane', 'NoWitness']
    """
    check_options(method, on_invalid)
    pairs = read_pairs(A, B, method)
    out = filtered(pairs, what="separating plane", missing=no_plane, float_stage=plane_float, exact_stage=plane_exact, counter=_PLANE)
    return finish(out, pairs, on_invalid)


# ------------------------------------------------------------------ contact point


@overload
def contact_point(A: Matrix, B: Matrix, *, method: Exact = ..., on_invalid: Literal["raise"] = ...) -> ContactPoint: ...
@overload
def contact_point(A: Matrix, B: Matrix, *, method: Method = ..., on_invalid: OnInvalid = ...) -> ContactPoint | NoWitness: ...
@overload
def contact_point(A: Stack, B: Stack | Matrix, *, method: Method = ..., on_invalid: OnInvalid = ...) -> WitnessArray: ...
@overload
def contact_point(A: Matrix, B: Stack, *, method: Method = ..., on_invalid: OnInvalid = ...) -> WitnessArray: ...
@overload
def contact_point(A: object, B: object, *, method: Method = ..., on_invalid: OnInvalid = ...) -> ContactPoint | NoWitness | WitnessArray: ...
def contact_point(
    A: object, B: object, *, method: Method = "adaptive", on_invalid: OnInvalid = "raise"
) -> ContactPoint | NoWitness | WitnessArray:
    """Where the pair meets: the exact contact point and normal (tangent) or a point inside both (overlap).

    Args:
        A: one matrix, or a stack (..., n, n); any input form of :func:`core.classify`.
        B: the same for B (stacks broadcast).
        method: "adaptive", "float" or "exact" (module docstring). A tangent pair's point is
            exact algebra: under "float" it is undecided.
        on_invalid: "raise" or "mark" (module docstring); a separate pair has no contact point.

    Returns:
        One pair: a :class:`ContactPoint`. Tangent: exact point and common normal (rational, or
        real algebraic with isolating intervals; decimals to any digits). Overlap: a rational
        point certified strictly inside both shapes. A stack: an object array of them.

    Raises:
        ValueError: the pair is separate or invalid (``on_invalid="raise"``), or a bad option.

    Examples:
        >>> circle = lambda x, r: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - r * r]]
        >>> c = contact_point(circle(0, 1), circle(3, 2))          # touch at (1, 0)
        >>> c.rational_point, [str(v.value) for v in c.normal], str(c.relation)
        ((1, 0), ['1', '0'], 'tangent')
        >>> contact_point(circle(0, 1), circle(1, 1)).rational_point   # inside both
        (1/2, 0)
    """
    check_options(method, on_invalid)
    pairs = read_pairs(A, B, method)
    out = filtered(pairs, what="contact point", missing=no_point, float_stage=point_float, exact_stage=point_exact, counter=_POINT)
    return finish(out, pairs, on_invalid)


# ------------------------------------------------------------------ distance


@overload
def distance(A: Matrix, B: Matrix, *, rtol: float = ..., method: Exact = ..., on_invalid: Literal["raise"] = ...) -> DistanceBracket: ...
@overload
def distance(A: Matrix, B: Matrix, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> DistanceBracket | NoWitness: ...
@overload
def distance(A: Stack, B: Stack | Matrix, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> WitnessArray: ...
@overload
def distance(A: Matrix, B: Stack, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> WitnessArray: ...
@overload
def distance(A: object, B: object, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> DistanceBracket | NoWitness | WitnessArray: ...
def distance(
    A: object, B: object, *, rtol: float = 1e-12, method: Method = "adaptive", on_invalid: OnInvalid = "raise"
) -> DistanceBracket | NoWitness | WitnessArray:
    """Certified bracket of the Euclidean distance between two ellipses/ellipsoids.

    Args:
        A: one matrix, or a stack (..., n, n); any input form of :func:`core.classify`.
        B: the same for B (stacks broadcast).
        rtol: relative width asked of the bracket, hi - lo <= rtol * hi (> 0).
        method: "adaptive", "float" or "exact" (module docstring).
        on_invalid: "raise" or "mark" (module docstring).

    Returns:
        One pair: a :class:`DistanceBracket` (lo <= dist <= hi exactly, with a direction n whose
        empty slab proves ``lo`` and points p in A, q in B with |p - q| <= hi; 0 exactly for
        tangent and overlapping pairs); a stack: an object array of them.

    Examples:
        >>> from flint import fmpq
        >>> circle = lambda x, r: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - r * r]]
        >>> b = distance(circle(0, 1), circle(5, 2))          # 5 - 1 - 2
        >>> b.lo <= 2 <= b.hi, b.hi - b.lo <= b.hi * fmpq(1, 10**12)
        (True, True)
        >>> distance(circle(0, 1), circle(2, 1)).hi
        0
    """
    check_rtol(rtol)
    check_options(method, on_invalid)
    pairs = read_pairs(A, B, method)
    out = filtered(
        pairs,
        what="distance",
        missing=_none,
        float_stage=lambda p, todo: distance_float(p, todo, rtol),
        exact_stage=lambda p, i: distance_exact(p, i, rtol),
        counter=_DISTANCE,
    )
    return finish(out, pairs, on_invalid)


# ------------------------------------------------------------------ witness


@overload
def witness(A: Matrix, B: Matrix, *, rtol: float = ..., method: Exact = ..., on_invalid: Literal["raise"] = ...) -> Witness: ...
@overload
def witness(A: Matrix, B: Matrix, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> Witness | NoWitness: ...
@overload
def witness(A: Stack, B: Stack | Matrix, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> WitnessArray: ...
@overload
def witness(A: Matrix, B: Stack, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> WitnessArray: ...
@overload
def witness(A: object, B: object, *, rtol: float = ..., method: Method = ..., on_invalid: OnInvalid = ...) -> Witness | NoWitness | WitnessArray: ...
def witness(
    A: object, B: object, *, rtol: float = 1e-12, method: Method = "adaptive", on_invalid: OnInvalid = "raise"
) -> Witness | NoWitness | WitnessArray:
    """The witness of the certified relation, with the sentence that explains it.

    The contact scale for every relation, and the separating plane (separate), the exact
    contact point and normal (tangent) or a point inside both (overlap). One read of the pairs
    and one contact function per pair serve all of them. For one float pair the floats do the
    work in a few tenths of a millisecond (the scene's drag path), exact rationals only what
    they cannot certify; ``method="float"`` never goes exact.

    Args:
        A: one matrix, or a stack (..., n, n); any input form of :func:`core.classify`.
        B: the same for B (stacks broadcast).
        rtol: relative width of the contact-scale bracket.
        method: "adaptive", "float" or "exact" (module docstring).
        on_invalid: "raise" or "mark" (module docstring).

    Returns:
        One pair: a :class:`Witness` (relation, sentence, contact scale, plane or point); a
        stack: an object array of them.

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> w = witness(circle(0), circle(3))
        >>> w.sentence, w.plane.normal, w.plane.offset, w.margin
        ('separate: this plane separates them', (1, 0), 3/2, '50 % apart')
        >>> witness(circle(0), circle(2)).point.rational_point
        (1, 0)
    """
    check_rtol(rtol)
    check_options(method, on_invalid)
    pairs = read_pairs(A, B, method)
    return finish(_witnesses(pairs, rtol), pairs, on_invalid)


def _witnesses(pairs: Pairs, rtol: float) -> list[Witness | NoWitness]:
    scales = filtered(
        pairs,
        what="contact scale",
        missing=_none,
        float_stage=lambda p, todo: scale_float(p, todo, rtol),
        exact_stage=lambda p, i: scale_exact(p, i, rtol),
        counter=_SCALE,
    )
    planes = filtered(pairs, what="separating plane", missing=no_plane, float_stage=plane_float, exact_stage=plane_exact, counter=_PLANE)
    points = filtered(pairs, what="contact point", missing=no_point, float_stage=point_float, exact_stage=point_exact, counter=_POINT)
    out: list[Witness | NoWitness] = []
    for s, pl, pt in zip(scales, planes, points, strict=True):
        rel = s.relation
        out.append(compose(s, pl if rel == Relation.SEPARATE else pt))
    return out
