"""The float filter's driver, written once for numpy and for C: prepare, tree, s0, certificates.

Everything between the matrix entries of a pair and its rule id, as straight-line code on lanes
(one value per pair) through the operations ``x`` of :mod:`core.fixed.lanes`. Run with
:class:`~core.fixed.lanes.NumpyLanes` it is the numpy filter (:mod:`core.fixed.filters`); run with
:class:`~core.fixed.lanes.CLanes` it writes the C lane functions of ``core/fixed/_kernels.h``
(:mod:`core.fixed.kernelgen`), which ``core/fixed/_filter.h`` calls over blocks of pairs, SIMD
lanes across pairs. One description, so a certificate is changed in one place, and the two
agree bit for bit (``tests/test_filters.py``). The straight-line kernels it calls (pencil, s0,
P(T), X^T M X) are traced from the ring-generic formulas with their error constants
(:mod:`core.fixed.errorbound`).

Stages of one pair (the C runs each over many pairs at a time, the later ones only on the pairs
the earlier ones left open):

1. :func:`prepare` both matrices, :func:`pencil_bounds` (a_0..a_n and the validity minors with
   proven bounds), :func:`decide` (validity, and the paper's tree looked up in
   :data:`core.formulae.decision.TABLE3` / ``TABLE4`` with s0 pending);
2. where the tree asks for s0: :func:`decide_s0`, the semi-static test (one evaluation of hs0
   and one of its permanent, for a_i known to relative accuracy 2^-20: random pairs); not for
   ellipsoids whose quadratic blocks look proportional (:func:`skips_s0`: spheres, translated
   and homothetic copies, whose s0 vanishes), which go on as if it had failed;
3. where a valid pair is still open (s0 vanishes identically for spheres and translated or
   homothetic copies): :func:`certify_sep` (a T* > 0 with P(T*) > 0 guessed from the a_i and
   the traces: one division), then on the pairs still open :func:`certify` (a T* from the
   centres, or a point inside both);
4. where s0 is still needed and stage 2 could not tell its sign (near tangency):
   :func:`decide_s0_radius`, the running-error test (a radius for every operation).

Cheap tests first, each later one only on the pairs the earlier ones left (CGAL's static filter
before the dynamic one): the answers are certified whichever stage gives them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..formulae.decision import NEED_S0, TABLE3, TABLE4, rule_by_key
from ..shapes.quadrics import SYMMETRY_TOLERANCE
from .errorbound import (
    CERT_T_MAX,
    CERT_T_MIN,
    LEAF_MAX,
    NO_SCALE_MIN,
    RADIUS_FACTOR,
    S0_RHO,
    TRANSLATE_MAX,
)

__all__ = [
    "Prepared",
    "prepare",
    "radii",
    "pencil_bounds",
    "decide",
    "skips_s0",
    "decide_s0",
    "decide_s0_radius",
    "centre",
    "quad",
    "certify_sep",
    "certify",
    "TABLES",
    "RULE_SEP",
    "RULE_POINT",
    "NEEDS_S0",
    "NEEDS_CERT",
    "NEEDS_FULL",
    "NEEDS_S0_RADIUS",
    "NEEDS_SCALE",
    "LEAF_ROUNDING",
    "LEAF_UNDERFLOW",
]

TABLES = {n: t.reshape(-1, 5, 25)[:, :, 24].reshape(-1).astype(np.int64) for n, t in ((3, TABLE3), (4, TABLE4))}
"""The paper's tree with s1 and s1,0 pending (all the filter asks), indexed by 5 idx + digit of s0
(digit 4: pending): :data:`core.formulae.decision.TABLE3` / ``TABLE4`` at ``table_index(...)``,
small enough for the L1 cache and for SIMD gathers."""
RULE_SEP = rule_by_key("sep-witness").id
RULE_POINT = rule_by_key("common-point").id
NEEDS_S0 = NEED_S0
"""Stage-1 outcome: valid, the tree asks for s0."""
NEEDS_CERT = -8
"""Outcome: valid, the tree cannot decide: try the certificates."""
NEEDS_FULL = -9
"""Outcome of the fast first pass: a matrix is finite but not exactly symmetric: the full prepare."""
NEEDS_S0_RADIUS = -10
"""Outcome of :func:`decide_s0`: the semi-static test could not tell the sign of s0: the
certificates, then :func:`decide_s0_radius`."""

NEEDS_SCALE = -11
"""Outcome of the C's unscaled first pass: a matrix's largest entry is outside [2^-8, 2^24] (or
the matrix is not exactly symmetric, or not finite): the scaled fast pass decides."""

LEAF_ROUNDING = 2.0**-52
"""Radius of a rounded half sum, relative: 2^-52 >= u / (1 - u)."""
LEAF_UNDERFLOW = 1.0e-323
""">= 2^-1073: a scaled entry rounded in the subnormal range."""
_TOL2 = float(SYMMETRY_TOLERANCE) ** 2
PROPORTIONAL = 2.0**-40
"""Relative tolerance of :func:`skips_s0`: far above the rounding of copies built in floats (a
few units of 2^-53), far below the difference of two shapes that are not copies."""
_DBL_MAX = 1.7976931348623157e308


@dataclass
class Prepared:
    """One matrix per lane as the filter reads it."""

    W: dict[tuple[int, int], Any]
    """Upper triangle of 2^k * sign * (symmetric part of M): a negative interior, largest entry
    in [2^-8, 2^24] (or at most 2), exact for an exactly symmetric M, else rounded half sums."""
    k: Any
    """The exponent k (int per lane): W = 2^k * sign * S."""
    ok: Any
    """Mask: finite, M_00 != 0, symmetric or clearly within the tolerance."""
    rounded: Any
    """Mask: W holds rounded half sums (radii :func:`radii`, the rounded-leaf constants)."""
    open: Any
    """Mask (``exact_only``): finite but not exactly symmetric, left to the full prepare;
    (``unscaled``) not prepared by the unscaled pass, left to the scaled one."""
    sign: Any = None
    """``unscaled`` only: -1.0 where M_00 < 0, else 1.0, the flip to a negative interior that W
    does not carry (:func:`pencil_bounds` applies it to the results)."""


def prepare(x: Any, n: int, entry: Any, tag: str, *, exact_only: bool = False, unscaled: bool = False) -> Prepared:
    """Validate cheaply, flip to a negative interior, scale by a power of two, symmetrise.

    ``exact_only``: the fast first pass of the C, for exactly symmetric matrices only (most
    inputs): it skips the tolerance test and the half sums and marks the other finite matrices
    ``open`` for the full prepare. On an exactly symmetric matrix both give the same W.

    ``unscaled`` (with ``exact_only``; the C's first try): only exactly symmetric matrices whose
    largest entry is already in [2^-8, 2^24] (k = 0, most inputs) are prepared, the others are
    ``open`` for the scaled pass. W is M itself, not sign * M: the sign is applied to the
    pencil's results instead (:func:`pencil_bounds`), which is the same rounding, so the values
    are bit for bit those of the scaled pass; the pass skips the exponent, the scale and the
    2 n^2 products.

    ``entry(i, j)`` reads M[i, j] of each lane as float64 (a float32 input is widened exactly).
    The scale 2^k (k = 1 - e, M's largest |entry| in [2^(e-1), 2^e)) is applied unless that
    entry is already in [2^-8, 2^24]; k is clamped to [-1022, 2044] and applied in two exact
    factors, so the only rounding is a result in the subnormal range (the kernels' underflow
    floor covers it). The tolerance test is conservative: (d^2 (1 + 2^-48) <= tol^2 m_i m_j
    (1 - 2^-48), with tol^2 m_i m_j >= 2^-1000) on the scaled values implies the exact rule of
    :data:`core.shapes.quadrics.SYMMETRY_TOLERANCE`.
    """
    idx = [(i, j) for i in range(n) for j in range(i, n)]
    off = [(i, j) for i, j in idx if i != j]
    X = {(i, j): x.let(f"{tag}x{i}{j}", entry(i, j)) for i, j in idx}
    Y = {(i, j): x.let(f"{tag}y{i}{j}", entry(j, i)) for i, j in off}
    # the fast pass reads the upper triangle for the scale and the finiteness: a lower entry
    # that differs (NaN included) makes the matrix not exactly symmetric, left to the full pass
    values = [*X.values()] if exact_only else [*X.values(), *Y.values()]
    mx, all_finite = x.abs_max_finite(f"{tag}mx", values)
    mx = x.let(f"{tag}mx", mx)
    finite = x.let(f"{tag}finite", all_finite & (X[0, 0] != 0.0))
    in_range = (mx >= float(NO_SCALE_MIN)) & (mx <= float(LEAF_MAX))
    sym = X[off[0]] == Y[off[0]]
    for ij in off[1:]:
        sym = sym & (X[ij] == Y[ij])
    sym = x.let(f"{tag}sym", sym)
    if unscaled:
        ok = x.let(f"{tag}ok", finite & in_range & sym)
        sign = x.let(f"{tag}sign", x.where(X[0, 0] < 0.0, -1.0, 1.0))
        return Prepared(dict(X), x.integer(0, mx), ok, ok & ~ok, x.let(f"{tag}open", ~ok), sign)
    e = x.frexp_exponent(x.where(finite, mx, 1.0))
    k = x.let(f"{tag}k", x.where(in_range, x.integer(0, mx), x.imin(x.imax(1 - e, -1022), 2044)))
    k1 = x.let(f"{tag}k1", x.imin(k, 1000))
    # the sign flip to a negative interior rides on the first factor (exact either way)
    g1 = x.let(f"{tag}g1", x.where(X[0, 0] < 0.0, -x.pow2(k1), x.pow2(k1)))
    if exact_only:
        # one exact factor (2^k1 = 2^k unless the largest entry is below 2^-999: the full pass)
        W = {ij: x.let(f"{tag}w{ij[0]}{ij[1]}", v * g1) for ij, v in X.items()}
        fast = x.let(f"{tag}fast", sym & (mx >= 2.0**-1000))  # i.e. k <= 1000: g2 = 1
        return Prepared(W, k, x.let(f"{tag}ok", finite & fast), sym & ~sym, x.let(f"{tag}open", finite & ~fast))
    g2 = x.let(f"{tag}g2", x.pow2(k - k1))
    XS = {ij: x.let(f"{tag}X{ij[0]}{ij[1]}", (v * g1) * g2) for ij, v in X.items()}
    YS = {ij: x.let(f"{tag}Y{ij[0]}{ij[1]}", (v * g1) * g2) for ij, v in Y.items()}
    m = []
    for i in range(n):
        row = [XS[min(i, j), max(i, j)] for j in range(n)] + [YS[min(i, j), max(i, j)] for j in range(n) if j != i]
        acc = x.abs(row[0])
        for v in row[1:]:
            acc = x.max(acc, x.abs(v))
        m.append(x.let(f"{tag}m{i}", acc))
    near = None
    for i, j in off:
        d = x.let(f"{tag}d{i}{j}", x.abs(XS[i, j] - YS[i, j]))
        r = x.let(f"{tag}r{i}{j}", (_TOL2 * m[i]) * m[j])
        term = (X[i, j] == Y[i, j]) | ((r >= 2.0**-1000) & (((d * d) * (1 + 2.0**-48)) <= (r * (1 - 2.0**-48))))
        near = term if near is None else near & term
    ok = x.let(f"{tag}ok", finite & (sym | near))
    rounded = x.let(f"{tag}rounded", ok & ~sym)
    W = {}
    for i, j in idx:
        if i == j:
            W[i, j] = XS[i, j]
        else:
            W[i, j] = x.let(f"{tag}w{i}{j}", x.where(sym, XS[i, j], (XS[i, j] * 0.5) + (YS[i, j] * 0.5)))
    return Prepared(W, k, ok, rounded, sym & ~sym)


def radii(x: Any, W: dict[tuple[int, int], Any], rounded: Any, tag: str) -> dict[tuple[int, int], Any]:
    """Radius of each prepared entry: 0 when exact, else |w| 2^-52 + 1e-323 (a rounded half sum)."""
    return {ij: x.let(f"{tag}q{ij[0]}{ij[1]}", x.where(rounded, (x.abs(w) * LEAF_ROUNDING) + LEAF_UNDERFLOW, 0.0)) for ij, w in W.items()}


def pencil_bounds(x: Any, n: int, Pa: Prepared, Pb: Prepared) -> tuple[list[Any], list[Any], list[tuple[Any, Any]]]:
    """a_0..a_n of P(T) = det(T A + B) with certified radii, and the validity minors with bounds.

    ``|error of x| <= C_x * x_M + floor`` (permanent style, :mod:`core.fixed.errorbound`); the
    constants of rounded leaves apply to a pair with a rounded matrix.
    """
    name = f"pencil{n}"
    info = x.info(name)
    rounded = x.let("rounded", Pa.rounded | Pb.rounded)
    r = x.call(name, [x.matrix(Pa.W, n, "wa"), x.matrix(Pb.W, n, "wb")])
    F = x.let("F", x.where(rounded, info.floor_rounded, info.floor))
    values: dict[str, tuple[Any, Any]] = {}
    for k, out in enumerate(info.outputs):
        if out.endswith("_M"):
            continue
        C = x.where(rounded, info.constants_rounded[k], info.constants[k])
        values[out] = (x.let(out, r[k]), x.let(f"{out}r", (C * r[k + 1]) + F))
    if Pa.sign is not None:  # unscaled W: a value of degree d in A's entries takes sign_A^d
        sab = None
        for key, (v, bound) in list(values.items()):
            odd_a, odd_b = (d % 2 == 1 for d in _degrees(key, n))
            if odd_a and odd_b:
                sab = sab if sab is not None else x.let("sab", Pa.sign * Pb.sign)
                values[key] = (x.let(f"{key}s", v * sab), bound)
            elif odd_a or odd_b:
                values[key] = (x.let(f"{key}s", v * (Pa.sign if odd_a else Pb.sign)), bound)
    c = [values[f"c{i}"][0] for i in range(n + 1)]
    cr = [values[f"c{i}"][1] for i in range(n + 1)]
    minors = [v for key, v in values.items() if key.startswith("d")]
    return c, cr, minors


def _degrees(key: str, n: int) -> tuple[int, int]:
    """Degrees in A's and in B's entries of a pencil output: ``c{i}`` (i, n - i), ``dA{k}`` (k, 0), ``dB{k}`` (0, k)."""
    if key[0] == "c":
        return int(key[1:]), n - int(key[1:])
    k = int(key[2:])
    return (k, 0) if key[1] == "A" else (0, k)


def decide(x: Any, n: int, c: list[Any], cr: list[Any], minors: list[tuple[Any, Any]], ok: Any) -> tuple[Any, Any, Any]:
    """Validity and the tree with s0 pending: (code, valid, idx).

    Valid: both matrices prepared, the leading minors of both quadratic blocks positive
    (Sylvester) and a_n < 0, a_0 < 0 (det A < 0, det B < 0), all certified. ``code`` is a rule
    id, :data:`NEEDS_S0` or :data:`NEEDS_CERT` for a valid pair, -1 for the others; ``idx`` the
    table index of the middle signs a_{n-1}..a_1 (base-5 digits: 0 for -, 2 for +, 3 uncertain).
    """
    valid = ok
    for v, bound in minors:
        valid = valid & (v > bound)
    valid = x.let("valid", valid & (c[n] < -cr[n]) & (c[0] < -cr[0]))
    idx = x.digit(c[n - 1], cr[n - 1])
    for i in range(n - 2, 0, -1):
        idx = (idx * 5) + x.digit(c[i], cr[i])
    idx = x.let("idx", idx)
    code = x.let("code", x.table(TABLES[n], f"TAB{n}", (idx * 5) + 4))
    open_ = x.where(code == NEED_S0, NEEDS_S0, NEEDS_CERT)
    return x.let("first", x.where(valid, x.where(code >= 0, code, open_), -1)), valid, idx


def skips_s0(x: Any, n: int, entry_a: Any, entry_b: Any) -> Any:
    """Mask (3D; False in 2D): stage 2 is skipped, the blocks' diagonals being proportional.

    The diagonals of the quadratic blocks of A and B as given, within :data:`PROPORTIONAL`:
    |b_ii tA - a_ii tB| <= 2^-40 |tA tB|, tA and tB the traces. Where Q_B = rho Q_A (spheres, translated and homothetic copies), P(T) = (T + rho)^2 q(T) in
    3D: s0 vanishes and no bound can tell its sign, so the semi-static test would only fail. Such
    a pair goes on as if it had (its code NEEDS_S0_RADIUS): the certificates, then the
    running-error test of s0. A routing choice from the pair's own entries (the same for every
    prepare: a flip of sign or a power-of-two scale changes no comparison), not a proof: every
    stage is certified, and a pair whose diagonals alone are proportional only loses the cheaper
    test of s0. In 2D P is (T + rho) q(T) and s0 is generic: stage 2 is kept.
    """
    if n != 4:
        return False
    d = n - 1
    da = [x.let(f"pa{i}", entry_a(i, i)) for i in range(d)]
    db = [x.let(f"pb{i}", entry_b(i, i)) for i in range(d)]
    ta = x.let("pta", (da[0] + da[1]) + da[2])
    tb = x.let("ptb", (db[0] + db[1]) + db[2])
    bound = x.let("pbound", x.abs(ta * tb) * PROPORTIONAL)
    out = x.abs((db[0] * ta) - (da[0] * tb)) <= bound
    for i in range(1, d):
        out = out & (x.abs((db[i] * ta) - (da[i] * tb)) <= bound)
    return x.let("skip", out)


def decide_s0(x: Any, n: int, c: list[Any], cr: list[Any], idx: Any) -> Any:
    """The tree with the sign of s0 from the semi-static test (stage 2).

    Where every a_i is known to relative accuracy rho = :data:`~core.fixed.errorbound.S0_RHO`
    (cr_i 2^20 <= |a_i|, exact: cr_i is at least the pencil's underflow floor, so the product by
    2^20 stays normal), |fl(hs0) - hs0| <= C M + floor with M the permanent of hs0 evaluated
    alongside (:func:`core.fixed.errorbound.relative_input_constant`): two evaluations of a
    30-operation program instead of a radius for every operation. Returns a rule id or
    :data:`NEEDS_S0_RADIUS` (the sign of s0 not told here, or the tree still open with it: one
    outcome, so that the compiler keeps the loop branch-free).
    """
    name = f"hat_s0_rel_{n}"
    info = x.info(name)
    v, m = x.call(name, [x.vector(c, "c")])
    inv_rho = float(1 / S0_RHO)
    accurate = (cr[0] * inv_rho) <= x.abs(c[0])
    for i in range(1, n + 1):
        accurate = accurate & ((cr[i] * inv_rho) <= x.abs(c[i]))
    # where the a_i are not accurate enough the bound is the largest float: digit 3 (a select
    # of the bound, not of the digit: the compiler keeps the loop branch-free)
    bound = x.let("s0b", x.where(accurate, (m * info.constants[0]) + info.floor, _DBL_MAX))
    digit = x.let("s0d", x.digit(v, bound))
    code = x.let("code_s0", x.table(TABLES[n], f"TAB{n}", (idx * 5) + digit))
    # open: s0 unknown, or known and the tree still open (rare: the later stages end the same way)
    return x.where(code >= 0, code, NEEDS_S0_RADIUS)


def decide_s0_radius(x: Any, n: int, c: list[Any], cr: list[Any], idx: Any) -> Any:
    """The tree with the sign of s0 from the running-error test (stage 4: near tangency).

    Midpoint-radius arithmetic on the a_i with their radii (every operation carries a bound):
    tighter than :func:`decide_s0` where the a_i are inaccurate or s0 is small. Returns a rule
    id, or :data:`NEEDS_CERT` when s0 is not certified.
    """
    name = f"hat_s0_{n}"
    v, r = x.call(name, [x.vector(c, "c"), x.vector(cr, "cr")])
    bound = x.let("s0r", (r * RADIUS_FACTOR) + x.info(name).floor)
    code = x.let("code_s0", x.table(TABLES[n], f"TAB{n}", (idx * 5) + x.digit(v, bound)))
    return x.where(code >= 0, code, NEEDS_CERT)


def centre(x: Any, n: int, W: dict[tuple[int, int], Any], tag: str) -> tuple[list[Any], Any, Any]:
    """Float centre (Q c = -m, by the adjugate and one division), scale k = -m.c - M_dd and the mask det Q > 0.

    Estimates: the certificates (and the bounding spheres of :mod:`core.bodies.bounds`) hold
    for any float centre.
    """
    def w(i: int, j: int) -> Any:
        return W[min(i, j), max(i, j)]

    if n == 3:
        a00, a01, a11 = w(1, 1), -w(0, 1), w(0, 0)
        det = x.let(f"{tag}det", (w(0, 0) * w(1, 1)) - (w(0, 1) * w(0, 1)))
        inv = x.let(f"{tag}inv", -1.0 / det)
        m0, m1 = w(0, 2), w(1, 2)
        ctr = [x.let(f"{tag}c0", ((a00 * m0) + (a01 * m1)) * inv), x.let(f"{tag}c1", ((a01 * m0) + (a11 * m1)) * inv)]
        k = x.let(f"{tag}k", -((m0 * ctr[0]) + (m1 * ctr[1])) - w(2, 2))
    else:
        a00 = x.let(f"{tag}a00", (w(1, 1) * w(2, 2)) - (w(1, 2) * w(1, 2)))
        a01 = x.let(f"{tag}a01", (w(0, 2) * w(1, 2)) - (w(0, 1) * w(2, 2)))
        a02 = x.let(f"{tag}a02", (w(0, 1) * w(1, 2)) - (w(0, 2) * w(1, 1)))
        a11 = x.let(f"{tag}a11", (w(0, 0) * w(2, 2)) - (w(0, 2) * w(0, 2)))
        a12 = x.let(f"{tag}a12", (w(0, 1) * w(0, 2)) - (w(0, 0) * w(1, 2)))
        a22 = x.let(f"{tag}a22", (w(0, 0) * w(1, 1)) - (w(0, 1) * w(0, 1)))
        det = x.let(f"{tag}det", ((w(0, 0) * a00) + (w(0, 1) * a01)) + (w(0, 2) * a02))
        inv = x.let(f"{tag}inv", -1.0 / det)
        m0, m1, m2 = w(0, 3), w(1, 3), w(2, 3)
        ctr = [
            x.let(f"{tag}c0", (((a00 * m0) + (a01 * m1)) + (a02 * m2)) * inv),
            x.let(f"{tag}c1", (((a01 * m0) + (a11 * m1)) + (a12 * m2)) * inv),
            x.let(f"{tag}c2", (((a02 * m0) + (a12 * m1)) + (a22 * m2)) * inv),
        ]
        k = x.let(f"{tag}k", -(((m0 * ctr[0]) + (m1 * ctr[1])) + (m2 * ctr[2])) - w(3, 3))
    return ctr, k, det > 0.0


def quad(x: Any, n: int, W: dict[tuple[int, int], Any], u: list[Any]) -> Any:
    """u^T Q u: the diagonal terms, then 2 w_ij u_i u_j."""
    d = n - 1
    acc = (W[0, 0] * u[0]) * u[0]
    for i in range(1, d):
        acc = acc + ((W[i, i] * u[i]) * u[i])
    for i in range(d):
        for j in range(i + 1, d):
            acc = acc + (((2.0 * W[i, j]) * u[i]) * u[j])
    return acc


def certify_sep(
    x: Any, n: int, WA: dict[tuple[int, int], Any], WB: dict[tuple[int, int], Any], c: list[Any], cr: list[Any],
    signs: tuple[Any, Any] | None = None,
) -> Any:
    """Rule id sep-witness or -1: a T* > 0 with P(T*) > 0 guessed from the a_i alone (stage 3a).

    The cheap first try of the certificates, before :func:`certify`. Where the quadratic blocks
    are proportional, Q_B = rho Q_A (spheres, translated and homothetic copies: the pairs whose
    s0 vanishes identically), P(T) = (T + rho)^(d-1) q(T) with q quadratic, and the two positive
    roots of P (a separate pair) are those of q, around the vertex T* = -e1 / (2 e2) of q, where
    e2 = a_n and e1 = a_{n-1} - (d-1) rho a_n: T* = ((d-1) rho a_n - a_{n-1}) / (2 a_n), with
    rho = tr Q_B / tr Q_A from the prepared matrices. T* is only a guess (one division, no
    centre): it is verified as :func:`certify` verifies its own, P(T*) > 0 certified with a_n,
    a_0 < 0 (a valid pair), so a pair of any shape gains a certificate where the guess holds and
    loses nothing where it does not (the full certificates follow).

    ``signs``: the flips to a negative interior that W does not carry (the unscaled first pass,
    :attr:`Prepared.sign`); times +-1 is exact, so the traces are those of the prepared matrices.
    """
    d = n - 1
    ta = WA[0, 0]
    tb = WB[0, 0]
    for i in range(1, d):
        ta = ta + WA[i, i]
        tb = tb + WB[i, i]
    if signs is not None:
        ta, tb = ta * signs[0], tb * signs[1]
    # T* = ((d-1) tb a_n - ta a_{n-1}) / (2 ta a_n): rho = tb / ta folded into one division
    num = (((2.0 * tb) if d == 3 else tb) * c[n]) - (ta * c[n - 1])
    T = x.let("Tq", num / ((2.0 * ta) * c[n]))
    tin = x.let("tqin", (T >= float(CERT_T_MIN)) & (T <= float(CERT_T_MAX)))
    name = f"pencil_at{n}"
    p, pr = x.call(name, [x.vector(c, "c"), x.vector(cr, "cr")], [x.where(tin, T, 1.0)])
    sep = x.let("sepq", tin & (p > ((pr * RADIUS_FACTOR) + x.info(name).floor)))
    return x.let("certq", x.where(sep, RULE_SEP, -1))


def certify(
    x: Any, n: int, WA: dict[tuple[int, int], Any], RA: dict[tuple[int, int], Any],
    WB: dict[tuple[int, int], Any], RB: dict[tuple[int, int], Any], c: list[Any], cr: list[Any],
) -> Any:
    """Rule id (sep-witness, common-point) or -1, for a valid pair the tree left open.

    Candidates from the shapes' centres: with tA, tB the distances (in units of the centre
    segment) from each centre to its own boundary along the segment, T* = (tA/tB)(kB/kA) is the
    Perram-Wertheim optimum for spheres and for translated or homothetic copies, and the point
    at tA / (tA + tB) of the segment lies inside both exactly when such shapes overlap. Both
    are then verified with certified bounds (P(T*) > 0 with a_n, a_0 < 0: two positive roots;
    X^T M X < 0 for both); a wrong guess only abstains. Every operation is unconditional (NaN
    or inf where a guess makes no sense) and then selected: no control flow, so it vectorises.
    """
    d = n - 1
    ca, ka, oka = centre(x, n, WA, "ca")
    cb, kb, okb = centre(x, n, WB, "cb")
    ok = x.let("ok", ((oka & okb) & (ka > 0.0)) & (kb > 0.0))
    u = [x.let(f"u{i}", cb[i] - ca[i]) for i in range(d)]
    qa = x.let("qa", quad(x, n, WA, u))
    qb = x.let("qb", quad(x, n, WB, u))
    pos = x.let("pos", (qa > 0.0) & (qb > 0.0))
    # tA = sqrt(kA / qA), tB = sqrt(kB / qB), so T* = (tA / tB)(kB / kA) = sqrt(qB kB / (qA kA))
    # and tA / (tA + tB) = kA T* / (kA T* + kB): one square root and two divisions
    T = x.let("T", x.sqrt((qb * kb) / (qa * ka)))
    tin = x.let("tin", (pos & (T >= float(CERT_T_MIN))) & (T <= float(CERT_T_MAX)))
    name = f"pencil_at{n}"
    p, pr = x.call(name, [x.vector(c, "c"), x.vector(cr, "cr")], [x.where(tin, T, 1.0)])
    sep = x.let("sep", (ok & tin) & (p > ((pr * RADIUS_FACTOR) + x.info(name).floor)))
    kT = x.let("kT", ka * T)
    s = x.let("s", x.where(pos, kT / (kT + kb), 0.0))  # concentric shapes: A's centre
    pt = [x.let(f"x{i}", ca[i] + (s * u[i])) for i in range(d)]
    xin = x.abs(pt[0]) <= float(TRANSLATE_MAX)
    for i in range(1, d):
        xin = xin & (x.abs(pt[i]) <= float(TRANSLATE_MAX))
    xin = x.let("xin", xin)
    pt = [x.let(f"xs{i}", x.where(xin, pt[i], 0.0)) for i in range(d)]
    # X^T M X with its bound f * Q(|M| g + R, |x|) (core.fixed.errorbound.form_constants)
    name = f"form{n}"
    info = x.info(name)
    g, f = info.constants
    point = x.vector(pt, "pt")
    fa, fma = x.call(name, [x.matrix(WA, n, "fwa"), x.matrix(RA, n, "fra"), point], [g])
    fb, fmb = x.call(name, [x.matrix(WB, n, "fwb"), x.matrix(RB, n, "frb"), point], [g])
    inside = (fa < -((fma * f) + info.floor)) & (fb < -((fmb * f) + info.floor))
    return x.let("cert", x.where(sep, RULE_SEP, x.where((ok & xin) & inside, RULE_POINT, -1)))
