"""A certified bracket of the Euclidean distance between two separate ellipses/ellipsoids.

For a direction n, every point of A has n.x <= n.c_A + sqrt(n^T S_A n) and every point of B has
n.x >= n.c_B - sqrt(n^T S_B n) (support functions, :mod:`core.witness.centred`), so

    dist(A, B) >= g(n) / |n|,   g(n) = n.(c_B - c_A) - sqrt(n^T S_A n) - sqrt(n^T S_B n)

(the width of the empty slab between two parallel planes), with equality at the best n (strong
duality for convex sets). And for any points p in A and q in B, dist(A, B) <= |p - q|. The best
direction is found in floats (Newton on the strictly concave g(n) - |n|^2 / 2, whose maximiser is
dist * unit normal), refined in arb ball arithmetic when floats are not precise enough; the
bracket itself is computed exactly: the lower bound with rational upper bounds of the square
roots, the upper bound from the rational points p = c_A + S_A n / s_A and q = c_B - S_B n / s_B
with s >= sqrt(n^T S n) (so that p lies in A and q in B exactly). Near the best n both bounds are
off by second-order terms only, so the bracket is tight. Tangent and overlapping pairs are at
distance 0 exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from flint import arb, fmpq, fmpq_mat

from ..algebra.algebraic import working_precision
from ..fixed.classify import Certifier, classify
from ..relation import Relation
from .centred import CentredShape, centred_pair, column, dot
from .contact_function import ContactFunction, log2_abs, pow2
from .floatcert import distances
from .floats import dot as fdot
from .floats import inverse, mat_vec, maximise
from .numbers import sqrt_bounds, to_float

if TYPE_CHECKING:
    from .filtered import Pairs

__all__ = ["DistanceBracket", "distance_pair", "distance_exact", "distance_float", "distance_from"]

_MAX_ROUNDS = 8


@dataclass(frozen=True)
class DistanceBracket:
    """``lo <= dist(A, B) <= hi`` (exact rationals), with the witnesses of both bounds."""

    lo: fmpq
    hi: fmpq
    relation: Relation
    normal: tuple[fmpq, ...] | None = None
    """Separate: the direction n whose empty slab gives ``lo`` (A below, B above)."""
    point_a: tuple[fmpq, ...] | None = None
    """Separate: a point of A (exactly: X^T A X <= 0) ..."""
    point_b: tuple[fmpq, ...] | None = field(default=None)
    """... and a point of B with |point_a - point_b| <= hi."""
    certified_by: Certifier = Certifier.EXACT
    """Which arithmetic proved the bracket (exact rationals either way)."""

    @property
    def approx(self) -> float:
        """The midpoint as a float."""
        return to_float((self.lo + self.hi) / 2)

    def to_dict(self) -> dict[str, Any]:
        """JSON form (exact values as strings)."""

        def vec(v: tuple[fmpq, ...] | None) -> list[str] | None:
            return None if v is None else [str(x) for x in v]

        return {
            "lo": str(self.lo),
            "hi": str(self.hi),
            "approx": self.approx,
            "relation": str(self.relation),
            "normal": vec(self.normal),
            "point_a": vec(self.point_a),
            "point_b": vec(self.point_b),
            "certified_by": str(self.certified_by),
        }


def _newton(SA: Any, SB: Any, delta: list[Any], n: list[Any], sqrt: Any, iterations: int, tol: Any = 1e-30) -> list[Any]:
    """Newton steps on h(n) = n.delta - |n|_A - |n|_B - |n|^2 / 2, halving while h does not grow.

    h is strictly concave and its maximiser is dist * unit normal. Floats or arb balls.
    """
    d = len(delta)

    def h(v: list[Any]) -> Any:
        return fdot(v, delta) - sqrt(fdot(v, mat_vec(SA, v))) - sqrt(fdot(v, mat_vec(SB, v))) - fdot(v, v) / 2

    for _ in range(iterations):
        san, sbn = mat_vec(SA, n), mat_vec(SB, n)
        a, b = sqrt(fdot(n, san)), sqrt(fdot(n, sbn))
        grad = [delta[i] - san[i] / a - sbn[i] / b - n[i] for i in range(d)]
        # -Hessian = S_A/a - (S_A n)(S_A n)^T/a^3 + (same for B) + I: positive definite
        H = [
            [SA[i][j] / a - san[i] * san[j] / (a * a * a) + SB[i][j] / b - sbn[i] * sbn[j] / (b * b * b) + (1 if i == j else 0)
             for j in range(d)]
            for i in range(d)
        ]
        step = mat_vec(inverse(H), grad)
        if not fdot(step, step) > tol * fdot(n, n):  # converged (to the working precision)
            return n
        h0, t = h(n), 1.0
        for _ in range(30):
            trial = [n[i] + t * step[i] for i in range(d)]
            if fdot(trial, trial) > 0 and not h(trial) < h0:
                break
            t /= 2
        else:
            return n
        n = trial
    return n


def _float_normal(cf: ContactFunction) -> list[float]:
    """The best direction in floats, for the pair at unit size (the direction is scale-free)."""
    delta, SA, SB = cf.unit_floats()
    # start from the contact function's normal: its slab is empty for a separate pair (g > 0)
    _, _, y = maximise(SA, SB, delta)
    norm = math.sqrt(fdot(y, y))
    u = [v / norm for v in y]
    gap = fdot(u, delta) - math.sqrt(fdot(u, mat_vec(SA, u))) - math.sqrt(fdot(u, mat_vec(SB, u)))
    n0 = [v * max(gap, 1e-300) for v in u]
    n = _newton(SA, SB, delta, n0, math.sqrt, 40)
    if not all(math.isfinite(v) for v in n) or not any(n):
        raise ArithmeticError("no finite direction")
    return n


def _arb_normal(cf: ContactFunction, n: list[Any], prec: int) -> list[fmpq]:
    """More Newton steps at ``prec`` bits on the pair at unit size (arb balls; midpoints used)."""
    from .numbers import arb_bounds

    r, r2 = pow2(cf.exponent), pow2(2 * cf.exponent)
    with working_precision(prec):
        d = cf.A.d
        SA = [[arb(cf.A.S[i, j] * r2) for j in range(d)] for i in range(d)]
        SB = [[arb(cf.B.S[i, j] * r2) for j in range(d)] for i in range(d)]
        delta = [arb(cf.delta[i, 0] * r) for i in range(d)]
        v = [arb(x) for x in n]
        v = _newton(SA, SB, delta, v, lambda x: x.sqrt(), 8, arb(2) ** (-2 * prec + 8))
        out = []
        for x in v:
            lo, _ = arb_bounds(x.mid())
            out.append(lo)
        return out


def _bracket(A: CentredShape, B: CentredShape, n: fmpq_mat, bits: int) -> tuple[fmpq, fmpq, fmpq_mat, fmpq_mat] | None:
    """Exact (lo, hi, p, q) for the direction n, or None if n gives no positive slab."""
    _, sa = sqrt_bounds(dot(n, A.S * n), bits)
    _, sb = sqrt_bounds(dot(n, B.S * n), bits)
    delta = B.centre - A.centre
    slab = dot(n, delta) - sa - sb
    if not slab > 0:
        return None
    _, norm = sqrt_bounds(dot(n, n), bits)
    p = A.centre + A.S * n * (1 / sa)
    q = B.centre - B.S * n * (1 / sb)
    _, hi = sqrt_bounds(dot(p - q, p - q), bits)
    return slab / norm, hi, p, q


def distance_pair(A: Any, B: Any, *, rtol: float = 1e-12) -> DistanceBracket:
    """Certified bracket of the Euclidean distance between two ellipses/ellipsoids (the exact stage alone).

    :func:`core.witness.distance` is the public form (stacks, ``method``).

    Args:
        A: one matrix, any input form of :func:`core.classify`.
        B: the other.
        rtol: relative width asked of the bracket, hi - lo <= rtol * hi (> 0).

    Returns:
        :class:`DistanceBracket`: lo <= dist <= hi exactly, with a direction n whose empty slab
        proves ``lo`` and points p in A, q in B with |p - q| <= hi. 0 exactly for tangent and
        overlapping pairs.

    Raises:
        ValueError: an invalid matrix or rtol.

    Examples:
        >>> circle = lambda x, r: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - r * r]]
        >>> b = distance_pair(circle(0, 1), circle(5, 2))          # 5 - 1 - 2
        >>> b.lo <= 2 <= b.hi, float(b.hi - b.lo) < 1e-12, b.point_a, b.point_b
        (True, True, (1, 0), (3, 0))
        >>> distance_pair(circle(0, 1), circle(2, 1)).hi
        0
    """
    if not (rtol > 0 and math.isfinite(rtol)):
        raise ValueError(f"rtol must be a finite number > 0, got {rtol!r}")
    a, b = centred_pair(A, B)
    rel = classify(A, B)
    return distance_from(ContactFunction(a, b), rel, rtol)


def distance_exact(pairs: Pairs, i: int, rtol: float) -> DistanceBracket:
    """The exact stage: pair i's distance bracket."""
    return distance_from(pairs.contact_function(i), Relation(int(pairs.relation[i])), rtol)


def distance_float(pairs: Pairs, todo: np.ndarray, rtol: float) -> dict[int, DistanceBracket]:
    """The float stage: certified float brackets of separate pairs (vectorised); 0 for the others.

    A tangent or overlapping pair is at distance 0 exactly (its relation is certified).
    """
    fp = pairs.floats
    assert fp is not None
    out: dict[int, DistanceBracket] = {}
    for i in np.flatnonzero(todo & (pairs.relation != Relation.SEPARATE)):
        out[int(i)] = DistanceBracket(fmpq(0), fmpq(0), Relation(int(pairs.relation[i])), certified_by=Certifier.FLOAT)
    mask = todo & (pairs.relation == Relation.SEPARATE)
    if not mask.any():
        return out
    lo, hi, n, pa, pb, ok = distances(fp, mask, rtol)

    def exact(v: np.ndarray) -> tuple[fmpq, ...]:
        return tuple(fmpq(*float(x).as_integer_ratio()) for x in v)

    for i in np.flatnonzero(ok & mask):
        out[int(i)] = DistanceBracket(
            fmpq(*float(lo[i]).as_integer_ratio()), fmpq(*float(hi[i]).as_integer_ratio()), Relation.SEPARATE,
            exact(n[i]), exact(pa[i]), exact(pb[i]), Certifier.FLOAT,
        )
    return out


def distance_from(cf: ContactFunction, rel: Relation, rtol: float) -> DistanceBracket:
    """The bracket from a pair's contact function and certified relation (see :func:`distance_pair`)."""
    if rel != Relation.SEPARATE:
        return DistanceBracket(fmpq(0), fmpq(0), rel)
    a, b = cf.A, cf.B
    tol = fmpq(*float(rtol).as_integer_ratio())
    try:
        n: list[Any] = [fmpq(*float(x).as_integer_ratio()) for x in _float_normal(cf)]
    except (ArithmeticError, ValueError):  # float trouble: the exact normal of the contact function
        n = _exact_normal(cf)
    best = None
    bits, prec = 64, 128
    for _ in range(_MAX_ROUNDS):
        got = _bracket(a, b, column(n), bits)
        if got is not None:
            lo, hi, p, q = got
            if best is None or hi - lo < best[1] - best[0]:
                best = (lo, hi, column(n), p, q)
            if hi - lo <= tol * hi:
                break
        try:
            n = _arb_normal(cf, n, prec)
        except (ArithmeticError, ValueError, ZeroDivisionError):
            break
        if not any(n):
            break
        bits, prec = bits * 2, prec * 2
    if best is None:  # the verified separating plane's normal has a positive slab
        from .plane import plane_from

        plane = plane_from(cf)
        n = list(plane.normal)
        got = _bracket(a, b, column(n), max(bits, 64 - log2_abs(plane.support_b - plane.support_a)))
        if got is None:  # a lower bound 0 is still true; the upper bound needs only two points
            return _points_only(a, b, rel, column(n), bits)
        lo, hi, p, q = got
        best = (lo, hi, column(n), p, q)
    lo, hi, nv, p, q = best
    d = a.d
    return DistanceBracket(
        lo, hi, rel,
        tuple(nv[i, 0] for i in range(d)), tuple(p[i, 0] for i in range(d)), tuple(q[i, 0] for i in range(d)),
    )


def _exact_normal(cf: ContactFunction) -> list[fmpq]:
    """The contact function's normal y(lambda) at its best lambda (exact; used when floats fail)."""
    br = cf.start()
    assert br is not None  # separate shapes have distinct centres
    y = cf.normal(br.best)
    return [y[i, 0] for i in range(cf.A.d)]


def _points_only(A: CentredShape, B: CentredShape, rel: Relation, n: fmpq_mat, bits: int) -> DistanceBracket:
    """The bracket [0, hi]: 0 is true for any pair, hi comes from the two support points along n."""
    _, sa = sqrt_bounds(dot(n, A.S * n), bits)
    _, sb = sqrt_bounds(dot(n, B.S * n), bits)
    p = A.centre + A.S * n * (1 / sa)
    q = B.centre - B.S * n * (1 / sb)
    _, hi = sqrt_bounds(dot(p - q, p - q), bits)
    d = A.d
    return DistanceBracket(
        fmpq(0), hi, rel, tuple(n[i, 0] for i in range(d)), tuple(p[i, 0] for i in range(d)), tuple(q[i, 0] for i in range(d))
    )
