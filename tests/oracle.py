"""Independent ground truth: the relation from the positive roots of the exact P(T).

Does not use the code under test: P(T) = det(A) * charpoly(-A^-1 B) is computed with flint's
``fmpq_mat`` (not the pencil formula), and the positive real roots are counted with flint's
certified complex root isolation (real roots come back with an exactly zero imaginary part) or,
when their order does not matter, exactly by Sturm sequences of the squarefree factors.
Wang-Wang-Kim / paper Theorem 7 and 19: two distinct positive roots -> separate, a positive
double root -> tangent, no positive root -> overlap.
"""

from __future__ import annotations

from typing import Any

from flint import ctx, fmpq, fmpq_mat, fmpq_poly, fmpz_poly

from core.shapes.numbers import to_fmpq


def exact_matrix(M: Any) -> fmpq_mat:
    rows = [[to_fmpq(v) for v in row] for row in M]
    return fmpq_mat(rows)


def pencil_oracle(A: Any, B: Any) -> fmpz_poly:
    """Integer multiple (positive) of det(T A + B), via the characteristic polynomial."""
    MA, MB = exact_matrix(_normalise(A)), exact_matrix(_normalise(B))
    P = MA.det() * (-(MA.inv() * MB)).charpoly()
    num, den = P.numer(), P.denom()
    assert den > 0
    return fmpz_poly(num.coeffs()) if hasattr(num, "coeffs") else fmpz_poly(num)


def _sturm_positive(f: fmpz_poly) -> int:
    """Number of distinct positive real roots of a squarefree f (Sturm's theorem, exact rationals)."""
    g = fmpq_poly(f)
    while g.degree() > 0 and g[0] == 0:  # roots at 0 are not positive
        g = fmpq_poly(g.coeffs()[1:])
    if g.degree() <= 0:
        return 0
    chain = [g, g.derivative()]
    while chain[-1].degree() > 0:
        r = -(chain[-2] % chain[-1])
        if r == 0:
            break
        chain.append(r)

    def changes(signs: list[int]) -> int:
        nz = [v for v in signs if v != 0]
        return sum(1 for a, b in zip(nz, nz[1:], strict=False) if a != b)

    def sgn(q: fmpq) -> int:
        return (q > 0) - (q < 0)

    at_zero = changes([sgn(q[0]) for q in chain])
    at_infinity = changes([sgn(q[q.degree()]) for q in chain])
    return at_zero - at_infinity


def positive_roots(p: fmpz_poly) -> list[int]:
    """Multiplicities of the distinct positive real roots of p (certified).

    Counted exactly (squarefree factors, Sturm sequences) when every positive root has the same
    multiplicity (the list is then the same in any order); otherwise listed as flint's certified
    complex root isolation finds them (slow for roots 1e-200 apart, hence not the first way).
    """
    while p.degree() > 0 and p[0] == 0:  # roots at 0 are not positive (and never isolated from it)
        p = fmpz_poly(p.coeffs()[1:])
    counts = [(m, _sturm_positive(f)) for f, m in p.factor_squarefree()[1]]
    found = [(m, k) for m, k in counts if k]
    if len({m for m, _ in found}) <= 1:
        return [m for m, k in found for _ in range(k)]
    old = ctx.prec
    try:
        prec = 64
        while True:
            ctx.prec = prec
            out: list[int] = []
            undecided = False
            for r, m in p.complex_roots():
                if not r.imag == 0:
                    continue
                if r.real > 0:
                    out.append(m)
                elif not r.real < 0:
                    undecided = True
            if not undecided:
                return out
            prec *= 2
    finally:
        ctx.prec = old


def oracle_relation(A: Any, B: Any) -> str:
    """'separate', 'tangent' or 'overlap' for two valid ellipses/ellipsoids (signs normalised)."""
    A = _normalise(A)
    B = _normalise(B)
    mults = positive_roots(pencil_oracle(A, B))
    if mults == [1, 1]:
        return "separate"
    if mults == [2]:
        return "tangent"
    if not mults:
        return "overlap"
    raise AssertionError(f"impossible positive-root pattern {mults} for two ellipsoids")


def _normalise(M: Any) -> list[list[fmpq]]:
    """Exact symmetric part (the quadratic form the shape is), negative interior."""
    E = [[to_fmpq(v) for v in row] for row in M]
    n = len(E)
    E = [[(E[i][j] + E[j][i]) / 2 for j in range(n)] for i in range(n)]
    if E[0][0] < 0:
        E = [[-v for v in row] for row in E]
    return E
