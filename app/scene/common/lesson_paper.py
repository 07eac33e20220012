"""The built-in lesson ``paper``: the paper of Caravantes et al. played step by step.

"Solving the interference problem for ellipses and ellipsoids: new formulae", in the format of
:mod:`app.scene.common.lesson`. From an ellipse as a matrix to P(T) = det(TA + B), Descartes' law of signs, tangency as a double
root, ellipsoids, and the moving Examples 29, 30 and 33. The numbers quoted are the paper's
(Example 29's P(t, T) and α1, α2; Example 30's α3 = 1/2; Example 33's P) or worked out by hand
for the static pairs (tests/test_classroom.py checks each against exact arithmetic of its own).
"""

from __future__ import annotations

from typing import Any

__all__ = ["PAPER"]

_ELLIPSE_A = {"matrix": [["1/4", "0", "0"], ["0", "1", "0"], ["0", "0", "-1"]]}
"""x²/4 + y² − 1: the ellipse with semi-axes 2 and 1 at the origin, as the paper writes it."""

_PREDICT = "Predict: separate, tangent or overlap?"


def _circle(x: str, y: str) -> dict[str, Any]:
    return {"center": [x, y], "semi_axes": ["1", "1"], "orientation": ["0"]}


def _static2(b: dict[str, Any]) -> dict[str, Any]:
    return {"dim": 2, "preset": None, "A": _ELLIPSE_A, "B": b, "gizmos": False}


PAPER: dict[str, Any] = {
    "title": "Ellipses and ellipsoids: the paper, step by step",
    "steps": [
        {
            "title": "An ellipse is a matrix",
            "scene": _static2({"matrix": [["1", "0", "-4"], ["0", "1", "0"], ["-4", "0", "15"]]}),
            "words": (
                "Section 3: a conic is 𝒳A𝒳ᵗ = 0 with 𝒳 = (X, Y, 1) and A symmetric, "
                "presented so that the **interior is 𝒳A𝒳ᵗ < 0**; for an ellipse **det(A) < 0**. "
                "Here A = [1/4, 0, 0; 0, 1, 0; 0, 0, −1] is x²/4 + y² = 1 and "
                "B = [1, 0, −4; 0, 1, 0; −4, 0, 15] is (x − 4)² + y² = 1. Open *Shape A* and *Shape B*: "
                "the Matrix field holds the exact matrix, the other fields its centre and semi-axes."
            ),
            "question": "Read B's matrix: where is its centre, and what is its radius?",
            "answer": "Centre (4, 0), radius 1: (x − 4)² + y² − 1 = x² − 8x + y² + 15, so a13 = −4 and a33 = 15.",
            "open": ["shape A", "shape B"],
        },
        {
            "title": "P(T) = det(TA + B) and its roots",
            "scene": _static2({"matrix": [["1", "0", "-4"], ["0", "1", "0"], ["-4", "0", "15"]]}),
            "words": (
                "Definition 6: the characteristic equation is **P(T) = det(TA + B) = det(A)T³ + … + det(B)**, "
                "a cubic for two ellipses. Theorem 7: its leading coefficient and constant term are strictly "
                "negative, it has at least one negative real root, and the ellipses are **separated by a line "
                "if and only if P(T) has two distinct positive roots**. Here "
                "P(T) = −¼(T + 1)(T² − 11T + 4): roots −1 and (11 ± √105)/2."
            ),
            "question": _PREDICT,
            "answer": "Separate: the roots (11 ± √105)/2 ≈ 0.377 and 10.62 are two distinct positive roots (Theorem 7.3).",
            "open": ["roots"],
            "roots": True,
        },
        {
            "title": "Separate ⇔ Var = 2 and s0 > 0 (Descartes)",
            "scene": _static2(_circle("3", "1")),
            "words": (
                "Proposition 4 (Descartes' law of signs): the number of positive roots is Var(a3, a2, a1, a0) "
                "minus an even number; when all roots are real it *is* Var (Proposition 5). Theorem 12: "
                "**ellipses are separate iff s0 > 0 and (a1 > 0 or a2 > 0)**; Corollary 13: iff "
                "Var(−, a2, a1, −) = 2 and s0 > 0. No root needs to be computed: only signs of the a_i and "
                "of s0. The circle B now has its centre at (3, 1). *What am I seeing?* names Var and s0."
            ),
            "question": _PREDICT,
            "answer": "Separate: s0 > 0 and Var(−, a2, a1, −) = 2 (Corollary 13); the circle stays ≈ 0.29 away from the ellipse.",
            "open": ["words", "roots"],
            "roots": True,
        },
        {
            "title": "External tangency ⇔ a positive double root (s0 = 0)",
            "scene": _static2(_circle("3", "0")),
            "words": (
                "Theorem 7.4: the ellipses **touch externally iff P(T) has a positive double root**. "
                "A double root makes the resultant of P and P′ vanish: **s0 = 0**. Theorem 14: externally "
                "tangent **iff s0 = 0 and s1,0 > 0**, and then the double root is β = −s1,0/s1. Here B is the "
                "unit circle at (3, 0): P(T) = −¼(T + 1)(T − 2)², a double root at T = 2 (the ring marked ×2)."
            ),
            "question": _PREDICT,
            "answer": "Tangent at (2, 0): s0 = 0 and s1,0 > 0 (Theorem 14); β = 2 is the positive double root.",
            "open": ["roots", "words"],
            "roots": True,
        },
        {
            "title": "Overlap: no two positive roots",
            "scene": _static2(_circle("5/2", "0")),
            "words": (
                "If P(T) has neither two distinct positive roots nor a positive double root, the ellipses are "
                "neither separate nor externally tangent: their **interiors meet**. Here B is the unit circle at "
                "(5/2, 0): P(T) = −(T + 1)(4T² − 5T + 16)/16, one negative root and a **complex pair**: "
                "s0 < 0, so Theorem 12 cannot hold."
            ),
            "question": _PREDICT,
            "answer": "Overlap: s0 < 0 (a complex pair of roots), so neither Theorem 12 nor Theorem 14 holds.",
            "open": ["roots"],
            "roots": True,
        },
        {
            "title": "Ellipsoids: the quartic",
            "scene": {
                "dim": 3, "preset": None, "gizmos": False,
                "A": {"center": ["0", "0", "0"], "semi_axes": ["2", "1", "1"], "orientation": ["1", "0", "0", "0"]},
                "B": {"center": ["0", "0", "5/2"], "semi_axes": ["1", "1", "1"], "orientation": ["1", "0", "0", "0"]},
            },
            "words": (
                "Section 4: for ellipsoids the matrices are 4×4 and **P(T) = det(TA + B) is a quartic** "
                "(Definition 18). Theorem 19: at least **two negative roots**; separated by a plane iff two "
                "distinct positive roots; externally tangent iff a positive double root. Theorem 28: "
                "separated iff Var(a4, a3, a2, a1, a0) = 2 and (s0 < 0, or s0 = 0, s1 < 0, s1,0 < 0); "
                "Theorem 24: externally tangent iff s0 = 0 and (s1 = 0 and Var = 2, or s1 < 0 and s1,0 > 0). "
                "Here the unit sphere sits at height 5/2 above A (semi-axes 2, 1, 1): "
                "P(T) = −(T + 4)(T + 1)(T − 4)(T − 1/4)/4."
            ),
            "question": _PREDICT,
            "answer": "Separate: two distinct positive roots 1/4 and 4 (reciprocal here), two negative roots −4 and −1.",
            "open": ["roots", "words"],
            "roots": True,
        },
        {
            "title": "A motion: only the roots of s0(t) (or s1(t)) can change the relation (Example 29)",
            "scene": {"dim": 3, "preset": "example-29", "t": "0"},
            "words": (
                "Section 4.4: when the ellipsoids move, A(t) and B(t) give **P(t, T)** and the a_i, s0, s1, s1,0 "
                "become polynomials in t. The relation can only change where the conditions of Theorems 24 and "
                "28 change: at the **real roots of s0(t)**, or of s1(t) when s0 ≡ 0. Example 29: "
                "P(t, T) = −¼(T + 1)²(T² + (−68t² + 96t − 34)T + 1), so **s0 ≡ 0** and the events are the roots "
                "of s1(t) = −½(17t² − 24t + 8)(17t² − 24t + 9)³ in I = [0, 1]. Press Play, or drag t."
            ),
            "question": "At t = 0: separate, tangent or overlap? And how many times will the relation change on [0, 1]?",
            "answer": (
                "Separate at t = 0: s1(0) < 0 and Var(−, 8, 33/2, 8, −) = 2 (Theorem 28). It changes four times, at the "
                "two tangencies α1 = (12 − 2√2)/17 and α2 = (12 + 2√2)/17: separate, tangent, overlap, tangent, separate."
            ),
            "open": ["timeline", "plots"],
        },
        {
            "title": "Example 29 at the event α1 = (12 − 2√2)/17",
            "scene": {"dim": 3, "preset": "example-29", "event": 1},
            "words": (
                "At the root α1 = (12 − 2√2)/17 ≈ 0.5395042868 of 17t² − 24t + 8, "
                "**Var(−, a3(α1), a2(α1), a1(α1), −) = Var(−, 0, 1/2, 0, −) = 2** and s0 = s1 = 0: Theorem 24(1). "
                "P(α1, T) = −¼(T + 1)²(T − 1)²: a positive double root T = 1 and a negative double root T = −1, "
                "both drawn with their multiplicity. The time is exact (an algebraic number), not a decimal."
            ),
            "question": _PREDICT,
            "answer": "Tangent (externally), exactly at α1: Theorem 24(1), a double positive root at T = 1.",
            "open": ["roots", "timeline"],
            "roots": True,
        },
        {
            "title": "The sign table over the intervals (Example 29)",
            "scene": {"dim": 3, "preset": "example-29", "t": "3/4"},
            "words": (
                "Between two events nothing changes, so one test point per interval decides it: the paper takes "
                "δ1 = 0 ∈ [0, α1), δ2 = 3/4 ∈ (α1, α2), δ3 = 1 ∈ (α2, 1]. *Sign table* lists, interval by interval, "
                "the signs of a3, a2, a1, s0, s1, s1,0 and the relation they certify. t is now 3/4."
            ),
            "question": "At t = δ2 = 3/4: separate, tangent or overlap?",
            "answer": "Overlap: s1(3/4) = s1,0(3/4) > 0, so A(t) and B(t) overlap on the whole of (α1, α2).",
            "open": ["sign table", "timeline"],
        },
        {
            "title": "An event in Q(√2): Example 30 at α3 = 1/2",
            "scene": {"dim": 3, "preset": "example-30", "t": "1/2"},
            "words": (
                "Example 30 moves both ellipsoids by degree-two rotations and degree-three translations whose "
                "coefficients involve **√2**: ŝ0 has degree 84 in t with coefficients in Q(√2), and six real roots. "
                "By Theorem 24 the shapes are externally tangent at α1, α2, α3 = 1/2 and α6. With **√2 kept exact**, "
                "t = 1/2 is exactly tangent; a decimal √2 would turn it into a slight overlap (the paper's Remark 34 "
                "needed 35 digits)."
            ),
            "question": "At t = 1/2: separate, tangent or overlap?",
            "answer": "Tangent: α3 = 1/2 is a root of ŝ0 with ŝ1(α3) < 0 and ŝ1,0(α3) > 0 (Theorem 24(2)).",
            "open": ["timeline", "roots"],
            "roots": True,
        },
        {
            "title": "A degenerate motion: s0 ≡ 0 (Example 33)",
            "scene": {"dim": 3, "preset": "example-33", "t": "0"},
            "words": (
                "Example 33 moves the ellipsoids of Example 32 so that they always touch: "
                "**P(t, T) = −(1/576)(T + 1)(T + 4)(T − 1)²** does not depend on t, with **s0 ≡ 0, s1 < 0 and "
                "s1,0 > 0 for all t ∈ ℝ**. The second condition of Theorem 24 holds for every t. Type any t in the "
                "t box (say 3, or −5/2): I = ℝ, the slider widens to show it."
            ),
            "question": "For which t are they separate, tangent, or overlapping?",
            "answer": "Tangent for every real t: P(t, T) always has the positive double root T = 1 (Theorem 24(2)).",
            "open": ["roots", "timeline"],
            "roots": True,
        },
    ],
}
"""The lesson as its JSON form (what a teacher's lesson file holds)."""
