"""Vectorised witnesses for stacks of float pairs: contact-scale brackets and separating planes.

Contact scale (:func:`contact_scale_batch`): a float estimate s of s* = mu*^2 (Newton on the
contact function, all pairs at once) is bracketed by two certified classifications of the pairs
*scaled* about their centres. Scaling a shape to s means adding k (1 - s) to the last entry of
its matrix (:mod:`core.witness.centred`); the float written there is an exact binary rational,
and the scale s' it really stands for is enclosed from certified float determinants
(k = -det A / det M, :mod:`core.witness.floatdet`) with directed rounding (one ``nextafter`` per
correctly rounded operation). Scaled shapes are nested in s, so

* scaled pair certified SEPARATE at scales (s_A', s_B')  =>  s* > min(s_A', s_B'),
* scaled pair certified TANGENT or OVERLAP              =>  s* <= max(s_A', s_B').

``classify`` certifies those labels (float filter; ``method="float"`` so nothing escalates).
Pairs the floats cannot bracket within ``rtol`` (near s* = 0, or a scaled pair the filter leaves
undecided) get the exact one-pair computation; tangent pairs are exactly mu* = 1.

Planes (:func:`separating_plane_batch`): the candidate normal y(lambda*) of the contact function,
the offset halfway between the two support values, and a certificate from determinant signs:
the plane pi = (n, -d) misses the ellipsoid A iff pi^T adj(A) pi > 0, i.e. the bordered
determinant det [[A, pi], [pi^T, 0]] < 0, and A lies on the side n.x < d iff det(A with its last
column replaced by pi) < 0 (Cramer: that is (A^-1 pi)_last det A, and (A^-1 pi)_last = (d - n.c)/k).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from flint import fmpq

from ..classify import Stats, classify
from ..relation import Relation
from .floatdet import certified_sign, det_with_bound
from .floats import centred_floats, maximise, stack_lists
from .numbers import to_float

__all__ = ["ContactScaleBatch", "PlaneBatch", "contact_scale_batch", "separating_plane_batch"]

_INF = np.inf
_SMALLEST_S = 1e-8
"""Below this estimate of s* the float scaled matrices lose the scale: exact path instead."""


def _up(x: np.ndarray) -> np.ndarray:
    return np.nextafter(x, _INF)


def _down(x: np.ndarray) -> np.ndarray:
    return np.nextafter(x, -_INF)


@dataclass
class ContactScaleBatch:
    """Certified float brackets ``lo <= mu* <= hi`` of a stack of pairs (batch shape)."""

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


@dataclass
class PlaneBatch:
    """Separating planes n.x = d of a stack of pairs: A in n.x < d, B in n.x > d where certified."""

    normal: np.ndarray
    """(..., dim) float normals (unit length up to rounding; NaN where the pair is not separate)."""
    offset: np.ndarray
    """(...) float offsets d."""
    certified: np.ndarray
    """(...) bool: the float plane, as the exact binary rationals it holds, was verified to
    separate the pair strictly (certified determinant signs)."""
    relation: np.ndarray
    """int8 Relation codes of the pairs."""


def _stacks(A: Any, B: Any) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    """Broadcast float stacks (N, n, n) and the batch shape; ValueError for non-float input."""
    a = np.asarray(A)
    b = np.asarray(B)
    if a.dtype.kind not in "fiu" or b.dtype.kind not in "fiu":
        raise TypeError("not float stacks")
    a = a.astype(np.float64, copy=False)
    b = b.astype(np.float64, copy=False)
    if a.ndim < 2 or b.ndim < 2:
        raise ValueError(f"A and B must be matrices or stacks of them, got shapes {a.shape} and {b.shape}")
    n = a.shape[-1]
    if a.shape[-2:] != (n, n) or b.shape[-2:] != (n, n) or n not in (3, 4):
        raise ValueError(f"A and B must be stacks of 3x3 or 4x4 matrices of one size, got {a.shape} and {b.shape}")
    shape = np.broadcast_shapes(a.shape[:-2], b.shape[:-2])
    a = np.ascontiguousarray(np.broadcast_to(a, (*shape, n, n))).reshape(-1, n, n)
    b = np.ascontiguousarray(np.broadcast_to(b, (*shape, n, n))).reshape(-1, n, n)
    return _normalised(a), _normalised(b), shape


def _normalised(M: np.ndarray) -> np.ndarray:
    """Interior negative (signs flipped where needed) and the largest |entry| in [1, 2): both exact
    (a power of two and a sign), and neither changes the shape.
    """
    mx = np.abs(M).max(axis=(1, 2))
    _, e = np.frexp(np.where((mx > 0) & np.isfinite(mx), mx, 1.0))
    factor = np.ldexp(np.where(M[:, 0, 0] < 0, -1.0, 1.0), 1 - e)
    return M * factor[:, None, None]


_U = 2.0**-53
_SPLIT = 134217729.0  # 2^27 + 1 (Veltkamp)


def _two_sum(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """S + e = a + b exactly (Knuth)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _two_product(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """P + e = a * b exactly (Dekker, Veltkamp splitting; no overflow or underflow)."""
    p = a * b
    ca, cb = _SPLIT * a, _SPLIT * b
    ah = ca - (ca - a)
    al = a - ah
    bh = cb - (cb - b)
    bl = b - bh
    return p, al * bl - (((p - ah * bh) - al * bh) - ah * bl)


def _dot2(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Compensated dot products over the last axis and certified error bounds.

    Ogita, Rump, Oishi, "Accurate sum and dot product" (2005), Dot2:
    |res - x.y| <= u |x.y| + gamma_n^2 |x|.|y| (no underflow). The bound returned doubles both
    terms, which also covers |x.y| <= |res| + bound and the rounding of the bound itself, and adds
    an absolute floor for products below the normal range.
    """
    n = x.shape[-1]
    p, s = _two_product(x[..., 0], y[..., 0])
    for i in range(1, n):
        h, r = _two_product(x[..., i], y[..., i])
        p, q = _two_sum(p, h)
        s = s + (q + r)
    res = p + s
    g = n * _U / (1 - n * _U)
    absdot = np.einsum("...i,...i->...", np.abs(x), np.abs(y))
    return res, 4.0 * _U * np.abs(res) + 4.0 * g * g * absdot + 2.0**-1000


def _k_enclosure(M: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Certified [k_lo, k_hi] of k = -det(M) / det(quadratic block), NaN where not certified.

    With V = (v, 1) for any v (here the float centre c), X^T M X at V is F(v) = (v - c)^T Q (v - c) - k,
    so k = -F(v) + r^T Q^-1 r with r = Q v + m (Q the quadratic block). F(v) = v.r + (m.v + a)
    is evaluated from M V by compensated dot products (the cancellation between c^T Q c and a
    costs nothing), and 0 <= r^T Q^-1 r <= |r|^2 / lambda_min(Q), lambda_min >= det Q / tr(Q)^(d-1).
    """
    d = M.shape[-1] - 1
    V = np.concatenate([c, np.ones((c.shape[0], 1))], axis=-1)
    with np.errstate(all="ignore"):
        w, wb = _dot2(M, V[:, None, :])
        r, rb = w[:, :d], wb[:, :d]
        F = np.einsum("ni,ni->n", c, r) + w[:, d]
        Fb = (np.einsum("ni,ni->n", np.abs(c), rb) + wb[:, d]
              + 4.0 * (d + 2) * _U * (np.einsum("ni,ni->n", np.abs(c), np.abs(r)) + np.abs(w[:, d]))) * (1 + 2.0**-40)
        det, detb, e = det_with_bound(M[:, :d, :d])
        det_lo = np.ldexp(_down(det - detb), e)
        trace = np.trace(M[:, :d, :d], axis1=1, axis2=2)
        lam_lo = _down(det_lo / _up(trace ** (d - 1) * (1 + 2.0**-40)))
        rr = np.einsum("ni,ni->n", np.abs(r) + rb, np.abs(r) + rb)
        extra = 2.0 * rr / lam_lo
        k_lo = _down(-F - Fb)
        k_hi = _up(-F + Fb + extra)
    ok = np.isfinite(k_lo) & np.isfinite(k_hi) & (k_lo > 0) & (lam_lo > 0) & np.isfinite(V).all(axis=-1)
    ok &= (np.abs(M).max(axis=(1, 2)) < 2.0**500) & (np.abs(V).max(axis=-1) < 2.0**200)
    return np.where(ok, k_lo, np.nan), np.where(ok, k_hi, np.nan)


def _scaled(M: np.ndarray, k_est: np.ndarray, k_lo: np.ndarray, k_hi: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """M scaled about its centre to about s; returns (matrix, s_lo, s_hi) enclosing its true scale."""
    d = M.shape[-1] - 1
    a = M[:, d, d]
    with np.errstate(all="ignore"):
        new = a + k_est * (1.0 - s)
        diff, err = _two_sum(new, -a)  # alpha = new - a = diff + err exactly
        alpha = diff + err
        al_lo, al_hi = _down(alpha), _up(alpha)
        q = [al_lo / k_lo, al_lo / k_hi, al_hi / k_lo, al_hi / k_hi]
        q_lo = _down(np.minimum.reduce(q))
        q_hi = _up(np.maximum.reduce(q))
        s_lo = _down(1.0 - q_hi)
        s_hi = _up(1.0 - q_lo)
    out = M.copy()
    out[:, d, d] = new
    return out, s_lo, s_hi


def _estimate(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """(s estimate, y, (c_A, S_A, k_A), (c_B, S_B, k_B)) floats for normalised stacks (N, n, n)."""
    with np.errstate(all="ignore"):
        ca, SA, ka = centred_floats(a)
        cb, SB, kb = centred_floats(b)
        SAl, delta = stack_lists(SA, cb - ca)
        SBl, _ = stack_lists(SB, cb - ca)
        _, s, y = maximise(SAl, SBl, delta)
    return np.asarray(s, dtype=np.float64), np.stack(y, axis=-1), (ca, SA, ka), (cb, SB, kb)


def contact_scale_batch(A: Any, B: Any, *, rtol: float = 1e-12) -> ContactScaleBatch:
    """Certified float brackets of mu* for stacks of pairs (see the module docstring).

    Args:
        A, B: stacks (..., n, n) that broadcast; float input runs vectorised, exact input
            (fractions, strings) pair by pair through :func:`core.witness.contact_scale`.
        rtol: relative width asked of each bracket (floats: about ``rtol``; at least about
            1e-15 is reachable in float64, tighter requests go to the exact path).

    Returns:
        :class:`ContactScaleBatch` with float arrays of the batch shape.

    Raises:
        ValueError: an invalid matrix (the message names the pair), or shapes that do not broadcast.

    Examples:
        >>> sphere = lambda x, r: [[1, 0, 0, -x], [0, 1, 0, 0], [0, 0, 1, 0], [-x, 0, 0, x * x - r * r]]
        >>> r = contact_scale_batch(np.array([sphere(0, 1)] * 2, float), np.array([sphere(3, 1), sphere(2, 1)], float))
        >>> bool(r.lo[0] <= 1.5 <= r.hi[0]), float(r.lo[1]), float(r.hi[1]), r.relation.tolist()
        (True, 1.0, 1.0, [0, 1])
    """
    codes_full = classify(A, B)
    codes_full = np.asarray(codes_full, dtype=np.int8)
    try:
        a, b, shape = _stacks(A, B)
    except TypeError:
        return _exact_batch(A, B, rtol, codes_full)
    N = a.shape[0]
    codes = codes_full.reshape(-1)
    s_est, _, (ca, _, ka), (cb, _, kb) = _estimate(a, b)
    lo_s = np.zeros(N)
    hi_s = np.full(N, _INF)
    found_lo = np.zeros(N, bool)
    found_hi = np.zeros(N, bool)
    todo = (codes != Relation.TANGENT) & np.isfinite(s_est) & (s_est > _SMALLEST_S)
    eps = 0.45 * rtol  # bracket width about 2 eps mu*, below rtol mu*
    stats = Stats()
    if eps >= 2.0**-48 and todo.any():
        idx = np.flatnonzero(todo)
        kal, kah = _k_enclosure(a[idx], ca[idx])
        kbl, kbh = _k_enclosure(b[idx], cb[idx])
        ok = np.isfinite(kal) & np.isfinite(kbl)
        idx, kal, kah, kbl, kbh = idx[ok], kal[ok], kah[ok], kbl[ok], kbh[ok]
        s = s_est[idx]
        for sign in (-1, 1):
            goal = s * (1.0 + sign * eps) ** 2
            As, sal, sah = _scaled(a[idx], ka[idx], kal, kah, goal)
            Bs, sbl, sbh = _scaled(b[idx], kb[idx], kbl, kbh, goal)
            valid = (sal > 0) & (sbl > 0) & np.isfinite(As).all(axis=(1, 2)) & np.isfinite(Bs).all(axis=(1, 2))
            got = np.full(idx.size, Relation.UNDECIDED, dtype=np.int8)
            if valid.any():  # float filter, exact rationals where it abstains (valid: s > 0)
                got[valid] = classify(As[valid], Bs[valid], stats=stats)
            if sign < 0:
                hit = got == Relation.SEPARATE
                lo_s[idx[hit]] = np.minimum(sal, sbl)[hit]
                found_lo[idx[hit]] = True
            else:
                hit = (got == Relation.TANGENT) | (got == Relation.OVERLAP)
                hi_s[idx[hit]] = np.maximum(sah, sbh)[hit]
                found_hi[idx[hit]] = True
    with np.errstate(invalid="ignore"):
        mu_lo = np.where(lo_s > 0, _down(np.sqrt(np.maximum(lo_s, 0.0))), 0.0)
        mu_lo = np.maximum(mu_lo, 0.0)
        mu_hi = _up(np.sqrt(hi_s))
    # one pair at a time where the floats could not bracket (rare: the tests count them)
    with np.errstate(invalid="ignore"):
        wide = ~(mu_hi - mu_lo <= rtol * mu_hi)  # e.g. deep overlaps: the floats lose s* ~ 0
    need = (codes != Relation.TANGENT) & (~(found_lo & found_hi) | wide)
    from .scale import _contact_scale_pair

    for i in np.flatnonzero(need):
        cs = _contact_scale_pair(a[i], b[i], max(rtol, 1e-15))
        mu_lo[i], mu_hi[i] = _float_down(cs.lo), _float_up(cs.hi)
    # the relation at scale 1 is certified too: it puts 1 on the right side of the bracket
    sep, ovl, tan = codes == Relation.SEPARATE, codes == Relation.OVERLAP, codes == Relation.TANGENT
    mu_lo = np.where(sep, np.maximum(mu_lo, 1.0), np.where(tan, 1.0, mu_lo))
    mu_hi = np.where(ovl, np.minimum(mu_hi, 1.0), np.where(tan, 1.0, mu_hi))
    with np.errstate(invalid="ignore"):
        approx = np.clip(np.sqrt(np.maximum(np.nan_to_num(s_est), 0.0)), mu_lo, mu_hi)
    return ContactScaleBatch(
        mu_lo.reshape(shape), mu_hi.reshape(shape), approx.reshape(shape), codes.reshape(shape),
        int(need.sum()), stats.escalated,
    )


def _float_down(q: Any) -> float:
    """The largest float <= the rational q."""
    f = to_float(q)
    return f if not np.isfinite(f) or fmpq(*f.as_integer_ratio()) <= q else float(np.nextafter(f, -_INF))


def _float_up(q: Any) -> float:
    """The smallest float >= the rational q."""
    f = to_float(q)
    return f if not np.isfinite(f) or fmpq(*f.as_integer_ratio()) >= q else float(np.nextafter(f, _INF))


def _exact_batch(A: Any, B: Any, rtol: float, codes: np.ndarray) -> ContactScaleBatch:
    """Pair by pair for exact (non-float) stacks."""
    from .scale import _contact_scale_pair

    a = np.asarray(A, dtype=object)
    b = np.asarray(B, dtype=object)
    shape = codes.shape
    n = a.shape[-1]
    a = np.broadcast_to(a, (*shape, n, n)).reshape(-1, n, n)
    b = np.broadcast_to(b, (*shape, n, n)).reshape(-1, n, n)
    lo, hi, ap = (np.empty(a.shape[0]) for _ in range(3))
    for i in range(a.shape[0]):
        cs = _contact_scale_pair(a[i].tolist(), b[i].tolist(), max(rtol, 1e-15))
        lo[i], hi[i] = _float_down(cs.lo), _float_up(cs.hi)
        ap[i] = cs.approx
    return ContactScaleBatch(lo.reshape(shape), hi.reshape(shape), ap.reshape(shape), codes, a.shape[0])


def _plane_certified(M: np.ndarray, pi: np.ndarray, side: int) -> np.ndarray:
    """Certified: plane pi misses ellipsoid M (normalised) and M lies on the ``side`` of it
    (-1: n.x < d, +1: n.x > d).
    """
    N, n, _ = M.shape
    bordered = np.zeros((N, n + 1, n + 1))
    bordered[:, :n, :n] = M
    bordered[:, :n, n] = pi
    bordered[:, n, :n] = pi
    replaced = M.copy()
    replaced[:, :, n - 1] = pi
    return (certified_sign(bordered) < 0) & (certified_sign(replaced) == side)


def separating_plane_batch(A: Any, B: Any) -> PlaneBatch:
    """Float separating planes of stacks of pairs, each with a certified flag.

    For every pair certified SEPARATE a plane n.x = d (n of unit length) is computed from the
    contact function and verified with certified float determinant signs as the binary
    rationals it holds; pairs the floats cannot verify (gaps near rounding) get the exact plane
    of :func:`core.witness.separating_plane` rounded to floats, flagged certified only if the
    rounded plane passes the same check. Not separate: NaN plane, ``certified`` False.

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> p = separating_plane_batch(np.array([circle(0)] * 2, float), np.array([circle(3), circle(1)], float))
        >>> p.normal[0].tolist(), float(p.offset[0]), p.certified.tolist()
        ([1.0, 0.0], 1.5, [True, False])
    """
    codes_full = np.asarray(classify(A, B), dtype=np.int8)
    try:
        a, b, shape = _stacks(A, B)
    except TypeError:
        a = np.asarray(A, dtype=object)
        b = np.asarray(B, dtype=object)
        n = a.shape[-1]
        shape = codes_full.shape
        a = np.broadcast_to(a, (*shape, n, n)).reshape(-1, n, n)
        b = np.broadcast_to(b, (*shape, n, n)).reshape(-1, n, n)
        return _planes_exact(a, b, codes_full.reshape(-1), shape, np.ones(a.shape[0], bool))
    codes = codes_full.reshape(-1)
    N, n, _ = a.shape
    d = n - 1
    normal = np.full((N, d), np.nan)
    offset = np.full(N, np.nan)
    certified = np.zeros(N, bool)
    sep = np.flatnonzero(codes == Relation.SEPARATE)
    if sep.size:
        aa, bb = a[sep], b[sep]
        with np.errstate(all="ignore"):
            _, y, (ca, SA, _), (cb, SB, _) = _estimate(aa, bb)
            nrm = y / np.linalg.norm(y, axis=-1, keepdims=True)
            ha = np.einsum("ni,ni->n", nrm, ca) + np.sqrt(np.einsum("ni,nij,nj->n", nrm, SA, nrm))
            hb = np.einsum("ni,ni->n", nrm, cb) - np.sqrt(np.einsum("ni,nij,nj->n", nrm, SB, nrm))
            off = 0.5 * (ha + hb)
        pi = np.concatenate([nrm, -off[:, None]], axis=-1)
        fin = np.isfinite(pi).all(axis=-1)
        ok = np.zeros(sep.size, bool)
        if fin.any():
            ok[fin] = _plane_certified(aa[fin], pi[fin], -1) & _plane_certified(bb[fin], pi[fin], 1)
        normal[sep], offset[sep], certified[sep] = nrm, off, ok
    retry = np.zeros(N, bool)
    retry[sep] = ~certified[sep]
    if retry.any():
        exact = _planes_exact(a, b, codes, (N,), retry)
        normal[retry] = exact.normal[retry]
        offset[retry] = exact.offset[retry]
        certified[retry] = exact.certified[retry]
    return PlaneBatch(normal.reshape(*shape, d), offset.reshape(shape), certified.reshape(shape), codes.reshape(shape))


def _planes_exact(a: np.ndarray, b: np.ndarray, codes: np.ndarray, shape: tuple[int, ...], which: np.ndarray) -> PlaneBatch:
    """Exact planes for the pairs ``which`` that are separate, rounded to floats and re-checked."""
    from ..rationals import to_fmpq
    from .plane import separating_plane

    N, n = a.shape[0], a.shape[-1]
    d = n - 1
    normal = np.full((N, d), np.nan)
    offset = np.full(N, np.nan)
    certified = np.zeros(N, bool)
    for i in np.flatnonzero(which & (codes == Relation.SEPARATE)):
        plane = separating_plane(a[i].tolist(), b[i].tolist())
        big = max(abs(v) for v in plane.normal)  # exact scaling: the largest component is +-1
        normal[i] = [to_float(v / big) for v in plane.normal]
        offset[i] = to_float(plane.offset / big)
    idx = np.flatnonzero(np.isfinite(offset))
    if idx.size:
        fa = np.array([[[to_float(to_fmpq(v)) for v in row] for row in a[i]] for i in idx])
        fb = np.array([[[to_float(to_fmpq(v)) for v in row] for row in b[i]] for i in idx])
        fa, fb = _normalised(fa), _normalised(fb)
        exact_floats = all(_is_float_exact(a[i]) and _is_float_exact(b[i]) for i in idx)
        pi = np.concatenate([normal[idx], -offset[idx][:, None]], axis=-1)
        if exact_floats:
            certified[idx] = _plane_certified(fa, pi, -1) & _plane_certified(fb, pi, 1)
    return PlaneBatch(normal.reshape(*shape, d), offset.reshape(shape), certified.reshape(shape), codes.reshape(shape))


def _is_float_exact(M: Any) -> bool:
    """True when every entry of M is a binary64 value (so float(M) is M itself)."""
    from ..rationals import to_fmpq

    for row in M:
        for v in row:
            if isinstance(v, float | np.floating):
                continue
            q = to_fmpq(v)
            if to_fmpq(float(q)) != q:
                return False
    return True
