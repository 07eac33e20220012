"""Result of a motion analysis: events, intervals, the sign table, exact polynomials (paper 4.5).

:class:`MotionAnalysis` is what :func:`core.moving.analysis.analyse` returns: typed, JSON-ready
(``to_dict``), with ``relation_at(t)`` for timeline scrubbing and lazy float ``samples`` for plots.
"""

from __future__ import annotations

import bisect
import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from flint import fmpq

from ..algebra.algebraic import RealAlgebraic
from ..algebra.qsqrt import QSqrtPoly
from ..formulae.decision import RULES
from ..formulae.subresultants import hat_s0, hat_s1, hat_s10, hat_scale
from ..options import check_choice
from ..relation import Relation
from ..shapes.numbers import to_fmpq
from .motions import Motion, motion_to_dict
from .signs import SignRow, sign_row_at

__all__ = ["MotionAnalysis", "MotionPencil", "Event", "Interval", "SignRow", "EVENT_KINDS"]

EVENT_KINDS = ("change", "touch", "endpoint")
"""change: relation differs on the two sides; touch: tangent and the same relation on both
sides (touch and leave); endpoint: tangent at a finite end of I."""

_SIGN = {1: "+", 0: "0", -1: "-"}


def _alg_dict(a: RealAlgebraic | None, digits: int) -> dict[str, Any] | None:
    return None if a is None else a.to_dict(digits)


@dataclass
class Event:
    """A tangency instant: an exact real algebraic time with its isolating interval."""

    time: RealAlgebraic
    """The exact time (``.lo``/``.hi`` isolating interval with rational ends, ``.value`` if rational)."""
    relation: Relation
    """Relation at that instant (TANGENT for events; any relation for ``roots``)."""
    kind: str
    """One of :data:`EVENT_KINDS` (events); "root" for non-tangency roots."""
    before: Relation | None
    """Relation just before (None at the left end of I)."""
    after: Relation | None
    """Relation just after (None at the right end of I)."""
    value: str
    """Decimal value to the requested digits."""
    rule: str = ""

    @property
    def lo(self) -> fmpq:
        """Left end of the isolating interval."""
        return self.time.lo

    @property
    def hi(self) -> fmpq:
        """Right end of the isolating interval."""
        return self.time.hi

    def decimal(self, digits: int) -> str:
        """The time to ``digits`` significant digits (refines as needed)."""
        return self.time.decimal(digits)

    def __float__(self) -> float:
        return float(self.time)

    def to_dict(self, digits: int) -> dict[str, Any]:
        """JSON form."""
        out = _alg_dict(self.time, digits) or {}
        out.update(
            relation=str(self.relation),
            kind=self.kind,
            before=None if self.before is None else str(self.before),
            after=None if self.after is None else str(self.after),
            rule=self.rule,
        )
        return out


@dataclass
class Interval:
    """An open interval of constant relation (ends None = infinite)."""

    lo: RealAlgebraic | None
    hi: RealAlgebraic | None
    relation: Relation
    sample: fmpq
    """The rational point where the relation was decided exactly."""

    def to_dict(self, digits: int) -> dict[str, Any]:
        """JSON form."""
        return {
            "lo": _alg_dict(self.lo, digits),
            "hi": _alg_dict(self.hi, digits),
            "relation": str(self.relation),
            "sample": str(self.sample),
        }


@dataclass
class MotionPencil:
    """P(t, T) = det(T A(t) + B(t)) of a pair on I: its coefficients a_i(t) and the hat subresultants.

    What :func:`core.moving.analysis.analyse` computes first and :class:`MotionAnalysis` keeps
    (its ``n``, ``a``, ``s0``, ... are this pencil's). ŝ0, ŝ1, ŝ1,0 are computed on first use:
    the full analysis reads all three, the first contact
    (:mod:`core.moving.first_contact`) often only ŝ0.
    """

    n: int
    """3 (ellipses) or 4 (ellipsoids): degree of P in T."""
    a: list[QSqrtPoly]
    """[a_0, ..., a_n] of P(t, T): numerator of det(T A(t) + B(t)), common factors in t removed
    (a positive multiple of the true coefficients on I; exact)."""
    sqrt_d: int
    """d of the sqrt(d) in the coefficients (1: all rational)."""
    A: Motion
    B: Motion
    matrices: tuple[list[list[QSqrtPoly]], list[list[QSqrtPoly]]]
    """The denominator-free matrices (positive multiples of A(t), B(t) on I)."""
    _hats: dict[str, QSqrtPoly] = field(default_factory=dict, repr=False, compare=False)

    def _hat(self, name: str) -> QSqrtPoly:
        if name not in self._hats:
            c0, c1, c10 = hat_scale(self.n)
            fn, c = {"s0": (hat_s0, c0), "s1": (hat_s1, c1), "s10": (hat_s10, c10)}[name]
            self._hats[name] = fn(self.a).scale_positive(fmpq(c.numerator, c.denominator))
        return self._hats[name]

    @property
    def s0(self) -> QSqrtPoly:
        """ŝ0 = -s0/a_n (same sign as s0; exact)."""
        return self._hat("s0")

    @property
    def s1(self) -> QSqrtPoly:
        """ŝ1 = -s1/a_n."""
        return self._hat("s1")

    @property
    def s10(self) -> QSqrtPoly:
        """ŝ1,0 = -s1,0/a_n."""
        return self._hat("s10")

    def polynomials(self) -> dict[str, QSqrtPoly]:
        """``a0``..``a{n}``, ``s0``, ``s1``, ``s10`` (hat forms) by name, as the sign table uses them."""
        out = {f"a{i}": p for i, p in enumerate(self.a)}
        out.update(s0=self.s0, s1=self.s1, s10=self.s10)
        return out


@dataclass
class MotionAnalysis:
    """Result of :func:`analyse`: the pencil, the paper's case, events, intervals, sign table."""

    pencil: MotionPencil
    """P(t, T) of the pair on I (``n``, ``a``, ``s0``, ``s1``, ``s10``, ``sqrt_d``, ``A``, ``B``,
    ``matrices`` below are its fields)."""
    interval: tuple[fmpq | None, fmpq | None]
    """I (None = infinite end); finite ends are included."""
    case: str
    """"s0" (4.4.1), "s1" (s0 = 0 identically, 4.4.2) or "none" (s0 = s1 = 0, 4.4.3)."""
    events: list[Event]
    """Tangency events, ascending."""
    roots: list[Event]
    """Candidates (roots of s0, or s1) that are not events, with the relation there."""
    intervals: list[Interval]
    """Maximal open intervals of constant relation covering I minus the events."""
    sign_table: list[SignRow]
    """Rows for every candidate and for the sample of every interval between candidates."""
    digits: int
    paper_case: str = ""
    """The paper's case: "3.4(1)", "3.4(2)" for ellipses; "4.4.1", "4.4.2(1)".."4.4.2(3)",
    "4.4.3(1)", "4.4.3(2)" for ellipsoids (see :func:`core.moving.analysis.analyse`)."""
    _points: list[RealAlgebraic] = field(default_factory=list, repr=False)
    _point_rel: list[Relation] = field(default_factory=list, repr=False)
    _seg_rel: list[Relation] = field(default_factory=list, repr=False)
    _his: list[fmpq] = field(default_factory=list, repr=False)

    # -- the pencil's fields ---------------------------------------------------------------
    @property
    def n(self) -> int:
        """3 (ellipses) or 4 (ellipsoids): degree of P in T."""
        return self.pencil.n

    @property
    def a(self) -> list[QSqrtPoly]:
        """[a_0, ..., a_n] of P(t, T) (:attr:`MotionPencil.a`)."""
        return self.pencil.a

    @property
    def s0(self) -> QSqrtPoly:
        """ŝ0 = -s0/a_n (same sign as s0)."""
        return self.pencil.s0

    @property
    def s1(self) -> QSqrtPoly:
        """ŝ1 = -s1/a_n."""
        return self.pencil.s1

    @property
    def s10(self) -> QSqrtPoly:
        """ŝ1,0 = -s1,0/a_n."""
        return self.pencil.s10

    @property
    def sqrt_d(self) -> int:
        """D of the sqrt(d) in the coefficients (1: all rational)."""
        return self.pencil.sqrt_d

    @property
    def A(self) -> Motion:
        """The motion of the first shape."""
        return self.pencil.A

    @property
    def B(self) -> Motion:
        """The motion of the second shape."""
        return self.pencil.B

    @property
    def matrices(self) -> tuple[list[list[QSqrtPoly]], list[list[QSqrtPoly]]]:
        """The denominator-free matrices (positive multiples of A(t), B(t) on I)."""
        return self.pencil.matrices

    # -- queries ---------------------------------------------------------------------------
    def _in_interval(self, t: Any) -> fmpq:
        """T as an exact rational, checked to lie in I (ValueError otherwise)."""
        tq = to_fmpq(t)
        lo, hi = self.interval
        if (lo is not None and tq < lo) or (hi is not None and tq > hi):
            raise ValueError(f"t = {t} is outside the analysed interval [{lo}, {hi}]")
        return tq

    def relation_at(self, t: Any, *, via: str = "lookup", method: str | None = None) -> Relation:
        """Certified relation at one time t (float = exact binary rational, int, "p/q", "0.1").

        ``via="lookup"`` (default, a few microseconds) compares t exactly with the candidates'
        isolating intervals (one polynomial evaluation when t falls inside one) and returns the
        relation of that instant or open interval, decided exactly during :func:`analyse`.
        ``via="classify"`` evaluates the exact matrices A(t), B(t) and runs the static
        classifier :func:`core.classify` on them (an independent check; rational motions only,
        ~0.1-1 ms). Both are exact: ``method=`` means the arithmetic everywhere else in core, so
        the choice of algorithm is ``via=`` (``method="lookup" | "classify"`` still works, with a
        DeprecationWarning).

        Raises:
            ValueError: t outside I or not a number; "classify" on a motion with sqrt(d) entries.
        """
        if method is not None:
            warnings.warn('relation_at(t, method=...) chooses the algorithm: use via="lookup" or via="classify"',
                          DeprecationWarning, stacklevel=2)
            via = method
        check_choice(via, ("lookup", "classify"), "via")
        tq = self._in_interval(t)
        if via == "classify":
            from ..fixed.classify import classify
            from .motions import matrix_at_exact

            return classify(matrix_at_exact(self.A, tq), matrix_at_exact(self.B, tq))
        i = bisect.bisect_left(self._his, tq)
        if i < len(self._points):
            c = self._points[i].compare(tq)
            if c == 0:
                return self._point_rel[i]
            if c < 0:
                return self._seg_rel[i + 1]
        return self._seg_rel[i]

    def polynomials(self) -> dict[str, QSqrtPoly]:
        """``a0``..``a{n}``, ``s0``, ``s1``, ``s10`` (hat forms) by name, as the sign table uses them."""
        return self.pencil.polynomials()

    def sign_row_at(self, t: Any) -> SignRow:
        """Sign-table row at one rational time t in I.

        Exact signs of a_n..a_0, ŝ0, ŝ1, ŝ1,0, Var, relation and rule, as the analysis' own
        rows (exact polynomial evaluation).

        Raises:
            ValueError: t outside I or not a number.
        """
        return sign_row_at(self.n, self.polynomials(), self._in_interval(t))

    def samples(self, num: int = 256, lo: float | None = None, hi: float | None = None) -> dict[str, Any]:
        """Float samples of a_i, ŝ0, ŝ1, ŝ1,0 on a uniform grid, for plots (display only).

        Each polynomial is divided by its largest |coefficient| (a positive constant: signs and
        roots are kept) so that huge exact coefficients do not overflow. Computed on request.

        Args:
            num: number of grid points (2..10000).
            lo: left end of the window; defaults to I's, or around the events when I is unbounded.
            hi: right end, likewise.
        """
        if not 2 <= int(num) <= 10000:
            raise ValueError(f"num must be in 2..10000, got {num}")
        wlo, whi = self._window(lo, hi)
        ts = np.linspace(wlo, whi, int(num))
        out: dict[str, Any] = {"t": ts.tolist()}
        out["a"] = [_eval_scaled(p, ts).tolist() for p in self.a]
        for name in ("s0", "s1", "s10"):
            out[name] = _eval_scaled(getattr(self, name), ts).tolist()
        return out

    def _window(self, lo: float | None, hi: float | None) -> tuple[float, float]:
        ilo = None if self.interval[0] is None else float(self.interval[0])
        ihi = None if self.interval[1] is None else float(self.interval[1])
        pts = [float(p) for p in self._points]
        if lo is None:
            lo = ilo if ilo is not None else (min(pts) - max(1.0, 0.25 * (max(pts) - min(pts))) if pts else (ihi - 2.0 if ihi is not None else -1.0))
        if hi is None:
            hi = ihi if ihi is not None else (max(pts) + max(1.0, 0.25 * (max(pts) - min(pts))) if pts else (lo + 2.0))
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ValueError(f"bad sample window [{lo}, {hi}]")
        return float(lo), float(hi)

    def subresultants(self) -> dict[str, QSqrtPoly]:
        """The paper's s0, s1, s1,0 themselves: s_j = -a_n * ŝ_j (Examples 29, 32 print these)."""
        an = self.a[-1]
        return {"s0": -(an * self.s0), "s1": -(an * self.s1), "s10": -(an * self.s10)}

    def degrees(self) -> dict[str, Any]:
        """Degrees in t of the coefficients and of both forms of the subresultants.

        ``a`` (a_0..a_n), ``s0``/``s1``/``s10`` of the hat forms ŝ_j = -s_j/a_n that are stored
        and plotted, and ``paper_s0``/``paper_s1``/``paper_s10`` of the paper's
        s_j = -a_n ŝ_j themselves (Example 32: 26, 20, 20 where the hat forms have 22, 16, 16).
        A polynomial that is identically 0 has degree -1.
        """
        dn = self.a[-1].degree()
        out: dict[str, Any] = {"a": [p.degree() for p in self.a]}
        for name in ("s0", "s1", "s10"):
            d = getattr(self, name).degree()
            out[name] = d
            out[f"paper_{name}"] = d + dn if d >= 0 else -1
        return out

    def polynomial_strings(self) -> dict[str, Any]:
        """a_i, ŝ0, ŝ1, ŝ1,0 as parseable strings in t, with their degrees (:meth:`degrees`)."""
        return {
            "a": [str(p) for p in self.a],
            "s0": str(self.s0),
            "s1": str(self.s1),
            "s10": str(self.s10),
            "degrees": self.degrees(),
        }

    def to_dict(self, *, polynomials: bool = True) -> dict[str, Any]:
        """JSON-ready form: exact numbers as "p/q" strings, floats alongside."""
        lo, hi = self.interval
        out: dict[str, Any] = {
            "dimension": self.n - 1,
            "interval": [None if lo is None else str(lo), None if hi is None else str(hi)],
            "case": self.case,
            "paper_case": self.paper_case,
            "sqrt_d": self.sqrt_d,
            "digits": self.digits,
            "events": [e.to_dict(self.digits) for e in self.events],
            "roots": [e.to_dict(self.digits) for e in self.roots],
            "intervals": [iv.to_dict(self.digits) for iv in self.intervals],
            "sign_table": [r.to_dict() for r in self.sign_table],
            "rules": {r.rule: RULES[r.rule] for r in self.sign_table if r.rule in RULES},
            "A": motion_to_dict(self.A),
            "B": motion_to_dict(self.B),
        }
        if polynomials:
            out["polynomials"] = self.polynomial_strings()
        return out


def _eval_scaled(p: QSqrtPoly, ts: np.ndarray) -> np.ndarray:
    if p.is_zero():
        return np.zeros_like(ts)
    c = p.coefficients_float()
    big = max(abs(v) for v in c if math.isfinite(v)) if any(math.isfinite(v) for v in c) else 1.0
    if not all(math.isfinite(v) for v in c) or big == 0:
        # scale exactly before converting (huge coefficients)
        m = max(max((abs(x) for x in p.p.coeffs()), default=fmpq(0)), max((abs(x) for x in p.q.coeffs()), default=fmpq(0)))
        c = p.scale_positive(1 / m).coefficients_float()
        big = max(abs(v) for v in c)
    return np.polynomial.polynomial.polyval(ts, np.array(c) / big)
