"""Real roots of Q(sqrt d)[t] polynomials in an interval, isolated exactly (paper 3.4, 4.4).

Real roots of ``s = p + q sqrt(d)`` are among the real roots of the norm N = p^2 - d q^2 in Q[t].
N is made squarefree and factored over Q (flint); a linear factor gives a rational root, every
other irreducible factor is isolated by Descartes' rule of signs (Collins-Akritas bisection with
Taylor shifts in Z[x]); the roots of N that are roots of s are kept (:func:`core.algebra.algebraic.sign_at`).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from flint import fmpq, fmpq_poly, fmpz, fmpz_poly

from ..shapes.numbers import sign_variations
from .algebraic import RealAlgebraic, sign_at
from .qsqrt import QSqrtPoly

__all__ = ["real_roots", "roots_in_order"]


def _squarefree_integer(f: fmpq_poly) -> fmpz_poly:
    """Primitive squarefree integer polynomial with the roots of f."""
    g = f.gcd(f.derivative())
    sq = f if g.degree() < 1 else _exact_div(f, g)
    num = sq.numer()
    c = num.content()
    out = fmpz_poly([v // c for v in num.coeffs()])
    if out.coeffs() and out.coeffs()[-1] < 0:
        out = -out
    return out


def _exact_div(f: fmpq_poly, g: fmpq_poly) -> fmpq_poly:
    q, r = divmod(f, g)
    assert r.is_zero()
    return q


_X_PLUS_1 = fmpz_poly([1, 1])


def _positive_root_boxes(f: fmpz_poly) -> list[tuple[fmpq, fmpq]]:
    """Isolating intervals of the roots of squarefree f in (0, inf), f(0) != 0 (Descartes).

    Collins-Akritas bisection: the roots in (0, B) with B = 2^k a Cauchy bound are mapped to
    (0, 1); a box whose Descartes count (sign variations of (x+1)^n h(1/(x+1))) is 0 has no
    root, 1 has exactly one; otherwise it is halved. Returns (lo, hi), or (r, r) for an exact
    rational root met at a bisection point, in ascending order.
    """
    return list(_iter_positive_root_boxes(f))


def _iter_positive_root_boxes(f: fmpz_poly) -> Iterator[tuple[fmpq, fmpq]]:
    """:func:`_positive_root_boxes` lazily, smallest root first (left boxes are explored first)."""
    coeffs = f.coeffs()
    n = len(coeffs) - 1
    if n < 1 or sign_variations(coeffs) == 0:
        return
    # Fujiwara's bound: every root has |x| < 2 max_i |a_{n-i}/a_n|^(1/i) <= 2^k (bit lengths)
    lead_bits = int(abs(coeffs[-1]).bit_length())
    k = 0
    for i in range(1, n + 1):
        c = coeffs[n - i]
        if c != 0:
            excess = int(abs(c).bit_length()) - lead_bits + 1 + (1 if i == n else 0)
            k = max(k, -(-excess // i))
    k += 1
    B = fmpq(2) ** k if k >= 0 else fmpq(1, 2 ** (-k))
    # h(x) = f(B x)
    if k >= 0:
        h = fmpz_poly([c * fmpz(2) ** (k * i) for i, c in enumerate(coeffs)])
    else:
        h = fmpz_poly([c * fmpz(2) ** (-k * (n - i)) for i, c in enumerate(coeffs)])
    stack: list[tuple[fmpz_poly, Any, int]] = [(h, 0, 0)]
    while stack:
        h, c, depth = stack.pop()
        scale = B / fmpq(2) ** depth
        hc = h.coeffs()
        if hc and hc[0] == 0:  # root exactly at the left end of this box
            r = scale * c
            yield (r, r)
            h = fmpz_poly(hc[1:])
            hc = h.coeffs()
        m = len(hc) - 1
        if m < 1:
            continue
        v = sign_variations(fmpz_poly(hc[::-1])(_X_PLUS_1).coeffs())
        if v == 0:
            continue
        if v == 1:
            yield (scale * c, scale * (c + 1))
            continue
        left = fmpz_poly([a * fmpz(2) ** (m - i) for i, a in enumerate(hc)])  # 2^m h(x/2)
        right = left(_X_PLUS_1)
        stack.append((right, 2 * c + 1, depth + 1))
        stack.append((left, 2 * c, depth + 1))


def _isolate(F: fmpz_poly, lo: fmpq | None, hi: fmpq | None) -> list[RealAlgebraic]:
    """Real roots of a squarefree integer F in the closed interval [lo, hi] (None: infinite)."""
    if F.degree() < 1:
        return []
    out: list[RealAlgebraic] = []
    for f, _e in F.factor()[1]:
        fc = f.coeffs()
        if len(fc) == 2:  # linear factor: a rational root
            cands = [RealAlgebraic.rational(fmpq(-fc[0], fc[1]))]
        else:
            fq = fmpq_poly(f)
            cands = []
            neg = fmpz_poly([c if i % 2 == 0 else -c for i, c in enumerate(fc)])  # f(-x)
            for a, b in _positive_root_boxes(neg):
                cands.append(RealAlgebraic.rational(-a) if a == b else RealAlgebraic.isolating(fq, -b, -a))
            for a, b in _positive_root_boxes(f):
                cands.append(RealAlgebraic.rational(a) if a == b else RealAlgebraic.isolating(fq, a, b))
        for alpha in cands:
            if lo is not None and alpha.compare(lo) < 0:
                continue
            if hi is not None and alpha.compare(hi) > 0:
                continue
            out.append(alpha)
    return _sorted_disjoint(out)


def _sorted_disjoint(nums: list[RealAlgebraic]) -> list[RealAlgebraic]:
    """Sort distinct algebraic numbers, refining until consecutive intervals are disjoint."""
    while True:
        nums.sort(key=lambda a: (a.lo, a.hi))
        clash = False
        for a, b in zip(nums, nums[1:], strict=False):
            if not a.hi < b.lo and not (a.value is not None and a.value == b.value):
                clash = True
                (a if a.width >= b.width else b).bisect()
        if not clash:
            return nums


def real_roots(s: QSqrtPoly, lo: fmpq | None = None, hi: fmpq | None = None) -> list[RealAlgebraic]:
    """Distinct real roots of a nonzero ``s`` in [lo, hi] (None = unbounded), ascending.

    Examples:
        >>> s = QSqrtPoly(fmpq_poly([0, 1]), -1, 2)          # t - sqrt(2)
        >>> [r.decimal(12) for r in real_roots(s)]
        ['1.41421356237']
        >>> real_roots(QSqrtPoly(fmpq_poly([-1, 0, 4])), fmpq(0), None)   # 4t^2 - 1 on [0, inf)
        [RealAlgebraic(1/2)]
    """
    if s.is_zero():
        raise ValueError("the zero polynomial has every t as a root")
    F = _squarefree_integer(s.p if s.is_rational() else s.norm())
    cands = _isolate(F, lo, hi)
    if s.is_rational():
        return cands
    return [a for a in cands if sign_at(s, a) == 0]


def roots_in_order(s: QSqrtPoly, lo: fmpq, hi: fmpq | None = None) -> Iterator[RealAlgebraic]:
    """The distinct real roots of a nonzero ``s`` in (lo, hi], smallest first, found lazily.

    For a search that stops at the first root with some property (the first contact of two
    moving shapes, :mod:`core.moving.first_contact`): nothing right of the roots already
    yielded is isolated. No factorisation: Descartes' rule on the squarefree part (of the norm
    for Q(sqrt d)[t]) after the Moebius map t = (lo + hi x) / (1 + x) that sends (lo, hi) to
    (0, inf) (t = lo + x when hi is None), so the left-first bisection meets the roots in
    increasing order; a root of the norm that is not one of ``s`` (a root of its conjugate) is
    skipped (:func:`core.algebra.algebraic.sign_at`). A root at ``hi`` comes last.

    Examples:
        >>> s = QSqrtPoly(fmpq_poly([6, -5, 1]))               # (t - 2)(t - 3)
        >>> [r.decimal(5) for r in roots_in_order(s, fmpq(0), fmpq(3))]
        ['2.0000', '3']
        >>> next(roots_in_order(QSqrtPoly(fmpq_poly([-2, 0, 1])), fmpq(0))).decimal(8)   # t^2 - 2
        '1.4142136'
    """
    if s.is_zero():
        raise ValueError("the zero polynomial has every t as a root")
    if hi is not None and not lo < hi:
        raise ValueError(f"need lo < hi, got ({lo}, {hi}]")
    F = _squarefree_integer(s.p if s.is_rational() else s.norm())
    if F.degree() < 1:
        return
    Fq = fmpq_poly(F)
    if hi is None:
        G = _numerator(Fq(fmpq_poly([lo, 1])))
    else:
        H = _numerator(Fq(fmpq_poly([lo, hi - lo])))  # roots in (0, 1) <-> (lo, hi)
        n = H.degree()
        rev = fmpz_poly(H.coeffs()[::-1] + [0] * (n + 1 - len(H.coeffs())))
        shifted = rev(_X_PLUS_1).coeffs()
        G = fmpz_poly((shifted + [fmpz(0)] * (n + 1 - len(shifted)))[::-1])  # (1+x)^n H(x/(1+x))
    for a, b in _iter_positive_root_boxes(_strip_zero_roots(G)):
        ta, tb = _moebius(a, lo, hi), _moebius(b, lo, hi)
        alpha = RealAlgebraic.rational(ta) if a == b else RealAlgebraic.isolating(_without_roots_at(Fq, ta, tb), ta, tb)
        if s.is_rational() or sign_at(s, alpha) == 0:
            yield alpha
    if hi is not None and Fq(hi) == 0 and s.sign_at_rational(hi) == 0:
        yield RealAlgebraic.rational(hi)


def _without_roots_at(F: fmpq_poly, a: fmpq, b: fmpq) -> fmpq_poly:
    """F without the roots a and b (where they are roots): the box's one root stays, its ends are none.

    F is squarefree, so a root at an end is simple and (t - a) divides it once.
    """
    for e in (a, b):
        if F(e) == 0:
            F = _exact_div(F, fmpq_poly([-e, 1]))
    return F


def _numerator(f: fmpq_poly) -> fmpz_poly:
    """A positive multiple of f with integer coefficients."""
    return f.numer() if f.denom() > 0 else -f.numer()


def _strip_zero_roots(G: fmpz_poly) -> fmpz_poly:
    """G / x^k, so that G(0) != 0 (a root at x = 0 is t = lo, outside (lo, hi])."""
    c = G.coeffs()
    k = 0
    while k < len(c) and c[k] == 0:
        k += 1
    return fmpz_poly(c[k:])


def _moebius(x: fmpq, lo: fmpq, hi: fmpq | None) -> fmpq:
    """T = (lo + hi x) / (1 + x), or lo + x when hi is None."""
    return lo + x if hi is None else (lo + hi * x) / (1 + x)
