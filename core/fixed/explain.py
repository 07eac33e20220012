"""``explain(A, B)``: everything behind one decision, for the scene, the API and students.

Reports the coefficients a_i of P(T) = det(T A + B) (true values, not scaled), the s0, s1, s1,0
the tree needed (exact rationals when the exact path ran, floats with a proven error bound when
the float filter certified the answer), their signs, Var(a_n..a_0), the rule of the paper that
decided, and which arithmetic certified it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from flint import fmpq

from ..filtered import predicate
from ..formulae.decision import RULE_LIST, RULES, sign_variations
from ..formulae.subresultants import hat_scale
from ..shapes.numbers import binary64_array, format_rational, sign, to_float, to_fmpq
from . import _kernels as K
from .errorbound import RADIUS_FACTOR
from .exact import exact_pair
from .explanation import Explanation, Quantity
from .filters import first_stage

__all__ = ["Quantity", "Explanation", "explain", "explain_float", "display_float", "HAT_DEGREE_WEIGHT"]

HAT_DEGREE_WEIGHT: dict[tuple[int, str], tuple[int, int]] = {
    (3, "s0"): (4, 6), (3, "s1"): (2, 4), (3, "s10"): (2, 3),
    (4, "s0"): (6, 12), (4, "s1"): (4, 10), (4, "s10"): (4, 9),
}
"""(degree, weight) of each hat form: hs(mu * lambda^i a_i) = mu^deg lambda^weight hs(a)."""

_EXPLAIN = predicate("explain")
"""The filtered predicate of :func:`explain` (float explanation, else exact; :func:`core.filter_stats`)."""


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

    The float filter's explanation where it certifies the pair (binary64 input), else the exact
    one: one evaluation of the ``explain`` predicate (:mod:`core.filtered`).

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> e = explain(circle(0), circle(2))
        >>> str(e.relation), e.rule, e.var, [q.exact for q in e.coefficients]
        ('tangent', '2d-s0=0', 2, ['-1', '1', '1', '-1'])
    """
    a, b = binary64_array(A, typed=True), binary64_array(B, typed=True)  # exact numbers: the exact explanation
    floats = a is not None and b is not None
    e, _ = _EXPLAIN.one(lambda: _explain_float(a, b), lambda: _explain_exact(A, B), "adaptive" if floats else "exact")
    assert e is not None  # "adaptive" and "exact" always answer
    return e


def _explain_exact(A: Any, B: Any) -> Explanation:
    """The exact stage of :func:`explain`: every number an exact rational."""
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


def explain_float(A: Any, B: Any) -> Explanation | None:
    """Explanation from the float filter if it certifies the pair, else None (exact path then).

    The numbers are those the filter's run computed (:func:`core.fixed.filters.first_stage`, the
    description the compiled kernels also run): a_i with their bounds, and s0 exactly when the
    tree asked for it. They come from the power-of-two scaled matrices (where the bounds are
    proven) and are scaled back exactly; a value that would leave the float range defers to the
    exact path.
    """
    return _explain_float(binary64_array(A, typed=True), binary64_array(B, typed=True))


def _explain_float(a: np.ndarray | None, b: np.ndarray | None) -> Explanation | None:
    """The float stage of :func:`explain` on binary64 arrays (None: not binary64, or not certified)."""
    if a is None or b is None:
        return None
    if a.ndim != 2 or a.shape != b.shape or a.shape[0] not in (3, 4) or a.shape[0] != a.shape[1]:
        return None
    n = a.shape[0]
    run = first_stage(a[None], b[None])
    code = int(run.rules[0])
    if code < 0:
        return None
    rule = RULE_LIST[code]
    ea, eb = int(run.a.k[0]), int(run.b.k[0])

    def quantity(name: str, v: float, bd: float, e: int, s: int | None) -> Quantity | None:
        """V * 2^e with bound bd * 2^e; None if either leaves the normal float range."""
        with np.errstate(all="ignore"):
            val, bound = float(np.ldexp(v, e)), float(np.ldexp(bd, e))
        if not (math.isfinite(val) and math.isfinite(bound)) or (val == 0.0) != (v == 0.0):
            return None
        exact_value = to_fmpq(v) * (fmpq(2) ** e if e >= 0 else fmpq(1, 2 ** (-e)))
        return Quantity(name, val, None, bound, s, format_rational(exact_value))

    vals = [float(run.c[i][0]) for i in range(n + 1)]
    radii = [float(run.cr[i][0]) for i in range(n + 1)]
    coeffs = []
    for i in range(n + 1):
        v, bd = vals[i], radii[i]
        s = 1 if v > bd else (-1 if v < -bd else None)
        q = quantity(f"a{i}", v, bd, -(i * ea + (n - i) * eb), s)
        if q is None:  # a value beyond the float range: the exact path shows it
            return None
        coeffs.append(q)
    needed = ["s0"] if bool(run.asked_s0[0]) else []
    s0 = None
    if needed:
        an = coeffs[n].approx
        an_bound = coeffs[n].bound
        assert an is not None and an_bound is not None  # a_n was certified (< 0) and fits a float
        hv, hr = getattr(K, f"hat_s0_{n}")(vals, radii)
        hv0, hb0 = float(hv), float(hr) * RADIUS_FACTOR + getattr(K, f"HAT_S0_{n}_FLOOR")
        deg, w = HAT_DEGREE_WEIGHT[(n, "s0")]
        # scaled a_i = mu lambda^i a_i with mu = 2^(n eb), lambda = 2^(ea - eb)
        e = -(n * eb * deg + (ea - eb) * w)
        with np.errstate(all="ignore"):
            hvs, hbs = float(np.ldexp(hv0, e)), float(np.ldexp(hb0, e))
        # s0 = -a_n c_0 hs0; a_n < 0 is certified, so sign(s0) = sign(hs0)
        factor = -an * float(hat_scale(n)[0])
        value = factor * hvs
        bound = abs(factor) * (hbs + abs(hvs) * (an_bound / abs(an))) * (1 + 2.0**-40)
        if not (math.isfinite(value) and math.isfinite(bound)) or (value == 0.0) != (hv0 == 0.0):
            return None
        s0 = Quantity("s0", value, None, bound, 1 if hv0 > hb0 else (-1 if hv0 < -hb0 else None), format_rational(to_fmpq(value)))
    return Explanation(
        n=n,
        relation=rule.relation,
        certified_by="float",
        rule=rule.key,
        rule_text=rule.text,
        var=sign_variations([q.sign or 0 for q in reversed(coeffs)]),
        coefficients=coeffs,
        s0=s0,
        subresultants_needed=needed,
    )
