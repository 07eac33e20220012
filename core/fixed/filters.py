"""The certified float filter: the paper's trees on float values whose signs are proven (Shewchuk/CGAL).

For every pair it computes a_0..a_n of P(T) = det(T A + B) straight from the matrix entries (no
inversion), the leading principal minors that certify both matrices are ellipses/ellipsoids, and,
only for the pairs whose Descartes count Var(a_n..a_0) is 2, the sign-equivalent ``hs0`` of s0.
Each value comes with a proven error bound (:mod:`core.fixed.errorbound`); a sign is used only
when ``|value| > bound``, and the decision is looked up in :data:`core.formulae.decision.TABLE3`
/ ``TABLE4``. Where s0 cannot be certified (it vanishes identically for spheres and translated or
homothetic copies) two certificates that do not need it are tried: a T* > 0 with P(T*) > 0
(separate), and a point inside both shapes (overlap). Otherwise the pair is UNDECIDED and
:func:`core.fixed.classify.classify` sends it to exact arithmetic.

The steps are written once, in :mod:`core.fixed.driver`; the compiled extension
(:mod:`core.fixed.compiled`, generated C, SIMD across pairs, every core) and the numpy code here
(:func:`rules_numpy`: the same description run on arrays) take the same decisions bit for bit.
A float filter never certifies ``s0 = 0``: TANGENT always comes from the exact path.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..formulae.decision import RULE_RELATION
from ..relation import Relation
from . import _kernels as K
from . import compiled
from .driver import (
    NEEDS_CERT,
    NEEDS_S0,
    NEEDS_S0_RADIUS,
    Prepared,
    certify,
    certify_sep,
    decide,
    decide_s0,
    decide_s0_radius,
    pencil_bounds,
    prepare,
    radii,
    skips_s0,
)
from .driver import centre as _centre
from .errorbound import RADIUS_FACTOR, TRANSLATE_MAX
from .lanes import NumpyLanes

__all__ = [
    "classify_float",
    "classify_float_counted",
    "rules_float",
    "rules_numpy",
    "classify_float_numpy",
    "classify_translated",
    "first_stage",
    "FirstStage",
    "prepared",
    "centres",
    "certified_valid",
]

_CHUNK = 4096
"""Pairs per numpy chunk: keeps the temporaries in cache."""

_X = NumpyLanes()
Entries = dict[tuple[int, int], Any]
_TINY_RADIUS = 2.0**-1073
"""Covers an exact power-of-two rescaling that lands in the subnormal range (error <= 2^-1075)."""


def _entries(M: np.ndarray) -> Any:
    """``entry(i, j)`` of a stack (N, n, n): column (i, j) as float64 (float32 widens exactly)."""
    return lambda i, j: M[:, i, j].astype(np.float64)


def _upper(M: np.ndarray) -> Entries:
    n = M.shape[-1]
    return {(i, j): M[:, i, j] for i in range(n) for j in range(i, n)}


def _full(W: Entries, n: int) -> np.ndarray:
    N = np.shape(W[0, 0])[0]
    S = np.empty((N, n, n))
    for (i, j), v in W.items():
        S[:, i, j] = S[:, j, i] = v
    return S


def _take(values: Any, rows: np.ndarray) -> Any:
    if isinstance(values, dict):
        return {k: v[rows] for k, v in values.items()}
    return [v[rows] for v in values]


# -------------------------------------------------------------------------------------------
# stage 1: the description of core.fixed.driver on arrays


@dataclass
class FirstStage:
    """Everything the first stage computed for a stack of pairs (numpy)."""

    a: Prepared
    b: Prepared
    c: list[np.ndarray]
    """a_0..a_n on the prepared matrices."""
    cr: list[np.ndarray]
    """Their certified error bounds."""
    rules: np.ndarray
    """int8 rule ids (-1 where no sign is proven)."""
    asked_s0: np.ndarray
    """Mask: the tree asked for s0 (it was computed)."""


def first_stage(a: np.ndarray, b: np.ndarray) -> FirstStage:
    """Run the driver on stacks (N, n, n) of float64 or float32: prepare, tree, s0, certificates."""
    n = a.shape[-1]
    with np.errstate(all="ignore"):  # non-finite intermediate values only make the filter abstain
        Pa = prepare(_X, n, _entries(a), "a")
        Pb = prepare(_X, n, _entries(b), "b")
        c, cr, minors = pencil_bounds(_X, n, Pa, Pb)
        code, _, idx = decide(_X, n, c, cr, minors, Pa.ok & Pb.ok)
        code = np.asarray(code, dtype=np.int64).copy()
        asked = code == NEEDS_S0
        code = _later_stages(n, code, idx, c, cr, skips_s0(_X, n, _entries(a), _entries(b)), lambda rows: (
            _take(Pa.W, rows), radii(_X, _take(Pa.W, rows), Pa.rounded[rows], "a"),
            _take(Pb.W, rows), radii(_X, _take(Pb.W, rows), Pb.rounded[rows], "b"),
        ))
    return FirstStage(Pa, Pb, c, cr, code.astype(np.int8), asked)


def _later_stages(
    n: int, code: np.ndarray, idx: np.ndarray, c: list[np.ndarray], cr: list[np.ndarray], skip: Any, matrices: Any,
) -> np.ndarray:
    """Stages 2-4 of :mod:`core.fixed.driver` on the pairs each one needs (C: the same order).

    ``skip``: :func:`~core.fixed.driver.skips_s0` of the pairs (stage 2 not run where it holds);
    ``matrices(rows)`` gives (WA, RA, WB, RB) of those pairs for the certificates.
    """
    code[(code == NEEDS_S0) & skip] = NEEDS_S0_RADIUS
    need = np.flatnonzero(code == NEEDS_S0)
    if need.size:  # s0, semi-static, only where the tree asks for it
        code[need] = decide_s0(_X, n, _take(c, need), _take(cr, need), idx[need])
    todo = np.flatnonzero((code == NEEDS_CERT) | (code == NEEDS_S0_RADIUS))
    if todo.size:  # the cheap separation certificate where a valid pair is still open
        WA, _, WB, _ = matrices(todo)
        cert = np.asarray(certify_sep(_X, n, WA, WB, _take(c, todo), _take(cr, todo)), dtype=np.int64)
        code[todo] = np.where(cert >= 0, cert, code[todo])
    todo = np.flatnonzero((code == NEEDS_CERT) | (code == NEEDS_S0_RADIUS))
    if todo.size:  # the full certificates where one is still open
        WA, RA, WB, RB = matrices(todo)
        cert = np.asarray(certify(_X, n, WA, RA, WB, RB, _take(c, todo), _take(cr, todo)), dtype=np.int64)
        code[todo] = np.where(cert >= 0, cert, np.where(code[todo] == NEEDS_S0_RADIUS, NEEDS_S0_RADIUS, -1))
    need = np.flatnonzero(code == NEEDS_S0_RADIUS)
    if need.size:  # s0 with a radius per operation, where it is still needed (near tangency)
        code[need] = decide_s0_radius(_X, n, _take(c, need), _take(cr, need), idx[need])
    return np.where(code == NEEDS_CERT, -1, code)


def certified_valid(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Mask (N,): the filter proves both matrices of the pair ellipses/ellipsoids, as given.

    The validity test every label of the filter rests on (:func:`core.fixed.driver.decide`:
    symmetric within the exact tolerance, Sylvester's minors, det A < 0 and det B < 0, each sign
    certified), run alone on float64 or float32 stacks (N, n, n). Where it holds, exact validation
    (0.05-0.15 ms per pair, against ~4 us here) can only agree; where it does not, the pair may
    still be valid (a sign too close to zero) and only exact validation can tell.
    """
    n = a.shape[-1]
    out = np.empty(a.shape[0], dtype=bool)
    with np.errstate(all="ignore"):  # non-finite intermediate values only make the test abstain
        for s in range(0, a.shape[0], _CHUNK):
            part = slice(s, s + _CHUNK)
            Pa = prepare(_X, n, _entries(a[part]), "a")
            Pb = prepare(_X, n, _entries(b[part]), "b")
            c, cr, minors = pencil_bounds(_X, n, Pa, Pb)
            out[part] = decide(_X, n, c, cr, minors, Pa.ok & Pb.ok)[1]
        # then the second stage's proof, on both shapes moved so that A is centred near the origin
        # (an exact congruence of determinant 1: minors and det unchanged, the entries' rounding
        # carried as radii), where centres far from the origin make det A, det B cancellations
        rest = np.flatnonzero(~out)
        for s in range(0, rest.size, _CHUNK):
            rows = rest[s : s + _CHUNK]
            c, cr, minors, ok, *_ = _translated_pencil(a[rows].astype(np.float64), b[rows].astype(np.float64), None)
            out[rows] = decide(_X, n, c, cr, minors, ok)[1]
    return out


def rules_numpy(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rule ids of the first stage, numpy (the last resort without the compiled extension)."""
    N = a.shape[0]
    codes = np.empty(N, dtype=np.int8)
    for s in range(0, N, _CHUNK):
        codes[s : s + _CHUNK] = first_stage(a[s : s + _CHUNK], b[s : s + _CHUNK]).rules
    return codes


def classify_float_numpy(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Relation codes of the numpy first stage (UNDECIDED where it abstains)."""
    return relations(rules_numpy(a, b))


_RELATION_OF = np.full(256, Relation.UNDECIDED, dtype=np.int8)
_RELATION_OF[: len(RULE_RELATION)] = RULE_RELATION
"""Relation code by rule id read as a byte (-1 is 255: UNDECIDED): one table lookup per pair."""


def relations(rules: np.ndarray) -> np.ndarray:
    """Relation codes of int8 rule ids (UNDECIDED for -1)."""
    return np.take(_RELATION_OF, np.ascontiguousarray(rules, dtype=np.int8).view(np.uint8))


def prepared(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Matrices as the filter reads them, with the radius of each entry.

    Args:
        M: float64 stack (N, n, n).

    Returns:
        ``(S, status, radius)``: S = 2^k * sign * (symmetric part of M), scaled by an exact
        power of two into the filter's range and flipped to a negative interior; status 1
        (exactly symmetric), 2 (symmetric up to rounding: S holds rounded half sums, each within
        ``radius`` of the exact one) or 0 (the filter abstains: NaN/inf, M_00 = 0, asymmetry
        not clearly within the tolerance); radius 0 where S is exact. S describes the same
        shape as M (a positive multiple of its quadratic form).
    """
    n = M.shape[-1]
    with np.errstate(all="ignore"):
        P = prepare(_X, n, _entries(M), "m")
        R = radii(_X, P.W, P.rounded, "m")
    status = np.where(P.ok, np.where(P.rounded, 2, 1), 0).astype(np.int8)
    return _full(P.W, n), status, _full(R, n)


def centres(W: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Float centres (Q c = -m, adjugate), scales k = -m.c - M_dd and the mask det Q > 0.

    ``W``: a stack (N, n, n) of symmetric matrices (upper triangle read). Estimates: the
    certificates and the bounding spheres of :mod:`core.bodies.bounds` hold for any float centre.
    """
    with np.errstate(all="ignore"):
        c, k, ok = _centre(_X, W.shape[-1], _upper(W), "c")
    return np.stack(c, axis=1), k, ok


# -------------------------------------------------------------------------------------------
# stage 2: far from the origin


def _translated(M: Entries, Mr: Entries, t: np.ndarray, n: int) -> tuple[Entries, Entries]:
    """Values and certified radii of G^T M G (origin moved to t), rescaled so |v| + r < 2."""
    fn, outputs, floor = getattr(K, f"translate{n}"), getattr(K, f"TRANSLATE{n}_OUTPUTS"), getattr(K, f"TRANSLATE{n}_FLOOR")
    res = fn(M, Mr, [t[:, i] for i in range(n - 1)])
    k = len(outputs)
    V: Entries = {}
    R: Entries = {}
    for name, v, r in zip(outputs, res[:k], res[k:], strict=True):
        ij = (int(name[1]), int(name[2]))
        V[ij], R[ij] = v, np.asarray(r) * RADIUS_FACTOR + floor
    mx = np.max([np.abs(V[ij]) + R[ij] for ij in V], axis=0)
    _, e = np.frexp(np.where(np.isfinite(mx) & (mx > 0), mx, 1.0))
    return {ij: np.ldexp(v, 1 - e) for ij, v in V.items()}, {ij: np.ldexp(r, 1 - e) + _TINY_RADIUS for ij, r in R.items()}


def twice_log2_size(M: np.ndarray) -> np.ndarray:
    """Twice log2 of each body's size (about sqrt(|c|^2 + r^2)), an int64 from its matrix: 0 where undefined.

    For [[Q, m], [m^T, g]], by the frexp exponents E of the largest entries: max(E(g) - E(Q),
    2 (E(m) - E(Q))), a term skipped where m or g is zero; 0 for a non-finite entry, a zero Q, or
    m and g both zero. Exponents, not logarithms: no square overflows, and the C twin in
    ``core/fixed/_filter.c`` (``balance``) gets the same integers on any platform.
    """
    d = M.shape[-1] - 1
    with np.errstate(invalid="ignore"):
        q = np.abs(M[:, :d, :d]).max(axis=(1, 2))
        m = np.abs(M[:, :d, d]).max(axis=1)
        g = np.abs(M[:, d, d])
    eq = np.frexp(q)[1].astype(np.int64)
    low = np.iinfo(np.int64).min
    s = np.maximum(np.where(g != 0, np.frexp(g)[1] - eq, low), np.where(m != 0, 2 * (np.frexp(m)[1] - eq), low))
    ok = np.isfinite(M).all(axis=(1, 2)) & (q != 0) & ((m != 0) | (g != 0))
    return np.where(ok, s, 0).astype(np.int64)


def log2_size(M: np.ndarray) -> np.ndarray:
    """log2 of each body's size, to a power of two (:func:`twice_log2_size` halved): 0 where undefined."""
    out: np.ndarray = 0.5 * twice_log2_size(M)
    return out


def times_power_of_two(x: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The products x 2^k, and elementwise whether each is exact (finite, normal, x again scaled back).

    Exact means finite, normal unless x is 0, and x again when scaled back. A power of two changes only the exponent of a normal result; a subnormal one may drop bits
    (counted as inexact), an overflow gives inf, and a product just below 2^-1022 may round up to
    it (normal, but not x 2^k: the way back tells).
    """
    with np.errstate(over="ignore", under="ignore"):
        y = np.ldexp(x, k)
        back = np.ldexp(y, -np.asarray(k))
    return y, np.isfinite(y) & ((x == 0) | (np.abs(y) >= np.finfo(np.float64).tiny)) & (back == x)


def space_scaled(M: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The bodies scaled by 2^e (x -> 2^e x): the congruence by diag(1, .., 1, 2^e), and where it is exact.

    X^T M X < 0 with X = (x, 1) ~ (2^e x, 2^e): the last column and row times 2^e, the corner
    times 2^2e. Returns (M', exact): exact where the matrix is exactly symmetric (the tolerance
    for matrices symmetric up to rounding is relative to rows this changes unequally) and every
    changed entry is exact (:func:`times_power_of_two`).
    """
    d = M.shape[-1] - 1
    exact = (M == np.swapaxes(M, 1, 2)).all(axis=(1, 2))
    out = np.array(M, dtype=np.float64)
    for idx, k in (((slice(None), slice(None, d), d), e[:, None]), ((slice(None), d, slice(None, d)), e[:, None]),
                   ((slice(None), d, d), 2 * e)):
        out[idx], ok = times_power_of_two(M[idx], k)
        exact &= ok.reshape(len(e), -1).all(axis=1)
    return out, exact


def _balanced(a: np.ndarray, b: np.ndarray, shift_b: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
    """Both shapes in units of their own size: the same :func:`space_scaled` for both, per pair.

    Bodies of size s far from 1 (1e9, 1e-150) have |Q| ~ 1/s^2, |m| ~ |c|/s^2 and a corner
    ~ |c|^2/s^2: entries spread over decades that the bounds, relative to the largest entry,
    cannot follow. Scaling space by 2^e, e = -rint((S_a + S_b) / 4) with S = :func:`twice_log2_size`
    (about the geometric mean over both shapes of 1/size), keeps the relative position and brings
    them to order 1. A pair is scaled only where :func:`space_scaled` is exact for both matrices
    and for ``shift_b`` (which scales with space); else it keeps e = 0. Returns (a, b, shift_b)
    in the new units and the mask of the pairs scaled (e != 0). The compiled extension runs the
    same steps per pair in one loop (``balance`` in ``core/fixed/_filter.c``: the same integers
    and floats, ~50x faster than these array passes); this numpy code is its twin.
    """
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    if compiled.balance_available():
        return compiled.balance(a, b, shift_b)
    e = -np.rint((twice_log2_size(a) + twice_log2_size(b)) * 0.25)
    e = np.clip(e, -1000, 1000).astype(np.int64)
    if not e.any():
        return a, b, shift_b, e != 0
    a2, exact = space_scaled(a, e)
    b2, exact_b = space_scaled(b, e)
    exact &= exact_b
    if shift_b is not None:
        s = np.asarray(shift_b, dtype=np.float64)
        s2, ok = times_power_of_two(s, e[:, None])
        exact &= ok.all(axis=1)
        shift_b = np.where(exact[:, None], s2, s)
    keep = exact[:, None, None]
    return np.where(keep, a2, a), np.where(keep, b2, b), shift_b, exact & (e != 0)


def classify_translated(a: np.ndarray, b: np.ndarray, shift_b: np.ndarray | None = None) -> np.ndarray:
    """Second stage: rule ids after moving both shapes so that A is centred near the origin.

    The relation is invariant under a common translation and a common scaling. Far from the
    origin (centres at 1e6) the entries c^T Q c dominate the first stage's bound, and bodies far
    from size 1 (1e9, 1e-150) spread their entries over decades; after scaling space by a power
    of two to the bodies' size (:func:`_balanced`) and moving the origin to (a float
    approximation of) A's centre, with every entry's rounding error carried as a radius
    (:mod:`core.fixed.errorbound`, midpoint-radius), most such pairs are certified without exact
    arithmetic, by the tree or by the certificates of :mod:`core.fixed.driver`. -1 where no
    sign is proven.

    Args:
        a: float64 stack (N, n, n).
        b: the same shape.
        shift_b: optional (N, n - 1) float vectors s: classify A against B moved by exactly s
            (the periodic image of B, :mod:`core.bodies.periodic`); the translated entries of B
            carry their rounding as radii, so the answer is certified for the exact translate.
    """
    n = a.shape[-1]
    with np.errstate(all="ignore"):
        c, cr, minors, ok, VA, RA, VB, RB = _translated_pencil(a, b, shift_b)
        code, _, idx = decide(_X, n, c, cr, minors, ok)
        code = _later_stages(n, np.asarray(code, dtype=np.int64).copy(), idx, c, cr, skips_s0(_X, n, _entries(a), _entries(b)),
                             lambda rows: (_take(VA, rows), _take(RA, rows), _take(VB, rows), _take(RB, rows)))
    return code.astype(np.int8)


def _translated_pencil(a: np.ndarray, b: np.ndarray, shift_b: np.ndarray | None) -> tuple[Any, ...]:
    """The second stage's pencil on both shapes moved so that A is centred near the origin.

    Returns a_0..a_n with their bounds, the validity minors, the pairs the move applies to, and
    the translated matrices with their radii (:func:`classify_translated`, :func:`certified_valid`).
    """
    n = a.shape[-1]
    a, b, shift_b, _ = _balanced(a, b, shift_b)
    Pa = prepare(_X, n, _entries(a), "a")
    Pb = prepare(_X, n, _entries(b), "b")
    ra, rb = radii(_X, Pa.W, Pa.rounded, "a"), radii(_X, Pb.W, Pb.rounded, "b")
    ctr, _, okc = _centre(_X, n, Pa.W, "c")
    centre = np.stack(ctr, axis=1)
    ok = Pa.ok & Pb.ok & okc & np.isfinite(centre).all(axis=1) & (np.abs(centre) <= TRANSLATE_MAX).all(axis=1)
    centre = np.where(ok[:, None], centre, 0.0)  # any float vector is exact: it is the chosen t
    b_moved, radius_b = Pb.W, rb
    if shift_b is not None:  # origin at -s: B moves by +s (s is exact, entries gain radii)
        s = np.asarray(shift_b, dtype=np.float64)
        ok &= np.isfinite(s).all(axis=1) & (np.abs(s) <= TRANSLATE_MAX).all(axis=1)
        b_moved, radius_b = _translated(Pb.W, rb, np.where(ok[:, None], -s, 0.0), n)
    VA, RA = _translated(Pa.W, ra, centre, n)
    VB, RB = _translated(b_moved, radius_b, centre, n)
    fn, outputs, floor = getattr(K, f"pencil_radius{n}"), getattr(K, f"PENCIL_RADIUS{n}_OUTPUTS"), getattr(K, f"PENCIL_RADIUS{n}_FLOOR")
    res = fn(VA, RA, VB, RB)
    k = len(outputs)
    out = {name: (v, np.asarray(r) * RADIUS_FACTOR + floor) for name, v, r in zip(outputs, res[:k], res[k:], strict=True)}
    c = [out[f"c{i}"][0] for i in range(n + 1)]
    cr = [out[f"c{i}"][1] for i in range(n + 1)]
    minors = [v for key, v in out.items() if key.startswith("d")]
    return c, cr, minors, ok, VA, RA, VB, RB


def _second_stage(a: np.ndarray, b: np.ndarray, rules: np.ndarray, threads: int | None = None) -> np.ndarray:
    """Run :func:`classify_translated` on the pairs the first stage left undecided.

    The pairs that :func:`_balanced` scales (bodies far from size 1) first go through the first
    stage again in their own units (compiled, or its numpy twin: the same answers), the
    translated stage only for what it still leaves. Chunks of pairs run on the compiled filter's
    threads (each writes its own rows of ``rules``; the compiled calls release the GIL).
    """
    idx = np.flatnonzero(rules < 0)
    first = (lambda x, y: compiled.rules(x, y, threads=1)) if compiled.available() else rules_numpy

    def run(part: np.ndarray) -> None:
        A, B = np.asarray(a[part], dtype=np.float64), np.asarray(b[part], dtype=np.float64)
        A2, B2, _, moved = _balanced(A, B, None)
        if moved.any():
            if moved.all():
                rules[part] = first(A2, B2)
            else:
                rows = np.flatnonzero(moved)
                rules[part[rows]] = first(A2[rows], B2[rows])
            left = rules[part] < 0
            part, A, B = part[left], A[left], B[left]
        if part.size:
            rules[part] = classify_translated(A, B)

    chunks = [idx[s : s + _CHUNK] for s in range(0, idx.size, _CHUNK)]
    k = min(threads or compiled.get_threads(), len(chunks))
    if k <= 1:
        for part in chunks:
            run(part)
    else:
        for f in [compiled.pool(k).submit(run, part) for part in chunks]:
            f.result()
    return rules


# -------------------------------------------------------------------------------------------
# entry points


def rules_float(a: np.ndarray, b: np.ndarray, *, scalar: bool = False, threads: int | None = None) -> np.ndarray:
    """Rule ids (int8; -1 where no sign is proven) for float64 or float32 stacks (N, n, n), n = 3 or 4.

    Not validated here: invalid or non-finite pairs come back -1 so that the exact path reports
    the error. The compiled extension serves (loaded at import; the numpy code only as the last
    resort, with a warning), then the second stage on what is left, except for a single pair
    (exact arithmetic is as fast as numpy on one pair).
    """
    if compiled.available():
        rules = compiled.rules(a, b, threads=threads)
    else:
        rules = rules_numpy(a, b)
    if not scalar and (rules < 0).any():
        rules = _second_stage(a, b, rules, threads)
    return rules


def classify_float(a: np.ndarray, b: np.ndarray, *, scalar: bool = False, threads: int | None = None) -> np.ndarray:
    """Certified float classification of stacked pairs; UNDECIDED where no sign is proven.

    Args:
        a: float64 or float32 array (N, n, n), n = 3 or 4 (float32 is certified for its own
            values: widening to float64 is exact).
        b: the same shape and type as ``a``.
        scalar: N == 1 (skips the second stage).
        threads: threads for the compiled kernels (None: :func:`core.fixed.compiled.get_threads`).

    Returns:
        int8 codes of :class:`Relation`, shape (N,). Never a wrong label.
    """
    return classify_float_counted(a, b, scalar=scalar, threads=threads)[0]


def classify_float_counted(a: np.ndarray, b: np.ndarray, *, scalar: bool = False, threads: int | None = None) -> tuple[np.ndarray, bool]:
    """:func:`classify_float` and whether every pair is decided.

    True: no UNDECIDED code, known without a pass over the codes (the compiled kernels count the
    pairs they leave); False: some may be undecided.
    """
    if not compiled.available():
        codes = relations(rules_float(a, b, scalar=scalar, threads=threads))
        return codes, False
    # the compiled kernels write the relation codes directly and count the undecided pairs
    codes, undecided = compiled.mapped(a, b, _RELATION_OF, threads=threads)
    if not scalar and undecided:
        idx = np.flatnonzero(codes == Relation.UNDECIDED)
        rules = np.full(idx.size, -1, dtype=np.int8)
        codes[idx] = relations(_second_stage(a[idx], b[idx], rules, threads))
    return codes, undecided == 0
