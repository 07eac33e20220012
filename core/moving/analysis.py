"""Moving ellipses/ellipsoids: exact interference intervals and tangency events (paper 3.4, 4.4).

``analyse(A_t, B_t, interval=(lo, hi), *, digits=20)`` takes two moving shapes (see
:mod:`core.moving.motions`), clears denominators with a factor of constant sign on I (checked), checks
that both stay ellipses/ellipsoids on I (leading principal minors and det keep their sign: no
root in I), and computes exactly, in Q[t] or Q(sqrt d)[t]:

* a_i(t), the coefficients of P(t, T) = det(T A(t) + B(t)), and the subresultants in the
  paper's hat form ŝ_j = -s_j / a_n (same signs as s_j because a_n < 0; Example 30 works with
  these), via the ring-generic :mod:`core.formulae.pencil` and :mod:`core.formulae.subresultants`;
* the candidates: real roots in I of s0 if s0 is not identically zero (4.4.1; 3.4 case 1), else
  of s1 if s1 is not (4.4.2; 3.4 case 2), else none (4.4.3). Between two consecutive candidates
  no tangency can happen, so the relation is constant there (paper 3.4/4.4, continuity);
* the relation at each candidate (exact signs at the real algebraic number, decision tree of
  :mod:`core.formulae.decision`) and on each open interval (exact signs at a rational sample point).

Candidates where the shapes are tangent and the relation changes or is left again are the
*events* (kind ``"change"`` or ``"touch"``; ``"endpoint"`` at a finite end of I); the other
candidates are reported in ``roots`` (e.g. Example 30's alpha_4, alpha_5: the shapes overlap
there) and do not split intervals. Finite ends of I are included (I is closed there).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from flint import fmpq, fmpq_poly

from ..algebra.algebraic import RealAlgebraic, simplest_between
from ..algebra.qsqrt import QSqrtPoly
from ..algebra.realroots import real_roots
from ..formulae.decision import sign_variations
from ..formulae.pencil import determinant, pencil_coefficients
from ..relation import Relation
from ..shapes.numbers import sign
from ..shapes.quadrics import interior_sign, not_a_quadric_message
from .expressions import RationalFunction
from .motions import as_motion, read_interval
from .result import EVENT_KINDS, Event, Interval, MotionAnalysis, MotionPencil, SignRow
from .signs import Signs, decide_with, sign_row

__all__ = ["analyse", "MotionAnalysis", "Event", "Interval", "SignRow", "EVENT_KINDS"]


# -------------------------------------------------------------------------------------------
# preparation: exact denominator-free matrices valid on I


def _sample_in(lo: fmpq | None, hi: fmpq | None) -> fmpq:
    """A simple rational point of I (inside when I has two finite ends)."""
    return _strictly_between(lo, hi)


def _strictly_between(a: fmpq | None, b: fmpq | None) -> fmpq:
    """A simple rational in the open interval (a, b) (None = infinite)."""
    if a is None and b is None:
        return fmpq(0)
    if a is None:
        assert b is not None
        f = b.p // b.q
        return fmpq(f - 1) if fmpq(f) >= b else fmpq(f)
    if b is None:
        f = a.p // a.q
        return fmpq(f + 1)
    c = simplest_between(a, b)
    if c == a or c == b:
        c = (a + b) / 2
    return c


def _fmt_t(a: RealAlgebraic) -> str:
    return f"{float(a):.6g}"


def _polynomial_matrix(
    M: list[list[RationalFunction]], lo: fmpq | None, hi: fmpq | None, name: str
) -> tuple[list[list[QSqrtPoly]], fmpq_poly]:
    """Clear denominators and normalise the interior sign on I; check validity on I.

    Returns (P, lam) with P = lam * M, lam in Q[t] with no root in I and P the matrix of a valid
    ellipse/ellipsoid (negative interior) at every t in I. The factor that multiplies the
    normalised matrix, P / sign, is |lam| > 0 on I: the caller divides by ``abs_lam`` = lam times
    its sign on I, so a flipped or negatively scaled input gives the same pencil as its
    normalised form (the same rule as the static :func:`core.shapes.quadrics.interior_sign`).
    """
    den = fmpq_poly([1])
    for row in M:
        for e in row:
            g = den.gcd(e.den)
            den = den * (e.den // g)
    where = _interval_text(lo, hi)
    if den.degree() > 0:
        bad = real_roots(QSqrtPoly(den), lo, hi)
        if bad:
            raise ValueError(f"{name}: a denominator vanishes at t ≈ {_fmt_t(bad[0])} in {where}")
    t0 = _sample_in(lo, hi)
    P = [[e.num * (den // e.den) for e in row] for row in M]
    k = len(P) - 1
    shape = "ellipse" if k == 2 else "ellipsoid"
    # leading minors (orders 1..k of the quadratic block, k+1 = det): a sign change in I, or
    # the wrong sign pattern, means the matrix is not an ellipse/ellipsoid somewhere in I
    minors = [determinant([row[:j] for row in P[:j]]) for j in range(1, k + 2)]
    for order, m in enumerate(minors, start=1):
        what = f"leading minor of order {order} of the quadratic part" if order <= k else "determinant"
        if m.is_zero():
            raise ValueError(f"{name} is not an {shape} for any t: its {what} is identically 0")
        roots = real_roots(m, lo, hi)
        if roots:
            raise ValueError(
                f"{name} stops being an {shape} at t ≈ {_fmt_t(roots[0])} in {where} "
                f"(its {what} vanishes there)"
            )
    signs = [m.sign_at_rational(t0) for m in minors]  # constant on I: no root there
    orient = interior_sign(signs[:k])
    if orient is None:
        raise ValueError(
            f"{name} is not an {shape} anywhere in {where} "
            f"(its quadratic part is indefinite: {not_a_quadric_message(name, k + 1).split('(')[-1].rstrip(')')})"
        )
    if signs[k] * orient ** (k + 1) >= 0:  # det of the normalised matrix must be negative
        raise ValueError(f"{name} is not an {shape} anywhere in {where} (its determinant has the wrong sign: no real points)")
    if orient < 0:
        P = [[-e for e in row] for row in P]
    lam = den * orient  # P = lam * M, normalised on all of I
    return P, lam * sign(lam(t0))  # |lam| on I: P = |lam| * (normalised M)


def _canonical_pencil(a: list[QSqrtPoly], lamA: fmpq_poly, lamB: fmpq_poly, t0: fmpq) -> list[QSqrtPoly]:
    """The numerator of det(T A(t) + B(t)) with the common factors in t removed.

    ``a`` are the coefficients for lamA*A, lamB*B, so the true a_i are a_i / (lamA^i lamB^(n-i)).
    Each is reduced, brought to the common denominator L, and the content in Q[t] of the result
    is divided out; both factors have no root in I and are taken positive there, so every sign
    (and the relation) is unchanged. This is the paper's P(t, T) (Examples 30, 32: degrees 14, 4).
    """
    n = len(a) - 1
    parts = []
    for i, ai in enumerate(a):
        D = lamA**i * lamB ** (n - i)
        if ai.is_zero():
            parts.append((ai, fmpq_poly([1])))
            continue
        g = D.gcd(ai.p if ai.q.is_zero() else ai.p.gcd(ai.q))
        parts.append((QSqrtPoly(ai.p // g, ai.q // g, ai.d), D // g))
    L = fmpq_poly([1])
    for _, den in parts:
        L = L * (den // L.gcd(den))
    out = [num * (L // den) for num, den in parts]
    c = fmpq_poly([0])
    for p in out:
        c = c.gcd(p.p).gcd(p.q)
    if c.is_zero():
        return out
    cs = sign(c(t0))
    if sign(L(t0)) < 0:
        cs = -cs
    # divide by c (and flip by the sign of L / c on I); normalise the scale to integers
    res = [QSqrtPoly(p.p // c, p.q // c, p.d) * cs for p in out]
    return res


def _interval_text(lo: fmpq | None, hi: fmpq | None) -> str:
    left = "(-inf" if lo is None else f"[{lo}"
    right = "inf)" if hi is None else f"{hi}]"
    return f"{left}, {right}"


# -------------------------------------------------------------------------------------------
# the analysis


def analyse(
    A_t: Any,
    B_t: Any,
    interval: tuple[Any, Any] = (None, None),
    *,
    digits: int = 20,
) -> MotionAnalysis:
    """Exact interference analysis of two moving ellipses/ellipsoids over a time interval.

    Args:
        A_t: the first moving shape: an n x n nested list of expression strings in t (n = 3
            ellipses, 4 ellipsoids; e.g. ``[["1", "0", "-t"], ...]``), a motion dict
            (``{"matrix": ...}`` or ``{"shape": ..., "translation": ..., "rotation": ...}``, see
            :mod:`core.moving.motions`) or a :class:`core.moving.motions.Motion`.
        B_t: the second moving shape, likewise.
        interval: (lo, hi) or the text "lo, hi": numbers, exact strings ("1/3", "0.5"), or
            None / "none" / "-inf" / "inf" / "infinity" for an infinite end
            (:func:`core.moving.motions.read_interval`, the one grammar). Finite ends belong to I.
        digits: significant digits of the decimal event values (1..1000; refine more later with
            ``event.decimal(k)``).

    Returns:
        :class:`MotionAnalysis` with ``.events`` (tangency times, exact isolating intervals,
        decimals, relation, kind), ``.roots`` (other candidates), ``.intervals`` (open intervals
        of constant relation), ``.sign_table``, the exact polynomials ``.a``, ``.s0``, ``.s1``,
        ``.s10``, ``.relation_at(t)``, ``.samples()`` and ``.to_dict()``.

    Raises:
        ValueError: unreadable input (message names the entry), lo >= hi, matrices of different
            sizes, two different square roots, a denominator vanishing in I, or a shape that is
            not an ellipse/ellipsoid somewhere in I (message gives an approximate t).

    Guarantee:
        Every relation and event is decided with exact arithmetic (rationals, or Q(sqrt d) with
        signs certified by exact zero tests and ball arithmetic); floats are display only.

    References:
        Caravantes et al., Sections 3.4 and 4.4; Examples 29-33 (Section 4.5).

    Examples:
        >>> circle = lambda x: [["1", "0", f"-({x})"], ["0", "1", "0"], [f"-({x})", "0", f"({x})^2 - 1"]]
        >>> r = analyse(circle("t"), circle("-t"), (-2, 2))      # centres 2|t| apart
        >>> [(e.value, str(e.relation), e.kind) for e in r.events]
        [('-1', 'tangent', 'change'), ('1', 'tangent', 'change')]
        >>> [str(iv.relation) for iv in r.intervals]
        ['separate', 'overlap', 'separate']
        >>> str(r.relation_at(0.5)), str(r.relation_at("1"))
        ('overlap', 'tangent')
    """
    if not isinstance(digits, int) or isinstance(digits, bool) or not 1 <= digits <= 1000:
        raise ValueError(f"digits must be an integer in 1..1000, got {digits!r}")
    lo, hi = read_interval(interval)
    pencil = _motion_pencil(A_t, B_t, lo, hi)
    case = _paper_case(pencil, lo, hi)
    cands = real_roots(case.candidates, lo, hi) if case.candidates is not None else []
    _separate(cands)
    points = [_decide_point(pencil, alpha, case.zero_at_candidates, digits) for alpha in cands]
    segments = _decide_segments(pencil, case, cands, lo, hi)
    events, roots, breaks = _events(cands, points, segments, digits)
    res = MotionAnalysis(
        pencil=pencil,
        interval=(lo, hi),
        case=case.name,
        events=events,
        roots=roots,
        intervals=_intervals(cands, segments, breaks, lo, hi),
        sign_table=_sign_table(cands, points, segments),
        digits=digits,
        paper_case=case.paper,
    )
    res._points = list(cands)
    res._point_rel = [p.relation for p in points]
    # empty end segments take the relation of the point itself (never queried strictly inside)
    res._seg_rel = [
        sg.relation if sg.relation != Relation.UNDECIDED else points[0 if k == 0 else -1].relation
        for k, sg in enumerate(segments)
    ]
    res._his = [c.hi for c in cands]
    return res


# -------------------------------------------------------------------------------------------
# the steps of analyse


def _motion_pencil(A_t: Any, B_t: Any, lo: fmpq | None, hi: fmpq | None) -> MotionPencil:
    """Read both motions, clear denominators, check validity on I, build a_i(t) and ŝ_j(t)."""
    mA, mB = as_motion(A_t), as_motion(B_t)
    if mA.dim != mB.dim:
        raise ValueError(f"A is {mA.dim + 1}x{mA.dim + 1} but B is {mB.dim + 1}x{mB.dim + 1}: both ellipses or both ellipsoids")
    dA, dB = mA.sqrt_d(), mB.sqrt_d()
    if dA != 1 and dB != 1 and dA != dB:
        raise ValueError(f"A uses sqrt({dA}) and B uses sqrt({dB}): only one square root per motion pair")
    PA, lamA = _polynomial_matrix(mA.matrix(), lo, hi, "A")
    PB, lamB = _polynomial_matrix(mB.matrix(), lo, hi, "B")
    a = _canonical_pencil(pencil_coefficients(PA, PB), lamA, lamB, _sample_in(lo, hi))
    return MotionPencil(n=len(a) - 1, a=a, sqrt_d=max(dA, dB), A=mA, B=mB, matrices=(PA, PB))


@dataclass
class _Case:
    """Which case of the paper applies, and where the relation can change."""

    name: str
    """"s0", "s1" or "none": the polynomial whose roots are the candidates (JSON ``case``)."""
    paper: str
    """The paper's name: 3.4(1), 3.4(2) for ellipses; 4.4.1, 4.4.2(1..3), 4.4.3(1..2)."""
    candidates: QSqrtPoly | None
    identically_zero: set[str]
    """Hat subresultants identically zero in this case (their sign is 0 everywhere)."""

    @property
    def zero_at_candidates(self) -> set[str]:
        """Also the candidate polynomial itself vanishes at its roots."""
        return self.identically_zero | ({self.name} if self.name != "none" else set())


def _paper_case(pencil: MotionPencil, lo: fmpq | None, hi: fmpq | None) -> _Case:
    """Which case of Sections 3.4 and 4.4 applies, and which polynomial gives the candidates.

    The real roots of s0(t) are the only times the relation can change (4.4.1, 3.4(1)); if s0 vanishes identically, those of s1(t) (4.4.2; for ellipses 3.4(2):
    tangent or overlapping on all of I); if s1 does too, none (4.4.3). The sub-case of 4.4.2
    (signs of s1, s1,0 at a point alpha where neither vanishes) and of 4.4.3 (Var at alpha)
    is named for the reader; the decisions below do not depend on it (each point and interval
    is decided by the tree itself).
    """
    if not pencil.s0.is_zero():
        return _Case("s0", "4.4.1" if pencil.n == 4 else "3.4(1)", pencil.s0, set())
    alpha = _sample_in(lo, hi)
    if not pencil.s1.is_zero():
        if pencil.n == 3:
            return _Case("s1", "3.4(2)", pencil.s1, {"s0"})
        # an alpha in I where s1 and s1,0 do not vanish (they have the same real roots, Lemma 17)
        for k in range(64):
            if pencil.s1.sign_at_rational(alpha) != 0 and pencil.s10.sign_at_rational(alpha) != 0:
                break
            alpha = _strictly_between(alpha, hi if hi is not None else alpha + 1 + k)
        s1a, s10a = pencil.s1.sign_at_rational(alpha), pencil.s10.sign_at_rational(alpha)
        sub = "1" if s1a > 0 else ("2" if s10a > 0 else "3")
        return _Case("s1", f"4.4.2({sub})", pencil.s1, {"s0"})
    if pencil.n == 3:
        return _Case("none", "3.4(2)", None, {"s0", "s1"})
    signs = [pencil.a[i].sign_at_rational(alpha) for i in range(pencil.n, -1, -1)]
    return _Case("none", "4.4.3(1)" if sign_variations(signs) == 2 else "4.4.3(2)", None, {"s0", "s1"})


@dataclass
class _Point:
    """The decision at one candidate root."""

    relation: Relation
    rule: str
    row: SignRow


@dataclass
class _Segment:
    """The decision on one open interval between consecutive candidates (UNDECIDED: empty)."""

    relation: Relation
    sample: fmpq
    row: SignRow | None


def _decide_point(pencil: MotionPencil, alpha: RealAlgebraic, known_zero: set[str], digits: int) -> _Point:
    sg = Signs(pencil.polynomials(), alpha, known_zero)
    dec = decide_with(pencil.n, sg)
    return _Point(dec.relation, dec.rule, sign_row("point", alpha.decimal(digits), pencil.n, sg, dec))


def _decide_segments(
    pencil: MotionPencil, case: _Case, cands: list[RealAlgebraic], lo: fmpq | None, hi: fmpq | None
) -> list[_Segment]:
    """The relation on each open interval between consecutive candidates.

    Exact signs at a rational sample point; constant there by continuity (paper 3.4/4.4).
    """
    zero = case.identically_zero
    out: list[_Segment] = []
    for i in range(len(cands) + 1):
        left = cands[i - 1].hi if i > 0 else lo
        right = cands[i].lo if i < len(cands) else hi
        if (i == 0 and cands and lo is not None and cands[0].compare(lo) == 0) or (
            i == len(cands) and cands and hi is not None and cands[-1].compare(hi) == 0
        ):
            out.append(_Segment(Relation.UNDECIDED, fmpq(0), None))  # empty: the candidate is the end of I
            continue
        if left is not None and right is not None and not left < right:
            # I's end inside a candidate's isolating interval: narrow it (the root is inside I)
            c = cands[0] if i == 0 else cands[-1]
            end: fmpq = left if i == 0 else right
            while c.value is None and not (c.lo > end if i == 0 else c.hi < end):
                c.bisect()
            left = cands[i - 1].hi if i > 0 else lo
            right = cands[i].lo if i < len(cands) else hi
            if left is None or right is None or not left < right:
                raise RuntimeError("candidate isolating intervals overlap")
        t = _strictly_between(left, right)
        sg = Signs(pencil.polynomials(), t, zero)
        dec = decide_with(pencil.n, sg)
        out.append(_Segment(dec.relation, t, sign_row("interval", str(t), pencil.n, sg, dec)))
    return out


def _events(
    cands: list[RealAlgebraic], points: list[_Point], segments: list[_Segment], digits: int
) -> tuple[list[Event], list[Event], list[int]]:
    """Tangency events, the other candidates (roots), and the candidates that split intervals.

    An event is a candidate where the shapes touch and the relation changes or is left again.
    """
    events: list[Event] = []
    roots: list[Event] = []
    breaks: list[int] = []
    for i, alpha in enumerate(cands):
        before = segments[i].relation if segments[i].relation != Relation.UNDECIDED else None
        after = segments[i + 1].relation if segments[i + 1].relation != Relation.UNDECIDED else None
        rel = points[i].relation
        sides = [r for r in (before, after) if r is not None]
        if rel == Relation.TANGENT and any(r != rel for r in sides):
            kind = "endpoint" if len(sides) < 2 else ("touch" if before == after else "change")
            events.append(Event(alpha, rel, kind, before, after, alpha.decimal(digits), points[i].rule))
            breaks.append(i)
        else:
            roots.append(Event(alpha, rel, "root", before, after, alpha.decimal(digits), points[i].rule))
            if any(r != rel for r in sides):
                breaks.append(i)  # not expected by the theory; keep the boundary honest
    return events, roots, breaks


def _intervals(
    cands: list[RealAlgebraic], segments: list[_Segment], breaks: list[int], lo: fmpq | None, hi: fmpq | None
) -> list[Interval]:
    """Maximal open intervals of constant relation (segments merged across non-event roots)."""
    intervals: list[Interval] = []
    start_lo: RealAlgebraic | None = None if lo is None else RealAlgebraic.rational(lo)
    seg_idx = 0
    for b in breaks + [len(cands)]:
        decided = [segments[k] for k in range(seg_idx, b + 1) if segments[k].relation != Relation.UNDECIDED]
        end_hi = cands[b] if b < len(cands) else (None if hi is None else RealAlgebraic.rational(hi))
        if decided:
            intervals.append(Interval(start_lo, end_hi, decided[0].relation, decided[0].sample))
        if b < len(cands):
            start_lo = cands[b]
        seg_idx = b + 1
    return intervals


def _sign_table(cands: list[RealAlgebraic], points: list[_Point], segments: list[_Segment]) -> list[SignRow]:
    """Rows in time order: each decided interval's sample, then the candidate after it."""
    rows: list[SignRow] = []
    for i in range(len(cands) + 1):
        row = segments[i].row
        if row is not None:
            rows.append(row)
        if i < len(cands):
            rows.append(points[i].row)
    return rows


def _separate(cands: list[RealAlgebraic]) -> None:
    """Refine isolating intervals until consecutive ones are disjoint (hi_i < lo_{i+1})."""
    for i in range(len(cands) - 1):
        a, b = cands[i], cands[i + 1]
        while not a.hi < b.lo:
            if a.width >= b.width:
                a.bisect()
            else:
                b.bisect()
