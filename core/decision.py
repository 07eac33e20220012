"""The paper's decision trees (Sections 3.3 and 4.3) on signs, evaluating s0, s1, s1,0 lazily.

Input are the *signs* of a_{n-1}..a_1 (a_n, a_0 < 0 for valid pairs) and callables that return
the signs of hs0, hs1, hs10 (see :mod:`core.subresultants`) when, and only when, the tree needs
them. The same tree serves the exact path (signs certain) and explain(); the vectorised float
filter in :mod:`core.filters` implements the two levels it can certify (Var and s0).

Ellipses (Corollaries 13, 16): Var(-, a2, a1, -) != 2 -> overlap; else s0 > 0 separate,
s0 = 0 tangent, s0 < 0 overlap.
Ellipsoids (Theorems 24, 28; tree of 4.3): Var(-, a3, a2, a1, -) != 2 -> overlap; else
s0 < 0 separate, s0 > 0 overlap; s0 = 0: s1 > 0 overlap, s1 = 0 tangent (24.1),
s1 < 0: s1,0 > 0 tangent (24.2), s1,0 < 0 separate (28.1).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from .relation import Relation

__all__ = ["Decision", "decide", "sign_variations", "RULES"]

RULES: dict[str, str] = {
    "var": "Var(a_n..a_0) != 2: fewer than two positive roots, the interiors meet "
    "(Cor. 13/16 for ellipses; Th. 24/28 for ellipsoids)",
    "2d-s0>0": "Var = 2 and s0 > 0: three distinct real roots, two positive (Th. 12, Cor. 13)",
    "2d-s0=0": "Var = 2 and s0 = 0: a positive double root (Th. 14, Cor. 16)",
    "2d-s0<0": "Var = 2 and s0 < 0: complex pair, no positive double root (Th. 12, 14)",
    "3d-s0<0": "Var = 2 and s0 < 0: four distinct real roots, two positive (Th. 28.2)",
    "3d-s0>0": "Var = 2 and s0 > 0: two complex roots, the real ones negative (4.4.1)",
    "3d-s1>0": "s0 = 0 and s1 > 0: double root with a complex pair, negative (Lemma 22)",
    "3d-s1=0": "s0 = s1 = 0 and Var = 2: positive and negative double roots (Th. 24.1)",
    "3d-s10>0": "s0 = 0, s1 < 0, s1,0 > 0: positive double root (Th. 24.2)",
    "3d-s10<0": "s0 = 0, s1 < 0, s1,0 < 0: negative double root, two positive roots (Th. 28.1)",
}


def sign_variations(signs: Sequence[int]) -> int:
    """Number of sign changes after dropping zeros (Descartes' Var).

    Examples:
        >>> sign_variations([-1, 1, 0, -1])
        2
        >>> sign_variations([0, 0])
        0
    """
    last = 0
    count = 0
    for s in signs:
        if s == 0:
            continue
        if last != 0 and s != last:
            count += 1
        last = s
    return count


@dataclass(frozen=True)
class Decision:
    """A relation and the rule of the paper that decided it (a key of :data:`RULES`)."""

    relation: Relation
    rule: str
    var: int


def decide(
    n: int,
    signs: Sequence[int],
    sign_s0: Callable[[], int],
    sign_s1: Callable[[], int],
    sign_s10: Callable[[], int],
) -> Decision:
    """Run the tree for degree n (3 or 4) on certain signs.

    Args:
        n: 3 for ellipses, 4 for ellipsoids.
        signs: signs of a_n, a_{n-1}, ..., a_0 (descending, as the paper writes Var). a_n and
            a_0 must be negative: the pencil of two normalised (negative interior) shapes.
        sign_s0, sign_s1, sign_s10: called only if the tree needs that sign.

    Raises:
        RuntimeError: a_n or a_0 is not negative (a matrix was not normalised: a bug upstream,
            never a wrong answer).
        ValueError: s0 = 0, s1 < 0, s1,0 = 0, which no pair of ellipsoids can produce.

    Examples:
        >>> decide(3, [-1, 1, 1, -1], lambda: 1, lambda: 0, lambda: 0).relation
        <Relation.SEPARATE: 0>
    """
    if len(signs) != n + 1 or signs[0] >= 0 or signs[-1] >= 0:
        raise RuntimeError(
            f"decide needs a_n < 0 and a_0 < 0 (normalised shapes), got signs {list(signs)} for degree {n}"
        )
    var = sign_variations(signs)
    if var != 2:
        return Decision(Relation.OVERLAP, "var", var)
    s0 = sign_s0()
    if n == 3:
        if s0 > 0:
            return Decision(Relation.SEPARATE, "2d-s0>0", var)
        if s0 == 0:
            return Decision(Relation.TANGENT, "2d-s0=0", var)
        return Decision(Relation.OVERLAP, "2d-s0<0", var)
    if s0 < 0:
        return Decision(Relation.SEPARATE, "3d-s0<0", var)
    if s0 > 0:
        return Decision(Relation.OVERLAP, "3d-s0>0", var)
    s1 = sign_s1()
    if s1 > 0:
        return Decision(Relation.OVERLAP, "3d-s1>0", var)
    if s1 == 0:
        return Decision(Relation.TANGENT, "3d-s1=0", var)
    s10 = sign_s10()
    if s10 > 0:
        return Decision(Relation.TANGENT, "3d-s10>0", var)
    if s10 < 0:
        return Decision(Relation.SEPARATE, "3d-s10<0", var)
    raise ValueError("s0 = 0, s1 < 0, s1,0 = 0 cannot happen for two ellipsoids (P(0) != 0)")
