"""The Perram-Wertheim contact function of two ellipses/ellipsoids, exact at rational lambda.

For shapes {q_A <= 1}, {q_B <= 1} in centred form (:mod:`core.witness.centred`), with
delta = c_B - c_A and C(lambda) = (1 - lambda) S_A + lambda S_B (positive definite on [0, 1]),

    f(lambda) = min_x [lambda q_A(x) + (1 - lambda) q_B(x)] = lambda (1 - lambda) delta^T C^-1 delta.

f is a minimum of functions affine in lambda, hence concave, and by the minimax theorem

    s* = max_[0,1] f = min_x max(q_A(x), q_B(x)),

the smallest s at which the shapes scaled about their centres by mu = sqrt(s) meet: mu* = sqrt(s*)
is the contact scale (Perram & Wertheim 1985), mu* > 1 separate, = 1 tangent, < 1 overlap.
With y = C^-1 delta the minimiser is x(lambda) = c_A + (1 - lambda) S_A y = c_B - lambda S_B y,
and y is the common normal direction there (pointing from A to B). Unless the centres coincide,
f' has exactly one zero lambda* in (0, 1) (f is concave, rational and not constant), with
f'(0) > 0 > f'(1); so exact signs of f' at two rationals bracket lambda*, and concavity bounds
s* from both sides:

* below by f at any point (f <= s*),
* above by the two tangent lines at the ends of the bracket (f lies under each of them).

Everything is exact rational arithmetic; the float estimate that starts it comes from
:mod:`core.witness.floats`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

from flint import fmpq, fmpq_mat, fmpq_poly

from ..formulae.pencil import determinant
from .centred import CentredShape, dot
from .floats import maximise
from .numbers import simplest_between

__all__ = ["ContactFunction", "Bracket", "dyadic"]


def dyadic(x: fmpq, bits: int) -> fmpq:
    """X rounded to a multiple of 2^-bits (nearest); keeps exact iterates short."""
    scale = 1 << bits
    num = x * scale
    return fmpq((num.p * 2 + num.q) // (num.q * 2), scale)


@dataclass(frozen=True)
class Bracket:
    """lambda* in [lo, hi] (exact signs of f' at the ends) and the implied bounds of s*."""

    lo: fmpq
    hi: fmpq
    s_lo: fmpq
    """A value of f inside the bracket: s* >= s_lo."""
    s_hi: fmpq
    """Where the tangent lines at lo and hi cross: s* <= s_hi."""
    best: fmpq
    """The point of the bracket where f = s_lo (the best lambda known)."""
    exact: bool
    """True when f'(best) = 0: lambda* = best and s* = s_lo = s_hi exactly."""


class ContactFunction:
    """Exact Perram-Wertheim contact function of a pair (see the module docstring).

    Examples:
        >>> from core.witness.centred import centred_pair
        >>> circle = lambda x, r: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - r * r]]
        >>> cf = ContactFunction(*centred_pair(circle(0, 1), circle(6, 2)))
        >>> cf.values(fmpq(1, 3))[:2]        # lambda* = r_A / (r_A + r_B): f' = 0, f = (6/3)^2
        (4, 0)
    """

    def __init__(self, A: CentredShape, B: CentredShape) -> None:
        self.A = A
        self.B = B
        self.delta = B.centre - A.centre
        self.D = B.S - A.S
        self._first: Bracket | None = None

    @property
    def coincident(self) -> bool:
        """True when the centres coincide (then f = 0 and s* = 0)."""
        return all(self.delta[i, 0] == 0 for i in range(self.A.d))

    def C(self, lam: fmpq) -> fmpq_mat:
        """The matrix (1 - lambda) S_A + lambda S_B."""
        return self.A.S * (1 - lam) + self.B.S * lam

    def normal(self, lam: fmpq) -> fmpq_mat:
        """Y = C(lambda)^-1 delta: the normal of both level sets at x(lambda), from A towards B."""
        return self.C(lam).solve(self.delta)

    def point(self, lam: fmpq) -> fmpq_mat:
        """x(lambda) = c_A + (1 - lambda) S_A y, the minimiser of lambda q_A + (1 - lambda) q_B."""
        return self.A.centre + self.A.S * self.normal(lam) * (1 - lam)

    def values(self, lam: fmpq, order: int = 1) -> tuple[fmpq, fmpq, fmpq | None]:
        """(f, f', f'') at a rational lambda in [0, 1] (f'' only for ``order=2``)."""
        C = self.C(lam)
        y = C.solve(self.delta)
        phi = dot(self.delta, y)
        Dy = self.D * y
        psi = dot(y, Dy)
        w = lam * (1 - lam)
        f = w * phi
        f1 = (1 - 2 * lam) * phi - w * psi
        if order < 2:
            return f, f1, None
        chi = dot(Dy, C.solve(Dy))
        f2 = -2 * phi - 2 * (1 - 2 * lam) * psi + 2 * w * chi
        return f, f1, f2

    # ---------------------------------------------------------------- brackets
    def first_bracket(self, bits: int = 40) -> Bracket | None:
        """A first bracket of lambda*, started from a float estimate; None when the centres coincide.

        Relative width 2^-bits (wider if the estimate is off). Cached: later calls return the
        first one, whatever ``bits``.
        """
        if self.coincident:
            return None
        if self._first is None:
            self._first = self._start(bits)
        return self._first

    def _start(self, bits: int) -> Bracket:
        return self.bracket(self.float_guess, bits=bits)

    @cached_property
    def float_guess(self) -> float:
        """lambda* estimated in floats (0.5 when floats fail): where exact work starts."""
        ca, SA = self.A.floats()
        cb, SB = self.B.floats()
        try:
            guess = float(maximise(SA, SB, [q - p for p, q in zip(ca, cb, strict=True)])[0])
        except (ZeroDivisionError, OverflowError, ValueError):
            return 0.5
        return min(max(guess, 0.0), 1.0) if math.isfinite(guess) else 0.5

    def bracket(self, guess: float, *, bits: int = 40) -> Bracket:
        """Bracket lambda* around a float guess: width 2^-bits relative, widened until valid.

        The ends are dyadic rationals; the signs of f' there are exact, so the bracket is
        certified whatever the quality of the guess (in the worst case it grows to [0, 1]).
        """
        zero, one = fmpq(0), fmpq(1)
        g = min(max(fmpq(*float(guess).as_integer_ratio()), zero), one)
        h = fmpq(1, 1 << bits) * max(min(g, 1 - g), fmpq(1, 1 << 60))
        while True:
            lo, hi = max(g - h, zero), min(g + h, one)
            f_lo, d_lo, _ = self.values(lo)
            f_hi, d_hi, _ = self.values(hi)
            if d_lo >= 0 and d_hi <= 0:
                return self._bracket(lo, hi, (f_lo, d_lo), (f_hi, d_hi))
            h *= 256

    def refine(self, br: Bracket, bits: int) -> Bracket:
        """A narrower bracket: one exact Newton step from ``br.best``, rounded to 2^-bits."""
        if br.exact:
            return br
        _, f1, f2 = self.values(br.best, order=2)
        assert f2 is not None
        g = dyadic(br.best - f1 / f2, bits) if f2 < 0 else (br.lo + br.hi) / 2
        g = min(max(g, br.lo), br.hi)
        h = fmpq(1, 1 << max(bits - 8, 1))
        while True:
            lo, hi = max(g - h, br.lo), min(g + h, br.hi)
            f_lo, d_lo, _ = self.values(lo)
            f_hi, d_hi, _ = self.values(hi)
            if d_lo >= 0 and d_hi <= 0:
                return self._bracket(lo, hi, (f_lo, d_lo), (f_hi, d_hi))
            h *= 16

    def _bracket(self, lo: fmpq, hi: fmpq, end_lo: tuple[fmpq, fmpq], end_hi: tuple[fmpq, fmpq]) -> Bracket:
        (f_lo, d_lo), (f_hi, d_hi) = end_lo, end_hi
        if d_lo == 0:
            return Bracket(lo, lo, f_lo, f_lo, lo, True)
        if d_hi == 0:
            return Bracket(hi, hi, f_hi, f_hi, hi, True)
        # tangent lines L_lo (slope d_lo > 0) and L_hi (slope d_hi < 0) cross at x; f <= min(L_lo, L_hi)
        x = (f_hi - f_lo + d_lo * lo - d_hi * hi) / (d_lo - d_hi)
        s_hi = f_lo + d_lo * (x - lo)
        s_lo, best = max((f_lo, lo), (f_hi, hi))
        # a simple rational in the bracket is often lambda* itself (spheres, symmetric pairs)
        mid = simplest_between(lo, hi)
        if mid.q.bit_length() <= 32:
            f_m, d_m, _ = self.values(mid)
            if d_m == 0:
                return Bracket(mid, mid, f_m, f_m, mid, True)
            s_lo, best = max((s_lo, best), (f_m, mid))
            lo, hi = (mid, hi) if d_m > 0 else (lo, mid)
        return Bracket(lo, hi, s_lo, max(s_hi, s_lo), best, False)

    # ---------------------------------------------------------------- polynomials
    @cached_property
    def polynomials(self) -> tuple[fmpq_poly, fmpq_poly]:
        """(N, D) in Q[lambda] with f = N / D: D = det C(lambda) > 0 on [0, 1]."""
        d = self.A.d
        lam = fmpq_poly([0, 1])
        C = [[self.A.S[i, j] * (1 - lam) + self.B.S[i, j] * lam for j in range(d)] for i in range(d)]
        D = determinant(C)
        # delta^T adj(C) delta, from the cofactors (ring-generic determinant of minors)
        quad = fmpq_poly(0)
        for i in range(d):
            for j in range(d):
                minor = [[C[r][c] for c in range(d) if c != i] for r in range(d) if r != j]
                cof = determinant(minor) if d > 1 else fmpq_poly(1)
                if (i + j) % 2:
                    cof = -cof
                quad += cof * (self.delta[i, 0] * self.delta[j, 0])  # adj[i][j] = cofactor(j, i)
        return lam * (1 - lam) * quad, fmpq_poly(D)

    @cached_property
    def derivative_numerator(self) -> fmpq_poly:
        """G = N' D - N D' = f' D^2: the sign of f' on [0, 1]."""
        N, D = self.polynomials
        return N.derivative() * D - N * D.derivative()

    def root_factor(self, br: Bracket) -> fmpq_poly:
        """The irreducible factor of g that vanishes at lambda* (the one changing sign on the bracket)."""
        g = self.derivative_numerator
        for factor, _ in g.factor()[1]:
            if factor(br.lo) * factor(br.hi) < 0 or (br.exact and factor(br.lo) == 0):
                return factor
        raise RuntimeError("no factor of f' changes sign on the bracket of lambda*")

    def is_tangent(self, br: Bracket) -> bool:
        """Exactly whether s* = 1: lambda* is then a root of N - D, i.e. its factor divides N - D."""
        if br.exact:
            return br.s_lo == 1
        N, D = self.polynomials
        return (N - D) % self.root_factor(br) == 0
