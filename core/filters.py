"""The certified float64 filter: paper's trees on float values whose signs are proven (Shewchuk/CGAL style).

For every pair it computes a_0..a_n of P(T) = det(T A + B) straight from the matrix entries (no
inversion), the leading principal minors that certify both matrices are ellipses/ellipsoids, and,
only for the pairs whose Descartes count Var(a_n..a_0) is 2, the sign-equivalent ``hs0`` of s0.
Each value comes with a proven error bound (:mod:`core.errorbound`, kernels generated into
:mod:`core._kernels`); a sign is used only when ``|value| > bound``. Otherwise the pair is
UNDECIDED and :func:`core.classify.classify` sends it to exact arithmetic.

A float filter can never certify ``s0 = 0``, so TANGENT is always left to the exact path, and
s1, s1,0 (needed only when s0 = 0) are never used here for decisions; :func:`explain_float`
reports them, with bounds, for display. Two implementations of the same decisions: the per-pair
kernel of :mod:`core.fastpath` (numba) and the vectorised numpy code below (fallback without
numba); the tests check they agree.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from flint import fmpq

from . import _kernels as K
from .decision import RULES, sign_variations
from .errorbound import LEAF_MAX, NO_SCALE_MIN, RADIUS_FACTOR, TRANSLATE_MAX
from .fastpath import classify_one, classify_pairs, warm_up
from .quadrics import SYMMETRY_TOLERANCE
from .rationals import format_rational, to_fmpq
from .relation import Relation
from .subresultants import hat_scale

__all__ = ["classify_float", "classify_float_numpy", "classify_translated", "explain_float", "HAT_DEGREE_WEIGHT"]

_CHUNK = 4096
"""Pairs per numpy chunk: keeps the kernel's temporaries in cache."""

_PENCIL = {
    3: (K.pencil3, K.PENCIL3_OUTPUTS, K.PENCIL3_CONSTANTS, K.PENCIL3_FLOOR),
    4: (K.pencil4, K.PENCIL4_OUTPUTS, K.PENCIL4_CONSTANTS, K.PENCIL4_FLOOR),
}
_HAT = {
    (3, "s0"): (K.hat_s0_3, K.HAT_S0_3_FLOOR),
    (3, "s1"): (K.hat_s1_3, K.HAT_S1_3_FLOOR),
    (3, "s10"): (K.hat_s10_3, K.HAT_S10_3_FLOOR),
    (4, "s0"): (K.hat_s0_4, K.HAT_S0_4_FLOOR),
    (4, "s1"): (K.hat_s1_4, K.HAT_S1_4_FLOOR),
    (4, "s10"): (K.hat_s10_4, K.HAT_S10_4_FLOOR),
}

_PENCIL_ROUNDED = {
    3: (K.PENCIL3_CONSTANTS_ROUNDED, K.PENCIL3_FLOOR_ROUNDED),
    4: (K.PENCIL4_CONSTANTS_ROUNDED, K.PENCIL4_FLOOR_ROUNDED),
}
_TRANSLATE = {3: K.translate3, 4: K.translate4}
_TRANSLATE_OUTPUTS = {3: K.TRANSLATE3_OUTPUTS, 4: K.TRANSLATE4_OUTPUTS}
_TRANSLATE_FLOOR = {3: K.TRANSLATE3_FLOOR, 4: K.TRANSLATE4_FLOOR}
_PENCIL_RADIUS = {3: (K.pencil_radius3, K.PENCIL_RADIUS3_FLOOR), 4: (K.pencil_radius4, K.PENCIL_RADIUS4_FLOOR)}
_PENCIL_RADIUS_OUTPUTS = {3: K.PENCIL_RADIUS3_OUTPUTS, 4: K.PENCIL_RADIUS4_OUTPUTS}

HAT_DEGREE_WEIGHT: dict[tuple[int, str], tuple[int, int]] = {
    (3, "s0"): (4, 6), (3, "s1"): (2, 4), (3, "s10"): (2, 3),
    (4, "s0"): (6, 12), (4, "s1"): (4, 10), (4, "s10"): (4, 9),
}
"""(degree, weight) of each hat form: hs(mu * lambda^i a_i) = mu^deg lambda^weight hs(a)."""


_TOL2 = float(SYMMETRY_TOLERANCE) ** 2


def _prepare(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vectorised ``prepare{n}`` of :mod:`core._kernels` (same decisions, see kernelgen).

    Returns (scaled symmetric matrices, exponents e with scaled = 2^e * sign * S, status) where
    status is 1 (exactly symmetric), 2 (symmetric up to rounding: entries are rounded half sums)
    or 0 (abstain).
    """
    with np.errstate(all="ignore"):
        MT = np.swapaxes(M, 1, 2)
        finite = np.isfinite(M).all(axis=(1, 2))
        Mz = np.where(np.isfinite(M), M, 0.0)
        q00 = Mz[:, 0, 0]
        mx = np.abs(Mz).max(axis=(1, 2))
        _, e = np.frexp(np.where(mx > 0, mx, 1.0))
        keep = (mx >= float(NO_SCALE_MIN)) & (mx <= float(LEAF_MAX))
        e = np.where(keep, 1, e)  # no rescaling when already in range: f = +-1
        # exact power-of-two scaling (ldexp of each entry: 2^(1-e) itself may be no float)
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


class _Prepared:
    """Pairs flipped to negative interiors, symmetrised and scaled by 2^-ea, 2^-eb (exact)."""

    def __init__(self, a: np.ndarray, b: np.ndarray) -> None:
        self.a, self.ea, sa = _prepare(a)
        self.b, self.eb, sb = _prepare(b)
        """Scaled matrix = 2^ea * (symmetric part of A) after the sign flip."""
        self.ok = (sa > 0) & (sb > 0)
        self.rounded = (sa == 2) | (sb == 2)
        """Pairs whose entries are rounded half sums (leaf_K = 1 constants apply)."""
        self.radius_a = np.where((sa == 2)[:, None, None], np.abs(self.a) * 2.0**-52 + 2.0**-1073, 0.0)
        self.radius_b = np.where((sb == 2)[:, None, None], np.abs(self.b) * 2.0**-52 + 2.0**-1073, 0.0)
        """Radius of each prepared entry (0 when exact)."""


def _run_pencil(a: np.ndarray, b: np.ndarray, rounded: np.ndarray | None = None) -> dict[str, tuple[Any, Any]]:
    """Name -> (value, certified error bound) of every pencil output, for arrays (N, n, n).

    ``rounded`` marks the pairs whose entries are rounded values (their own constants).
    """
    n = a.shape[-1]
    fn, outputs, consts, floor = _PENCIL[n]
    consts_r, floor_r = _PENCIL_ROUNDED[n]
    res = dict(zip(outputs, fn(np.moveaxis(a, 0, -1), np.moveaxis(b, 0, -1))))
    out = {}
    for name, c, cr in zip(outputs, consts, consts_r):
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


def _certified_sign(v: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """+1 / -1 where |v| > bound, 0 where uncertain (0 never means 'zero' here)."""
    return np.where(v > bound, 1, np.where(v < -bound, -1, 0)).astype(np.int8)


def _decide(out: dict[str, tuple[Any, Any]], ok: np.ndarray, n: int) -> np.ndarray:
    """The certified tree (validity, Var, s0) on values with error bounds, for arrays of pairs."""
    N = ok.shape[0]
    codes = np.full(N, Relation.UNDECIDED, dtype=np.int8)
    ok = ok.copy()
    for key in [k for k in out if k.startswith("d")]:
        v, bd = out[key]
        ok &= v > bd  # quadratic block positive definite, certified (Sylvester)
    for key in (f"c{n}", "c0"):
        v, bd = out[key]
        ok &= v < -bd  # det A < 0 and det B < 0, certified
    signs = []
    for i in range(n - 1, 0, -1):
        v, bd = out[f"c{i}"]
        s = _certified_sign(v, bd)
        ok &= s != 0
        signs.append(s)
    # Var(-, a_{n-1}, ..., a_1, -) with every sign certified non-zero
    seq = [np.full(N, -1, np.int8), *signs, np.full(N, -1, np.int8)]
    var = sum((seq[i] != seq[i + 1]).astype(np.int8) for i in range(len(seq) - 1))
    codes[ok & (var != 2)] = Relation.OVERLAP
    idx = np.flatnonzero(ok & (var == 2))
    if idx.size:  # s0 only where the tree needs it
        vals = [np.asarray(out[f"c{i}"][0])[idx] for i in range(n + 1)]
        radii = [np.asarray(out[f"c{i}"][1])[idx] for i in range(n + 1)]
        s0 = _certified_sign(*_run_hat(n, "s0", vals, radii))
        first, second = (Relation.SEPARATE, Relation.OVERLAP) if n == 3 else (Relation.OVERLAP, Relation.SEPARATE)
        codes[idx] = np.where(s0 > 0, first, np.where(s0 < 0, second, Relation.UNDECIDED))
    return codes


def _classify_chunk(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    with np.errstate(all="ignore"):  # non-finite intermediate values only make the filter abstain
        prep = _Prepared(a, b)
        return _decide(_run_pencil(prep.a, prep.b, prep.rounded), prep.ok, a.shape[-1])


_TINY_RADIUS = 2.0**-1073
"""Covers an exact power-of-two rescaling that lands in the subnormal range (error <= 2^-1075)."""


def _translated(M: np.ndarray, Mr: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Values and certified radii of G^T M G (origin moved to t), rescaled so |v| + r < 2."""
    n = M.shape[-1]
    fn = _TRANSLATE[n]
    res = fn(np.moveaxis(M, 0, -1), np.moveaxis(Mr, 0, -1), np.moveaxis(t, 0, -1))
    outputs = _TRANSLATE_OUTPUTS[n]
    V = np.empty_like(M)
    R = np.empty_like(M)
    k = len(outputs)
    for name, v, r in zip(outputs, res[:k], res[k:]):
        i, j = int(name[1]), int(name[2])
        V[:, i, j] = V[:, j, i] = v
        R[:, i, j] = R[:, j, i] = np.asarray(r) * RADIUS_FACTOR + _TRANSLATE_FLOOR[n]
    mx = (np.abs(V) + R).max(axis=(1, 2))
    _, e = np.frexp(np.where(np.isfinite(mx) & (mx > 0), mx, 1.0))
    shift = (1 - e)[:, None, None]
    return np.ldexp(V, shift), np.ldexp(R, shift) + _TINY_RADIUS


def classify_translated(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Second filter stage: both shapes moved so that A is centred near the origin.

    The relation is invariant under a common translation. Far from the origin (centres at 1e6)
    the entries c^T Q c dominate the first stage's bound; after moving the origin to (a float
    approximation of) A's centre, with every entry's rounding error carried as a radius
    (:mod:`core.errorbound`, midpoint-radius), most such pairs are certified without exact
    arithmetic. Same contract as :func:`classify_float`: UNDECIDED where no sign is proven.
    """
    n = a.shape[-1]
    d = n - 1
    prep = _Prepared(a, b)
    Q, m = prep.a[:, :d, :d], prep.a[:, :d, d]
    with np.errstate(all="ignore"):
        try:
            centre = -np.linalg.solve(Q, m[..., None])[..., 0]
        except np.linalg.LinAlgError:  # a singular block somewhere: solve one by one
            centre = np.array([_solve_or_nan(q, v) for q, v in zip(Q, m)]).reshape(-1, d)
    ok = prep.ok & np.isfinite(centre).all(axis=1) & (np.abs(centre) <= TRANSLATE_MAX).all(axis=1)
    centre = np.where(ok[:, None], centre, 0.0)  # any float vector is exact: it is the chosen t
    VA, RA = _translated(prep.a, prep.radius_a, centre)
    VB, RB = _translated(prep.b, prep.radius_b, centre)
    fn, floor = _PENCIL_RADIUS[n]
    res = fn(*(np.moveaxis(X, 0, -1) for X in (VA, RA, VB, RB)))
    outputs = _PENCIL_RADIUS_OUTPUTS[n]
    k = len(outputs)
    out = {name: (v, np.asarray(r) * RADIUS_FACTOR + floor) for name, v, r in zip(outputs, res[:k], res[k:])}
    return _decide(out, ok, n)


def _solve_or_nan(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    try:
        return -np.linalg.solve(q, v)
    except np.linalg.LinAlgError:
        return np.full(v.shape, np.nan)


def classify_float_numpy(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The vectorised numpy first stage (used when numba is missing; cross-checked in the tests)."""
    N = a.shape[0]
    codes = np.empty(N, dtype=np.int8)
    for s in range(0, N, _CHUNK):
        codes[s : s + _CHUNK] = _classify_chunk(a[s : s + _CHUNK], b[s : s + _CHUNK])
    return codes


def _second_stage(a: np.ndarray, b: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """Run :func:`classify_translated` on the pairs the first stage left undecided."""
    idx = np.flatnonzero(codes == Relation.UNDECIDED)
    for s in range(0, idx.size, _CHUNK):
        part = idx[s : s + _CHUNK]
        codes[part] = classify_translated(a[part], b[part])
    return codes


def classify_float(a: np.ndarray, b: np.ndarray, *, scalar: bool = False) -> np.ndarray:
    """Certified float64 classification of stacked pairs; UNDECIDED where no sign is proven.

    Args:
        a, b: float64 arrays of shape (N, n, n), n = 3 or 4. Not validated here: invalid or
            non-finite pairs come back UNDECIDED so that the exact path reports the error.
        scalar: N == 1 (a single pair takes the per-pair kernel, and skips the second stage).

    Returns:
        int8 codes of :class:`Relation`, shape (N,). Never a wrong label.

    Batches use the numba kernel once it is compiled (started in the background on first use;
    :func:`core.fastpath.warm_up` waits for it) and the numpy code until then; the pairs this
    first stage leaves undecided go through :func:`classify_translated`. A single pair skips
    that second stage (exact arithmetic is as fast as numpy on one pair).
    """
    if scalar and warm_up(wait=False):
        codes = np.array([classify_one(a[0], b[0])], dtype=np.int8)
    elif scalar:  # numba still compiling (or absent): the numpy filter, same answers, ~1 ms
        codes = classify_float_numpy(a, b)
    elif warm_up(wait=False):  # compiled kernels ready (never wait for numba's first compile)
        codes = _second_stage(a, b, classify_pairs(a, b))
    else:
        codes = _second_stage(a, b, classify_float_numpy(a, b))
    return codes


def explain_float(A: Any, B: Any) -> Any:
    """Explanation from the float filter if it certifies the pair, else None (exact path then).

    Values are computed on the power-of-two scaled matrices (where the bounds are proven) and
    scaled back exactly (display may overflow to inf for extreme inputs; signs stay certified).
    """
    from .explain import Explanation, Quantity

    if not (_is_plain_floats(A) and _is_plain_floats(B)):
        return None
    a = np.asarray(A, dtype=np.float64)
    b = np.asarray(B, dtype=np.float64)
    if a.ndim != 2 or a.shape != b.shape or a.shape[0] not in (3, 4) or a.shape[0] != a.shape[1]:
        return None
    n = a.shape[0]
    with np.errstate(all="ignore"):  # non-finite intermediate values only make the filter abstain
        prep = _Prepared(a[None], b[None])
        out = _run_pencil(prep.a, prep.b, prep.rounded)
        code = _decide(out, prep.ok, n)[0]  # the same values the explanation shows decide
    if code == Relation.UNDECIDED:
        return None
    ea, eb = int(prep.ea[0]), int(prep.eb[0])

    def back(x: float, i: int) -> float:  # a_i(scaled) = 2^(i ea + (n - i) eb) a_i(true)
        return float(np.ldexp(x, -(i * ea + (n - i) * eb)))

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
        v, bd = (float(x[0]) for x in out[f"c{i}"])
        s = 1 if v > bd else (-1 if v < -bd else None)
        q = quantity(f"a{i}", v, bd, -(i * ea + (n - i) * eb), s)
        if q is None:  # a value beyond the float range: the exact path shows it
            return None
        coeffs.append(q)
    var = sign_variations([q.sign or 0 for q in reversed(coeffs)])
    subs: dict[str, Any] = {}
    needed: list[str] = []
    if var == 2:
        needed = ["s0"]
        vals = [float(out[f"c{i}"][0][0]) for i in range(n + 1)]
        radii = [float(out[f"c{i}"][1][0]) for i in range(n + 1)]
        an = coeffs[n].approx
        for which, scale in zip(("s0", "s1", "s10"), hat_scale(n)):
            hv, hb = _run_hat(n, which, vals, radii)
            deg, w = HAT_DEGREE_WEIGHT[(n, which)]
            # scaled a_i = mu lambda^i a_i with mu = 2^(n eb), lambda = 2^(ea - eb)
            e = -(n * eb * deg + (ea - eb) * w)
            hv0, hb0 = float(hv[0] if np.ndim(hv) else hv), float(hb[0] if np.ndim(hb) else hb)
            with np.errstate(all="ignore"):
                hv, hb = float(np.ldexp(hv0, e)), float(np.ldexp(hb0, e))
            # s_j = -a_n c_j hs_j; a_n < 0 is certified, so sign(s_j) = sign(hs_j)
            factor = -an * float(scale)
            s = 1 if hv0 > hb0 else (-1 if hv0 < -hb0 else None)
            rel_an = coeffs[n].bound / abs(an) if an else float("inf")
            value = factor * hv
            bound = abs(factor) * (hb + abs(hv) * rel_an) * (1 + 2.0**-40)
            if not (math.isfinite(value) and math.isfinite(bound)) or (value == 0.0) != (hv0 == 0.0):
                return None
            subs[which] = Quantity(which, value, None, bound, s, format_rational(to_fmpq(value)))
    rel = Relation(int(code))
    if var != 2:
        rule = "var"
    elif n == 3:
        rule = "2d-s0>0" if rel == Relation.SEPARATE else "2d-s0<0"
    else:
        rule = "3d-s0<0" if rel == Relation.SEPARATE else "3d-s0>0"
    return Explanation(
        n=n,
        relation=rel,
        certified_by="float",
        rule=rule,
        rule_text=RULES[rule],
        var=var,
        coefficients=coeffs,
        s0=subs.get("s0"),
        s1=subs.get("s1"),
        s10=subs.get("s10"),
        subresultants_needed=needed,
    )


def _is_plain_floats(M: Any) -> bool:
    if isinstance(M, np.ndarray):
        return M.dtype == np.float64 or (M.dtype.kind in "iu" and np.abs(M).max() < 2**53)
    try:
        return all(
            (type(v) is float or type(v) is np.float64 or (type(v) is int and abs(v) < 2**53))
            for row in M
            for v in row
        )
    except TypeError:
        return False
