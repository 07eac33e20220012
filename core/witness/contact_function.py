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

**Scale.** f is invariant under a common similarity of space (delta -> r delta, S -> r^2 S) and
does not see the matrices' own scale; so the float estimate that starts the exact work is taken
from the pair brought to unit size by an exact power of two (:func:`unit_exponent`): pairs at
1e±300 start as well as pairs at 1. **Precision.** The bracket is narrowed by a safeguarded
Newton iteration (:meth:`ContactFunction.narrow`): each step probes at the Newton point plus and
minus its predicted error, rounded to a dyadic with just the bits that error needs, and falls
back to bisection when a step does not halve the bracket. So the bits grow with the accuracy
reached (quadratically per step), never with the size of the numbers, and every step narrows
the bracket: the loop always ends, with a certified bracket.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

from flint import fmpq, fmpq_mat, fmpq_poly

from ..algebra.qsqrt import QSqrtPoly
from ..algebra.realroots import real_roots
from ..formulae.pencil import determinant
from .centred import CentredShape, dot
from .floats import maximise
from .numbers import simplest_between, to_float

__all__ = ["ContactFunction", "Bracket", "dyadic", "unit_exponent", "log2_abs"]

_MAX_STEPS = 400
"""Narrowing steps at most in one call (each at least halves the bracket): a safety net only."""


def dyadic(x: fmpq, bits: int) -> fmpq:
    """X rounded to a multiple of 2^-bits (nearest); keeps exact iterates short."""
    scale = pow2(bits)
    num = x * scale
    return fmpq((num.p * 2 + num.q) // (num.q * 2)) / scale


def log2_abs(q: fmpq) -> int:
    """An integer within 1 of log2 |q| for q != 0 (from bit lengths, never a float)."""
    return int(q.p.bit_length()) - int(q.q.bit_length()) if q.p > 0 else int((-q.p).bit_length()) - int(q.q.bit_length())


def unit_exponent(delta: fmpq_mat, SA: fmpq_mat, SB: fmpq_mat) -> int:
    """The exponent e such that the similarity x -> 2^e x brings the pair to about unit size.

    After it, max(|delta_i|, sqrt(S_ii)) is within a factor 4 of 1 (S_ii > 0: S is positive
    definite). Exact: a power of two changes no digit of a float or a rational.

    Examples:
        >>> unit_exponent(fmpq_mat([[fmpq(3, 2**400)]]), fmpq_mat([[fmpq(1, 4**400)]]), fmpq_mat([[fmpq(1, 4**401)]]))
        399
        >>> fmpq(3, 2**400) * pow2(399)      # delta at unit size
        3/2
    """
    d = delta.nrows()
    logs = [log2_abs(delta[i, 0]) for i in range(d) if delta[i, 0] != 0]
    logs += [log2_abs(S[i, i]) // 2 for S in (SA, SB) for i in range(d)]
    return -max(logs)


def pow2(e: int) -> fmpq:
    """2^e exactly, for any integer e."""
    return fmpq(1 << e) if e >= 0 else fmpq(1, 1 << -e)


@dataclass(frozen=True)
class Bracket:
    """lambda* in [lo, hi] (exact signs of f' at the ends) and the implied bounds of s*.

    f and f' at both ends are kept: they give s* >= max(f_lo, f_hi) and, by concavity, s* <=
    the value where the tangent lines at the ends cross.
    """

    lo: fmpq
    hi: fmpq
    f_lo: fmpq
    d_lo: fmpq
    """f'(lo) >= 0 (= 0 only for an exact bracket)."""
    f_hi: fmpq
    d_hi: fmpq
    """f'(hi) <= 0."""

    @property
    def exact(self) -> bool:
        """True when lambda* is known exactly (lo = hi, f' = 0 there): s* = s_lo = s_hi."""
        return self.lo == self.hi

    @property
    def best(self) -> fmpq:
        """The end where f is larger (the better lambda known)."""
        return self.lo if self.f_lo >= self.f_hi else self.hi

    @property
    def s_lo(self) -> fmpq:
        """A value of f in the bracket: s* >= s_lo."""
        return max(self.f_lo, self.f_hi)

    @cached_property
    def s_hi(self) -> fmpq:
        """Where the tangent lines at lo and hi cross: s* <= s_hi."""
        if self.exact:
            return self.f_lo
        # L_lo (slope d_lo > 0) and L_hi (slope d_hi < 0) cross at x; f <= min(L_lo, L_hi)
        x = (self.f_hi - self.f_lo + self.d_lo * self.lo - self.d_hi * self.hi) / (self.d_lo - self.d_hi)
        return max(self.f_lo + self.d_lo * (x - self.lo), self.s_lo)

    @property
    def width(self) -> fmpq:
        """The width hi - lo."""
        return self.hi - self.lo


class ContactFunction:
    """Exact Perram-Wertheim contact function of a pair (see the module docstring).

    Examples:
        >>> from core.witness.centred import centred_pair
        >>> circle = lambda x, r: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - r * r]]
        >>> cf = ContactFunction(*centred_pair(circle(0, 1), circle(6, 2)))
        >>> cf.values(fmpq(1, 3))[:2]        # lambda* = r_A / (r_A + r_B): f' = 0, f = (6/3)^2
        (4, 0)
        >>> cf.start().exact, cf.start().s_lo
        (True, 4)
    """

    def __init__(self, A: CentredShape, B: CentredShape) -> None:
        self.A = A
        self.B = B
        self.delta = B.centre - A.centre
        self.D = B.S - A.S
        self._start: Bracket | None = None

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

    # ---------------------------------------------------------------- floats (estimates only)
    @cached_property
    def exponent(self) -> int:
        """The power of two that brings the pair to unit size (:func:`unit_exponent`)."""
        return unit_exponent(self.delta, self.A.S, self.B.S)

    def unit_floats(self) -> tuple[list[float], list[list[float]], list[list[float]]]:
        """(delta, S_A, S_B) of the pair at unit size, as floats (estimates only)."""
        d = self.A.d
        r, r2 = pow2(self.exponent), pow2(2 * self.exponent)
        return (
            [to_float(self.delta[i, 0] * r) for i in range(d)],
            [[to_float(self.A.S[i, j] * r2) for j in range(d)] for i in range(d)],
            [[to_float(self.B.S[i, j] * r2) for j in range(d)] for i in range(d)],
        )

    @cached_property
    def float_estimate(self) -> tuple[float, list[float]] | None:
        """(lambda*, y(lambda*)) estimated in floats at unit size; None when floats fail."""
        delta, SA, SB = self.unit_floats()
        try:
            lam, _, y = maximise(SA, SB, delta)
        except (ZeroDivisionError, OverflowError, ValueError):
            return None
        lam = float(lam)
        if not (math.isfinite(lam) and all(math.isfinite(v) for v in y)):
            return None
        return min(max(lam, 0.0), 1.0), [float(v) for v in y]

    @property
    def float_guess(self) -> float:
        """lambda* estimated in floats (0.5 when floats fail): where exact work starts."""
        est = self.float_estimate
        return 0.5 if est is None else est[0]

    # ---------------------------------------------------------------- brackets
    def start(self) -> Bracket | None:
        """A first bracket of lambda* around the float estimate; None when the centres coincide.

        About 2^-40 wide (relative to min(lambda*, 1 - lambda*)) when the estimate is good,
        wider when it is not (in the worst case [0, 1]). Cached.
        """
        if self.coincident:
            return None
        if self._start is None:
            self._start = self._first()
        return self._start

    def _end(self, lam: fmpq) -> tuple[fmpq, fmpq]:
        f, f1, _ = self.values(lam)
        return f, f1

    def _first(self) -> Bracket:
        zero, one = fmpq(0), fmpq(1)
        g = dyadic(fmpq(*self.float_guess.as_integer_ratio()), 64)
        h = pow2(-40 + log2_abs(min(g, 1 - g))) if zero < g < one else fmpq(0)
        seen: list[tuple[fmpq, fmpq, fmpq]] = []
        if h and zero < g - h and g + h < one:  # the usual case: two evaluations straddle lambda*
            for x in (g - h, g + h):
                f, f1 = self._end(x)
                if f1 == 0:
                    return Bracket(x, x, f, f1, f, f1)
                seen.append((x, f, f1))
            (a, fa, da), (c, fc, dc) = seen
            if da > 0 > dc:
                return self._simplest(Bracket(a, c, fa, da, fc, dc))
        br = Bracket(zero, one, *self._end(zero), *self._end(one))
        for x, f, f1 in seen:  # what the first probes proved
            br = Bracket(x, br.hi, f, f1, br.f_hi, br.d_hi) if f1 > 0 else Bracket(br.lo, x, br.f_lo, br.d_lo, f, f1)
        if h:
            for _ in range(4):  # widen by 2^8 while the probes do not straddle lambda*
                h *= 256
                br, done = self._probe(br, g, h)
                if done or br.exact:
                    break
        return self._simplest(br)

    def _probe(self, br: Bracket, g: fmpq, h: fmpq) -> tuple[Bracket, bool]:
        """Evaluate f' at g - h and g + h (at g alone when h = 0); keep what their signs prove.

        Points outside the open bracket are skipped. Returns the narrowed bracket and whether
        both probes landed on the expected sides (lambda* between them).
        """
        hits = 0
        points = ((g - h, -1), (g + h, 1)) if h else ((g, 0),)
        for x, side in points:
            if not br.lo < x < br.hi:
                continue
            f, f1 = self._end(x)
            if f1 == 0:
                return Bracket(x, x, f, f1, f, f1), True
            if f1 > 0:
                br = Bracket(x, br.hi, f, f1, br.f_hi, br.d_hi)
            else:
                br = Bracket(br.lo, x, br.f_lo, br.d_lo, f, f1)
            hits += (f1 > 0) == (side < 0)
        return br, hits == 2

    def _simplest(self, br: Bracket) -> Bracket:
        """Test the simplest rational of the bracket: often lambda* itself (spheres, symmetric pairs)."""
        if br.exact:
            return br
        mid = simplest_between(br.lo, br.hi)
        if mid.q.bit_length() > 32 or not br.lo < mid < br.hi:
            return br
        f, f1 = self._end(mid)
        if f1 == 0:
            return Bracket(mid, mid, f, f1, f, f1)
        if f1 > 0:
            return Bracket(mid, br.hi, f, f1, br.f_hi, br.d_hi)
        return Bracket(br.lo, mid, br.f_lo, br.d_lo, f, f1)

    def step(self, br: Bracket) -> Bracket:
        """One safeguarded Newton step: a bracket at most half as wide (or exact).

        Newton from the better end predicts lambda* to within about (its step)^2 / lambda*; the
        prediction is probed at plus and minus that error (rounded to a dyadic with just the bits
        it needs) and widened by 16 while it does not straddle lambda*. A step that leaves the
        bracket, or does not halve it, is completed by bisection.
        """
        if br.exact:
            return br
        start = br.width
        b = br.best
        _, f1, f2 = self.values(b, order=2)
        assert f2 is not None
        x = b - f1 / f2 if f2 < 0 else None
        if x is not None and br.lo < x < br.hi:
            e = abs(x - b)
            scale = min(x, 1 - x)
            h_exact = max(4 * e * e / scale, br.width / pow2(200))
            k = -log2_abs(h_exact)  # h = 2^-k, a power of two about the predicted error
            h = pow2(-k)
            g = dyadic(x, k + 4)
            for _ in range(3):
                br, done = self._probe(br, g, h)
                if done or br.exact:
                    break
                h *= 16
        if not br.exact and br.width * 2 > start:  # bisection keeps the step honest
            mid = dyadic((br.lo + br.hi) / 2, max(8, -log2_abs(br.width) + 2))
            if not br.lo < mid < br.hi:
                mid = (br.lo + br.hi) / 2
            br, _ = self._probe(br, mid, fmpq(0))
        return self._simplest(br)

    def narrow(self, br: Bracket, s_width: fmpq) -> Bracket:
        """Steps until s_hi - s_lo <= s_width (or lambda* is exact); a certified bracket always.

        At most a few hundred steps (each at least halves the bracket; Newton needs a handful):
        when that is not enough the bracket reached so far is returned (still certified).
        """
        for _ in range(_MAX_STEPS):
            if br.exact or br.s_hi - br.s_lo <= s_width:
                return br
            br = self.step(br)
        return br

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

    def root_factor(self, br: Bracket) -> tuple[fmpq_poly, Bracket]:
        """The irreducible factor h of G that vanishes at lambda*, and a bracket isolating it.

        lambda* is a simple root of h, the only root of G where f' changes sign; the bracket
        is narrowed until h changes sign on it and no other factor does (then lambda* is the
        only root of h inside), or until lambda* is exact.
        """
        factors = [factor for factor, _ in self.derivative_numerator.factor()[1]]
        while not br.exact:
            changing = [h for h in factors if h(br.lo) * h(br.hi) < 0]
            if len(changing) == 1 and not any(h(br.lo) * h(br.hi) == 0 for h in factors):
                h = changing[0]
                if sum(1 for _ in _roots_between(h, br)) == 1:
                    return h, br
            br = self.step(br)
        return next(h for h in factors if h(br.lo) == 0), br


def _roots_between(h: fmpq_poly, br: Bracket) -> list[object]:
    """The real roots of h in [lo, hi] (certified isolation)."""
    return list(real_roots(QSqrtPoly(h), br.lo, br.hi))
