"""Witnesses from float arithmetic with proofs (vectorised): the float stage of every witness.

The same straight-line code runs on Python floats (one pair: a few hundred microseconds, the
scene's drag path) and on numpy arrays (N,) for stacks. :func:`prepare` reads float pairs once:
each pair is seen at unit extent (an exact power-of-two change of space, :func:`unit_space`) and
each matrix scaled by a power of two to a largest entry in [1, 2); both exact, neither changes a
relation or a contact scale, and planes and points are mapped back exactly. What the floats
cannot certify is left to the exact stage (:mod:`core.witness.filtered`).

Contact scale (:func:`scale_brackets`): a float estimate s of s* = mu*^2 (Newton on the
contact function) is bracketed by two certified classifications of the pairs *scaled* about
their centres. Scaling a shape to s means adding k (1 - s) to the last entry of its matrix
(:mod:`core.witness.centred`); the float written there is an exact binary rational, and the scale
s' it stands for is enclosed with directed rounding (one ``nextafter`` per correctly rounded
operation) from a certified enclosure of k: with V = (v, 1) at the float centre v,
k = -V^T A V + r^T Q^-1 r (r = Q v + m), where V^T A V comes from compensated dot products (no
loss to the cancellation between c^T Q c and the last entry) and 0 <= r^T Q^-1 r <= |r|^2 /
lambda_min(Q), lambda_min(Q) >= det Q / tr(Q)^(d-1) (certified determinant,
:mod:`core.witness.floatdet`). Scaled shapes are nested in s, so

* scaled pair certified SEPARATE at scales (s_A', s_B')  =>  s* > min(s_A', s_B'),
* scaled pair certified TANGENT or OVERLAP              =>  s* <= max(s_A', s_B').

:func:`core.classify` certifies those labels (float filter; exact where it abstains unless the
method is "float"). Pairs the floats cannot bracket within ``rtol`` (near s* = 0, centres far out
compared with the sizes, which put the scale in the last digits of the last entry) are left to
the exact stage; tangent pairs are exactly mu* = 1.

Planes (:func:`planes`): the normal y(lambda*) of the contact function, the offset halfway
between the two support values, and a certificate with directed rounding: the shape lies
strictly on one side iff side (n.c - d) > sqrt(k n^T Q^-1 n) (:func:`_plane_certified`).
Points (:func:`points`): x(lambda*) of an overlapping pair, certified inside both
(X^T A X < 0 with a compensated, bounded evaluation). Both are tried first in a simple form (the
normal scaled to a largest component 1, coordinates rounded to short dyadics) that the same
certificate must accept. Distances (:func:`distances`): the best direction by Newton, the empty
slab between certified support bounds along it below, two float points certified inside the
shapes above.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, cast

import numpy as np

from ..fixed.classify import Method, Stats, classify
from ..relation import Relation
from .floatdet import det_with_bound
from .floats import (
    Real,
    centred,
    dot,
    down,
    inverse,
    is_array,
    lists,
    maximise,
    scaled,
    stacked,
    up,
    where,
)

__all__ = ["FloatPairs", "prepare", "unit_space", "scale_brackets", "planes", "points", "distances"]

_SMALLEST_S = 1e-8
"""Below this estimate of s* the float scaled matrices lose the scale: exact path instead."""
_U = 2.0**-53
_SPLIT = 134217729.0  # 2^27 + 1 (Veltkamp)
_ARITHMETIC = (ZeroDivisionError, OverflowError, ValueError)
"""What Python floats raise where numpy arrays give inf/nan (one pair: that pair goes exact)."""


# ------------------------------------------------------------------ inputs


def _normalised(M: np.ndarray) -> np.ndarray:
    """Matrices with negative interiors and the largest |entry| in [1, 2).

    Both changes are exact (a sign and a power of two) and neither changes the shape.
    """
    mx = np.abs(M).max(axis=(-2, -1))
    _, e = np.frexp(np.where((mx > 0) & np.isfinite(mx), mx, 1.0))
    factor = np.ldexp(np.where(M[..., 0, 0] < 0, -1.0, 1.0), 1 - e)
    return np.asarray(M * factor[..., None, None])


def _log2(x: np.ndarray) -> np.ndarray:
    """Binary exponents of |x| (frexp), -inf-like (-10**6) for zeros."""
    _, e = np.frexp(x)
    return np.where(x != 0, e, -(10**6))


def _space_exponent(M: np.ndarray) -> np.ndarray:
    """log2 of a shape's extent from its float matrix (..., n, n): centre distance and size.

    With the quadratic block M ~ 1/L^2 (L the size), m ~ c / L^2 and a ~ |c|^2 / L^2 - 1, the
    extent max(|c|, L) is about max(|m| / |M|, sqrt(|a| / |M|)).
    """
    d = M.shape[-1] - 1
    eM = _log2(np.abs(M[..., :d, :d]).max(axis=(-2, -1)))
    em = _log2(np.abs(M[..., :d, d]).max(axis=-1))
    ea = _log2(np.abs(M[..., d, d]))
    return np.asarray(np.maximum(em - eM, (ea - eM) // 2))


def unit_space(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pairs seen through x' = 2^e x, with e per pair bringing them to about unit extent.

    A' = D A D with D = diag(2^-e, ..., 2^-e, 1): the quadratic block times 4^-e, the linear
    part 2^-e, the constant unchanged. Exact (powers of two) wherever no entry leaves the normal
    float range; a pair where one would keeps e = 0. The contact scale and the relation do not
    change; a plane n.x' = d' is n.x = 2^-e d', a point x' is 2^-e x'.

    Returns:
        (a', b', e) with e an int64 array of the batch shape (0-d for one pair).
    """
    d = a.shape[-1] - 1
    e = -np.maximum(_space_exponent(a), _space_exponent(b))
    e = np.where(np.abs(e) < 2100, e, 0)  # beyond: nothing representable on both sides anyway
    # exponent of each entry's factor: -2e on the quadratic block, -e on the linear part, 0 last
    e2 = np.broadcast_to(np.asarray(-e)[..., None, None], a.shape).copy()
    e2[..., :d, :d] *= 2
    e2[..., d, d] = 0
    with np.errstate(all="ignore"):
        a2, b2 = np.ldexp(a, e2), np.ldexp(b, e2)
        exact = (np.ldexp(a2, -e2) == a) & (np.ldexp(b2, -e2) == b) & np.isfinite(a2) & np.isfinite(b2)
    ok = exact.all(axis=(-2, -1))
    e = np.where(ok, e, 0)
    a2 = np.where(ok[..., None, None], a2, a)
    b2 = np.where(ok[..., None, None], b2, b)
    return a2, b2, e.astype(np.int64)


@dataclass
class FloatPairs:
    """Float pairs read once for every float certificate (see :func:`prepare`)."""

    a: np.ndarray
    """Matrices at unit extent, largest entry in [1, 2): (n, n) for one pair, else (N, n, n)."""
    b: np.ndarray
    exponent: np.ndarray
    """(N,) int64: the pair is seen through x' = 2^e x."""

    @property
    def size(self) -> int:
        """Number of pairs N."""
        return int(self.exponent.size)

    @property
    def dim(self) -> int:
        """Dimension of space (2 or 3)."""
        return int(self.a.shape[-1]) - 1

    @cached_property
    def pair(self) -> _Pair | None:
        """Centre facts and the maximiser, computed once; None when one pair's floats overflow."""
        try:
            with np.errstate(all="ignore"):
                return _pair(self.a, self.b)
        except _ARITHMETIC:  # one pair only: Python floats raise where arrays give inf/nan
            return None


def prepare(a: np.ndarray, b: np.ndarray) -> FloatPairs:
    """Float pairs (N, n, n) (binary64, as given) prepared for the certificates.

    One pair runs on Python floats (faster than numpy for one), stacks on (N,) arrays.
    """
    x, y = (a[0], b[0]) if a.shape[0] == 1 else (a, b)
    x, y, e = unit_space(x, y)
    return FloatPairs(_normalised(x), _normalised(y), np.asarray(e, dtype=np.int64).reshape(-1))


def scale_brackets(fp: FloatPairs, codes: np.ndarray, rtol: float, method: Method) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Certified float brackets of mu*: (lo, hi, estimate, ok), each (N,).

    ``codes`` are the pairs' certified relations; ``ok`` where the bracket is certified and
    within ``rtol`` (tangent pairs are not done here: mu* = 1 exactly).
    """
    N = fp.size
    P = fp.pair
    if P is None:
        return np.zeros(N), np.full(N, np.inf), np.zeros(N), np.zeros(N, bool)
    c: Any = codes if fp.a.ndim == 3 else int(codes[0])
    try:
        with np.errstate(all="ignore"):
            lo, hi, found = _float_bracket(P, c, rtol, Stats(), method)
            est = np.sqrt(np.maximum(np.nan_to_num(np.asarray(P.s_est, dtype=np.float64)), 0.0))
    except _ARITHMETIC:
        return np.zeros(N), np.full(N, np.inf), np.zeros(N), np.zeros(N, bool)
    flat = [np.asarray(v, dtype=np.float64).reshape(-1) for v in (lo, hi, est)]
    return flat[0], flat[1], flat[2], np.asarray(found, dtype=bool).reshape(-1)


def _snap(x: Any, bits: int) -> Any:
    """X rounded to a multiple of 2^-bits (a short dyadic), elementwise."""
    return np.ldexp(np.round(np.ldexp(x, bits)), -bits) if is_array(x) else math.ldexp(round(math.ldexp(x, bits)), -bits)


def planes(fp: FloatPairs, todo: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Certified float separating planes n.x = d in the pairs' own coordinates: (normal (N, d), d (N,), ok (N,)).

    ``ok``: A lies strictly in n.x < d and B strictly in n.x > d, for the floats as the binary
    rationals they are. Tried in order: the normal with a largest component 1 and coordinates
    rounded to 2^-20, with the offset rounded to 2^-20 at unit extent; then unrounded.
    """
    N, dim = fp.size, fp.dim
    normal, offset, ok = np.full((N, dim), np.nan), np.full(N, np.nan), np.zeros(N, bool)
    P = fp.pair
    if P is None or not todo.any():
        return normal, offset, ok
    try:
        with np.errstate(all="ignore"):
            n0, d0, ok0 = _float_planes(P)
            big = np.abs(n0).max(axis=1)
            n1, d1 = n0 / big[:, None], d0 / big
            tries = [(_snap(n1, 20), _snap(d1, 20)), (n1, d1), (n0, d0)]
            for nc, dc in tries:
                nl = [nc[:, i] if fp.a.ndim == 3 else float(nc[0, i]) for i in range(dim)]
                dl = dc if fp.a.ndim == 3 else float(dc[0])
                got = _plane_certified(P.A, P.al, nl, dl, -1) & _plane_certified(P.B, P.bl, nl, dl, 1)
                got = np.asarray(got, dtype=bool).reshape(-1) & todo & ~ok & np.isfinite(dc) & np.isfinite(nc).all(axis=1)
                normal[got], offset[got] = nc[got], dc[got]
                ok |= got
                if ok[todo].all():
                    break
    except _ARITHMETIC:
        return np.full((N, dim), np.nan), np.full(N, np.nan), np.zeros(N, bool)
    # back from the unit-extent view: n.x' = d' is n.x = 2^-e d' (exact unless it leaves the range)
    with np.errstate(all="ignore"):
        world = np.ldexp(offset, -fp.exponent)
        ok &= (np.ldexp(world, fp.exponent) == offset) & np.isfinite(world)
    return normal, world, ok


def points(fp: FloatPairs, todo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Float points certified strictly inside both shapes, in the pairs' own coordinates: (x (N, d), ok (N,)).

    x(lambda*) of the contact function, tried rounded to 2^-8 and 2^-20 at unit extent first.
    """
    N, dim = fp.size, fp.dim
    out, ok = np.full((N, dim), np.nan), np.zeros(N, bool)
    P = fp.pair
    if P is None or not todo.any():
        return out, ok
    try:
        with np.errstate(all="ignore"):
            x, _ = _float_point(P)
            x0 = np.stack([np.asarray(v, dtype=np.float64).reshape(-1) for v in x], axis=1)
            for xc in (_snap(x0, 8), _snap(x0, 20), x0):
                xl = [xc[:, i] if fp.a.ndim == 3 else float(xc[0, i]) for i in range(dim)]
                got = _inside_certified(P.al, xl) & _inside_certified(P.bl, xl)
                got = np.asarray(got, dtype=bool).reshape(-1) & todo & ~ok & np.isfinite(xc).all(axis=1)
                out[got] = xc[got]
                ok |= got
                if ok[todo].all():
                    break
    except _ARITHMETIC:
        return np.full((N, dim), np.nan), np.zeros(N, bool)
    with np.errstate(all="ignore"):
        world = np.ldexp(out, -fp.exponent[:, None])
        ok &= ((np.ldexp(world, fp.exponent[:, None]) == out) & np.isfinite(world)).all(axis=1)
    return world, ok


def _support_upper(C: _Centre, M: list[list[Any]], n: list[Any]) -> tuple[Any, Any]:
    """(certified upper bound of max n.x over the shape, where it is certified).

    max n.x = n.c + sqrt(k n^T Q^-1 n), bounded as in :func:`_plane_certified`:
    n.c <= n.v + |n| |r| / lambda_min and n^T Q^-1 n <= w.n + |w|.|e| + |e|^2 / lambda_min.
    """
    t, tb = _dot2(n, C.v)
    # (1 + 2^-48) covers the rounding of a sum of at most 4 nonnegative terms (4u < 2^-48)
    norm_n = up(_sqrt(up(dot(n, n) * (1 + 2.0**-48))))
    nc_hi = up(up(t + tb) + up(norm_n * C.offset_error()))
    w = [dot(row, n) for row in C.Qinv]
    e, eb = _sym_matvec(M, w, C.symmetric, minus=n)
    wn, wnb = _dot2(w, n)
    e_abs = [abs(x) + b for x, b in zip(e, eb, strict=True)]
    we = sum((abs(wi) * ei for wi, ei in zip(w, e_abs, strict=True)), 0.0)
    ee = sum((ei * ei for ei in e_abs), 0.0)
    q_hi = up((wn + wnb + we + ee / C.lam_lo) * (1 + 2.0**-48))
    return up(nc_hi + up(_sqrt(up(C.k_hi * q_hi)))), C.ok & (q_hi > 0)


def _best_direction(P: _Pair, iterations: int = 12) -> list[Any]:
    """The direction of the distance, estimated: Newton on h(n) = n.delta - |n|_A - |n|_B - |n|^2/2.

    h is strictly concave with maximiser dist * unit normal; each step is taken only where it
    increases h (else halved, three times), for one pair or elementwise for a stack. Started
    from the contact function's normal (its slab is empty for a separate pair).
    """
    SA, SB = P.SA, P.SB
    delta = [q - p for p, q in zip(P.A.v, P.B.v, strict=True)]
    d = len(delta)

    def norms(v: list[Any]) -> tuple[list[Any], list[Any], Any, Any]:
        san, sbn = [dot(r, v) for r in SA], [dot(r, v) for r in SB]
        return san, sbn, _sqrt(dot(v, san)), _sqrt(dot(v, sbn))

    def h(v: list[Any]) -> Any:
        _, _, a, b = norms(v)
        return dot(v, delta) - a - b - 0.5 * dot(v, v)

    norm = _sqrt(dot(P.y, P.y))
    u = [x / norm for x in P.y]
    _, _, a0, b0 = norms(u)
    gap = dot(u, delta) - a0 - b0
    n = [x * where(gap > 0, gap, 1e-300) for x in u]
    hn = h(n)
    for _ in range(iterations):
        san, sbn, a, b = norms(n)
        grad = [delta[i] - san[i] / a - sbn[i] / b - n[i] for i in range(d)]
        H = [
            [SA[i][j] / a - san[i] * san[j] / (a * a * a) + SB[i][j] / b - sbn[i] * sbn[j] / (b * b * b) + (1.0 if i == j else 0.0)
             for j in range(d)]
            for i in range(d)
        ]
        step = [dot(row, grad) for row in inverse(H)]
        t = 1.0
        for _ in range(4):
            trial = [n[i] + t * step[i] for i in range(d)]
            ht = h(trial)
            better = ht > hn
            n = [where(better, trial[i], n[i]) for i in range(d)]
            hn = where(better, ht, hn)
            t *= 0.5
    return n


def distances(fp: FloatPairs, todo: np.ndarray, rtol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Certified float distance brackets of separate pairs, in the pairs' own coordinates.

    Returns (lo (N,), hi (N,), direction (N, d), point_a (N, d), point_b (N, d), ok (N,)):
    ``lo`` is the empty slab between the certified support bounds along the direction
    (:func:`_support_upper`), ``hi`` the distance of two float points certified inside A and B
    (:func:`_inside_certified`), rounded up; ``ok`` where both hold and hi - lo <= rtol hi.
    """
    N, dim = fp.size, fp.dim
    nan = np.full(N, np.nan)
    out = (nan, nan.copy(), np.full((N, dim), np.nan), np.full((N, dim), np.nan), np.full((N, dim), np.nan), np.zeros(N, bool))
    P = fp.pair
    if P is None or not todo.any():
        return out
    try:
        with np.errstate(all="ignore"):
            n = _best_direction(P)
            sup_a, ok_a = _support_upper(P.A, P.al, n)
            sup_nb, ok_b = _support_upper(P.B, P.bl, [-x for x in n])  # min n.x over B = -max (-n).x
            norm_n = up(_sqrt(up(dot(n, n) * (1 + 2.0**-48))))
            lo = down(down(-sup_nb - sup_a) / norm_n)
            shrink = 1.0 - 2.0**-44  # a hair inside the boundary: certified strictly inside
            pts = []
            for C, S, M, sign in ((P.A, P.SA, P.al, 1.0), (P.B, P.SB, P.bl, -1.0)):
                sn = [dot(r, n) for r in S]
                scale = sign * shrink / _sqrt(dot(n, sn))
                x = [C.v[i] + scale * sn[i] for i in range(dim)]
                pts.append((x, _inside_certified(M, x)))
            (pa, in_a), (pb, in_b) = pts
            diff = [up(abs(pa[i] - pb[i]) * (1 + 2.0**-52)) for i in range(dim)]
            hi = up(_sqrt(up(sum((up(x * x) for x in diff), 0.0) * (1 + 2.0**-48))))
            ok = ok_a & ok_b & in_a & in_b & (lo > 0) & (hi - lo <= rtol * hi)
    except _ARITHMETIC:
        return out
    flat = [np.asarray(v, dtype=np.float64).reshape(-1) for v in (lo, hi)]
    vecs = [np.stack([np.asarray(v, dtype=np.float64).reshape(-1) for v in vec], axis=1) for vec in (n, pa, pb)]
    good = np.asarray(ok, dtype=bool).reshape(-1) & todo & np.isfinite(flat[0]) & np.isfinite(flat[1])
    # back from the unit-extent view: lengths and points times 2^-e (exact unless out of range)
    with np.errstate(all="ignore"):
        e = fp.exponent
        lo_w, hi_w = np.ldexp(flat[0], -e), np.ldexp(flat[1], -e)
        pa_w, pb_w = np.ldexp(vecs[1], -e[:, None]), np.ldexp(vecs[2], -e[:, None])
        good &= (np.ldexp(lo_w, e) == flat[0]) & (np.ldexp(hi_w, e) == flat[1]) & (lo_w > 0)
        good &= ((np.ldexp(pa_w, e[:, None]) == vecs[1]) & (np.ldexp(pb_w, e[:, None]) == vecs[2])).all(axis=1)
    return lo_w, hi_w, vecs[0], pa_w, pb_w, good


# ------------------------------------------------------------------ error-free arithmetic


def _two_sum(a: Any, b: Any) -> tuple[Any, Any]:
    """Exact sum: s + e = a + b (Knuth's TwoSum)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _two_product(a: Any, b: Any) -> tuple[Any, Any]:
    """Exact product: p + e = a * b (Dekker, Veltkamp splitting; no overflow or underflow)."""
    p = a * b
    ca, cb = _SPLIT * a, _SPLIT * b
    ah = ca - (ca - a)
    al = a - ah
    bh = cb - (cb - b)
    bl = b - bh
    return p, al * bl - (((p - ah * bh) - al * bh) - ah * bl)


def _dot2(x: list[Any], y: list[Any]) -> tuple[Any, Any]:
    """Compensated dot product and a certified error bound.

    Ogita, Rump, Oishi, "Accurate sum and dot product" (2005), Dot2:
    |res - x.y| <= u |x.y| + gamma_n^2 |x|.|y| (no underflow). The bound returned doubles both
    terms, which covers |x.y| <= |res| + bound and the rounding of the bound itself, and adds an
    absolute floor for products below the normal range.
    """
    n = len(x)
    p, s = _two_product(x[0], y[0])
    absdot = abs(x[0]) * abs(y[0])
    for i in range(1, n):
        h, r = _two_product(x[i], y[i])
        p, q = _two_sum(p, h)
        s = s + (q + r)
        absdot = absdot + abs(x[i]) * abs(y[i])
    res = p + s
    g = n * _U / (1 - n * _U)
    return res, 4.0 * _U * abs(res) + 4.0 * g * g * absdot + 2.0**-1000


@dataclass
class _Centre:
    """Certified float facts about one normalised matrix [[Q, m], [m^T, a]] (or a stack).

    v a float centre, r = Q v + m with |r - r_float| <= rb (componentwise), 0 < lam_lo <=
    lambda_min(Q), k_lo <= k <= k_hi, and ``ok`` where all of it is certified.
    """

    v: list[Any]
    Qinv: list[list[Any]]
    r: list[Any]
    rb: list[Any]
    lam_lo: Any
    k_lo: Any
    k_hi: Any
    ok: Any
    symmetric: bool
    """Every matrix exactly symmetric (else the exact symmetric part is what is certified)."""

    @property
    def k_mid(self) -> Real:
        return cast(Real, 0.5 * (self.k_lo + self.k_hi))

    def offset_error(self) -> Real:
        """An upper bound of |r|_2 / lambda_min: |u.(c - v)| <= |u|_2 times this, for any u."""
        rr = sum(((abs(ri) + b) * (abs(ri) + b) for ri, b in zip(self.r, self.rb, strict=True)), 0.0)
        return up(_sqrt(up(rr)) / self.lam_lo * (1 + 2.0**-40))


def _sqrt(x: Any) -> Any:
    return np.sqrt(x) if is_array(x) else math.sqrt(x)


def _is_symmetric(M: list[list[Any]]) -> bool:
    """True when every matrix is exactly symmetric (floats from rotations often are not)."""
    n = len(M)
    return all(bool(np.all(M[i][j] == M[j][i])) for i in range(n) for j in range(i + 1, n))


def _sym_matvec(M: list[list[Any]], x: list[Any], symmetric: bool, minus: list[Any] | None = None) -> tuple[list[Any], list[Any]]:
    """S x - minus, S the exact symmetric part of M's leading block: values and error bounds.

    Compensated dot products, certified error bounds componentwise.

    Core reads a matrix symmetric only up to rounding as its exact symmetric part (the quadratic
    form); a row of S is (row + column)/2, taken as 2m products with x/2 (halving is exact).
    """
    m = len(x)
    out, bounds = [], []
    for i in range(m):
        extra_x, extra_y = ([minus[i]], [-1.0]) if minus is not None else ([], [])
        if symmetric:
            val, b = _dot2([*M[i][:m], *extra_x], [*x, *extra_y])
        else:
            half = [0.5 * v for v in x]
            val, b = _dot2([*M[i][:m], *(M[j][i] for j in range(m)), *extra_x], [*half, *half, *extra_y])
        out.append(val)
        bounds.append(b)
    return out, bounds


def _centre(M: list[list[Any]]) -> _Centre:
    """Centre facts of M (see :class:`_Centre`).

    With V = (v, 1), V^T M V = (v - c)^T Q (v - c) - k, so k = -V^T M V + r^T Q^-1 r. V^T M V
    = v.r + (m.v + a) comes from compensated dot products (the cancellation between c^T Q c and
    a costs nothing) and 0 <= r^T Q^-1 r <= |r|^2 / lambda_min(Q), lambda_min(Q) >= det Q /
    tr(Q)^(d-1) (certified determinant).
    """
    d = len(M) - 1
    v, Qinv, _ = centred(M)
    V = [*v, 1.0]
    sym = _is_symmetric(M)
    w, wb = _sym_matvec(M, V, sym)
    r, rb = w[:d], wb[:d]
    F = dot(v, r) + w[d]
    spread = sum((abs(ci) * abs(ri) for ci, ri in zip(v, r, strict=True)), abs(w[d]))
    Fb = (sum((abs(ci) * b for ci, b in zip(v, rb, strict=True)), wb[d]) + 4.0 * (d + 2) * _U * spread) * (1 + 2.0**-40)
    Q = [row[:d] for row in M[:d]]
    if not sym:  # the float symmetric part, within u |entry| of the exact one (Weyl: shift lambda)
        Q = [[(Q[i][j] + Q[j][i]) * 0.5 for j in range(d)] for i in range(d)]
    det, detb, e = det_with_bound(Q)
    det_lo = np.ldexp(down(det - detb), e)
    trace = sum((Q[i][i] for i in range(1, d)), Q[0][0])
    lam_lo = down(det_lo / up(trace ** (d - 1) * (1 + 2.0**-40)))
    if not sym:
        frob = _sqrt(sum((Q[i][j] * Q[i][j] for i in range(d) for j in range(d)), 0.0))
        lam_lo = down(lam_lo - up(4.0 * _U * frob))
    lam_ok = lam_lo > 0
    lam_lo = where(lam_ok, lam_lo, 1.0)
    rr = sum(((abs(ri) + b) * (abs(ri) + b) for ri, b in zip(r, rb, strict=True)), 0.0)
    k_lo = down(-F - Fb)
    k_hi = up(-F + Fb + 2.0 * rr / lam_lo)
    big = max(abs(x) for row in M for x in row) if not is_array(M[0][0]) else np.max(np.abs(stacked(M)), axis=(1, 2))
    ok = np.isfinite(k_lo) & np.isfinite(k_hi) & (k_lo > 0) & lam_ok & (big < 2.0**500)
    for x in v:
        ok = ok & (abs(x) < 2.0**200)
    return _Centre(v, Qinv, r, rb, lam_lo, k_lo, k_hi, ok, sym)


def _scaled_last(M: list[list[Any]], k_mid: Any, k_lo: Any, k_hi: Any, s: Any) -> tuple[Any, Any, Any]:
    """Last entry of M scaled about its centre to about s, with an enclosure [s_lo, s_hi].

    The enclosure is of the scale the rounded float entry stands for.
    """
    a = M[-1][-1]
    new = a + k_mid * (1.0 - s)
    diff, err = _two_sum(new, -a)  # alpha = new - a = diff + err exactly
    alpha = diff + err
    al_lo, al_hi = down(alpha), up(alpha)
    q = [al_lo / k_lo, al_lo / k_hi, al_hi / k_lo, al_hi / k_hi]
    if is_array(new):
        q_lo, q_hi = down(np.minimum.reduce(q)), up(np.maximum.reduce(q))
    else:
        q_lo, q_hi = down(min(q)), up(max(q))
    return new, down(1.0 - q_hi), up(1.0 - q_lo)


def _with_last(M: list[list[Any]], value: Any) -> np.ndarray:
    out = stacked(M).copy()
    out[..., -1, -1] = value
    return out


def _classify_valid(A: np.ndarray, B: np.ndarray, valid: Any, stats: Stats, method: Method) -> Any:
    """Certified codes where ``valid`` (UNDECIDED elsewhere).

    The float filter, and exact arithmetic where it abstains unless ``method`` is "float".
    """
    if not is_array(valid):
        return int(classify(A, B, method=method, stats=stats)) if valid else int(Relation.UNDECIDED)
    got = np.full(valid.shape, Relation.UNDECIDED, dtype=np.int8)
    if valid.any():
        got[valid] = classify(A[valid], B[valid], method=method, stats=stats)
    return got


# ------------------------------------------------------------------ contact scale


@dataclass
class _Pair:
    """Float data of one pair or a stack, computed once: matrices, centre facts, the maximiser."""

    al: list[list[Any]]
    bl: list[list[Any]]
    A: _Centre
    B: _Centre
    SA: list[list[Any]]
    SB: list[list[Any]]
    lam: Any
    s_est: Any
    y: list[Any]


def _pair(a: np.ndarray, b: np.ndarray) -> _Pair:
    al, bl = lists(a), lists(b)
    A, B = _centre(al), _centre(bl)
    # S from the compensated k (the plain float k loses digits to cancellation)
    SA, SB = scaled(A.k_mid, A.Qinv), scaled(B.k_mid, B.Qinv)
    lam, s_est, y = maximise(SA, SB, [q - p for p, q in zip(A.v, B.v, strict=True)])
    return _Pair(al, bl, A, B, SA, SB, lam, s_est, y)


def _float_bracket(P: _Pair, codes: Any, rtol: float, stats: Stats, method: Method = "adaptive") -> tuple[Any, Any, Any]:
    """(mu_lo, mu_hi, certified) from floats, for one pair or a stack."""
    A, B, s_est = P.A, P.B, P.s_est
    eps = 0.45 * rtol  # bracket width about 2 eps mu*, below rtol mu*
    todo = (codes != Relation.TANGENT) & np.isfinite(s_est) & (s_est > _SMALLEST_S) & A.ok & B.ok & (eps >= 2.0**-48)
    s_lo = s_hi = None
    found = todo
    for sign in (-1, 1):
        goal = s_est * (1.0 + sign * eps) ** 2
        na, sal, sah = _scaled_last(P.al, A.k_mid, A.k_lo, A.k_hi, goal)
        nb, sbl, sbh = _scaled_last(P.bl, B.k_mid, B.k_lo, B.k_hi, goal)
        valid = todo & (sal > 0) & (sbl > 0) & np.isfinite(na) & np.isfinite(nb)
        got = _classify_valid(_with_last(P.al, na), _with_last(P.bl, nb), valid, stats, method)
        if sign < 0:
            found = found & valid & (got == Relation.SEPARATE)
            s_lo = where(sal < sbl, sal, sbl)
        else:
            found = found & valid & ((got == Relation.TANGENT) | (got == Relation.OVERLAP))
            s_hi = where(sah > sbh, sah, sbh)
    s_lo = where(found, s_lo, 0.0)
    s_hi = where(found, s_hi, 1.0)
    if is_array(s_lo):
        mu_lo, mu_hi = down(np.sqrt(np.maximum(s_lo, 0.0))), up(np.sqrt(np.maximum(s_hi, 0.0)))
    else:
        mu_lo, mu_hi = down(math.sqrt(max(s_lo, 0.0))), up(math.sqrt(max(s_hi, 0.0)))
    mu_lo = where(mu_lo > 0, mu_lo, 0.0)
    found = found & (mu_hi - mu_lo <= rtol * mu_hi)  # e.g. deep overlaps: floats lose s* ~ 0
    return mu_lo, mu_hi, found


# ------------------------------------------------------------------ planes


def _plane_certified(C: _Centre, M: list[list[Any]], n: list[Any], d: Any, side: int) -> Any:
    """Certified: the plane n.x = d misses the shape, which lies on ``side`` of it.

    ``side`` -1: n.x < d, +1: n.x > d. Elements floats (one pair) or (N,) arrays.

    The shape lies strictly on that side iff h = side (n.c - d) > sqrt(k n^T Q^-1 n) (its
    support in direction -side n stays beyond the plane). With the float centre v:
    n.c = n.v - n.Q^-1 r, so h >= side (n.v - d) - |n| |r| / lambda_min (n.v - d by a compensated
    dot product). With w the float Q^-1 n and e = Q w - n (compensated):
    n^T Q^-1 n = w.n - w.e + e^T Q^-1 e <= w.n + |w|.|e| + |e|^2 / lambda_min.
    """
    t, tb = _dot2([*n, d], [*C.v, -1.0])  # n.v - d
    norm_n = up(_sqrt(up(dot(n, n))) * (1 + 2.0**-40))
    h_lo = down(side * t - tb - up(norm_n * C.offset_error()))
    w = [dot(row, n) for row in C.Qinv]
    e, eb = _sym_matvec(M, w, C.symmetric, minus=n)
    wn, wnb = _dot2(w, n)
    e_abs = [abs(x) + b for x, b in zip(e, eb, strict=True)]
    we = sum((abs(wi) * ei for wi, ei in zip(w, e_abs, strict=True)), 0.0)
    ee = sum((ei * ei for ei in e_abs), 0.0)
    q_hi = up((wn + wnb + we + ee / C.lam_lo) * (1 + 2.0**-40))
    return C.ok & (h_lo > 0) & (q_hi > 0) & (down(h_lo * h_lo) > up(C.k_hi * q_hi))


def _float_planes(P: _Pair) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate planes (unit normal (N, d), offset (N,)) and their certificates (N,)."""
    y = P.y
    sqrt = np.sqrt if is_array(y[0]) else math.sqrt
    norm = sqrt(dot(y, y))
    nrm = [v / norm for v in y]
    wa = dot(nrm, [dot(row, nrm) for row in P.SA])
    wb = dot(nrm, [dot(row, nrm) for row in P.SB])
    off = 0.5 * ((dot(nrm, P.A.v) + sqrt(wa)) + (dot(nrm, P.B.v) - sqrt(wb)))
    ok = _plane_certified(P.A, P.al, nrm, off, -1) & _plane_certified(P.B, P.bl, nrm, off, 1)
    normal = np.stack(nrm, axis=-1)
    return normal.reshape(-1, normal.shape[-1]), np.asarray(off, dtype=np.float64).reshape(-1), np.asarray(ok).reshape(-1)


def _inside_certified(M: list[list[Any]], x: list[Any]) -> Any:
    """Certified: X^T M X < 0 at X = (x, 1), the float point as the binary rationals it holds."""
    V = [*x, 1.0]
    w, wb = _sym_matvec(M, V, True)  # the form X^T M X is that of the symmetric part
    val, vb = _dot2(V, w)
    spread = sum((abs(v) * b for v, b in zip(V, wb, strict=True)), 0.0)
    return up(val + up((vb + spread) * (1 + 2.0**-40))) < 0


def _float_point(P: _Pair) -> tuple[list[Any], Any]:
    """x(lambda*) = c_A + (1 - lambda*) S_A y, and whether it is certified inside both shapes."""
    d = len(P.y)
    x = [P.A.v[i] + (1 - P.lam) * dot(P.SA[i], P.y) for i in range(d)]
    return x, _inside_certified(P.al, x) & _inside_certified(P.bl, x)


