"""Where two shapes meet: exact contact point and normal, or a point inside both.

Tangent pairs get the exact contact point and common normal; overlapping pairs a rational point
strictly inside both shapes.

Tangent (paper, Theorems 14 and 24): P(T) = det(T A + B) has a positive double root T*, a root of
gcd(P, P'). For a quartic or cubic with rational coefficients that gcd has degree <= 2 unless
the root is triple, so T* is rational or quadratic. The contact point X = (x, 1) spans the kernel
of T* A + B: (T* M_A + M_B) x = -(T* m_A + m_B), a positive definite system, so x(T) is a
rational function of T (Cramer) evaluated at T*, and exact: rational when T* is, otherwise a
real algebraic number (:func:`core.witness.numbers.value_at_root`) with an isolating interval and
decimals to any number of digits. The common normal is n = M_A x + m_A (half the gradient of
X^T A X: out of A, into B). The point is checked to lie on both boundaries exactly (X^T A X and
X^T B X vanish at T*: a rational zero test, or divisibility by T*'s minimal polynomial).

Overlap: the contact function's minimiser x(lambda*) has q_A = q_B = s* < 1, so it lies strictly
inside both (the point that is deepest in both, in the scaled sense). A simple rational point
near it is checked exactly (X^T A X < 0 and X^T B X < 0); lambda* is refined exactly when the
overlap is too thin for the first candidates.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from flint import fmpq, fmpq_mat, fmpq_poly

from ..algebra.algebraic import RealAlgebraic
from ..algebra.qsqrt import QSqrtPoly
from ..algebra.realroots import real_roots
from ..fixed.classify import Certifier, classify
from ..formulae.pencil import determinant, pencil_coefficients
from ..relation import Relation
from .centred import CentredShape, column
from .contact_function import ContactFunction, log2_abs, pow2
from .floatcert import points
from .numbers import algebraic_dict, simplest_between

if TYPE_CHECKING:
    from .filtered import Pairs

__all__ = ["ContactPoint", "contact_point_pair", "tangent_point", "overlap_point", "point_exact", "point_float", "no_point"]

_MAX_STEPS = 400
"""Narrowing steps at most (a handful are needed): a safety net."""


@dataclass
class ContactPoint:
    """Tangent pair: the contact point and common normal, exact. Overlap: a rational point in both."""

    relation: Relation
    """TANGENT or OVERLAP."""
    point: tuple[RealAlgebraic, ...]
    """Coordinates (rational or real algebraic; ``.value`` set when rational)."""
    normal: tuple[RealAlgebraic, ...] | None = None
    """Tangent: n = M_A x + m_A, the common normal out of A into B (not unit length)."""
    pencil_root: RealAlgebraic | None = None
    """Tangent: the positive double root T* of P(T) = det(T A + B) (A, B normalised)."""
    certified_by: Certifier = Certifier.EXACT
    """Exact rationals (always for a tangent pair), or floats with directed rounding (a point
    inside both; its coordinates are exact rationals either way)."""

    @property
    def is_rational(self) -> bool:
        """True when every coordinate (and normal component) is rational."""
        return all(c.value is not None for c in (*self.point, *(self.normal or ())))

    @property
    def rational_point(self) -> tuple[fmpq, ...] | None:
        """The coordinates as fmpq when all are rational, else None."""
        if any(c.value is None for c in self.point):
            return None
        return tuple(c.value for c in self.point)  # type: ignore[misc]

    def approx(self) -> tuple[list[float], list[float] | None]:
        """(point, unit normal) as floats (for drawing)."""
        p = [float(c) for c in self.point]
        if self.normal is None:
            return p, None
        n = [float(c) for c in self.normal]
        s = sum(v * v for v in n) ** 0.5
        return p, [v / s for v in n]

    def to_dict(self, digits: int = 20) -> dict[str, Any]:
        """JSON form: each number as ``algebraic_dict`` (decimal, exact or polynomial + interval)."""
        return {
            "relation": str(self.relation),
            "point": [algebraic_dict(c, digits) for c in self.point],
            "normal": None if self.normal is None else [algebraic_dict(c, digits) for c in self.normal],
            "pencil_root": None if self.pencil_root is None else algebraic_dict(self.pencil_root, digits),
            "certified_by": str(self.certified_by),
        }


def _blocks(E: fmpq_mat) -> tuple[list[list[fmpq]], list[fmpq], fmpq]:
    d = E.nrows() - 1
    return [[E[i, j] for j in range(d)] for i in range(d)], [E[i, d] for i in range(d)], E[d, d]


def _form_numerator(E: fmpq_mat, P: list[fmpq_poly], Q: fmpq_poly) -> fmpq_poly:
    """Q^2 X^T E X with x = P / Q, as a polynomial in T."""
    M, m, a = _blocks(E)
    d = len(m)
    out = Q * Q * a
    for i in range(d):
        out += P[i] * Q * (2 * m[i])
        for j in range(d):
            out += P[i] * P[j] * M[i][j]
    return out


def tangent_point(A: CentredShape, B: CentredShape) -> ContactPoint:
    """The exact contact point and normal of a tangent pair (see the module docstring)."""
    EA, EB = A.matrix, B.matrix
    n = EA.nrows()
    d = n - 1
    la = [[EA[i, j] for j in range(n)] for i in range(n)]
    lb = [[EB[i, j] for j in range(n)] for i in range(n)]
    P = fmpq_poly(pencil_coefficients(la, lb))
    G = P.gcd(P.derivative())
    roots = [r for r in real_roots(QSqrtPoly(G), fmpq(0), None) if r.compare(0) > 0] if G.degree() > 0 else []
    if len(roots) != 1:
        raise RuntimeError(f"a tangent pair must have one positive double root of P(T), found {len(roots)}")
    T = roots[0]
    MA, mA, _ = _blocks(EA)
    MB, mB, _ = _blocks(EB)
    if T.value is not None:
        t = T.value
        x = fmpq_mat([[MA[i][j] * t + MB[i][j] for j in range(d)] for i in range(d)]).solve(
            column([-(mA[i] * t + mB[i]) for i in range(d)])
        )
        if A.form(x) != 0 or B.form(x) != 0:
            raise RuntimeError("the kernel of T* A + B is not on both boundaries")
        nrm = [sum((MA[i][j] * x[j, 0] for j in range(d)), mA[i]) for i in range(d)]
        return ContactPoint(
            Relation.TANGENT,
            tuple(RealAlgebraic.rational(x[i, 0]) for i in range(d)),
            tuple(RealAlgebraic.rational(v) for v in nrm),
            T,
        )
    from .numbers import value_at_root

    lam = fmpq_poly([0, 1])
    Mt = [[lam * MA[i][j] + MB[i][j] for j in range(d)] for i in range(d)]
    rhs = [-(lam * mA[i] + mB[i]) for i in range(d)]
    Q = determinant(Mt)
    Ps = [determinant([[rhs[r] if c == i else Mt[r][c] for c in range(d)] for r in range(d)]) for i in range(d)]
    h = T.poly
    for E in (EA, EB):
        if not (_form_numerator(E, Ps, Q) % h).is_zero():
            raise RuntimeError("the kernel of T* A + B is not on both boundaries")
    point = tuple(value_at_root(T, Ps[i], Q) for i in range(d))
    normal = tuple(value_at_root(T, sum((Ps[j] * MA[i][j] for j in range(d)), Q * mA[i]), Q) for i in range(d))
    return ContactPoint(Relation.TANGENT, point, normal, T)


def _candidates(x: fmpq_mat, size: fmpq) -> Iterator[fmpq_mat]:
    """Simple rationals near x (coarse first, at scales of the shapes' size), then x itself."""
    d = x.nrows()
    for k in (4, 10, 20, 40):
        tol = size / 2**k
        yield column([simplest_between(x[i, 0] - tol, x[i, 0] + tol) for i in range(d)])
    yield x


def _inside_both(A: CentredShape, B: CentredShape, x: fmpq_mat) -> bool:
    return A.form(x) < 0 and B.form(x) < 0


def overlap_point(A: CentredShape, B: CentredShape, cf: ContactFunction | None = None) -> ContactPoint:
    """A rational point inside both shapes of an overlapping pair (see the module docstring).

    ``cf``: the pair's contact function if already built (its first bracket is cached). The
    candidates are simple rationals near x(lambda) at the best lambda known; the bracket of
    lambda* is narrowed a step at a time until one of them is inside both (x(lambda*) is, with
    depth 1 - s* > 0, and each step at least halves the bracket).
    """
    # a length of the order of the smaller semi-axis (S_ii is a squared length), a power of two
    size = pow2(min(log2_abs(S[i, i]) for S in (A.S, B.S) for i in range(A.d)) // 2)
    cf = cf or ContactFunction(A, B)
    if cf.coincident:  # same centre: it is inside both
        return _rational_point(A.centre)
    quick = _float_candidate(cf)
    if quick is not None:
        for cand in _candidates(quick, size):
            if _inside_both(A, B, cand):
                return _rational_point(cand)
    br = cf.start()
    assert br is not None
    for k in range(_MAX_STEPS):
        for x in (cf.point(br.best), A.centre, B.centre) if k == 0 else (cf.point(br.best),):
            for cand in _candidates(x, size):
                if _inside_both(A, B, cand):
                    return _rational_point(cand)
        if br.exact:
            break
        br = cf.step(br)
    raise RuntimeError("contact_point: no common interior point found (please report this pair)")


def _float_candidate(cf: ContactFunction) -> fmpq_mat | None:
    """x(lambda*) from floats at unit size, back in world coordinates (a candidate only)."""
    est = cf.float_estimate
    if est is None:
        return None
    lam, y = est
    try:
        _, SA, _ = cf.unit_floats()
        d = len(y)
        off = [(1 - lam) * sum(SA[i][j] * y[j] for j in range(d)) for i in range(d)]
        r = pow2(-cf.exponent)
        return column([cf.A.centre[i, 0] + fmpq(*float(v).as_integer_ratio()) * r for i, v in enumerate(off)])
    except (ArithmeticError, ValueError):
        return None


def _rational_point(x: fmpq_mat) -> ContactPoint:
    return ContactPoint(Relation.OVERLAP, tuple(RealAlgebraic.rational(x[i, 0]) for i in range(x.nrows())))


def contact_point_pair(A: Any, B: Any) -> ContactPoint:
    """The exact contact point of one pair (the exact stage alone; :func:`core.witness.contact_point` is the public form).

    Examples:
        >>> circle = lambda x, r: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - r * r]]
        >>> c = contact_point_pair(circle(0, 1), circle(3, 2))          # touch at (1, 0)
        >>> c.rational_point, [str(v.value) for v in c.normal], str(c.relation)
        ((1, 0), ['1', '0'], 'tangent')
    """
    from .centred import centred_pair

    rel = classify(A, B)
    why = no_point(rel)
    if why is not None:
        raise ValueError(why)
    a, b = centred_pair(A, B)
    return tangent_point(a, b) if rel == Relation.TANGENT else overlap_point(a, b)


def no_point(rel: Relation) -> str | None:
    """Why a pair with relation ``rel`` has no contact point (None: it has one)."""
    if rel == Relation.SEPARATE:
        return "A and B are separate: they have no point in common (separating_plane gives a plane between them)"
    return None


def point_exact(pairs: Pairs, i: int) -> ContactPoint:
    """The exact stage: pair i's contact point and normal (tangent) or a rational point in both (overlap)."""
    cf = pairs.contact_function(i)
    if Relation(int(pairs.relation[i])) == Relation.TANGENT:
        return tangent_point(cf.A, cf.B)
    return overlap_point(cf.A, cf.B, cf)


def point_float(pairs: Pairs, todo: np.ndarray) -> dict[int, ContactPoint]:
    """The float stage: for overlapping pairs, a float point certified inside both (vectorised).

    A tangent pair's contact point is exact algebra: the floats leave it to the exact stage.
    """
    fp = pairs.floats
    assert fp is not None
    mask = todo & (pairs.relation == Relation.OVERLAP)
    x, ok = points(fp, mask)
    out: dict[int, ContactPoint] = {}
    for i in np.flatnonzero(ok & mask):
        coords = tuple(RealAlgebraic.rational(fmpq(*float(v).as_integer_ratio())) for v in x[i])
        out[int(i)] = ContactPoint(Relation.OVERLAP, coords, certified_by=Certifier.FLOAT)
    return out
