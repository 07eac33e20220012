"""What the scene shows about contact: the certified witnesses, and float display helpers.

:func:`witness_view` asks ``core.witness`` for the witness of a certified pair, as the readout
and the 3D view show it: the contact scale as a margin ("1.8 % apart"), the sentence that
explains the relation, the certified separating plane (separate), the exact contact point and
normal (tangent) or a rational point inside both (overlap). Float shapes (gizmo drags) take the
float forms, which are certified too (a drag costs a few tenths of a millisecond more); exact
shapes (typed fractions) the exact ones.

The float helpers below only say *where* to draw when no exact witness applies (the timeline at
an algebraic event time, where the float matrices are not exactly tangent): at an external
tangency P(T) = det(T A + B) has a positive double root beta, and the contact point X spans the
kernel of beta A + B (then A X = -(1/beta) B X: the normals are opposite).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.polynomial import polynomial as npoly

__all__ = ["contact_point", "WitnessView", "witness_view"]

MARGIN_RTOL = 1e-6
"""Relative width of the contact-scale bracket the readout asks for (floats decide it)."""


@dataclass
class WitnessView:
    """The witness of one certified pair, as the scene shows it."""

    relation: str
    margin: str | None
    """"1.8 % apart", "touching", "overlapping by 3 %" (None if it could not be computed)."""
    mu: tuple[float, float] | None
    """Certified bracket of the contact scale."""
    sentence: str
    detail: str
    """The witness's numbers, short ("n = (1, 0, 0), d = 3/2")."""
    point: tuple[float, ...] | None = None
    """Contact point (tangent) or a point inside both (overlap), for drawing."""
    point_label: str = "contact"
    normal: tuple[float, ...] | None = None
    """Unit common normal at the contact point (out of A), for drawing."""
    plane: tuple[np.ndarray, float] | None = None
    """Certified separating plane (unit normal n, offset d: n.x = d), for drawing."""

    def readout(self) -> str:
        """Markdown lines for the readout panel."""
        lines = []
        if self.margin is not None and self.mu is not None:
            lo, hi = self.mu
            if self.relation == "tangent":
                lines.append(f"**Margin** {self.margin} (contact scale μ = 1)")
            else:  # a rounded percentage and bracket: marked, never a number that looks exact
                side = ">" if self.relation == "separate" else "<"
                bracket = f"μ ∈ [{lo:.7g}, {hi:.7g}]"
                if f"{lo:.7g}" == f"{hi:.7g}" == "1":
                    bracket = f"μ {side} 1 by less than float64 can show"
                lines.append(f"**Margin** ≈ {self.margin} (contact scale {bracket})")
        lines.append("")
        lines.append(f"**Witness** {self.sentence}: {self.detail}" if self.detail else f"**Witness** {self.sentence}")
        return "\n".join(lines)


def _short(values: Sequence[Any]) -> str:
    """Exact numbers as text, decimals when a fraction is long."""
    out = []
    for v in values:
        text = str(v)
        if len(text) > 14:
            text = f"{float(v):.6g}"
        out.append(text)
    return "(" + ", ".join(out) + ")"


def witness_view(A: Any, B: Any, relation: str) -> WitnessView | None:
    """The certified witness of a pair whose relation ``core`` certified (None if it fails).

    One call of ``core.witness.witness`` (adaptive): float shapes (a drag) are certified by
    floats with directed rounding in a few tenths of a millisecond, exact shapes (typed values)
    and what floats cannot certify (gaps at rounding level) by exact rationals.

    Args:
        A: matrix of shape A (float array, or exact lists).
        B: matrix of shape B.
        relation: the certified relation ("separate", "tangent", "overlap").
    """
    from core import Relation
    from core.witness import Witness, witness

    rel = Relation.parse(relation)
    try:
        w = witness(A, B, rtol=MARGIN_RTOL)
    except (ValueError, ArithmeticError, RuntimeError):
        return None
    if not isinstance(w, Witness) or w.relation != rel:
        return None
    try:
        lo, hi = float(w.scale.lo), float(w.scale.hi)
        view = WitnessView(str(rel), w.margin, (lo, hi), w.sentence, "")
        if w.plane is not None:
            view.plane = w.plane.unit()
            view.detail = f"n·x = d with n = {_short(w.plane.normal)}, d = {_short([w.plane.offset])[1:-1]}"
        elif w.point is not None:
            cp = w.point
            point, normal = cp.approx()
            view.point = tuple(point)
            view.normal = None if normal is None else tuple(normal)
            exact = cp.rational_point
            shown = _short(exact) if exact is not None else _short([c.decimal(8) for c in cp.point])
            if rel == Relation.TANGENT:
                kind = "exact" if exact is not None else "exact algebraic, 8 digits shown"
                view.detail = f"at {shown} ({kind}), common normal ≈ {_short([f'{v:.4g}' for v in normal or ()])}"
            else:
                view.point_label = "inside both"
                view.detail = shown
        return view
    except (ValueError, ArithmeticError, RuntimeError):
        return None


def contact_point(A: Any, B: Any, coefficients: Sequence[float]) -> np.ndarray | None:
    """Approximate contact point of two tangent shapes (floats, for drawing).

    Args:
        A: one matrix (3x3 or 4x4; floats or exact numbers).
        B: the other.
        coefficients: a_0..a_n of P(T) (floats, ascending).

    Returns:
        (d,) coordinates of the contact point, or None when no positive root is found.

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> contact_point(circle(0), circle(2), [-1, 1, 1, -1]).round(9).tolist()
        [1.0, 0.0]
    """
    a = np.asarray(coefficients, dtype=float)
    if not np.all(np.isfinite(a)) or a[-1] == 0:
        return None
    # the double root is a root of P'; pick the positive root of P' where |P| is smallest
    cands = npoly.polyroots(npoly.polyder(a))
    cands = cands[np.abs(cands.imag) <= 1e-6 * (1 + np.abs(cands.real))].real
    cands = cands[cands > 0]
    if cands.size == 0:
        return None
    beta = float(cands[np.argmin(np.abs(npoly.polyval(cands, a)))])
    Af = np.array([[float(v) for v in row] for row in A], dtype=float)
    Bf = np.array([[float(v) for v in row] for row in B], dtype=float)
    _, _, vt = np.linalg.svd(beta * Af + Bf)
    v = vt[-1]
    if v[-1] == 0:
        return None
    point: np.ndarray = v[:-1] / v[-1] + 0.0  # + 0.0 turns -0.0 into 0.0
    return point
