"""Notes the scene adds under a preset's description: what the paper prints against what is certified.

A teacher projecting Example 30 should not be caught out: the paper's printed decimals of three
of its six roots do not satisfy its own data (``shared/spec/NOTES.md``, erratum 11), and the
scene's numbering of events differs from the paper's numbering of the roots of ŝ0. Each note
says what the paper prints, what the scene certifies, and why they differ.
"""

from __future__ import annotations

__all__ = ["PRESET_NOTES", "preset_notes"]

PRESET_NOTES: dict[str, str] = {
    "example-30": (
        "\n\n**The paper and this scene.** The paper lists six real roots of ŝ0 (its hat form "
        "ŝ0 = −s0/a4, of degree 84 in t with coefficients in Q(√2); the paper's s0 itself has degree 92) "
        "and finds external tangency at α1 ≈ −0.2439303678, α2 ≈ −0.1859966702, α3 = 1/2 and "
        "α6 ≈ 0.9007790307; its α4 ≈ 0.6329555326 and α5 ≈ 0.7719039167 are roots of ŝ0 where the "
        "shapes overlap. The scene lists only the instants where the relation is tangent (its *events*), "
        "so the paper's α6 is the scene's **α4**, certified at **0.9008011319…**, not 0.9007790307.\n\n"
        "Why: α1, α2 and α3 agree with the paper to more than 10 digits, and so do the degrees and every "
        "conclusion (tangent at four instants, overlap on (α1, α2) and (α3, α6)). But the printed decimals "
        "of α4, α5 and α6 do not satisfy the printed data: det(T A(t) + B(t)) has no double root there. "
        "The exact analysis here (isolating intervals over Q(√2), checked by an independent exact oracle "
        "in the tests) does have one at 0.9008011319…; trust the certified value. Each event is stored "
        "exactly as a root of a polynomial over Q of degree 166 (a factor of the norm of ŝ0, degree 168): "
        "that is why the event list says 166 where the paper says 84. √2 stays exact: with a rational "
        "approximation of √2 the tangency at t = 1/2 turns into a very slight overlap."
    ),
}
"""Preset name -> Markdown appended to its description."""


def preset_notes(name: str | None) -> str:
    """The scene's note on a preset ("" for none).

    Examples:
        >>> "0.9008011319" in preset_notes("example-30"), preset_notes("example-29")
        (True, '')
    """
    return PRESET_NOTES.get(name or "", "")
