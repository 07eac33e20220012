"""``explain(A, B)``: everything behind one decision, for the scene, the API and students.

Reports the coefficients a_i of P(T) = det(T A + B) (true values, not scaled), the s0, s1, s1,0
the tree needed (exact rationals when the exact path ran, floats with a proven error bound when
the float filter certified the answer), their signs, Var(a_n..a_0), the rule of the paper that
decided, and which arithmetic certified it.
"""

from __future__ import annotations

import math
from typing import Any

from flint import fmpq

from ..formulae.decision import RULES, sign_variations
from ..formulae.subresultants import hat_scale
from ..shapes.numbers import format_rational, sign, to_float
from .exact import exact_pair
from .explanation import Explanation, Quantity
from .filters import explain_float

__all__ = ["Quantity", "Explanation", "explain", "display_float"]


def display_float(v: fmpq) -> float | None:
    """The nearest float of an exact value, or None when it does not fit.

    None on overflow, or for a nonzero value that rounds to 0: a display value never misstates
    the sign or the size.
    """
    f = to_float(v)
    if math.isinf(f) or (f == 0 and v != 0):
        return None
    return f


def _q(name: str, v: fmpq) -> Quantity:
    return Quantity(name, display_float(v), str(v), None, sign(v), format_rational(v))


def explain(A: Any, B: Any) -> Explanation:
    """Explain the relation of one pair (see module docstring).

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> e = explain(circle(0), circle(2))
        >>> str(e.relation), e.rule, e.var, [q.exact for q in e.coefficients]
        ('tangent', '2d-s0=0', 2, ['-1', '1', '1', '-1'])
    """
    fl = explain_float(A, B)
    if fl is not None:
        return fl
    pair = exact_pair(A, B, scaled=False)
    dec = pair.decide()
    n = pair.n
    a = pair.coefficients
    coeffs = [_q(f"a{i}", fmpq(a[i])) for i in range(n + 1)]
    scale = hat_scale(n)
    subs: dict[str, Quantity | None] = {"s0": None, "s1": None, "s10": None}
    needed: list[str] = [k for k in ("s0", "s1", "s10") if k in pair._cache]
    for k, c in zip(("s0", "s1", "s10"), scale, strict=False):
        if k in pair._cache:
            true = -fmpq(a[n]) * fmpq(c.numerator, c.denominator) * fmpq(pair._cache[k])
            subs[k] = _q(k, true)
    return Explanation(
        n=n,
        relation=dec.relation,
        certified_by="exact",
        rule=dec.rule,
        rule_text=RULES[dec.rule],
        var=sign_variations([sign(x) for x in reversed(a)]),
        coefficients=coeffs,
        s0=subs["s0"],
        s1=subs["s1"],
        s10=subs["s10"],
        subresultants_needed=needed,
    )
