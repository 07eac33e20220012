"""Witnesses from float arithmetic with proofs: contact-scale brackets and separating planes.

For stacks of float pairs (vectorised) and for one float pair (the scene's drag path: the same
code on Python floats, a few hundred microseconds).

Contact scale (:func:`contact_scale_batch`): a float estimate s of s* = mu*^2 (Newton on the
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

:func:`core.classify` certifies those labels (float filter, exact where it abstains). Pairs the
floats cannot bracket within ``rtol`` (near s* = 0, extreme magnitudes) get the exact one-pair
computation; tangent pairs are exactly mu* = 1; the relation at scale 1 (certified) puts 1 on
the right side of every bracket. Centres far from the origin compared with the sizes (about
1e3 times and more) put the scale in the last digits of the last entry: those pairs go exact.

Planes (:func:`separating_plane_batch`): the normal y(lambda*) of the contact function, the
offset halfway between the two support values, and a certificate from determinant signs: the
plane pi = (n, -d) misses the ellipsoid A iff pi^T adj(A) pi > 0, i.e. the bordered determinant
det [[A, pi], [pi^T, 0]] < 0, and A lies on the side n.x < d iff det(A with its last column
replaced by pi) < 0 (Cramer: (A^-1 pi)_last = (d - n.c) / k, and det A < 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from flint import fmpq

from ..fixed.classify import OnInvalid, Stats, classify, classify_detailed
from ..relation import Relation
from .centred import centred_pair
from .contact_function import ContactFunction
from .floatdet import det_with_bound
from .floats import centred, dot, down, is_array, lists, maximise, scaled, stacked, up, where
from .numbers import to_float
from .plane import plane_from
from .scale import check_rtol, scale_from

__all__ = ["ContactScaleBatch", "PlaneBatch", "FloatWitness", "contact_scale_batch", "separating_plane_batch", "float_witness"]

_SMALLEST_S = 1e-8
"""Below this estimate of s* the float scaled matrices lose the scale: exact path instead."""
_U = 2.0**-53
_SPLIT = 134217729.0  # 2^27 + 1 (Veltkamp)
_ARITHMETIC = (ZeroDivisionError, OverflowError, ValueError)
"""What Python floats raise where numpy arrays give inf/nan (one pair: that pair goes exact)."""


@dataclass
class ContactScaleBatch:
    """Certified float brackets ``lo <= mu* <= hi`` for pairs (arrays of the batch shape)."""

    lo: np.ndarray
    hi: np.ndarray
    approx: np.ndarray
    """A float estimate inside [lo, hi]."""
    relation: np.ndarray
    """int8 Relation codes (SEPARATE, TANGENT, OVERLAP), as from :func:`core.classify`."""
    exact_pairs: int = 0
    """How many pairs needed the exact one-pair computation (the floats could not bracket them)."""
    exact_classifications: int = 0
    """How many scaled pairs the float filter left to exact classification (gaps near rtol)."""
    errors: dict[int, str] = field(default_factory=dict)
    """Flat pair index -> why the pair has no bracket (``on_invalid="mark"``: invalid input)."""


@dataclass
class PlaneBatch:
    """Separating planes n.x = d of pairs: A in n.x < d, B in n.x > d where ``certified``."""

    normal: np.ndarray
    """(..., dim) float normals of unit length (up to rounding); NaN where the pair is not separate."""
    offset: np.ndarray
    """(...) float offsets d."""
    certified: np.ndarray
    """(...) bool: the float plane, as the exact binary rationals it holds, was verified to
    separate the pair strictly (certified determinant signs)."""
    relation: np.ndarray
    """int8 Relation codes of the pairs."""
    errors: dict[int, str] = field(default_factory=dict)
    """Flat pair index -> why the pair has no plane (``on_invalid="mark"``: invalid input)."""


# ------------------------------------------------------------------ inputs


def _normalised(M: np.ndarray) -> np.ndarray:
    """Matrices with negative interiors and the largest |entry| in [1, 2).

    Both changes are exact (a sign and a power of two) and neither changes the shape.
    """
    mx = np.abs(M).max(axis=(-2, -1))
    _, e = np.frexp(np.where((mx > 0) & np.isfinite(mx), mx, 1.0))
    factor = np.ldexp(np.where(M[..., 0, 0] < 0, -1.0, 1.0), 1 - e)
    return M * factor[..., None, None]


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
    return np.maximum(em - eM, (ea - eM) // 2)


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


def _float_input(A: Any, B: Any) -> tuple[np.ndarray, np.ndarray, tuple[int, ...], np.ndarray] | None:
    """Normalised float arrays, (n, n) for one pair or (N, n, n), the batch shape, and the space exponents.

    None for exact input (fractions, strings), which goes pair by pair. The pairs are seen at
    unit extent (:func:`unit_space`, exponents e per pair) and each matrix is scaled by a power of
    two to a largest entry in [1, 2): both exact, neither changes a shape's relation or scale.
    """
    a, b = np.asarray(A), np.asarray(B)
    if a.dtype.kind not in "fiu" or b.dtype.kind not in "fiu":
        return None
    a, b = a.astype(np.float64), b.astype(np.float64)
    shape = np.broadcast_shapes(a.shape[:-2], b.shape[:-2])
    if shape != ():
        n = a.shape[-1]
        a = np.ascontiguousarray(np.broadcast_to(a, (*shape, n, n))).reshape(-1, n, n)
        b = np.ascontiguousarray(np.broadcast_to(b, (*shape, n, n))).reshape(-1, n, n)
    a, b, e = unit_space(a, b)
    return _normalised(a), _normalised(b), shape, e


def _object_pairs(A: Any, B: Any, shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    a, b = np.asarray(A, dtype=object), np.asarray(B, dtype=object)
    n = a.shape[-1]
    return np.broadcast_to(a, (*shape, n, n)).reshape(-1, n, n), np.broadcast_to(b, (*shape, n, n)).reshape(-1, n, n)


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
    def k_mid(self) -> Any:
        return 0.5 * (self.k_lo + self.k_hi)

    def offset_error(self) -> Any:
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


def _classify_valid(A: np.ndarray, B: np.ndarray, valid: Any, stats: Stats) -> Any:
    """Certified codes where ``valid`` (UNDECIDED elsewhere): float filter, exact where it abstains."""
    if not is_array(valid):
        return int(classify(A, B, stats=stats)) if valid else int(Relation.UNDECIDED)
    got = np.full(valid.shape, Relation.UNDECIDED, dtype=np.int8)
    if valid.any():
        got[valid] = classify(A[valid], B[valid], stats=stats)
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


def _float_bracket(P: _Pair, codes: Any, rtol: float, stats: Stats) -> tuple[Any, Any, Any]:
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
        got = _classify_valid(_with_last(P.al, na), _with_last(P.bl, nb), valid, stats)
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


def contact_scale_batch(A: Any, B: Any, *, rtol: float = 1e-12, on_invalid: OnInvalid = "raise") -> ContactScaleBatch:
    """Certified float brackets of mu* for one float pair or stacks of pairs (module docstring).

    Args:
        A: a matrix or a stack (..., n, n); float input runs in floats (vectorised), exact input
            (fractions, strings) pair by pair through the exact one-pair computation.
        B: the same for B (the stacks broadcast).
        rtol: relative width asked of each bracket (hi - lo <= rtol * hi); float64 reaches about
            1e-14, tighter requests go to the exact path. 1e-9 and above stay in floats for
            nearly every pair; near 1e-12 the scaled pairs are a hair from touching and the float
            filter leaves some to exact classification.

        on_invalid: "raise" (default) for the first invalid pair, or "mark" it (relation
            INVALID, NaN bracket, the reason in ``errors``) and answer the others.

    Returns:
        :class:`ContactScaleBatch` with float arrays of the batch shape (0-d for one pair).
        Every valid pair gets its certified bracket: one hard pair never costs the others theirs.

    Raises:
        ValueError: an invalid matrix (the message names the pair), or shapes that do not broadcast.

    Examples:
        >>> sphere = lambda x, r: [[1, 0, 0, -x], [0, 1, 0, 0], [0, 0, 1, 0], [-x, 0, 0, x * x - r * r]]
        >>> r = contact_scale_batch(np.array([sphere(0, 1)] * 2, float), np.array([sphere(3, 1), sphere(2, 1)], float))
        >>> bool(r.lo[0] <= 1.5 <= r.hi[0]), float(r.lo[1]), float(r.hi[1]), r.relation.tolist()
        (True, 1.0, 1.0, [0, 1])
    """
    check_rtol(rtol)
    res = classify_detailed(A, B, on_invalid=on_invalid)  # validates, names a bad pair
    codes_full = res.relation
    errors = dict(res.errors)
    stats = Stats()
    floats = _float_input(A, B)
    if floats is None:
        a_obj, b_obj = _object_pairs(A, B, codes_full.shape)
        N = a_obj.shape[0]
        mu_lo: Any = np.zeros(N)
        mu_hi: Any = np.full(N, np.inf)
        approx: Any = np.zeros(N)
        need = np.ones(N, bool)
    else:
        a, b, shape, _ = floats
        codes = codes_full.reshape(-1) if shape != () else int(codes_full)
        try:
            with np.errstate(all="ignore"):
                P = _pair(a, b)
                s_est = P.s_est
                mu_lo, mu_hi, found = _float_bracket(P, codes, rtol, stats)
        except _ARITHMETIC:  # one pair only: Python floats raise where arrays give inf/nan
            mu_lo, mu_hi, found, s_est = 0.0, math.inf, False, 0.0
        with np.errstate(all="ignore"):
            approx = np.sqrt(np.maximum(np.nan_to_num(np.asarray(s_est, dtype=np.float64)), 0.0)).reshape(-1)
        mu_lo = np.asarray(mu_lo, dtype=np.float64).reshape(-1)
        mu_hi = np.asarray(mu_hi, dtype=np.float64).reshape(-1)
        need = (codes_full.reshape(-1) != Relation.TANGENT) & ~np.asarray(found).reshape(-1)
        a_obj, b_obj = (a, b) if a.ndim == 3 else (a[None], b[None])
    codes = codes_full.reshape(-1)
    need &= codes >= 0
    for i in np.flatnonzero(need):
        try:  # one pair's trouble (never expected) stays that pair's: the others keep their answers
            cs = scale_from(ContactFunction(*centred_pair(a_obj[i].tolist(), b_obj[i].tolist())), Relation(int(codes[i])), max(rtol, 1e-15))
        except (ArithmeticError, RuntimeError, ValueError) as e:
            errors[int(i)] = f"contact scale: {e}"
            mu_lo[i], mu_hi[i], approx[i] = 0.0, math.inf, math.nan
            continue
        mu_lo[i], mu_hi[i], approx[i] = _float_down(cs.lo), _float_up(cs.hi), cs.approx
    sep, ovl, tan = codes == Relation.SEPARATE, codes == Relation.OVERLAP, codes == Relation.TANGENT
    mu_lo = np.where(sep, np.maximum(mu_lo, 1.0), np.where(tan, 1.0, mu_lo))
    mu_hi = np.where(ovl, np.minimum(mu_hi, 1.0), np.where(tan, 1.0, mu_hi))
    bad = codes < 0
    mu_lo, mu_hi = np.where(bad, np.nan, mu_lo), np.where(bad, np.nan, mu_hi)
    with np.errstate(invalid="ignore"):
        approx = np.where(bad, np.nan, np.clip(approx, mu_lo, mu_hi))
    shape = codes_full.shape
    return ContactScaleBatch(
        mu_lo.reshape(shape), mu_hi.reshape(shape), approx.reshape(shape), codes_full,
        int(need.sum()), stats.escalated, errors,
    )


def _float_down(q: Any) -> float:
    """The largest float <= the rational q."""
    f = to_float(q)
    return f if not math.isfinite(f) or fmpq(*f.as_integer_ratio()) <= q else math.nextafter(f, -math.inf)


def _float_up(q: Any) -> float:
    """The smallest float >= the rational q."""
    f = to_float(q)
    return f if not math.isfinite(f) or fmpq(*f.as_integer_ratio()) >= q else math.nextafter(f, math.inf)


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


def separating_plane_batch(A: Any, B: Any, *, on_invalid: OnInvalid = "raise") -> PlaneBatch:
    """Float separating planes of one float pair or stacks of pairs, each with a certified flag.

    Every pair certified SEPARATE gets a plane n.x = d (n of unit length) from the contact
    function, verified with certified float determinant signs as the binary rationals it holds;
    pairs the floats cannot verify (gaps near rounding) get the exact plane of
    :func:`core.witness.separating_plane` rounded to floats, flagged certified only if the rounded
    plane passes the same check. Pairs that are not separate: NaN plane, ``certified`` False.
    ``on_invalid="mark"``: invalid pairs are marked (relation INVALID, the reason in
    ``errors``) and the others answered.

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> p = separating_plane_batch(np.array([circle(0)] * 2, float), np.array([circle(3), circle(1)], float))
        >>> p.normal[0].tolist(), float(p.offset[0]), p.certified.tolist()
        ([1.0, 0.0], 1.5, [True, False])
    """
    res = classify_detailed(A, B, on_invalid=on_invalid)
    codes_full = res.relation
    errors = dict(res.errors)
    shape = codes_full.shape
    codes = codes_full.reshape(-1)
    floats = _float_input(A, B)
    if floats is None:
        a_obj, b_obj = _object_pairs(A, B, shape)
        dim = a_obj.shape[-1] - 1
        normal, offset, certified = np.full((codes.size, dim), np.nan), np.full(codes.size, np.nan), np.zeros(codes.size, bool)
        retry = codes == Relation.SEPARATE
        e = np.zeros(codes.size, np.int64)
    else:
        a, b, _, e = floats
        e = e.reshape(-1)
        a_obj, b_obj = (a, b) if a.ndim == 3 else (a[None], b[None])
        try:
            with np.errstate(all="ignore"):
                normal, offset, certified = _float_planes(_pair(a, b))  # one pair: Python floats
        except _ARITHMETIC:
            dim = a.shape[-1] - 1
            normal, offset, certified = np.full((1, dim), np.nan), np.full(1, np.nan), np.zeros(1, bool)
        sep = codes == Relation.SEPARATE
        certified = certified & sep
        retry = sep & ~certified
        normal = np.where(sep[:, None], normal, np.nan)
        offset = np.where(sep, offset, np.nan)
    if retry.any():
        _exact_planes(a_obj, b_obj, retry, normal, offset, certified, floats is not None, errors)
    # back from the unit-extent view: n.x' = d' is n.x = 2^-e d' (exact unless it leaves the range)
    with np.errstate(all="ignore"):
        world = np.ldexp(offset, -e)
        certified = certified & (np.ldexp(world, e) == offset) & np.isfinite(world)
    offset = world
    dim = normal.shape[-1]
    return PlaneBatch(normal.reshape(*shape, dim), offset.reshape(shape), certified.reshape(shape), codes_full, errors)


@dataclass
class FloatWitness:
    """The witnesses of one float pair from float arithmetic with proofs (see :func:`float_witness`)."""

    relation: Relation
    lo: float
    hi: float
    """Certified lo <= mu* <= hi (or 0 and inf when the floats could not bracket it)."""
    plane: tuple[np.ndarray, float] | None = None
    """Separate: a certified plane n.x = d (unit n, float values as the exact binary rationals
    they are: A in n.x < d, B in n.x > d); None if the floats could not certify one."""
    point: tuple[float, ...] | None = None
    """Overlap: a float point certified inside both (X^T A X < 0 and X^T B X < 0 exactly)."""


def float_witness(A: np.ndarray, B: np.ndarray, *, rtol: float = 1e-6) -> FloatWitness:
    """Contact-scale bracket, plane (separate) and interior point (overlap) of ONE float pair.

    They share one float preparation: the scene's drag path (a few tenths of a millisecond).

    Everything returned is certified; what the floats cannot certify is left out (``lo = 0``,
    ``hi = inf``, ``plane``/``point`` None), for the caller to ask the exact functions.

    Examples:
        >>> circle = lambda x: np.array([[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]], float)
        >>> w = float_witness(circle(0), circle(3))
        >>> str(w.relation), w.lo <= 1.5 <= w.hi, w.plane[0].tolist(), w.plane[1]
        ('separate', True, [1.0, 0.0], 1.5)
        >>> float_witness(circle(0), circle(1)).point
        (0.5, 0.0)
    """
    rel = Relation(classify(A, B))
    floats = _float_input(A, B)
    if floats is None or floats[2] != ():
        raise ValueError("float_witness takes one pair of float matrices")
    a, b, _, e0 = floats
    e = int(e0)  # the pair is seen at unit extent: x' = 2^e x
    out = FloatWitness(rel, 0.0, math.inf)
    if rel == Relation.TANGENT:
        out.lo = out.hi = 1.0
        return out
    try:
        P = _pair(a, b)
        lo, hi, found = _float_bracket(P, int(rel), rtol, Stats())
        if found:
            out.lo, out.hi = (max(lo, 1.0), hi) if rel == Relation.SEPARATE else (lo, min(hi, 1.0))
        if rel == Relation.SEPARATE:
            normal, offset, ok = _float_planes(P)
            d = math.ldexp(float(offset[0]), -e)
            if ok[0] and math.ldexp(d, e) == float(offset[0]):
                out.plane = (normal[0], d)
        else:
            x, ok = _float_point(P)
            xw = tuple(math.ldexp(float(v), -e) for v in x)
            if ok and all(math.ldexp(w, e) == float(v) for w, v in zip(xw, x, strict=True)):
                out.point = xw
    except _ARITHMETIC:
        pass
    return out


def _exact_planes(
    a: np.ndarray,
    b: np.ndarray,
    which: np.ndarray,
    normal: np.ndarray,
    offset: np.ndarray,
    certified: np.ndarray,
    float_input: bool,
    errors: dict[int, str],
) -> None:
    """Exact planes for the pairs ``which``, rounded to floats (in place) and re-checked.

    A pair whose exact plane fails (never expected) keeps a NaN plane and its reason in
    ``errors``: the other pairs keep theirs.
    """
    from ..shapes.numbers import to_fmpq

    idx = []
    for i in np.flatnonzero(which):
        try:
            plane = plane_from(ContactFunction(*centred_pair(a[i].tolist(), b[i].tolist())))
        except (ArithmeticError, RuntimeError, ValueError) as e:
            errors[int(i)] = f"separating plane: {e}"
            continue
        big = max(abs(v) for v in plane.normal)  # exact scaling: the largest component is +-1
        n = np.array([to_float(v / big) for v in plane.normal])
        norm = float(np.linalg.norm(n))
        normal[i] = n / norm
        offset[i] = to_float(plane.offset / big) / norm
        idx.append(int(i))
    if not idx:
        return
    fa = np.array([[[to_float(to_fmpq(v)) for v in row] for row in a[i]] for i in idx])
    fb = np.array([[[to_float(to_fmpq(v)) for v in row] for row in b[i]] for i in idx])
    exact_floats = float_input or all(_is_float_exact(a[i]) and _is_float_exact(b[i]) for i in idx)
    if exact_floats:  # the float matrices are the input itself: their check is the pair's
        al, bl = lists(_normalised(fa)), lists(_normalised(fb))
        normals = [np.ascontiguousarray(normal[idx, i]) for i in range(normal.shape[-1])]
        with np.errstate(all="ignore"):
            certified[idx] = _plane_certified(_centre(al), al, normals, offset[idx], -1) & _plane_certified(
                _centre(bl), bl, normals, offset[idx], 1
            )


def _is_float_exact(M: Any) -> bool:
    """True when every entry of M is a binary64 value (so its float matrix is M itself)."""
    from ..shapes.numbers import to_fmpq

    for row in M:
        for v in row:
            q = to_fmpq(v)
            f = to_float(q)
            if not math.isfinite(f) or fmpq(*f.as_integer_ratio()) != q:
                return False
    return True
