"""One instant of a loaded motion: the certified relation and the readout at a time t.

What the timeline asks at every step, answered from the analysis data the worker sent back (its
result dict and the exact polynomials): exact comparisons with the isolating intervals for the
relation, exact signs of a_i(t), s_j(t) at t (``core.moving.signs.decide_at``) for the readout.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .analysis import MotionModel

__all__ = ["RelationLookup", "explain_at", "SIGN_VALUE"]

SIGN_VALUE = {"+": 1, "-": -1, "0": 0}
"""Sign characters of the rows of the analysis JSON, as ints."""


class RelationLookup:
    """Certified relation at a float t from the analysis data (exact rational comparisons).

    A float t is an exact binary rational. It is compared exactly with each event's isolating
    interval and each open interval of constant relation; inside an isolating interval (only
    possible when it is wider than the float spacing) a rational event is compared with its
    exact value, and otherwise the exact signs at t decide (``core.moving.signs.decide_at``).
    """

    def __init__(self, result: dict[str, Any], polys: dict[str, Any]) -> None:
        from core.shapes.numbers import to_fmpq

        self._n = int(result["dimension"]) + 1
        self._polys = polys
        self._events = []
        for e in result["events"]:
            lo, hi = (to_fmpq(x) for x in e["isolating"])
            exact = to_fmpq(e["exact"]) if e.get("exact") is not None else None
            self._events.append((lo, hi, exact, e["relation"]))
        self._intervals = []
        for iv in result["intervals"]:
            lo = None if iv["lo"] is None else to_fmpq(iv["lo"]["isolating"][1])
            hi = None if iv["hi"] is None else to_fmpq(iv["hi"]["isolating"][0])
            self._intervals.append((lo, hi, iv["relation"]))

    def __call__(self, t: Any) -> str:
        """Relation ("separate", "tangent", "overlap") at the exact value of t."""
        from core.shapes.numbers import to_fmpq

        tq = to_fmpq(t)
        for lo, hi, exact, rel in self._events:
            if lo <= tq <= hi:
                if exact is not None and tq == exact:
                    return rel
                return self._direct(tq)
        for lo, hi, rel in self._intervals:
            if (lo is None or lo < tq) and (hi is None or tq < hi):
                return rel
        return self._direct(tq)

    def _direct(self, tq: Any) -> str:
        from core.moving.signs import decide_at

        return str(decide_at(self._n, self._polys, tq)[0].relation)


def explain_at(model: MotionModel, result: dict[str, Any], polys: dict[str, Any], t: float, event: int | None) -> dict[str, Any] | None:
    """Readout data at t, or at the k-th event: exact signs, float values for display.

    At a float t (an exact binary rational) the signs of the a_i(t) of the analysis, and of the
    ŝ_j(t) the decision tree needs, are evaluated exactly (``core.moving.signs.decide_at``: tens of
    microseconds, sqrt(d) motions included; unneeded s_j show as "not needed", as in the static
    readout). At an event (an algebraic time) they are the sign-table row of that instant,
    decided exactly by the analysis. The values shown are float approximations of the
    coefficients of det(T A(t) + B(t)) and of s0, s1, s1,0 from the float matrices (display
    only; a value whose float falls on the wrong side of 0 is shown as "sign only").
    """
    from core.formulae.decision import RULES
    from core.moving.signs import decide_at

    n = int(result["dimension"]) + 1
    if event is None:
        dec, signs = decide_at(n, polys, t)
        row = {"a": [signs[f"a{i}"] for i in range(n, -1, -1)], **{k: signs.get(k) for k in ("s0", "s1", "s10")},
               "var": dec.var, "relation": str(dec.relation), "rule": dec.rule}
        t_float = float(t)
    else:
        ev = result["events"][event - 1]
        plain = next((r for r in result["sign_table"] if r["where"] == "point" and r["t"] == ev["value"]), None)
        if plain is None:
            return None
        row = {**plain, "a": [SIGN_VALUE[x] for x in plain["a"]], **{k: SIGN_VALUE[plain[k]] for k in ("s0", "s1", "s10")}}
        t_float = float(ev["approx"])
    approx = _float_readout_values(model, t_float)
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


def _float_readout_values(model: MotionModel, t: float) -> dict[str, float]:
    """Float a_i, s0, s1, s1,0 of the float matrices at t (display only; {} if they fail)."""
    from core.formulae.pencil import pencil_coefficients
    from core.formulae.subresultants import s0_full, s1_full, s10_full

    try:
        Af, Bf = model.float_matrices(t)
        fa = [float(v) for v in pencil_coefficients(Af, Bf)]
        out = {f"a{i}": v for i, v in enumerate(fa)}
        out.update(s0=float(s0_full(fa)), s1=float(s1_full(fa)), s10=float(s10_full(fa)))
        return out
    except (ValueError, ArithmeticError):
        return {}
