"""The readout of a motion at one instant: exact signs from the analysis, floats only for display.

:func:`explanation_at` gives what :func:`core.explain` gives for fixed shapes (the dict that
:func:`app.scene.pair.panels.readout_markdown` shows), for a moving pair at a time t:

* at a rational t (a slider float is the exact binary rational it is; a typed "2/3"), the
  signs of a_i(t) and of the ŝ_j(t) the decision tree asks for, evaluated exactly
  (:func:`core.moving.signs.decide_at`, the function behind ``MotionAnalysis.sign_row_at``);
* at an irrational algebraic t (a typed closed form such as ``(12-2*sqrt(2))/17``), the same
  tree on exact signs at that real algebraic number (:class:`core.moving.signs.Signs`);
* at the k-th event, the analysis' own sign-table row of that instant.

The values shown next to the signs are floats of det(T A(t) + B(t)) at the float t, from the
float matrices (display only; a float on the wrong side of 0 shows as "sign only").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from core.algebra.algebraic import RealAlgebraic
from core.formulae.decision import RULES
from core.moving.result import MotionAnalysis
from core.moving.signs import Signs, decide_at, decide_with

__all__ = ["explanation_at"]

FloatMatrices = Callable[[float], tuple[np.ndarray, np.ndarray]]


def _signs_at(result: MotionAnalysis, polys: dict[str, Any], t: Any) -> dict[str, Any]:
    n = result.n
    if isinstance(t, RealAlgebraic):
        sg = Signs(polys, t, set())
        for i in (0, n):
            sg(f"a{i}")
        dec, signs = decide_with(n, sg), sg.cache
    else:
        dec, signs = decide_at(n, polys, t)
    return {
        "a": [signs[f"a{i}"] for i in range(n, -1, -1)],
        **{k: signs.get(k) for k in ("s0", "s1", "s10")},
        "var": dec.var,
        "relation": str(dec.relation),
        "rule": dec.rule,
    }


def _event_row(result: MotionAnalysis, event: int) -> dict[str, Any] | None:
    ev = result.events[event - 1]
    for r in result.sign_table:
        if r.where == "point" and r.t == ev.value:
            return {"a": list(r.a), "s0": r.s0, "s1": r.s1, "s10": r.s10, "var": r.var, "relation": str(r.relation), "rule": r.rule}
    return None


def _float_values(matrices: FloatMatrices, t: float) -> dict[str, float]:
    """Float a_i, s0, s1, s1,0 of the float matrices at t (display only; {} if they fail)."""
    from core.formulae.pencil import pencil_coefficients
    from core.formulae.subresultants import s0_full, s1_full, s10_full

    try:
        Af, Bf = matrices(t)
        fa = [float(v) for v in pencil_coefficients(Af, Bf)]
        out = {f"a{i}": v for i, v in enumerate(fa)}
        out.update(s0=float(s0_full(fa)), s1=float(s1_full(fa)), s10=float(s10_full(fa)))
        return out
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return {}


def explanation_at(
    result: MotionAnalysis,
    polys: dict[str, Any],
    matrices: FloatMatrices,
    t: Any,
    t_float: float,
    event: int | None = None,
) -> dict[str, Any] | None:
    """Readout data at t, or at the k-th event (the dict of ``core.explain(...).to_dict()``).

    Args:
        result: the motion's analysis.
        polys: ``result.polynomials()`` (kept by the caller: built once per analysis).
        matrices: float A(t), B(t) for the values shown (display only).
        t: the exact time: a float (its binary value), a rational, or a RealAlgebraic.
        t_float: t as a float (for the values shown).
        event: 1-based event index: the analysis' row of that instant instead of ``t``.

    Returns:
        The explanation dict, or None if an event's row is missing.
    """
    if event is not None:
        row = _event_row(result, event)
        if row is None:
            return None
    else:
        row = _signs_at(result, polys, t)
    n = result.n
    approx = _float_values(matrices, t_float)
    nan = float("nan")

    def q(name: str, sign: int | None) -> dict[str, Any] | None:
        if sign is None:  # the tree did not need it
            return None
        v = approx.get(name, nan)
        if sign == 0:
            v = 0.0
        elif (v > 0) - (v < 0) != sign:  # NaN, or a float on the wrong side of 0
            v = nan
        return {"name": name, "approx": v, "exact": "0" if sign == 0 else None, "bound": None, "sign": sign}

    a_signs = list(reversed(row["a"]))
    return {
        "n": n,
        "relation": row["relation"],
        "certified_by": "exact",
        "rule": row["rule"],
        "rule_text": RULES.get(row["rule"], row["rule"]),
        "var": row["var"],
        "coefficients": [q(f"a{i}", a_signs[i]) for i in range(n + 1)],
        "s0": q("s0", row["s0"]),
        "s1": q("s1", row["s1"]),
        "s10": q("s10", row["s10"]),
    }
