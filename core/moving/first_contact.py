"""First contact of two moving shapes: the first t in I where they stop being separate (paper 3.4, 4.4).

A step of the moving analysis (:mod:`core.moving.analysis`) that stops early. With the shapes
separate at the start lo of I, the relation can only change at a real root of the candidate
polynomial of the paper's case (ŝ0 if it is not identically zero, 4.4.1 / 3.4(1); else ŝ1,
4.4.2; none in 4.4.3: the relation is then the same on all of I). So the roots of that
polynomial in (lo, hi] are isolated one at a time, smallest first
(:func:`core.algebra.realroots.roots_in_order`: Descartes after a Moebius map, nothing right of
the current root is isolated), and at each one the relation is decided exactly (the paper's
tree on exact signs, :mod:`core.moving.signs`, asking for ŝ1, ŝ1,0 only when the tree needs
them). The first root where the shapes are not separate is the first contact: they are tangent
there (separation is an open condition in t and an interior point of both shapes stays one
for nearby t, so the first time the closed shapes meet they only touch). Nothing after it is
computed: no sign table, no intervals, no further roots beyond the next one (which bounds the
interval where the relation just after the contact is read).

If the shapes already touch or overlap at lo, the first contact is lo itself.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from flint import fmpq

from ..algebra.algebraic import RealAlgebraic
from ..algebra.qsqrt import QSqrtPoly
from ..algebra.realroots import roots_in_order
from ..filtered import predicate
from ..fixed.exact import classify_exact
from ..options import SWEEP_METHODS, SweepMethod, check_choice
from ..relation import Relation
from .analysis import (
    _Case,
    _motion_pencil,
    _paper_case,
    _strictly_between,
)
from .linear import LinearMotions
from .motions import read_interval
from .result import Event, MotionPencil
from .signs import Signs, decide_with
from .sweep_filter import CONTACT, OVERLAP_AT_START, UNDECIDED, first_contacts_float

__all__ = ["first_contact", "first_contact_of", "first_contacts", "FirstContacts", "bracket"]

_FIRST_CONTACT = predicate("sweep_first_contact")
"""The filtered predicate of :func:`first_contacts` (the sweep's narrow phase; :func:`core.filter_stats`)."""


def first_contact(A_t: Any, B_t: Any, interval: tuple[Any, Any] = (0, 1), *, digits: int = 20) -> Event | None:
    """The first time in I = [lo, hi] at which two moving shapes are not separate, exactly.

    Args:
        A_t: the first moving shape, as for :func:`core.analyse` (nested lists of expressions
            in t, a motion dict, or a :class:`core.moving.motions.Motion`).
        B_t: the second moving shape, likewise.
        interval: (lo, hi) as for :func:`core.analyse`; lo must be finite (the search starts
            there), hi may be None (no end). Default (0, 1): one time step.
        digits: significant digits of the decimal value (1..1000).

    Returns:
        None if the shapes are separate at every t in I. Otherwise the first contact as an
        :class:`core.moving.result.Event` (the type of :func:`core.analyse`'s events):
        ``time`` is t* exactly (a real algebraic number with its isolating interval),
        ``relation`` the relation at t*, ``before``/``after`` the relations just before/after
        (None outside I), ``value`` t* in decimals, ``rule`` the rule of the paper's tree that
        decided at t*. ``kind`` is ``"endpoint"`` when t* = lo (the shapes already touch or
        overlap at the start, relation TANGENT or OVERLAP) or t* = hi, ``"change"`` when the
        relation after t* is not separate, ``"touch"`` when the shapes only touch at t* and
        separate again.

    Raises:
        ValueError: as :func:`core.analyse` (unreadable input, a shape that is not an
            ellipse/ellipsoid somewhere in I, ...), or an infinite lo.

    Guarantee:
        Exact: every sign is decided with exact arithmetic (rationals, Q(sqrt d)); t* is
        the first root of the candidate polynomial where the exact relation is not separate.

    References:
        Caravantes et al., Sections 3.4 and 4.4.

    Examples:
        >>> circle = lambda x: [["1", "0", f"-({x})"], ["0", "1", "0"], [f"-({x})", "0", f"({x})^2 - 1"]]
        >>> e = first_contact(circle("3 - 4*t"), circle("0"), (0, 1))    # centres 3 - 4t apart
        >>> e.value, str(e.relation), e.kind, str(e.before), str(e.after)
        ('0.25', 'tangent', 'change', 'separate', 'overlap')
        >>> first_contact(circle("3 + t"), circle("0"), (0, 1)) is None  # moving apart
        True
        >>> e = first_contact(circle("1"), circle("0"), (0, 1))          # overlapping at the start
        >>> e.value, str(e.relation), e.kind
        ('0', 'overlap', 'endpoint')
    """
    if not isinstance(digits, int) or isinstance(digits, bool) or not 1 <= digits <= 1000:
        raise ValueError(f"digits must be an integer in 1..1000, got {digits!r}")
    lo, hi = read_interval(interval)
    if lo is None:
        raise ValueError("first_contact needs a finite start: interval = (lo, hi) with lo a number (hi may be None)")
    return first_contact_of(_motion_pencil(A_t, B_t, lo, hi), lo, hi, digits=digits)


def first_contact_of(pencil: MotionPencil, lo: fmpq, hi: fmpq | None, *, digits: int = 20) -> Event | None:
    """:func:`first_contact` on the exact pencil of a pair (built by :func:`core.moving.analysis._motion_pencil`)."""
    case = _paper_case(pencil, lo, hi)
    polys = _LazyPolys(pencil)
    n = pencil.n
    start = decide_with(n, Signs(polys, lo, set(case.identically_zero)))
    roots = _candidates(case, lo, hi)
    after: Relation | None
    if start.relation != Relation.SEPARATE:
        after = _relation_between(pencil, case, lo, next(roots, None), hi)
        return Event(RealAlgebraic.rational(lo), start.relation, "endpoint", None, after, _decimal(lo, digits), start.rule)
    for alpha in roots:
        dec = decide_with(n, Signs(polys, alpha, case.zero_at_candidates))
        if dec.relation == Relation.SEPARATE:
            continue
        if hi is not None and alpha.compare(hi) == 0:
            after, kind = None, "endpoint"
        else:
            after = _relation_between(pencil, case, alpha, next(roots, None), hi)
            kind = "touch" if after == Relation.SEPARATE else "change"
        _spot_rational(alpha)
        return Event(alpha, dec.relation, kind, Relation.SEPARATE, after, alpha.decimal(digits), dec.rule)
    return None


class _LazyPolys(Mapping[str, QSqrtPoly]):
    """``a0``..``a{n}``, ``s0``, ``s1``, ``s10`` of a pencil; the hats are computed when first read."""

    def __init__(self, pencil: MotionPencil) -> None:
        self.pencil = pencil
        self.names = [f"a{i}" for i in range(pencil.n + 1)] + ["s0", "s1", "s10"]

    def __getitem__(self, name: str) -> QSqrtPoly:
        if name.startswith("a"):
            return self.pencil.a[int(name[1:])]
        return {"s0": lambda: self.pencil.s0, "s1": lambda: self.pencil.s1, "s10": lambda: self.pencil.s10}[name]()

    def __iter__(self) -> Iterator[str]:
        return iter(self.names)

    def __len__(self) -> int:
        return len(self.names)


def _candidates(case: _Case, lo: fmpq, hi: fmpq | None) -> Iterator[RealAlgebraic]:
    """Roots of the case's candidate polynomial in (lo, hi], smallest first (none in 4.4.3)."""
    if case.candidates is None:
        return iter(())
    return roots_in_order(case.candidates, lo, hi)


def _relation_between(
    pencil: MotionPencil, case: _Case, left: RealAlgebraic | fmpq, right: RealAlgebraic | None, hi: fmpq | None
) -> Relation:
    """The relation on the open interval from ``left`` to the next candidate root ``right`` (or hi).

    Constant there (no candidate root inside: paper 3.4/4.4); read exactly at a rational
    sample point right of ``left``'s isolating interval and left of ``right``'s.
    """
    while True:
        a = left if isinstance(left, fmpq) else left.hi
        b = hi if right is None else right.lo
        if b is None or a < b or (right is not None and right.value is not None and a < right.value):
            break
        # the isolating intervals touch: narrow the wider one (a rational one is a point)
        if isinstance(left, RealAlgebraic) and left.value is None and (right is None or left.width >= right.width):
            left.bisect()
        elif right is not None and right.value is None:
            right.bisect()
        else:  # pragma: no cover - two distinct exact points always separate
            raise RuntimeError("candidate roots are not separated")
    if right is not None and right.value is not None:
        b = right.value
    t = _strictly_between(a, b)
    return decide_with(pencil.n, Signs(_LazyPolys(pencil), t, set(case.identically_zero))).relation


def _spot_rational(alpha: RealAlgebraic) -> None:
    """Recognise a simple rational root (printed exactly then, as :func:`core.analyse` does)."""
    if alpha.value is None and not alpha.try_rational():
        alpha.refine_to(alpha.width / 2**40)
        alpha.try_rational()


def _decimal(x: fmpq, digits: int) -> str:
    return RealAlgebraic.rational(x).decimal(digits)


# -------------------------------------------------------------------------------------------
# many pairs of bodies in linear motion: the float filter, exact arithmetic where it abstains


@dataclass
class FirstContacts:
    """First contacts of pairs of bodies in linear motion (see :func:`first_contacts`)."""

    relation: np.ndarray
    """int8 per pair: SEPARATE (never meet in [0, 1]), else the relation at t* (TANGENT, or
    OVERLAP when they already overlap at t = 0)."""
    t_lo: np.ndarray
    """float64: t_lo <= t* (NaN for SEPARATE)."""
    t_hi: np.ndarray
    """float64: t* <= t_hi, t_hi - t_lo <= 1e-9 (NaN for SEPARATE)."""
    certified_by: np.ndarray
    """int8 :class:`core.Certifier`: FLOAT (the filter) or EXACT."""
    times: dict[int, RealAlgebraic] = field(default_factory=dict)
    """t* of the pairs decided by exact arithmetic (by pair index); the others on request."""


def first_contacts(
    bodies: LinearMotions,
    i: np.ndarray,
    j: np.ndarray,
    shift: np.ndarray | None = None,
    *,
    method: SweepMethod = "adaptive",
    chunk: int = 1 << 16,
    progress: Callable[[int, int], None] | None = None,
) -> FirstContacts:
    """Certified first contact of each pair (i[k], j[k]) of bodies in linear motion over [0, 1].

    The certified float filter (:mod:`core.moving.sweep_filter`) brackets t* or proves that the
    pair never meets; where it abstains, exact arithmetic decides on the pair's exact motions
    (:meth:`core.moving.linear.LinearMotions.motion`): the static exact classifier at t = 0 first
    (touching or overlapping there: t* = 0, no motion analysis needed), else
    :func:`first_contact`; the exact t* is bracketed by the floats just below and above.

    Args:
        bodies: the bodies.
        i: int64 (M,) first body of each pair.
        j: int64 (M,) second body.
        shift: (M, d) float vectors added to body j's centre (a periodic image), or None.
        method: "adaptive" (filter, then exact) or "exact" (every pair exactly: slow; tests).
        chunk: pairs per filter call (progress is reported after each).
        progress: optional ``progress(done, total)``.

    Returns:
        :class:`FirstContacts`.
    """
    check_choice(method, SWEEP_METHODS, "method")
    M = int(np.asarray(i).size)
    done = 0

    def blank(_: None) -> FirstContacts:
        """Every pair still to decide: SEPARATE, no bracket (the exact stage writes its answers)."""
        return FirstContacts(np.full(M, Relation.SEPARATE, np.int8), np.full(M, np.nan), np.full(M, np.nan), np.zeros(0, np.int8))

    def floats(_: None) -> tuple[FirstContacts, np.ndarray | None]:
        """The float stage: the certified filter by chunks; its UNDECIDED pairs are the unsure."""
        nonlocal done
        out = blank(None)
        status = np.full(M, UNDECIDED, np.int8)
        for s in range(0, M, chunk):
            part = slice(s, min(s + chunk, M))
            r = first_contacts_float(bodies, i[part], j[part], None if shift is None else shift[part])
            status[part], out.t_lo[part], out.t_hi[part] = r.status, r.t_lo, r.t_hi
            done = part.stop
            if progress is not None:
                progress(done, M)
        out.relation[status == CONTACT] = Relation.TANGENT
        out.relation[status == OVERLAP_AT_START] = Relation.OVERLAP
        unsure = status == UNDECIDED
        return out, unsure if unsure.any() else None

    def exact(_: None, out: FirstContacts, todo: np.ndarray) -> None:
        """The exact stage: pair by pair on the exact motions (module docstring of :func:`first_contacts`)."""
        nonlocal done
        rel, lo, hi = out.relation, out.t_lo, out.t_hi
        at_start: dict[int, list[list[fmpq]]] = {}
        for k in todo.tolist():
            a, b, sh = int(i[k]), int(j[k]), None if shift is None else shift[k]
            if a not in at_start:
                at_start[a] = bodies.matrix_at_start(a)
            if sh is not None and np.any(sh):
                B0 = bodies.matrix_at_start(b, sh)
            else:
                if b not in at_start:
                    at_start[b] = bodies.matrix_at_start(b)
                B0 = at_start[b]
            start = classify_exact(at_start[a], B0).relation  # touching or overlapping at t = 0: t* = 0 (cheap)
            if start != Relation.SEPARATE:
                rel[k], lo[k], hi[k] = start, 0.0, 0.0
                out.times[k] = RealAlgebraic.rational(fmpq(0))
            elif (e := first_contact(bodies.motion(a), bodies.motion(b, sh), (0, 1))) is not None:
                rel[k] = e.relation
                lo[k], hi[k] = bracket(e.time)
                out.times[k] = e.time
            done += 1
            if progress is not None:
                progress(done, M)

    out, by, _ = _FIRST_CONTACT.run(None, M, floats, exact, method, blank=blank)
    out.certified_by = by if by.flags.writeable else np.array(by)  # FLOAT (the filter) or EXACT
    return out


def bracket(alpha: RealAlgebraic) -> tuple[float, float]:
    """Floats t_lo <= alpha <= t_hi with t_hi - t_lo <= 1e-9 (equal when alpha is that float).

    Examples:
        >>> bracket(RealAlgebraic.rational(fmpq(1, 4)))
        (0.25, 0.25)
        >>> a, b = bracket(RealAlgebraic.rational(fmpq(1, 3)))      # the floats on either side
        >>> fmpq(*a.as_integer_ratio()) < fmpq(1, 3) < fmpq(*b.as_integer_ratio()), b == math.nextafter(a, 1)
        (True, True)
    """
    if alpha.value is None:
        alpha.refine_to(fmpq(1, 2**40))
    a = alpha.value if alpha.value is not None else alpha.lo
    b = alpha.value if alpha.value is not None else alpha.hi
    return _float_below(a), _float_above(b)


def _float_below(x: fmpq) -> float:
    f = int(x.p) / int(x.q)  # correctly rounded
    return f if fmpq(*f.as_integer_ratio()) <= x else math.nextafter(f, -math.inf)


def _float_above(x: fmpq) -> float:
    f = int(x.p) / int(x.q)
    return f if fmpq(*f.as_integer_ratio()) >= x else math.nextafter(f, math.inf)
