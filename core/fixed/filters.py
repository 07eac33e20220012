"""The certified float64 filter: the paper's trees on float values whose signs are proven (Shewchuk/CGAL).

For every pair it computes a_0..a_n of P(T) = det(T A + B) straight from the matrix entries (no
inversion), the leading principal minors that certify both matrices are ellipses/ellipsoids, and,
only for the pairs whose Descartes count Var(a_n..a_0) is 2, the sign-equivalent ``hs0`` of s0.
Each value comes with a proven error bound (:mod:`core.fixed.errorbound`, kernels generated into
:mod:`core.fixed._kernels` and ``core/fixed/_kernels.c``); a sign is used only when ``|value| > bound``, and
the decision is looked up in :data:`core.formulae.decision.TABLE3` / ``TABLE4`` (the paper's tree,
tabulated from :func:`core.formulae.decision.decide_signs`). Where s0 cannot be certified (it vanishes
identically for spheres and translated or homothetic copies) two certificates that do not need
it are tried: a T* > 0 with P(T*) > 0 (separate), and a point inside both shapes (overlap).
Otherwise the pair is UNDECIDED and :func:`core.fixed.classify.classify` sends it to exact arithmetic.

Two producers of the same rule ids: the compiled C kernels (:mod:`core.fixed.compiled`; fast, on every
core) and the vectorised numpy code below (used when no C compiler is available or while the
library builds, and by :func:`explain_float`; the tests check that both agree pair by pair).
A float filter never certifies ``s0 = 0``: TANGENT always comes from the exact path.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from flint import fmpq

from ..formulae.decision import (
    NEED_S0,
    RULE_LIST,
    RULE_RELATION,
    TABLE3,
    TABLE4,
    rule_by_key,
    sign_variations,
)
from ..formulae.subresultants import hat_scale
from ..relation import Relation
from ..shapes.numbers import format_rational, to_fmpq
from ..shapes.quadrics import SYMMETRY_TOLERANCE
from . import _kernels as K
from . import compiled
from .errorbound import CERT_T_MAX, CERT_T_MIN, LEAF_MAX, NO_SCALE_MIN, RADIUS_FACTOR, TRANSLATE_MAX
from .explanation import Explanation, Quantity

__all__ = [
    "classify_float",
    "rules_float",
    "rules_numpy",
    "classify_float_numpy",
    "classify_translated",
    "prepared",
    "centres",
    "explain_float",
    "HAT_DEGREE_WEIGHT",
]

_CHUNK = 4096
"""Pairs per numpy chunk: keeps the kernel's temporaries in cache."""

_TABLE = {3: TABLE3, 4: TABLE4}
_RULE_SEP = rule_by_key("sep-witness").id
_RULE_POINT = rule_by_key("common-point").id

_PENCIL = {
    3: (K.pencil3, K.PENCIL3_OUTPUTS, K.PENCIL3_CONSTANTS, K.PENCIL3_FLOOR),
    4: (K.pencil4, K.PENCIL4_OUTPUTS, K.PENCIL4_CONSTANTS, K.PENCIL4_FLOOR),
}
_PENCIL_ROUNDED = {
    3: (K.PENCIL3_CONSTANTS_ROUNDED, K.PENCIL3_FLOOR_ROUNDED),
    4: (K.PENCIL4_CONSTANTS_ROUNDED, K.PENCIL4_FLOOR_ROUNDED),
}
_HAT = {
    (3, "s0"): (K.hat_s0_3, K.HAT_S0_3_FLOOR),
    (3, "s1"): (K.hat_s1_3, K.HAT_S1_3_FLOOR),
    (3, "s10"): (K.hat_s10_3, K.HAT_S10_3_FLOOR),
    (4, "s0"): (K.hat_s0_4, K.HAT_S0_4_FLOOR),
    (4, "s1"): (K.hat_s1_4, K.HAT_S1_4_FLOOR),
    (4, "s10"): (K.hat_s10_4, K.HAT_S10_4_FLOOR),
}
_TRANSLATE = {3: (K.translate3, K.TRANSLATE3_OUTPUTS, K.TRANSLATE3_FLOOR), 4: (K.translate4, K.TRANSLATE4_OUTPUTS, K.TRANSLATE4_FLOOR)}
_PENCIL_RADIUS = {
    3: (K.pencil_radius3, K.PENCIL_RADIUS3_OUTPUTS, K.PENCIL_RADIUS3_FLOOR),
    4: (K.pencil_radius4, K.PENCIL_RADIUS4_OUTPUTS, K.PENCIL_RADIUS4_FLOOR),
}
_PENCIL_AT = {3: (K.pencil_at3, K.PENCIL_AT3_FLOOR), 4: (K.pencil_at4, K.PENCIL_AT4_FLOOR)}
_FORM = {3: (K.form3, K.FORM3_FLOOR), 4: (K.form4, K.FORM4_FLOOR)}

HAT_DEGREE_WEIGHT: dict[tuple[int, str], tuple[int, int]] = {
    (3, "s0"): (4, 6), (3, "s1"): (2, 4), (3, "s10"): (2, 3),
    (4, "s0"): (6, 12), (4, "s1"): (4, 10), (4, "s10"): (4, 9),
}
"""(degree, weight) of each hat form: hs(mu * lambda^i a_i) = mu^deg lambda^weight hs(a)."""

_TOL2 = float(SYMMETRY_TOLERANCE) ** 2
_LEAF_ROUNDING = 2.0**-52  # radius of a rounded half sum, relative: 2^-52 >= u / (1 - u)
_LEAF_UNDERFLOW = 1.0e-323  # >= 2^-1073: a scaled entry rounded in the subnormal range
_TINY_RADIUS = 2.0**-1073
"""Covers an exact power-of-two rescaling that lands in the subnormal range (error <= 2^-1075)."""


# -------------------------------------------------------------------------------------------
# stage 1: prepared matrices, the pencil with bounds, the tree


def _prepare(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vectorised ``prepare{n}`` of core/fixed/_kernels.c (the same decisions and operations).

    Returns (scaled symmetric matrices, exponents e with scaled = 2^e * sign * S, status) where
    status is 1 (exactly symmetric), 2 (symmetric up to rounding: entries are rounded half sums)
    or 0 (abstain: NaN/inf, M_00 = 0, or asymmetry not clearly within the tolerance).
    """
    with np.errstate(all="ignore"):
        MT = np.swapaxes(M, 1, 2)
        finite = np.isfinite(M).all(axis=(1, 2))
        Mz = np.where(np.isfinite(M), M, 0.0)
        q00 = Mz[:, 0, 0]
        mx = np.abs(Mz).max(axis=(1, 2))
        _, e = np.frexp(np.where(mx > 0, mx, 1.0))
        keep = (mx >= float(NO_SCALE_MIN)) & (mx <= float(LEAF_MAX))
        e = np.where(keep, 1, e)  # no rescaling when already in range
        # exact power-of-two scaling, entry by entry (2^(1-e) itself may be no float)
        X = np.ldexp(Mz * np.where(q00 < 0, -1.0, 1.0)[:, None, None], (1 - e)[:, None, None])
        XT = np.swapaxes(X, 1, 2)
        sym = (Mz == np.swapaxes(Mz, 1, 2)).all(axis=(1, 2))
        m = np.maximum(np.abs(X).max(axis=2), np.abs(X).max(axis=1))  # row/column scales
        d = np.abs(X - XT)
        r = _TOL2 * m[:, :, None] * m[:, None, :]
        within = (MT == M) | ((r >= 2.0**-1000) & (d * d * (1 + 2.0**-48) <= r * (1 - 2.0**-48)))
        near = within.all(axis=(1, 2))
        S = np.where(sym[:, None, None], X, X * 0.5 + XT * 0.5)
    status = np.where(finite & (q00 != 0), np.where(sym, 1, np.where(near, 2, 0)), 0).astype(np.int8)
    return S, 1 - e, status


def prepared(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Matrices as the filter reads them, with the radius of each entry.

    Args:
        M: float64 stack (N, n, n).

    Returns:
        ``(S, status, radius)``: S = 2^e * sign * (symmetric part of M), scaled by an exact
        power of two into the filter's range and flipped to a negative interior; status 1
        (exactly symmetric), 2 (symmetric up to rounding: S holds rounded half sums, each within
        ``radius`` of the exact one) or 0 (the filter abstains: NaN/inf, M_00 = 0, asymmetry
        not clearly within the tolerance); radius 0 where S is exact. S describes the same
        shape as M (a positive multiple of its quadratic form).
    """
    S, _, status, radius = _prepared(M)
    return S, status, radius


def _prepared(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_prepare` plus the radius of each entry: (S, e, status, radius)."""
    S, e, status = _prepare(M)
    radius = np.where((status == 2)[:, None, None], np.abs(S) * _LEAF_ROUNDING + _LEAF_UNDERFLOW, 0.0)
    return S, e, status, radius


class _Prepared:
    """Pairs flipped to negative interiors, symmetrised and scaled by 2^-ea, 2^-eb (exact)."""

    def __init__(self, a: np.ndarray, b: np.ndarray) -> None:
        self.a, self.ea, sa, self.radius_a = _prepared(a)
        self.b, self.eb, sb, self.radius_b = _prepared(b)
        """Scaled matrix = 2^ea * (symmetric part of A) after the sign flip; radius of each
        prepared entry (0 when exact)."""
        self.ok = (sa > 0) & (sb > 0)
        self.rounded = (sa == 2) | (sb == 2)
        """Pairs whose entries are rounded half sums (leaf_K = 1 constants apply)."""


def _run_pencil(a: np.ndarray, b: np.ndarray, rounded: np.ndarray | None = None) -> dict[str, tuple[Any, Any]]:
    """Name -> (value, certified error bound) of every pencil output, for arrays (N, n, n).

    ``rounded`` marks the pairs whose entries are rounded values (their own constants).
    """
    n = a.shape[-1]
    fn, outputs, consts, floor = _PENCIL[n]
    consts_r, floor_r = _PENCIL_ROUNDED[n]
    res = dict(zip(outputs, fn(np.moveaxis(a, 0, -1), np.moveaxis(b, 0, -1)), strict=True))
    out = {}
    for name, c, cr in zip(outputs, consts, consts_r, strict=True):
        if name.endswith("_M"):
            continue
        if rounded is None or not rounded.any():
            bound = c * res[name + "_M"] + floor
        else:
            bound = np.where(rounded, cr * res[name + "_M"] + floor_r, c * res[name + "_M"] + floor)
        out[name] = (res[name], bound)
    return out


def _run_hat(n: int, which: str, vals: list[Any], radii: list[Any]) -> tuple[Any, Any]:
    """(value, certified error bound) of hs_which from a_i values and their error bounds."""
    fn, floor = _HAT[(n, which)]
    v, r = fn(vals, radii)
    return v, r * RADIUS_FACTOR + floor


def _digit(v: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """Table digit of a certified sign: 0 for -1, 2 for +1, 3 uncertain (never 'zero')."""
    return np.where(v > bound, 2, np.where(v < -bound, 0, 3)).astype(np.int64)


def _tree(out: dict[str, tuple[Any, Any]], ok: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Rule ids (-1 undecided) from pencil outputs with bounds, and the mask of valid pairs.

    Valid: validity minors positive, a_n and a_0 negative, all certified.
    """
    ok = ok.copy()
    for key in [k for k in out if k.startswith("d")]:
        v, bd = out[key]
        ok &= v > bd  # quadratic block positive definite, certified (Sylvester)
    for key in (f"c{n}", "c0"):
        v, bd = out[key]
        ok &= v < -bd  # det A < 0 and det B < 0, certified
    idx = np.zeros(ok.shape, dtype=np.int64)
    for i in range(n - 1, 0, -1):
        idx = idx * 5 + _digit(*out[f"c{i}"])
    table = _TABLE[n]
    codes = table[idx * 125 + 124]  # s0, s1, s1,0 pending
    need = np.flatnonzero(ok & (codes == NEED_S0))
    if need.size:  # s0 only where the tree needs it
        vals = [np.asarray(out[f"c{i}"][0])[need] for i in range(n + 1)]
        radii = [np.asarray(out[f"c{i}"][1])[need] for i in range(n + 1)]
        hv, hb = _run_hat(n, "s0", vals, radii)
        codes = codes.copy()
        codes[need] = table[idx[need] * 125 + _digit(hv, hb) * 25 + 24]
    codes = np.where(ok & (codes >= 0), codes, -1).astype(np.int8)
    return codes, ok


# -------------------------------------------------------------------------------------------
# certificates that do not need s0 (same operations as certify{n} in core/fixed/_kernels.c)


def _w(W: np.ndarray, i: int, j: int) -> np.ndarray:
    return W[:, min(i, j), max(i, j)]


def centres(W: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Float centres (Q c = -m, adjugate), scales k = -m.c - M_dd and the mask det Q > 0.

    ``W``: a stack (N, n, n) of symmetric matrices (upper triangle read). Estimates: the
    certificates and the bounding spheres of :mod:`core.bodies.bounds` hold for any float centre.
    """
    n = W.shape[-1]
    d = n - 1
    w = lambda i, j: _w(W, i, j)  # noqa: E731
    if d == 2:
        a00, a01, a11 = w(1, 1), -w(0, 1), w(0, 0)
        det = w(0, 0) * w(1, 1) - w(0, 1) * w(0, 1)
        m0, m1 = w(0, 2), w(1, 2)
        c = np.stack([-(a00 * m0 + a01 * m1) / det, -(a01 * m0 + a11 * m1) / det], axis=1)
        k = -(m0 * c[:, 0] + m1 * c[:, 1]) - w(2, 2)
    else:
        a00 = w(1, 1) * w(2, 2) - w(1, 2) * w(1, 2)
        a01 = w(0, 2) * w(1, 2) - w(0, 1) * w(2, 2)
        a02 = w(0, 1) * w(1, 2) - w(0, 2) * w(1, 1)
        a11 = w(0, 0) * w(2, 2) - w(0, 2) * w(0, 2)
        a12 = w(0, 1) * w(0, 2) - w(0, 0) * w(1, 2)
        a22 = w(0, 0) * w(1, 1) - w(0, 1) * w(0, 1)
        det = w(0, 0) * a00 + w(0, 1) * a01 + w(0, 2) * a02
        m0, m1, m2 = w(0, 3), w(1, 3), w(2, 3)
        c = np.stack(
            [
                -(a00 * m0 + a01 * m1 + a02 * m2) / det,
                -(a01 * m0 + a11 * m1 + a12 * m2) / det,
                -(a02 * m0 + a12 * m1 + a22 * m2) / det,
            ],
            axis=1,
        )
        k = -(m0 * c[:, 0] + m1 * c[:, 1] + m2 * c[:, 2]) - w(3, 3)
    return c, k, det > 0


def _quad(W: np.ndarray, u: np.ndarray) -> np.ndarray:
    """u^T Q u, terms in the order of ``quad{n}`` in C: diagonal terms, then 2 w_ij u_i u_j."""
    d = W.shape[-1] - 1
    acc = _w(W, 0, 0) * u[:, 0] * u[:, 0]
    for i in range(1, d):
        acc = acc + _w(W, i, i) * u[:, i] * u[:, i]
    for i in range(d):
        for j in range(i + 1, d):
            acc = acc + 2.0 * _w(W, i, j) * u[:, i] * u[:, j]
    return acc


def _certify(
    WA: np.ndarray, RA: np.ndarray, WB: np.ndarray, RB: np.ndarray, c: list[np.ndarray], cr: list[np.ndarray]
) -> np.ndarray:
    """Rule ids (sep-witness, common-point, or -1) for valid pairs whose tree abstained.

    Candidates from the shapes' centres: with tA, tB the distances (in units of the centre
    segment) from each centre to its own boundary along the segment, T* = (tA/tB)(kB/kA) is the
    Perram-Wertheim optimum for spheres and for translated or homothetic copies, and the point at
    tA / (tA + tB) of the segment lies inside both exactly when such shapes overlap. Both are
    then verified with certified bounds; a wrong guess only abstains.
    """
    n = WA.shape[-1]
    d = n - 1
    with np.errstate(all="ignore"):
        ca, ka, oka = centres(WA)
        cb, kb, okb = centres(WB)
        ok = oka & okb & (ka > 0) & (kb > 0)
        u = cb - ca
        qa, qb = _quad(WA, u), _quad(WB, u)
        pos = (qa > 0) & (qb > 0)
        ta, tb = np.sqrt(ka / qa), np.sqrt(kb / qb)
        T = (ta / tb) * (kb / ka)
        tin = pos & (T >= float(CERT_T_MIN)) & (T <= float(CERT_T_MAX))
        fn, floor = _PENCIL_AT[n]
        pv, pr = fn(c, cr, np.where(tin, T, 1.0))
        sep = ok & tin & (pv > pr * RADIUS_FACTOR + floor)
        s = np.where(pos, ta / (ta + tb), 0.0)
        x = ca + s[:, None] * u
        xin = (np.abs(x) <= TRANSLATE_MAX).all(axis=1)
        x = np.where(xin[:, None], x, 0.0)
        fn, floor = _FORM[n]
        fa, fra = fn(np.moveaxis(WA, 0, -1), np.moveaxis(RA, 0, -1), np.moveaxis(x, 0, -1))
        fb, frb = fn(np.moveaxis(WB, 0, -1), np.moveaxis(RB, 0, -1), np.moveaxis(x, 0, -1))
        inside = (fa < -(fra * RADIUS_FACTOR + floor)) & (fb < -(frb * RADIUS_FACTOR + floor))
    del d
    return np.where(sep, _RULE_SEP, np.where(ok & xin & inside, _RULE_POINT, -1)).astype(np.int8)


def _stage1(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rule ids of the first stage for one chunk (numpy twin of classify{n} in C)."""
    n = a.shape[-1]
    with np.errstate(all="ignore"):  # non-finite intermediate values only make the filter abstain
        prep = _Prepared(a, b)
        out = _run_pencil(prep.a, prep.b, prep.rounded)
        codes, valid = _tree(out, prep.ok, n)
        todo = np.flatnonzero(valid & (codes < 0))
        if todo.size:
            c = [np.asarray(out[f"c{i}"][0])[todo] for i in range(n + 1)]
            cr = [np.asarray(out[f"c{i}"][1])[todo] for i in range(n + 1)]
            codes[todo] = _certify(prep.a[todo], prep.radius_a[todo], prep.b[todo], prep.radius_b[todo], c, cr)
    return codes


def rules_numpy(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rule ids of the first stage, vectorised numpy (no compiler needed; cross-checked with C)."""
    N = a.shape[0]
    codes = np.empty(N, dtype=np.int8)
    for s in range(0, N, _CHUNK):
        codes[s : s + _CHUNK] = _stage1(a[s : s + _CHUNK], b[s : s + _CHUNK])
    return codes


def classify_float_numpy(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Relation codes of the numpy first stage (UNDECIDED where it abstains)."""
    return _relations(rules_numpy(a, b))


def _relations(rules: np.ndarray) -> np.ndarray:
    return np.where(rules >= 0, RULE_RELATION[np.maximum(rules, 0)], Relation.UNDECIDED).astype(np.int8)


# -------------------------------------------------------------------------------------------
# stage 2: far from the origin


def _translated(M: np.ndarray, Mr: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Values and certified radii of G^T M G (origin moved to t), rescaled so |v| + r < 2."""
    n = M.shape[-1]
    fn, outputs, floor = _TRANSLATE[n]
    res = fn(np.moveaxis(M, 0, -1), np.moveaxis(Mr, 0, -1), np.moveaxis(t, 0, -1))
    V = np.empty_like(M)
    R = np.empty_like(M)
    k = len(outputs)
    for name, v, r in zip(outputs, res[:k], res[k:], strict=True):
        i, j = int(name[1]), int(name[2])
        V[:, i, j] = V[:, j, i] = v
        R[:, i, j] = R[:, j, i] = np.asarray(r) * RADIUS_FACTOR + floor
    mx = (np.abs(V) + R).max(axis=(1, 2))
    _, e = np.frexp(np.where(np.isfinite(mx) & (mx > 0), mx, 1.0))
    shift = (1 - e)[:, None, None]
    return np.ldexp(V, shift), np.ldexp(R, shift) + _TINY_RADIUS


def classify_translated(a: np.ndarray, b: np.ndarray, shift_b: np.ndarray | None = None) -> np.ndarray:
    """Second stage: rule ids after moving both shapes so that A is centred near the origin.

    The relation is invariant under a common translation. Far from the origin (centres at 1e6)
    the entries c^T Q c dominate the first stage's bound; after moving the origin to (a float
    approximation of) A's centre, with every entry's rounding error carried as a radius
    (:mod:`core.fixed.errorbound`, midpoint-radius), most such pairs are certified without exact
    arithmetic, by the tree or by the certificates. -1 where no sign is proven.

    Args:
        a: float64 stack (N, n, n).
        b: the same shape.
        shift_b: optional (N, n - 1) float vectors s: classify A against B moved by exactly s
            (the periodic image of B, :mod:`core.bodies.periodic`); the translated entries of B
            carry their rounding as radii, so the answer is certified for the exact translate.
    """
    n = a.shape[-1]
    with np.errstate(all="ignore"):
        prep = _Prepared(a, b)
        centre, _, okc = centres(prep.a)
        ok = prep.ok & okc & np.isfinite(centre).all(axis=1) & (np.abs(centre) <= TRANSLATE_MAX).all(axis=1)
        centre = np.where(ok[:, None], centre, 0.0)  # any float vector is exact: it is the chosen t
        b_moved, radius_b = prep.b, prep.radius_b
        if shift_b is not None:  # origin at -s: B moves by +s (s is exact, entries gain radii)
            s = np.asarray(shift_b, dtype=np.float64)
            ok &= np.isfinite(s).all(axis=1) & (np.abs(s) <= TRANSLATE_MAX).all(axis=1)
            b_moved, radius_b = _translated(prep.b, prep.radius_b, np.where(ok[:, None], -s, 0.0))
        VA, RA = _translated(prep.a, prep.radius_a, centre)
        VB, RB = _translated(b_moved, radius_b, centre)
        fn, outputs, floor = _PENCIL_RADIUS[n]
        res = fn(*(np.moveaxis(X, 0, -1) for X in (VA, RA, VB, RB)))
        k = len(outputs)
        out = {name: (v, np.asarray(r) * RADIUS_FACTOR + floor) for name, v, r in zip(outputs, res[:k], res[k:], strict=True)}
        codes, valid = _tree(out, ok, n)
        todo = np.flatnonzero(valid & (codes < 0))
        if todo.size:
            c = [np.asarray(out[f"c{i}"][0])[todo] for i in range(n + 1)]
            cr = [np.asarray(out[f"c{i}"][1])[todo] for i in range(n + 1)]
            codes[todo] = _certify(VA[todo], RA[todo], VB[todo], RB[todo], c, cr)
    return codes


def _second_stage(a: np.ndarray, b: np.ndarray, rules: np.ndarray) -> np.ndarray:
    """Run :func:`classify_translated` on the pairs the first stage left undecided."""
    idx = np.flatnonzero(rules < 0)
    for s in range(0, idx.size, _CHUNK):
        part = idx[s : s + _CHUNK]
        rules[part] = classify_translated(a[part], b[part])
    return rules


# -------------------------------------------------------------------------------------------
# entry points


def rules_float(a: np.ndarray, b: np.ndarray, *, scalar: bool = False, threads: int | None = None) -> np.ndarray:
    """Rule ids (int8; -1 where no sign is proven) for float64 stacks (N, n, n), n = 3 or 4.

    Not validated here: invalid or non-finite pairs come back -1 so that the exact path reports
    the error. The compiled kernels serve when ready (built in the background on first use;
    never waited for), else the numpy code; then the second stage on what is left, except for
    a single pair (exact arithmetic is as fast as numpy on one pair).
    """
    if compiled.warm_up(wait=False):
        rules = compiled.rules(a, b, threads=threads)
    else:
        rules = rules_numpy(a, b)
    if not scalar and (rules < 0).any():
        rules = _second_stage(a, b, rules)
    return rules


def classify_float(a: np.ndarray, b: np.ndarray, *, scalar: bool = False, threads: int | None = None) -> np.ndarray:
    """Certified float64 classification of stacked pairs; UNDECIDED where no sign is proven.

    Args:
        a: float64 array (N, n, n), n = 3 or 4.
        b: the same shape as ``a``.
        scalar: N == 1 (skips the second stage).
        threads: threads for the compiled kernels (None: :func:`core.fixed.compiled.get_threads`).

    Returns:
        int8 codes of :class:`Relation`, shape (N,). Never a wrong label.
    """
    return _relations(rules_float(a, b, scalar=scalar, threads=threads))


# -------------------------------------------------------------------------------------------
# explain


def explain_float(A: Any, B: Any) -> Any:
    """Explanation from the float filter if it certifies the pair, else None (exact path then).

    Values are computed on the power-of-two scaled matrices (where the bounds are proven) and
    scaled back exactly; a value that would leave the float range defers to the exact path.
    The rule is the one the numpy first stage decides by (the compiled kernels take the same
    decisions), including the certificates that do not need s0.
    """
    if not (_is_plain_floats(A) and _is_plain_floats(B)):
        return None
    a = np.asarray(A, dtype=np.float64)
    b = np.asarray(B, dtype=np.float64)
    if a.ndim != 2 or a.shape != b.shape or a.shape[0] not in (3, 4) or a.shape[0] != a.shape[1]:
        return None
    n = a.shape[0]
    with np.errstate(all="ignore"):
        prep = _Prepared(a[None], b[None])
        out = _run_pencil(prep.a, prep.b, prep.rounded)
        codes, valid = _tree(out, prep.ok, n)
        if valid[0] and codes[0] < 0:
            c = [np.asarray(out[f"c{i}"][0]) for i in range(n + 1)]
            cr = [np.asarray(out[f"c{i}"][1]) for i in range(n + 1)]
            codes = _certify(prep.a, prep.radius_a, prep.b, prep.radius_b, c, cr)
    code = int(codes[0])
    if code < 0:
        return None
    rule = RULE_LIST[code]
    ea, eb = int(prep.ea[0]), int(prep.eb[0])

    def quantity(name: str, v: float, bd: float, e: int, s: int | None) -> Quantity | None:
        """V * 2^e with bound bd * 2^e; None if either leaves the normal float range."""
        with np.errstate(all="ignore"):
            val, bound = float(np.ldexp(v, e)), float(np.ldexp(bd, e))
        if not (math.isfinite(val) and math.isfinite(bound)) or (val == 0.0) != (v == 0.0):
            return None
        exact_value = to_fmpq(v) * (fmpq(2) ** e if e >= 0 else fmpq(1, 2 ** (-e)))
        return Quantity(name, val, None, bound, s, format_rational(exact_value))

    coeffs = []
    for i in range(n + 1):
        v, bd = (float(np.asarray(x).reshape(-1)[0]) for x in out[f"c{i}"])
        s = 1 if v > bd else (-1 if v < -bd else None)
        q = quantity(f"a{i}", v, bd, -(i * ea + (n - i) * eb), s)
        if q is None:  # a value beyond the float range: the exact path shows it
            return None
        coeffs.append(q)
    var = sign_variations([q.sign or 0 for q in reversed(coeffs)])
    subs: dict[str, Any] = {}
    needed: list[str] = []
    if rule.key != "var":
        needed = ["s0"] if rule.key not in ("sep-witness", "common-point") else []
        vals = [float(np.asarray(out[f"c{i}"][0]).reshape(-1)[0]) for i in range(n + 1)]
        radii = [float(np.asarray(out[f"c{i}"][1]).reshape(-1)[0]) for i in range(n + 1)]
        an = coeffs[n].approx
        assert an is not None  # a_n was certified (< 0) and fits a float: quantity() returned it
        for which, scale in zip(("s0", "s1", "s10"), hat_scale(n), strict=True):
            hv, hb = _run_hat(n, which, vals, radii)
            deg, w = HAT_DEGREE_WEIGHT[(n, which)]
            # scaled a_i = mu lambda^i a_i with mu = 2^(n eb), lambda = 2^(ea - eb)
            e = -(n * eb * deg + (ea - eb) * w)
            hv0, hb0 = float(hv), float(hb)
            with np.errstate(all="ignore"):
                hvs, hbs = float(np.ldexp(hv0, e)), float(np.ldexp(hb0, e))
            # s_j = -a_n c_j hs_j; a_n < 0 is certified, so sign(s_j) = sign(hs_j)
            factor = -an * float(scale)
            s = 1 if hv0 > hb0 else (-1 if hv0 < -hb0 else None)
            an_bound = coeffs[n].bound
            assert an_bound is not None  # float-certified quantities carry their bound
            rel_an = an_bound / abs(an) if an else float("inf")
            value = factor * hvs
            bound = abs(factor) * (hbs + abs(hvs) * rel_an) * (1 + 2.0**-40)
            if not (math.isfinite(value) and math.isfinite(bound)) or (value == 0.0) != (hv0 == 0.0):
                if which == "s0" and "s0" in needed:
                    return None
                continue
            subs[which] = Quantity(which, value, None, bound, s, format_rational(to_fmpq(value)))
    return Explanation(
        n=n,
        relation=rule.relation,
        certified_by="float",
        rule=rule.key,
        rule_text=rule.text,
        var=var,
        coefficients=coeffs,
        s0=subs.get("s0"),
        s1=subs.get("s1"),
        s10=subs.get("s10"),
        subresultants_needed=needed,
    )


def _is_plain_floats(M: Any) -> bool:
    if isinstance(M, np.ndarray):
        return M.dtype == np.float64 or (M.dtype.kind in "iu" and M.size > 0 and np.abs(M).max() < 2**53)
    try:
        return all(
            (type(v) is float or type(v) is np.float64 or (type(v) is int and abs(v) < 2**53))
            for row in M
            for v in row
        )
    except TypeError:
        return False
