""""What am I seeing?": the decision of the paper in plain words, next to the numbers of the readout.

:func:`plain_words` turns one explanation (``core.explain(...).to_dict()``, or the motion's at t)
into a few sentences for a class: what P(T) is, what Descartes' rule of signs says about its
positive roots (Var), what s0, s1 and s1,0 add when they were needed, and which theorem of the
paper decided. Text only: the numbers and signs are the readout's.
"""

from __future__ import annotations

from typing import Any

__all__ = ["plain_words", "RULE_WORDS"]

RULE_WORDS: dict[str, str] = {
    "var": "P has fewer than two positive roots, so no plane can separate the shapes: their interiors meet "
           "(Corollaries 13 and 16 for ellipses, Theorems 24 and 28 for ellipsoids).",
    "2d-s0>0": "The three roots of P are real and distinct, two of them positive: the ellipses are apart "
               "(Theorem 12, Corollary 13).",
    "2d-s0=0": "P has a positive double root: the ellipses touch at one point (Theorem 14, Corollary 16).",
    "2d-s0<0": "Two roots of P are complex, so there is no positive double root: the ellipses overlap (Theorems 12, 14).",
    "3d-s0<0": "The four roots of P are real and distinct, two of them positive: the ellipsoids are apart (Theorem 28.2).",
    "3d-s0>0": "Two roots of P are complex and the real ones are negative: the ellipsoids overlap (Section 4.4.1).",
    "3d-s1>0": "P has a double root next to a complex pair, and it is negative: the ellipsoids overlap (Lemma 22).",
    "3d-s1=0": "P has a positive and a negative double root: the ellipsoids touch (Theorem 24.1).",
    "3d-s10>0": "The double root of P is positive: the ellipsoids touch (Theorem 24.2).",
    "3d-s10<0": "The double root of P is negative and two other roots are positive: the ellipsoids are apart (Theorem 28.1).",
    "sep-witness": "P is positive at some T* > 0 while it starts negative at 0 and ends negative: it has two positive "
                   "roots, so the shapes are apart (Theorems 7 and 19), without computing s0.",
    "common-point": "A point was certified to lie inside both shapes: their interiors meet.",
}
"""Rule key (:data:`core.formulae.decision.RULES`) -> the conclusion in plain words."""

_SIGN_WORD = {1: "positive", -1: "negative", 0: "zero"}
_SIGN_CHAR: dict[int | None, str] = {1: "+", -1: "−", 0: "0"}
"""Sign -> the character in the list of signs (None: sign unknown, shown "?")."""


def plain_words(expl: dict[str, Any] | None) -> str:
    """Markdown: the decision of ``expl`` told in words (empty when nothing is decided).

    Examples:
        >>> expl = {"n": 3, "relation": "tangent", "rule": "2d-s0=0", "var": 2,
        ...         "coefficients": [{"sign": -1}, {"sign": 1}, {"sign": 1}, {"sign": -1}],
        ...         "s0": {"sign": 0}, "s1": None, "s10": None}
        >>> print(plain_words(expl).splitlines()[-1])
        **Decided**: P has a positive double root: the ellipses touch at one point (Theorem 14, Corollary 16).
    """
    if not expl or not expl.get("coefficients"):
        return ""
    n = expl["n"]
    shapes = "ellipses" if n == 3 else "ellipsoids"
    coeffs = expl["coefficients"]
    signs = ", ".join(_SIGN_CHAR.get(q.get("sign") if q else None, "?") for q in reversed(coeffs))
    var = expl["var"]
    lines = [
        f"**P(T) = det(T·A + B)** is a polynomial of degree {n} in T made from the two matrices. "
        f"Its coefficients a{n} … a0 have the signs ({signs}); a{n} = det A and a0 = det B are always negative.",
        "",
        f"**Var = {var}**: Descartes' rule of signs says that P has at most Var positive roots. The {shapes} can be "
        "apart or touching only if P has two positive roots (counted with multiplicity), so Var = 2 is needed"
        + (": it holds here." if var == 2 else f"; here Var = {var}."),
    ]
    for key, name, what in (
        ("s0", "s0", "the discriminant of P up to sign: zero exactly when P has a multiple root"),
        ("s1", "s1", "a subresultant of P and P′: with s0 = 0 it tells whether the multiple root is a double root "
                     "beside two other real roots or beside a complex pair"),
        ("s10", "s1,0", "another subresultant coefficient: with s0 = 0 and s1 < 0 its sign tells whether the double "
                        "root is positive (touching) or negative"),
    ):
        q = expl.get(key)
        if q is not None and q.get("sign") is not None:
            lines += ["", f"**{name} is {_SIGN_WORD[q['sign']]}**: {what}."]
    rule = expl.get("rule", "")
    if rule in RULE_WORDS:
        lines += ["", f"**Decided**: {RULE_WORDS[rule]}"]
    return "\n".join(lines)
