"""The paper's decision trees (Sections 3.3 and 4.3), written once, on certified signs.

:func:`decide_signs` is the only place where signs become a relation. It takes the signs of
a_n..a_0 of P(T) = det(T A + B) and of s0, s1, s1,0, each either certain (-1, 0, +1),
:data:`UNKNOWN` (the arithmetic at hand could not certify it: the float filter's
``|value| <= bound``) or :data:`PENDING` (not computed yet), and returns the :class:`Rule` that
decides, or asks for the next sign it needs (:data:`NEED_S0`, ...), or gives up
(:data:`UNDECIDED`). Every arithmetic feeds it: the exact path computes s0, s1, s1,0 only when
asked (the paper's point), the float kernels look the answer up in :data:`TABLE3` /
:data:`TABLE4`, which are generated from this function, and so do the moving-shape analysis and
``explain``. Two further certificates that do not need s0 (structured pairs: spheres, translated
or homothetic copies, where s0 vanishes identically) are rules too: ``"sep-witness"`` and
``"common-point"``.

Ellipses (Corollaries 13, 16): Var(-, a2, a1, -) != 2 -> overlap; else s0 > 0 separate,
s0 = 0 tangent, s0 < 0 overlap.
Ellipsoids (Theorems 24, 28; tree of 4.3): Var(-, a3, a2, a1, -) != 2 -> overlap; else
s0 < 0 separate, s0 > 0 overlap; s0 = 0: s1 > 0 overlap, s1 = 0 tangent (24.1),
s1 < 0: s1,0 > 0 tangent (24.2), s1,0 < 0 separate (28.1).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from itertools import product

import numpy as np

from ..relation import Relation
from ..shapes.numbers import sign_variations  # Var: defined beside sign, used by the trees

__all__ = [
    "Decision",
    "Rule",
    "RULE_LIST",
    "RULES",
    "RULE_RELATION",
    "UNKNOWN",
    "PENDING",
    "UNDECIDED",
    "NEED_S0",
    "NEED_S1",
    "NEED_S10",
    "decide",
    "decide_signs",
    "sign_variations",
    "rule_by_key",
    "TABLE3",
    "TABLE4",
    "table_index",
    "SIGN_CODES",
]

UNKNOWN = 2
"""Sign not certified by the arithmetic at hand (float: |value| <= bound)."""
PENDING = 3
"""Sign not computed yet (the exact path computes it when :func:`decide_signs` asks)."""

UNDECIDED = -1
"""Outcome: a sign the tree needs is UNKNOWN."""
NEED_S0, NEED_S1, NEED_S10 = -3, -4, -5
"""Outcome: compute this sign and call again."""


@dataclass(frozen=True)
class Rule:
    """One leaf of the trees (or a structural certificate): its id, key, relation and why."""

    id: int
    key: str
    relation: Relation
    text: str


RULE_LIST: tuple[Rule, ...] = (
    Rule(0, "var", Relation.OVERLAP, "Var(a_n..a_0) != 2: fewer than two positive roots, the interiors meet "
         "(Cor. 13/16 for ellipses; Th. 24/28 for ellipsoids)"),
    Rule(1, "2d-s0>0", Relation.SEPARATE, "Var = 2 and s0 > 0: three distinct real roots, two positive (Th. 12, Cor. 13)"),
    Rule(2, "2d-s0=0", Relation.TANGENT, "Var = 2 and s0 = 0: a positive double root (Th. 14, Cor. 16)"),
    Rule(3, "2d-s0<0", Relation.OVERLAP, "Var = 2 and s0 < 0: complex pair, no positive double root (Th. 12, 14)"),
    Rule(4, "3d-s0<0", Relation.SEPARATE, "Var = 2 and s0 < 0: four distinct real roots, two positive (Th. 28.2)"),
    Rule(5, "3d-s0>0", Relation.OVERLAP, "Var = 2 and s0 > 0: two complex roots, the real ones negative (4.4.1)"),
    Rule(6, "3d-s1>0", Relation.OVERLAP, "s0 = 0 and s1 > 0: double root with a complex pair, negative (Lemma 22)"),
    Rule(7, "3d-s1=0", Relation.TANGENT, "s0 = s1 = 0 and Var = 2: positive and negative double roots (Th. 24.1)"),
    Rule(8, "3d-s10>0", Relation.TANGENT, "s0 = 0, s1 < 0, s1,0 > 0: positive double root (Th. 24.2)"),
    Rule(9, "3d-s10<0", Relation.SEPARATE, "s0 = 0, s1 < 0, s1,0 < 0: negative double root, two positive roots (Th. 28.1)"),
    Rule(10, "sep-witness", Relation.SEPARATE, "P(T*) > 0 at a T* > 0 while P(0) = a_0 < 0 and a_n < 0: two positive "
         "roots, separate (Th. 7/19); a certificate that does not need s0"),
    Rule(11, "common-point", Relation.OVERLAP, "a point certified to lie inside both shapes: the interiors meet"),
)
"""Every rule, indexed by id (the int8 codes of the float kernels)."""

RULES: dict[str, str] = {r.key: r.text for r in RULE_LIST}
"""Rule key -> explanation (JSON ``rule_text``)."""

RULE_RELATION = np.array([int(r.relation) for r in RULE_LIST], dtype=np.int8)
"""Rule id -> Relation code (vectorised lookup)."""

_BY_KEY = {r.key: r for r in RULE_LIST}


def rule_by_key(key: str) -> Rule:
    """The :class:`Rule` with this key (ValueError listing the keys otherwise)."""
    try:
        return _BY_KEY[key]
    except KeyError:
        raise ValueError(f"unknown rule {key!r}; known: {', '.join(_BY_KEY)}") from None


def decide_signs(n: int, signs: Sequence[int], s0: int = PENDING, s1: int = PENDING, s10: int = PENDING) -> int:
    """The trees of 3.3 (n = 3) and 4.3 (n = 4) on sign codes: a rule id, or what is missing.

    Args:
        n: 3 for ellipses, 4 for ellipsoids.
        signs: sign codes of a_n, ..., a_0 (descending, as Var is written); a_n and a_0 must be
            certainly negative (two normalised shapes), else the outcome is UNDECIDED.
        s0: sign code of s0 (-1, 0, 1, :data:`UNKNOWN` or :data:`PENDING`).
        s1: the same for s1.
        s10: the same for s1,0.

    Returns:
        A rule id (>= 0, see :data:`RULE_LIST`), :data:`NEED_S0` / :data:`NEED_S1` /
        :data:`NEED_S10` (compute it and call again), or :data:`UNDECIDED` (a needed sign is
        UNKNOWN).

    Raises:
        ValueError: s0 = 0, s1 < 0, s1,0 = 0, which no pair of ellipsoids can produce.

    Examples:
        >>> RULE_LIST[decide_signs(3, [-1, 1, 1, -1], s0=1)].key
        '2d-s0>0'
        >>> decide_signs(4, [-1, 1, 1, 1, -1]) == NEED_S0, decide_signs(4, [-1, 1, UNKNOWN, 1, -1])
        (True, -1)
    """
    if len(signs) != n + 1:
        raise ValueError(f"need {n + 1} signs for degree {n}, got {len(signs)}")
    if signs[0] != -1 or signs[-1] != -1:
        return UNDECIDED
    if any(s == UNKNOWN or s == PENDING for s in signs):
        return UNDECIDED
    if sign_variations(signs) != 2:
        return 0
    if s0 == PENDING:
        return NEED_S0
    if s0 == UNKNOWN:
        return UNDECIDED
    if n == 3:
        return 1 if s0 > 0 else (2 if s0 == 0 else 3)
    if s0 < 0:
        return 4
    if s0 > 0:
        return 5
    if s1 == PENDING:
        return NEED_S1
    if s1 == UNKNOWN:
        return UNDECIDED
    if s1 > 0:
        return 6
    if s1 == 0:
        return 7
    if s10 == PENDING:
        return NEED_S10
    if s10 == UNKNOWN:
        return UNDECIDED
    if s10 > 0:
        return 8
    if s10 < 0:
        return 9
    raise ValueError("s0 = 0, s1 < 0, s1,0 = 0 cannot happen for two ellipsoids (P(0) != 0)")


SIGN_CODES: tuple[int, ...] = (-1, 0, 1, UNKNOWN, PENDING)
"""The sign codes, in the order the tables index them (code c has index SIGN_CODES.index(c))."""


def table_index(n: int, middle: Sequence[int], s0: int, s1: int, s10: int) -> int:
    """Flat index into TABLE{n}: middle signs a_{n-1}..a_1 and s0, s1, s1,0, each a sign code.

    The index of a code c is c + 1 for -1, 0, 1, then 3 (UNKNOWN), 4 (PENDING): base 5 digits.
    """
    idx = 0
    for c in (*middle, s0, s1, s10):
        idx = idx * 5 + SIGN_CODES.index(c)
    return idx


def _build_table(n: int) -> np.ndarray:
    """:func:`decide_signs` tabulated for a_n, a_0 < 0 (int8; an impossible triple maps to UNDECIDED)."""
    table = np.full(5 ** (n - 1 + 3), UNDECIDED, dtype=np.int8)
    for combo in product(SIGN_CODES, repeat=n - 1 + 3):
        middle, (s0, s1, s10) = combo[: n - 1], combo[n - 1 :]
        try:
            out = decide_signs(n, [-1, *middle, -1], s0, s1, s10)
        except ValueError:
            out = UNDECIDED
        table[table_index(n, middle, s0, s1, s10)] = out
    return table


TABLE3 = _build_table(3)
"""decide_signs for ellipses, by :func:`table_index` (the float kernels look decisions up here)."""
TABLE4 = _build_table(4)
"""decide_signs for ellipsoids, by :func:`table_index`."""


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
    """:func:`decide_signs` with certain signs, computing s0, s1, s1,0 only when asked.

    Args:
        n: 3 for ellipses, 4 for ellipsoids.
        signs: exact signs of a_n, a_{n-1}, ..., a_0 (descending); a_n and a_0 must be negative.
        sign_s0: returns the exact sign of s0; called only if the tree needs it.
        sign_s1: the same for s1.
        sign_s10: the same for s1,0.

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
    s = {"s0": PENDING, "s1": PENDING, "s10": PENDING}
    ask = {NEED_S0: ("s0", sign_s0), NEED_S1: ("s1", sign_s1), NEED_S10: ("s10", sign_s10)}
    while True:
        out = decide_signs(n, signs, s["s0"], s["s1"], s["s10"])
        if out >= 0:
            rule = RULE_LIST[out]
            return Decision(rule.relation, rule.key, sign_variations(signs))
        if out not in ask:
            raise RuntimeError(f"exact signs left the tree undecided: {list(signs)}, {s}")
        name, fn = ask[out]
        s[name] = fn()
