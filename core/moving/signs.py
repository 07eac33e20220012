"""Exact signs of a_i(t), ŝ_j(t) at one time (rational or real algebraic) and the decision there.

Shared by the analysis (at candidate roots and sample points, :mod:`.analysis`) and by the
result's queries at a user's t (:meth:`.result.MotionAnalysis.sign_row_at`): one evaluation of
the tree of :mod:`core.formulae.decision` on exact signs, computing ŝ0, ŝ1, ŝ1,0 only when it asks.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from flint import fmpq

from ..algebra.algebraic import RealAlgebraic, sign_at
from ..algebra.qsqrt import QSqrtPoly
from ..filtered import predicate
from ..formulae.decision import Decision, decide, sign_variations
from ..relation import Relation
from ..shapes.numbers import to_fmpq

__all__ = ["SignRow", "Signs", "decide_with", "sign_row", "decide_at", "sign_row_at"]


_SIGN = {1: "+", 0: "0", -1: "-"}

_SIGN_AT = predicate("motion_sign")
"""The filtered predicate of one sign a_i(t), ŝ_j(t) at a point (:func:`core.filter_stats`): the
float Horner filter at a float t, exact evaluation otherwise (rational or algebraic t)."""


def _no_float() -> int | None:
    """The float stage where there is none (an exact point): never certain."""
    return None


@dataclass(frozen=True)
class SignRow:
    """One row of the sign table (paper's example tables): at an instant or on an interval."""

    where: str
    """"point" (a candidate root) or "interval" (an open interval, signs at its sample)."""
    t: str
    """Decimal value of the point, or the rational sample point of the interval."""
    a: tuple[int, ...]
    """Signs of a_n, ..., a_0 (descending, as the paper writes Var)."""
    s0: int
    s1: int
    s10: int
    var: int
    """Var(a_n, ..., a_0)."""
    relation: Relation
    rule: str
    """Key of :data:`core.formulae.decision.RULES` that decided."""

    def to_dict(self) -> dict[str, Any]:
        """JSON form (signs as "+", "0", "-")."""
        return {
            "where": self.where,
            "t": self.t,
            "a": [_SIGN[s] for s in self.a],
            "s0": _SIGN[self.s0],
            "s1": _SIGN[self.s1],
            "s10": _SIGN[self.s10],
            "var": self.var,
            "relation": str(self.relation),
            "rule": self.rule,
        }


class Signs:
    """Exact signs of a_i, ŝ_j at one point (rational or algebraic), computed on demand."""

    def __init__(self, polys: Mapping[str, QSqrtPoly], point: fmpq | RealAlgebraic, zero: set[str], float_point: float | None = None) -> None:
        self.polys = polys
        self.point = point
        self.zero = zero  # names known to vanish at this point
        self.float_point = float_point  # the point as a float, when it is one exactly
        self.cache: dict[str, int] = {}

    def __call__(self, name: str) -> int:
        """Exact sign of the polynomial ``name`` ("a0".."a4", "s0", "s1", "s10") at the point."""
        if name not in self.cache:
            if name in self.zero:  # known to vanish here: no evaluation
                self.cache[name] = 0
            else:
                p, point, fp = self.polys[name], self.point, self.float_point
                if isinstance(point, RealAlgebraic):
                    s, _ = _SIGN_AT.one(_no_float, lambda: sign_at(p, point), "exact")
                elif fp is None:
                    s, _ = _SIGN_AT.one(_no_float, lambda: p.sign_at_rational(point), "exact")
                else:  # a float point: the certified float Horner step first
                    s, _ = _SIGN_AT.one(lambda: p.float_sign_at(fp), lambda: p.sign_at_rational(point))
                assert s is not None  # "adaptive" and "exact" always answer
                self.cache[name] = s
        return self.cache[name]


def decide_with(n: int, sg: Signs) -> Decision:
    """The tree on the signs of ``sg`` (a_n..a_0 always; ŝ_j when asked)."""
    return decide(n, [sg(f"a{i}") for i in range(n, -1, -1)], lambda: sg("s0"), lambda: sg("s1"), lambda: sg("s10"))


def sign_row(where: str, t: str, n: int, sg: Signs, dec: Any) -> SignRow:
    """A sign-table row: every a_i and ŝ_j evaluated (for display), with the decision."""
    a = tuple(sg(f"a{i}") for i in range(n, -1, -1))
    return SignRow(where, t, a, sg("s0"), sg("s1"), sg("s10"), sign_variations(list(a)), dec.relation, dec.rule)


def decide_at(n: int, polys: dict[str, QSqrtPoly], t: Any) -> tuple[Any, dict[str, int]]:
    """Decision at one rational time t from the exact polynomials, evaluating what the tree needs.

    Like the static :func:`core.explain`: the signs of a_n..a_0 always, ŝ0, ŝ1, ŝ1,0 only when
    the decision tree asks for them (the paper's point). Signs are exact: at a float t (its
    exact binary value) a float Horner filter with a proven bound decides first
    (:mod:`core.algebra.polysign`), exact evaluation otherwise; so the relation agrees with
    :meth:`MotionAnalysis.relation_at`.

    Args:
        n: 3 (ellipses) or 4 (ellipsoids).
        polys: ``a0``..``a{n}``, ``s0``, ``s1``, ``s10`` as in :class:`MotionAnalysis`.
        t: a rational time (float, int, Fraction, "p/q").

    Returns:
        (:class:`core.formulae.decision.Decision`, {name: sign} of the polynomials evaluated).
    """
    sg = Signs(polys, to_fmpq(t), set(), t if isinstance(t, float) else None)
    for i in (0, n):
        sg(f"a{i}")
    return decide_with(n, sg), sg.cache


def sign_row_at(n: int, polys: dict[str, QSqrtPoly], t: Any) -> SignRow:
    """The full sign-table row at one rational time t (every a_i, ŝ_j evaluated exactly).

    Same arguments as :func:`decide_at`; the relation and rule come from the same decision
    tree as the analysis' own rows.
    """
    tq = to_fmpq(t)
    sg = Signs(polys, tq, set())
    return sign_row("point", str(tq), n, sg, decide_with(n, sg))
