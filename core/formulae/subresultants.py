"""Subresultant coefficients s0, s1, s1,0 of P(T) and P'(T), ring-generic (paper Remarks 11, 23).

Signs follow the paper (and ``../shared/spec/NOTES.md``): s0 is Res(P, P') in Sylvester order,
s1 and s1,0 are the Basu-Pollack-Roy *signed* subresultant coefficients (Remark 11 as printed
lost two minus signs; corrected here).

The decision trees only need signs, and a_n < 0 for every valid pair, so we work with the
"hat" forms ``hs_j``, integer polynomials in the a_i with ``s_j = -a_n * c_j * hs_j`` for a
positive rational constant ``c_j`` (:func:`hat_scale`). For quartics the hats use Section 4.3's
18-multiplication layout with ``ã_i = 12 ā_i`` (integers, no division):
ã4 = 12a4, ã3 = -3a3, ã2 = 2a2, ã1 = -3a1, ã0 = 12a0.

Everything uses only ``+ - *`` and small integer constants, so the same code runs on floats,
numpy arrays, ``fmpq``, ``fmpq_poly`` in t and Q(sqrt d)[t] elements.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import Any

__all__ = [
    "hat_s0",
    "hat_s1",
    "hat_s10",
    "hat_scale",
    "s0_full",
    "s1_full",
    "s10_full",
]


def _quartic_terms(a: Sequence[Any]) -> tuple[Any, Any, Any, Any, Any, Any, Any, Any]:
    """Section 4.3's intermediate quantities on ã = 12 ā (all integer-scaled)."""
    a0, a1, a2, a3, a4 = a
    t4 = a4 * 12
    t3 = a3 * (-3)
    t2 = a2 * 2
    t1 = a1 * (-3)
    t0 = a0 * 12
    d2 = t3 * t3 - t2 * t4
    d3 = t2 * t2 - t3 * t1
    w1 = t1 * t4 - t3 * t2
    w3 = t0 * t4 - t3 * t1
    aa = w3 + d3 * 3
    bb = t1 * w1 + t0 * d2 + t2 * d3
    return t3, d2, d3, w1, w3, aa, bb, t2


def hat_s0(a: Sequence[Any]) -> Any:
    """Sign-equivalent of s0 (same sign whenever a_n < 0).

    Cubic: the discriminant of P. Quartic: 27 b² - a³ on ã (Section 4.3).

    Examples:
        >>> hat_s0([-1, 3, -3, 1])      # (T-1)^3 has a triple root
        0
    """
    if len(a) == 4:
        a0, a1, a2, a3 = a
        return -(
            a0 * a0 * a3 * a3 * 27
            - a0 * a1 * a2 * a3 * 18
            + a0 * a2 * a2 * a2 * 4
            + a1 * a1 * a1 * a3 * 4
            - a1 * a1 * a2 * a2
        )
    if len(a) == 5:
        _, _, _, _, _, aa, bb, _ = _quartic_terms(a)
        return bb * bb * 27 - aa * aa * aa
    raise ValueError(f"need 4 (cubic) or 5 (quartic) coefficients, got {len(a)}")


def hat_s1(a: Sequence[Any]) -> Any:
    """Sign-equivalent of s1 (same sign whenever a_n < 0)."""
    if len(a) == 4:
        _, a1, a2, a3 = a
        return a1 * a3 * 3 - a2 * a2
    if len(a) == 5:
        _, d2, d3, w1, w3, _, _, _ = _quartic_terms(a)
        return w3 * d2 + w1 * w1 * 3 - d2 * d3 * 9
    raise ValueError(f"need 4 (cubic) or 5 (quartic) coefficients, got {len(a)}")


def hat_s10(a: Sequence[Any]) -> Any:
    """Sign-equivalent of s1,0 (same sign whenever a_n < 0)."""
    if len(a) == 4:
        a0, a1, a2, a3 = a
        return a0 * a3 * 9 - a1 * a2
    if len(a) == 5:
        t3, _, _, w1, _, aa, bb, _ = _quartic_terms(a)
        return -(bb * t3 * 3 + aa * w1)
    raise ValueError(f"need 4 (cubic) or 5 (quartic) coefficients, got {len(a)}")


def hat_scale(n: int) -> tuple[Fraction, Fraction, Fraction]:
    """Positive constants (c0, c1, c10) with s_j = -a_n * c_j * hs_j for degree n = 3 or 4."""
    if n == 3:
        return Fraction(1), Fraction(2), Fraction(1)
    if n == 4:
        return Fraction(256, 12**6), Fraction(192, 12**4), Fraction(192, 12**4)
    raise ValueError(f"degree must be 3 or 4, got {n}")


# The paper's explicit formulas (NOTES.md), kept as an independent check of the hat forms.


def s0_full(a: Sequence[Any]) -> Any:
    """s0 = Res(P, P') from Remark 11 (cubic) / Remark 23 (quartic), as printed in NOTES.md."""
    if len(a) == 4:
        a0, a1, a2, a3 = a
        return a3 * (
            27 * a0**2 * a3**2 - 18 * a0 * a1 * a2 * a3 + 4 * a0 * a2**3 + 4 * a1**3 * a3
            - a1**2 * a2**2
        )
    a0, a1, a2, a3, a4 = a
    return a4 * (
        256 * a0**3 * a4**3 - 192 * a0**2 * a1 * a3 * a4**2 - 128 * a0**2 * a2**2 * a4**2
        + 144 * a0**2 * a2 * a3**2 * a4 - 27 * a0**2 * a3**4 + 144 * a0 * a1**2 * a2 * a4**2
        - 6 * a0 * a1**2 * a3**2 * a4 - 80 * a0 * a1 * a2**2 * a3 * a4 + 18 * a0 * a1 * a2 * a3**3
        + 16 * a0 * a2**4 * a4 - 4 * a0 * a2**3 * a3**2 - 27 * a1**4 * a4**2
        + 18 * a1**3 * a2 * a3 * a4 - 4 * a1**3 * a3**3 - 4 * a1**2 * a2**3 * a4
        + a1**2 * a2**2 * a3**2
    )


def s1_full(a: Sequence[Any]) -> Any:
    """Signed subresultant coefficient s1 (NOTES.md; Remark 11 with its sign restored)."""
    if len(a) == 4:
        _, a1, a2, a3 = a
        return 2 * a3 * (a2**2 - 3 * a1 * a3)
    a0, a1, a2, a3, a4 = a
    return 2 * a4 * (
        16 * a0 * a2 * a4**2 - 6 * a0 * a3**2 * a4 - 18 * a1**2 * a4**2 + 14 * a1 * a2 * a3 * a4
        - 3 * a1 * a3**3 - 4 * a2**3 * a4 + a2**2 * a3**2
    )


def s10_full(a: Sequence[Any]) -> Any:
    """Signed subresultant coefficient s1,0 (NOTES.md; Remark 11 with its sign restored)."""
    if len(a) == 4:
        a0, a1, a2, a3 = a
        return a3 * (a1 * a2 - 9 * a0 * a3)
    a0, a1, a2, a3, a4 = a
    return -a4 * (
        48 * a0 * a1 * a4**2 - 32 * a0 * a2 * a3 * a4 + 9 * a0 * a3**3 - 3 * a1**2 * a3 * a4
        + 4 * a1 * a2**2 * a4 - a1 * a2 * a3**2
    )
