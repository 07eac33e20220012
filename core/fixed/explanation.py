"""The record of one decision: the numbers behind it (:class:`Quantity`) and :class:`Explanation`.

Filled by the float filter (:func:`core.fixed.explain.explain_float`) or by exact arithmetic
(:func:`core.fixed.explain.explain`); a type of its own so that neither imports the other.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Literal

from ..relation import Relation

__all__ = ["Quantity", "Explanation"]


@dataclass(frozen=True)
class Quantity:
    """One number of the decision: name, exact value (if known), float value, bound, sign."""

    name: str
    """"a0".."a4", "s0", "s1" or "s10"."""
    approx: float | None
    """Nearest float (display only), or None when the value is outside the float range
    (|value| > 1.8e308, or nonzero and below the smallest subnormal): read ``text`` then."""
    exact: str | None = None
    """Exact rational as "p/q" when the exact path computed it."""
    bound: float | None = None
    """|exact - approx| <= bound, when the value comes from the float filter."""
    sign: int | None = None
    """Certified sign (-1, 0, 1), or None when the bound cannot certify it."""
    text: str = ""
    """The value in scientific notation at any size ("-1.23457e+612"), computed exactly."""


@dataclass(frozen=True)
class Explanation:
    """Why two shapes are in the relation they are in."""

    n: int
    """3 for ellipses, 4 for ellipsoids (degree of P)."""
    relation: Relation
    certified_by: Literal["float", "exact"]
    rule: str
    """Key of :data:`core.formulae.decision.RULES` that decided."""
    rule_text: str
    var: int
    """Var(a_n, ..., a_0): sign changes of the coefficients."""
    coefficients: list[Quantity]
    """a_0 .. a_n ascending."""
    s0: Quantity | None = None
    s1: Quantity | None = None
    s10: Quantity | None = None
    """Subresultant coefficients; None when the tree did not need them."""
    subresultants_needed: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (relation as its lower-case name)."""
        d = asdict(self)
        d["relation"] = str(self.relation)
        return d
