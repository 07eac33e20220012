"""Independent exact checks of witnesses (no code of core.witness), shared by the witness tests.

Written with ``fractions.Fraction`` and the Leibniz determinant:

* a plane misses a shape iff the quadric restricted to the plane has a positive minimum
  (Schur complement of the restricted matrix), and the shape lies on the side of its centre;
* a point is inside a shape iff X^T A X < 0, on its boundary iff X^T A X = 0;
* a contact-scale bracket is checked with the oracle of tests/oracle.py on the pair scaled about
  its centres to the ends of the bracket.
"""

from __future__ import annotations

import itertools
import math
from fractions import Fraction as F
from typing import Any

import numpy as np
from flint import fmpq
from oracle import oracle_relation


def frac(M: Any) -> list[list[F]]:
    """Exact Fraction matrix, normalised to a positive definite quadratic block (M[0][0] > 0)."""
    out = [[q(v) for v in row] for row in (np.asarray(M, dtype=object).tolist())]
    if out[0][0] < 0:
        out = [[-v for v in row] for row in out]
    n = len(out)  # the quadratic form: the exact symmetric part (floats symmetric up to rounding)
    return [[(out[i][j] + out[j][i]) / 2 for j in range(n)] for i in range(n)]


def q(x: Any) -> F:
    """An exact Fraction from fmpq / float / int / Fraction / number string (never via decimal text of a big int)."""
    if isinstance(x, fmpq):
        return F(int(x.p), int(x.q))
    if isinstance(x, np.floating):
        return F(float(x))
    return F(x)


def det(M: list[list[F]]) -> F:
    """Leibniz formula (independent of core.formulae.pencil.determinant)."""
    n = len(M)
    total = F(0)
    for perm in itertools.permutations(range(n)):
        inv = sum(1 for i in range(n) for j in range(i + 1, n) if perm[i] > perm[j])
        term = F(-1 if inv % 2 else 1)
        for i in range(n):
            term *= M[i][perm[i]]
            if term == 0:
                break
        total += term
    return total


def form(M: list[list[F]], x: list[F]) -> F:
    X = [*x, F(1)]
    return sum(M[i][j] * X[i] * X[j] for i in range(len(X)) for j in range(len(X)))


def centre(M: list[list[F]]) -> list[F]:
    """-Q^-1 m by Cramer's rule."""
    d = len(M) - 1
    Q = [row[:d] for row in M[:d]]
    rhs = [-M[i][d] for i in range(d)]
    D = det(Q)
    return [det([[rhs[r] if c == i else Q[r][c] for c in range(d)] for r in range(d)]) / D for i in range(d)]


def size_k(M: list[list[F]]) -> F:
    d = len(M) - 1
    return -det(M) / det([row[:d] for row in M[:d]])


def scaled(M: list[list[F]], mu: F) -> list[list[F]]:
    """The shape scaled about its centre by mu: the last entry gains k (1 - mu^2)."""
    out = [row[:] for row in M]
    out[-1][-1] += size_k(M) * (1 - mu * mu)
    return out


def plane_misses_on_side(M: list[list[F]], n: list[F], d: F, side: int) -> bool:
    """Plane n.x = d misses the closed shape M, which lies where sign(n.x - d) = side.

    Parametrise the plane x = p + E u (E: the coordinate axes but j, with x_j solved), restrict the
    quadric to (u, 1) and require its minimum (Schur complement) to be positive.
    """
    dim = len(n)
    j = max(range(dim), key=lambda i: abs(n[i]))
    free = [i for i in range(dim) if i != j]
    # homogeneous embedding T: (u, 1) -> (x, 1)
    T = [[F(0)] * dim for _ in range(dim + 1)]
    for k, i in enumerate(free):
        T[i][k] = F(1)
        T[j][k] = -n[i] / n[j]
    T[j][dim - 1] = d / n[j]
    T[dim][dim - 1] = F(1)
    R = [[sum(T[a][r] * M[a][b] * T[b][c] for a in range(dim + 1) for b in range(dim + 1)) for c in range(dim)] for r in range(dim)]
    minimum = det(R) / det([row[: dim - 1] for row in R[: dim - 1]])
    c = centre(M)
    s = sum(a * b for a, b in zip(n, c, strict=True)) - d
    return minimum > 0 and (s > 0) - (s < 0) == side


def mu_side(A: list[list[F]], B: list[list[F]], mu: F) -> str:
    """Oracle relation of the pair scaled about its centres by mu."""
    return oracle_relation(scaled(A, mu), scaled(B, mu))


def check_bracket(A: Any, B: Any, cs: Any) -> None:
    """Independent check of a bracket: just below lo the scaled pair is separate, above hi overlap."""
    check_mu_bracket(A, B, cs.lo, cs.hi)


def check_mu_bracket(A: Any, B: Any, lo_: Any, hi_: Any) -> None:
    """lo <= mu* <= hi by the oracle on the pair scaled about its centres (mu = lo, hi)."""
    fa, fb = frac(A), frac(B)
    lo, hi = q(lo_), q(hi_)
    assert lo <= hi
    if lo == hi:  # exact: separate just below, overlap just above, tangent at mu itself
        if lo > 0:
            assert mu_side(fa, fb, lo * (1 - F(1, 10**30))) == "separate"
            assert mu_side(fa, fb, lo) == "tangent"
        assert mu_side(fa, fb, hi * (1 + F(1, 10**30)) + F(1, 10**30)) == "overlap"
        return
    if lo > 0:  # at mu = 0 the shapes are points: nothing to check below
        assert mu_side(fa, fb, lo) in ("separate", "tangent")
    assert mu_side(fa, fb, hi) in ("overlap", "tangent")


def is_valid(M: Any) -> bool:
    """Exactly: an ellipse/ellipsoid (after sign normalisation): quadratic block positive definite
    (Sylvester's leading minors) and det < 0."""
    E = frac(M)
    d = len(E) - 1
    return all(det([row[:i] for row in E[:i]]) > 0 for i in range(1, d + 1)) and det(E) < 0


def check_plane(A: Any, B: Any, normal: Any, offset: Any) -> None:
    """The plane n.x = d has A strictly on n.x < d and B strictly on n.x > d (exactly)."""
    n = [q(v) for v in normal]
    d = q(offset)
    assert plane_misses_on_side(frac(A), n, d, -1)
    assert plane_misses_on_side(frac(B), n, d, 1)


def check_inside_both(A: Any, B: Any, point: Any) -> None:
    """The rational point lies strictly inside both shapes."""
    x = [q(c) for c in point]
    assert form(frac(A), x) < 0 and form(frac(B), x) < 0


def check_on_both(A: Any, B: Any, point: Any) -> None:
    """The rational point lies on both boundaries."""
    x = [q(c) for c in point]
    assert form(frac(A), x) == 0 and form(frac(B), x) == 0


def check_distance(A: Any, B: Any, lo: Any, hi: Any, point_a: Any, point_b: Any, normal: Any = None) -> None:
    """The points lie in their shapes, |p - q| <= hi, 0 <= lo <= hi, and (with the normal) the
    slab along it is at least lo wide: lo |n| + sqrt(n^T S_A n) + sqrt(n^T S_B n) <= n.(c_B - c_A)."""
    p, qq = [q(v) for v in point_a], [q(v) for v in point_b]
    assert form(frac(A), p) <= 0 and form(frac(B), qq) <= 0
    assert sum((x - y) ** 2 for x, y in zip(p, qq, strict=True)) <= q(hi) ** 2
    assert 0 <= q(lo) <= q(hi)
    if normal is not None:
        n = [q(v) for v in normal]
        fa, fb = frac(A), frac(B)
        gap = sum(x * (cb - ca) for x, ca, cb in zip(n, centre(fa), centre(fb), strict=True))
        total = q(lo) * sqrt_hi(sum(x * x for x in n)) + sqrt_hi(support_sq(fa, n)) + sqrt_hi(support_sq(fb, n))
        assert total <= gap


def sqrt_hi(x: F, bits: int = 256) -> F:
    """A rational upper bound of sqrt(x), relatively within 2^-bits (integer square root; x >= 0); exact for squares."""
    rn, rd = math.isqrt(x.numerator), math.isqrt(x.denominator)
    if rn * rn == x.numerator and rd * rd == x.denominator:
        return F(rn, rd)
    k = bits - (x.numerator.bit_length() - x.denominator.bit_length()) // 2  # sqrt(x) 2^k has ~bits bits
    scaled_x = x * F(4) ** k
    return F(math.isqrt(scaled_x.numerator // scaled_x.denominator) + 1) / F(2) ** k


def support_sq(M: list[list[F]], n: list[F]) -> F:
    """(max over the shape of n.x - n.c)^2 = n^T S n, S = k Q^-1 (Cramer: Q^-1 n)."""
    d = len(M) - 1
    Q = [row[:d] for row in M[:d]]
    D = det(Q)
    Qn = [det([[n[r] if c == i else Q[r][c] for c in range(d)] for r in range(d)]) / D for i in range(d)]
    return size_k(M) * sum(a * b for a, b in zip(n, Qn, strict=True))
