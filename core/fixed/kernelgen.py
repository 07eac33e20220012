"""Generate ``core/fixed/_kernels.py`` and ``core/fixed/_kernels.c``: the float filter's kernels.

They are traced from the generic formulas, with the per-pair C driver and the decision tables.

Run ``python -m core.fixed.kernelgen`` after changing :mod:`core.formulae.pencil`, :mod:`core.formulae.subresultants`,
:mod:`core.fixed.errorbound` or :mod:`core.formulae.decision`; ``tests/test_filters.py`` fails if the committed
files are not what this module generates. Committing the generated text (instead of ``exec`` at
import) keeps every line of the fast path readable and lets the compiled library be cached by
the hash of its source (:mod:`core.fixed.compiled`).
"""

from __future__ import annotations

import re
import sys
from collections.abc import Sequence
from fractions import Fraction
from functools import cache
from pathlib import Path
from typing import Any

from ..formulae.pencil import determinant, pencil_coefficients, poly_mul
from ..formulae.subresultants import hat_s0, hat_s1, hat_s10
from ..shapes.quadrics import SYMMETRY_TOLERANCE, origin_moved
from .errorbound import (
    CERT_T_MAX,
    CERT_T_MIN,
    LEAF_MAX,
    NO_SCALE_MIN,
    RADIUS_FACTOR,
    TRANSLATE_MAX,
    Kernel,
    build_kernel,
)

__all__ = [
    "pencil_kernel",
    "pencil_radius_kernel",
    "pencil_at_kernel",
    "form_kernel",
    "translate_kernel",
    "subresultant_kernel",
    "generate_module",
    "generate_c",
    "c_function",
    "GENERATED_PATH",
    "GENERATED_C_PATH",
    "HATS",
]

GENERATED_PATH = Path(__file__).with_name("_kernels.py")
HATS = {"s0": hat_s0, "s1": hat_s1, "s10": hat_s10}


def _leaf(prefix: str, i: int, j: int) -> str:
    i, j = min(i, j), max(i, j)
    return f"{prefix}{i}{j}"


def _leaf_names(n: int) -> list[str]:
    return [_leaf(p, i, j) for p in "ab" for i in range(n) for j in range(i, n)]


def _row_bound_poly(A: list[list[Any]], B: list[list[Any]]) -> list[Any]:
    """Coefficients of prod_i (T ra_i + rb_i), ra_i = sum_j |A_ij|: >= the permanent of each a_k."""
    poly: list[Any] = []
    for i in range(len(A)):
        ra = sum((abs(x) for x in A[i][1:]), abs(A[i][0]))
        rb = sum((abs(x) for x in B[i][1:]), abs(B[i][0]))
        poly = [rb, ra] if not poly else poly_mul(poly, [rb, ra])
    return poly


@cache
def pencil_kernel(n: int, leaf_K: int = 0) -> Kernel:
    """Kernel ``pencil{n}(A, B)``: a_0..a_n and the validity minors, each with a ``_M`` bound.

    Outputs, in order: c0, c0_M, ..., cn, cn_M, dA2, dA2_M[, dA3, dA3_M], dB2, dB2_M[, dB3, dB3_M].
    ``x_M`` bounds the permanent of ``x`` (products of absolute row sums), so the error of ``x``
    is at most ``constant * x_M`` (see :mod:`core.fixed.errorbound`). ``leaf_K = 1`` gives the
    constants for entries that are correctly rounded values (a matrix symmetrised in floats);
    the source is the same.
    """

    def formula(L: dict[str, Any]) -> dict[str, Any]:
        A = [[L[_leaf("a", i, j)] for j in range(n)] for i in range(n)]
        B = [[L[_leaf("b", i, j)] for j in range(n)] for i in range(n)]
        out: dict[str, Any] = {}
        for i, (c, m) in enumerate(zip(pencil_coefficients(A, B), _row_bound_poly(A, B), strict=False)):
            out[f"c{i}"] = c
            out[f"c{i}_M"] = m
        for name, M in (("A", A), ("B", B)):
            rows = [sum((abs(x) for x in M[i][1 : n - 1]), abs(M[i][0])) for i in range(n - 1)]
            for k in range(2, n):
                out[f"d{name}{k}"] = determinant([row[:k] for row in M[:k]])
                bound = rows[0]
                for r in rows[1:k]:
                    bound = bound * r
                out[f"d{name}{k}_M"] = bound
        return out

    names = _leaf_names(n)
    exprs = {nm: (f"{nm[0].upper()}[{nm[1]}, {nm[2]}]", "") for nm in names}
    return build_kernel(
        f"pencil{n}",
        names,
        formula,
        style="permanent",
        leaf_max={nm: Fraction(LEAF_MAX) for nm in names},
        leaf_exprs=exprs,
        params=["A", "B"],
        leaf_K=leaf_K,
    )


@cache
def translate_kernel(n: int) -> Kernel:
    """Kernel ``translate{n}(M, Mr, t)`` (midpoint-radius): upper triangle of G^T M G, G = [[I, t], [0, 1]].

    Moves the origin to the point t (both shapes of a pair get the same t: the relation is
    invariant). Entries carry radii Mr (0 for exact inputs; a symmetrised matrix has rounded
    entries); t is exact; outputs carry certified radii. Leaves: entries of
    the prepared matrix (|.| <= LEAF_MAX) and t (|t_i| <= TRANSLATE_MAX).
    """
    d = n - 1
    names = [_leaf("m", i, j) for i in range(n) for j in range(i, n)] + [f"t{i}" for i in range(d)]

    def formula(L: dict[str, Any]) -> dict[str, Any]:
        M = [[L[_leaf("m", i, j)] for j in range(n)] for i in range(n)]
        moved = origin_moved(M, [L[f"t{i}"] for i in range(d)])
        out = {_leaf("m", i, j): moved[i][j] * 1 for i in range(d) for j in range(i, d)}  # Q unchanged (exact)
        out.update({_leaf("m", i, d): moved[i][d] for i in range(n)})  # (Q t + m)_i, then the constant
        return out

    exprs = {nm: (f"M[{nm[1]}, {nm[2]}]", f"Mr[{nm[1]}, {nm[2]}]") for nm in names if nm[0] == "m"}
    exprs.update({f"t{i}": (f"t[{i}]", "0.0") for i in range(d)})
    leaf_max = {nm: Fraction(LEAF_MAX) for nm in names if nm[0] == "m"}
    leaf_max.update({f"t{i}": Fraction(TRANSLATE_MAX) for i in range(d)})
    return build_kernel(
        f"translate{n}", names, formula, style="radius", leaf_max=leaf_max, leaf_exprs=exprs, params=["M", "Mr", "t"]
    )


@cache
def pencil_radius_kernel(n: int) -> Kernel:
    """Kernel ``pencil_radius{n}(A, Ar, B, Br)`` (midpoint-radius): a_0..a_n and validity minors.

    From entries that carry radii (the translated matrices, rescaled to |entry| + radius <= 2).
    """
    names = _leaf_names(n)

    def formula(L: dict[str, Any]) -> dict[str, Any]:
        A = [[L[_leaf("a", i, j)] for j in range(n)] for i in range(n)]
        B = [[L[_leaf("b", i, j)] for j in range(n)] for i in range(n)]
        out = {f"c{i}": c for i, c in enumerate(pencil_coefficients(A, B))}
        for name, M in (("A", A), ("B", B)):
            for k in range(2, n):
                out[f"d{name}{k}"] = determinant([row[:k] for row in M[:k]])
        return out

    exprs = {nm: (f"{nm[0].upper()}[{nm[1]}, {nm[2]}]", f"{nm[0].upper()}r[{nm[1]}, {nm[2]}]") for nm in names}
    return build_kernel(
        f"pencil_radius{n}",
        names,
        formula,
        style="radius",
        leaf_max={nm: Fraction(2) for nm in names},
        leaf_exprs=exprs,
        params=["A", "Ar", "B", "Br"],
    )


@cache
def subresultant_kernel(n: int, which: str) -> Kernel:
    """Kernel ``hat_{which}_{n}(c, cr)`` (midpoint-radius): a_i with radii -> hs with a radius."""
    pk = pencil_kernel(n)
    pr = pencil_radius_kernel(n)
    f = HATS[which]
    names = [f"c{i}" for i in range(n + 1)]
    return build_kernel(
        f"hat_{which}_{n}",
        names,
        lambda L: {which: f([L[c] for c in names])},
        style="radius",
        # a_i from either pencil kernel (entries <= LEAF_MAX, or <= 2 with radii after translation)
        leaf_max={c: max(pk.output_max[pk.outputs.index(c)], pr.output_max[pr.outputs.index(c)] * 2) for c in names},
        leaf_exprs={f"c{i}": (f"c[{i}]", f"cr[{i}]") for i in range(n + 1)},
        params=["c", "cr"],
    )




@cache
def pencil_at_kernel(n: int) -> Kernel:
    """Kernel ``pencil_at{n}(c, cr, T)`` (midpoint-radius): P(T) = sum a_i T^i by Horner.

    From a_i with radii and an exact T in [CERT_T_MIN, CERT_T_MAX]: the separation certificate
    (P(T*) > 0 with a_n, a_0 < 0 means two positive roots).
    """
    pk = pencil_kernel(n)
    pr = pencil_radius_kernel(n)
    names = [f"c{i}" for i in range(n + 1)]

    def formula(L: dict[str, Any]) -> dict[str, Any]:
        acc = L[f"c{n}"]
        for i in range(n - 1, -1, -1):
            acc = acc * L["T"] + L[f"c{i}"]
        return {"p": acc}

    leaf_max = {c: max(pk.output_max[pk.outputs.index(c)], pr.output_max[pr.outputs.index(c)] * 2) for c in names}
    leaf_max["T"] = CERT_T_MAX
    exprs = {f"c{i}": (f"c[{i}]", f"cr[{i}]") for i in range(n + 1)}
    exprs["T"] = ("T", "0.0")
    return build_kernel(
        f"pencil_at{n}", [*names, "T"], formula, style="radius", leaf_max=leaf_max, leaf_exprs=exprs, params=["c", "cr", "T"]
    )


@cache
def form_kernel(n: int) -> Kernel:
    """Kernel ``form{n}(M, Mr, x)`` (midpoint-radius): X^T M X for X = (x, 1).

    M is the prepared matrix (entries with radii), x exact with |x_i| <= TRANSLATE_MAX: the
    common-point certificate (negative for both shapes means x is inside both).
    """
    d = n - 1
    mnames = [_leaf("m", i, j) for i in range(n) for j in range(i, n)]
    names = mnames + [f"x{i}" for i in range(d)]

    def formula(L: dict[str, Any]) -> dict[str, Any]:
        M = [[L[_leaf("m", i, j)] for j in range(n)] for i in range(n)]
        X = [L[f"x{i}"] for i in range(d)]
        acc = M[d][d]
        for i in range(d):  # 2 (m_i + sum_j<i M_ij x_j) x_i + M_ii x_i^2, row by row
            row = M[i][d] * 2
            for j in range(i):
                row = row + M[i][j] * X[j] * 2
            row = row + M[i][i] * X[i]
            acc = acc + row * X[i]
        return {"q": acc}

    exprs = {nm: (f"M[{nm[1]}, {nm[2]}]", f"Mr[{nm[1]}, {nm[2]}]") for nm in mnames}
    exprs.update({f"x{i}": (f"x[{i}]", "0.0") for i in range(d)})
    leaf_max = {nm: Fraction(LEAF_MAX) for nm in mnames}
    leaf_max.update({f"x{i}": Fraction(TRANSLATE_MAX) for i in range(d)})
    return build_kernel(f"form{n}", names, formula, style="radius", leaf_max=leaf_max, leaf_exprs=exprs, params=["M", "Mr", "x"])


# ---------------------------------------------------------------------------------------------
# C: the same traced kernels, the prepare step and the per-pair driver (core/fixed/_kernels.c)


def c_function(k: Kernel, n: int, scalars: Sequence[str] = (), unit: Sequence[str] = ()) -> str:
    """The kernel's straight-line Python source rewritten as a C function.

    The same operations in the same order: the error constants carry over (compile without
    contraction, -ffp-contract=off).

    Array inputs are strided (element k of X is ``X[k * s]``: ``s`` = 1 for one pair, the block
    length for the structure-of-arrays blocks of the fast path), except the ``unit`` ones (local
    arrays of one lane); matrix leaves ``X[i, j]`` read a row-major n x n layout; the outputs go
    to the local array ``out``.
    """
    lines = k.source.rstrip().split("\n")
    params = re.match(r"def \w+\((.*)\):", lines[0]).group(1).split(", ")  # type: ignore[union-attr]
    decl = [f"double {p}" if p in scalars else f"const double *restrict {p}" for p in params]
    body = [f"static inline __attribute__((always_inline)) void {k.name}({', '.join(decl)}, const int64_t s, double *restrict out) {{"]
    for raw in lines[1:]:
        ln = raw.strip()
        if ln.startswith("return"):
            for i, v in enumerate(ln[len("return (") : -len(",)")].split(", ")):
                body.append(f"    out[{i}] = {v};")
            continue
        name, rhs = ln.split(" = ", 1)
        def stride(name: str) -> str:
            return "" if name in unit else " * s"

        rhs = re.sub(r"(\w+)\[(\d+), (\d+)\]", lambda m: f"{m.group(1)}[{int(m.group(2)) * n + int(m.group(3))}{stride(m.group(1))}]", rhs)
        rhs = re.sub(r"(\w+)\[(\d+)\]", lambda m: f"{m.group(1)}[{int(m.group(2))}{stride(m.group(1))}]", rhs)
        rhs = rhs.replace("abs(", "fabs(")
        body.append(f"    const double {name} = {rhs};")
    body.append("}")
    return "\n".join(body) + "\n"


def prepare_c(n: int) -> str:
    """``prepare{n}``: the full prepare step for one pair, in C.

    Validate cheaply, flip to a negative interior, scale by a power of two when the largest
    entry is outside [NO_SCALE_MIN, LEAF_MAX], symmetrise. Returns 1 (exactly symmetric: exact entries), 2 (symmetric up to rounding:
    entries are the correctly rounded half sums, the ``leaf_K = 1`` constants apply) or 0
    (abstain: NaN/inf, M_00 = 0, or an asymmetry not clearly within
    :data:`core.shapes.quadrics.SYMMETRY_TOLERANCE`). The numpy filter's ``_prepare`` takes the same
    decisions with the same operations. The tolerance test is conservative:
    (d^2 (1 + 2^-48) <= tol^2 m_i m_j (1 - 2^-48), with tol^2 m_i m_j >= 2^-1000) on the scaled
    values implies the exact rule.
    """
    idx = [(i, j) for i in range(n) for j in range(i, n)]
    off = [(i, j) for i, j in idx if i != j]
    xs = [f"x{i}{j}" for i, j in idx] + [f"y{i}{j}" for i, j in off]
    tol2 = float(SYMMETRY_TOLERANCE) ** 2
    L = [f"static inline int prepare{n}(const double *restrict M, double *restrict out) {{"]
    L += [f"    double x{i}{j} = M[{i * n + j}];" for i, j in idx]
    L += [f"    double y{i}{j} = M[{j * n + i}];" for i, j in off]
    L.append("    if ((x00 == 0.0) | " + " | ".join(f"({x} != {x})" for x in xs) + ") return 0;")
    L.append("    double mx = 0.0;")
    L += [f"    if (fabs({x}) > mx) mx = fabs({x});" for x in xs]
    L.append("    if (!(mx <= 1.7976931348623157e308)) return 0;")
    L.append("    const double f = x00 < 0.0 ? -1.0 : 1.0;")
    L.append(f"    if (!({float(NO_SCALE_MIN)!r} <= mx && mx <= {float(LEAF_MAX)!r})) {{")
    L.append("        int e;")
    L.append("        frexp(mx, &e);")
    L.append("        const int k = 1 - e;  /* exact power-of-two scaling, entry by entry (2^k may be no float) */")
    L += [f"        {x} = ldexp({x}, k);" for x in xs]
    L.append("    }")
    L.append("    if (" + " & ".join(f"(x{i}{j} == y{i}{j})" for i, j in off) + ") {")
    L += [f"        out[{i * n + j}] = x{i}{j} * f;" for i, j in idx]
    L.append("        return 1;")
    L.append("    }")
    for i in range(n):
        row = [f"x{min(i, k)}{max(i, k)}" for k in range(n)] + [f"y{min(i, k)}{max(i, k)}" for k in range(n) if k != i]
        L.append(f"    double m{i} = 0.0;")
        L += [f"    if (fabs({v}) > m{i}) m{i} = fabs({v});" for v in row]
    conds = []
    for i, j in off:
        L.append(f"    const double d{i}{j} = fabs(x{i}{j} * f - y{i}{j} * f);")
        L.append(f"    const double r{i}{j} = {tol2!r} * m{i} * m{j};")
        conds.append(
            f"((x{i}{j} == y{i}{j}) | ((r{i}{j} >= 9.332636185032189e-302) & "
            f"(d{i}{j} * d{i}{j} * 1.0000000000000036 <= r{i}{j} * 0.9999999999999964)))"
        )
    L.append("    if (!(" + " & ".join(conds) + ")) return 0;")
    L.append("    const double h = 0.5 * f;")
    L += [f"    out[{i * n + i}] = x{i}{i} * f;" for i in range(n)]
    L += [f"    out[{i * n + j}] = x{i}{j} * h + y{i}{j} * h;" for i, j in off]
    L.append("    return 2;")
    L.append("}")
    return "\n".join(L) + "\n"


def generate_module() -> str:
    """Source text of ``core/fixed/_kernels.py`` (the numpy filter runs these on arrays of pairs)."""
    parts = [
        '"""Float kernels of the certified filter. GENERATED by ``python -m core.fixed.kernelgen``: do not edit.\n\n'
        "Each ``pencil{n}(A, B)`` reads ``A[i, j]`` (a float, or an array of floats for many pairs) and\n"
        "returns the outputs listed in ``PENCIL{n}_OUTPUTS``; |error of x| <= constant * x_M + floor.\n"
        "The midpoint-radius kernels (``hat_{s}_{n}``, ``translate{n}``, ``pencil_radius{n}``,\n"
        "``pencil_at{n}``, ``form{n}``) return values and radii; |error| <= radius * RADIUS_FACTOR + floor.\n"
        'See core/fixed/errorbound.py for the proofs; core/fixed/_kernels.c holds the same kernels in C.\n"""\n',
        "# ruff: noqa",
        "",
    ]
    for n in (3, 4):
        k = pencil_kernel(n)
        parts.append(f"PENCIL{n}_OUTPUTS = {k.outputs!r}")
        parts.append(f"PENCIL{n}_CONSTANTS = {tuple(float(c) for c in k.constants)!r}")
        kr = pencil_kernel(n, leaf_K=1)
        parts.append(f"PENCIL{n}_CONSTANTS_ROUNDED = {tuple(float(c) for c in kr.constants)!r}")
        parts.append(f"PENCIL{n}_FLOOR_ROUNDED = {kr.underflow_floor!r}")
        parts.append(f"PENCIL{n}_FLOOR = {k.underflow_floor!r}")
        parts.append("")
        parts.append(k.source)
        for extra in (translate_kernel(n), pencil_radius_kernel(n), pencil_at_kernel(n), form_kernel(n)):
            parts.append(f"{extra.name.upper()}_OUTPUTS = {extra.outputs!r}")
            parts.append(f"{extra.name.upper()}_FLOOR = {extra.underflow_floor!r}")
            parts.append("")
            parts.append(extra.source)
        for which in HATS:
            h = subresultant_kernel(n, which)
            parts.append(f"HAT_{which.upper()}_{n}_FLOOR = {h.underflow_floor!r}")
            parts.append("")
            parts.append(h.source)
    return "\n".join(parts)


_C_HEADER = """/* Float kernels of the certified filter, in C. GENERATED by `python -m core.fixed.kernelgen`: do not edit.
 *
 * The straight-line kernels are the traced formulas of core/fixed/_kernels.py (same operations, same
 * order, so the same proven error constants; compile with -ffp-contract=off and without
 * -ffast-math). The decision tables are core.formulae.decision.decide_signs tabulated. core/fixed/compiled.py
 * compiles this file once per machine and source hash and calls classify3/classify4 (the GIL
 * is released: ctypes) from a thread pool.
 *
 * Layout: blocks of BLOCK pairs are transposed to structure-of-arrays; the branch-free fast path
 * (fast{n}) and certificate pass (cert{n}) run over the lanes of a block and vectorise; pairs the
 * fast path cannot take (scaling, asymmetry beyond its cheap test, abstention of the
 * validity test) go through pair{n}, which takes the same decisions one pair at a time.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#define RADIUS_FACTOR @RF@
#define NEED_S0 @NEED_S0@
#define RULE_SEP @RULE_SEP@
#define RULE_POINT @RULE_POINT@
#define CERT_T_MIN @TMIN@
#define CERT_T_MAX @TMAX@
#define TRANSLATE_MAX @XMAX@
#define LEAF_ROUNDING 2.220446049250313e-16 /* 2^-52 >= u / (1 - u): radius of a rounded half sum */
#define LEAF_UNDERFLOW 1.0e-323           /* >= 2^-1073: subnormal rounding of a scaled entry */
#define BLOCK 16                          /* pairs per structure-of-arrays block of the fast path */
#define NEEDS_CERT -8                     /* fast path: valid, tree undecided: try the certificates */
#define NEEDS_PAIR -9                     /* fast path: not its case: the one-pair path decides */

/* Table digit of a certified sign: 0 for -1, 2 for +1, 3 for uncertain (core.formulae.decision.SIGN_CODES). */
static inline int sign_digit(double v, double b) { return v > b ? 2 : (v < -b ? 0 : 3); }
"""

_C_DRIVER = """
/* ---- degree @N@: ellipses (3) / ellipsoids (4) ------------------------------------------- */
static const double PC@N@[@NOUT@] = {@PC@};
static const double PCR@N@[@NOUT@] = {@PCR@};
static const double PF@N@ = @PF@, PFR@N@ = @PFR@, HF@N@ = @HF@, PAF@N@ = @PAF@, FF@N@ = @FF@;
static const int TAB@N@[@TABSIZE@] = {@TAB@};

/* Pencil with certified bounds, validity and the tree on prepared matrices (stride s): writes
 * a_i and their radii to c, cr; returns a rule id, NEEDS_CERT (valid, undecided) or -1 (not
 * certified valid). No control flow: it vectorises over the lanes of a block. */
static inline __attribute__((always_inline)) int tree@N@(const double *restrict wa, const double *restrict wb, const int rounded,
                                                       double *restrict c, double *restrict cr, const int64_t s) {
    double r[@NOUT@], h[2];
    pencil@N@(wa, wb, s, r);
    /* constants chosen by selects on unconditional loads */
    const double F = rounded ? PFR@N@ : PF@N@;
@BOUNDS@
    hat_s0_@N@(c, cr, s, h);
    const int code = TAB@N@[idx * 125 + sign_digit(h[0], h[1] * RADIUS_FACTOR + HF@N@) * 25 + 24];
    return valid ? (code >= 0 ? code : NEEDS_CERT) : -1;
}

/* Centre (Q c = -m, adjugate) and scale k = -m.c - M_dd of a prepared matrix (upper triangle);
 * returns det Q > 0. */
static inline __attribute__((always_inline)) int centre@N@(const double *restrict w, double *restrict ctr, double *restrict k, const int64_t s) {
@CENTRE@
}

static inline __attribute__((always_inline)) double quad@N@(const double *restrict w, const double *restrict u, const int64_t s) {
@QUAD@
}

/* Certificates that do not need s0 (spheres, translated and homothetic copies): sep-witness,
 * common-point or -1. Branch-free (vectorises over a block). */
static inline __attribute__((always_inline)) int cert@N@(const double *restrict wa, const double *restrict wb, const int rnd_a,
                                                       const int rnd_b, const double *restrict c, const double *restrict cr, const int64_t s) {
    double ca[@D@], cb[@D@], ka, kb, u[@D@], x[@D@], ra[@NN@], rb[@NN@], q[2], fa[2], fb[2];
    const int oka = centre@N@(wa, ca, &ka, s), okb = centre@N@(wb, cb, &kb, s);
@UVEC@
    const double qa = quad@N@(wa, u, s), qb = quad@N@(wb, u, s);
    const int ok = oka & okb & (ka > 0.0) & (kb > 0.0);
    const int pos = (qa > 0.0) & (qb > 0.0);
    /* every operation unconditional (NaN or inf where a guess makes no sense), then selects:
     * no control flow, so the loop over the lanes of a block vectorises */
    const double ta = sqrt(ka / qa), tb = sqrt(kb / qb);
    const double T = (ta / tb) * (kb / ka);
    const int tin = pos & (T >= CERT_T_MIN) & (T <= CERT_T_MAX);
    pencil_at@N@(c, cr, tin ? T : 1.0, s, q);
    const int sep = ok & tin & (q[0] > q[1] * RADIUS_FACTOR + PAF@N@);
    const double tt = ta / (ta + tb);
    const double st = pos ? tt : 0.0; /* concentric shapes: A's centre */
    /* unrolled (no inner loops: the compiler would not unroll them in a body this large) */
@XVEC@
    const double ga = rnd_a ? LEAF_ROUNDING : 0.0, gb = rnd_b ? LEAF_ROUNDING : 0.0;
    const double ha = rnd_a ? LEAF_UNDERFLOW : 0.0, hb = rnd_b ? LEAF_UNDERFLOW : 0.0;
    /* radii of the entries: exactly 0 for exact entries (finite times 0) */
@RADII@
    form@N@(wa, ra, x, s, fa); /* wa strided; the radii ra and the point x are this lane's */
    form@N@(wb, rb, x, s, fb);
    const int point = ok & xin & (fa[0] < -(fa[1] * RADIUS_FACTOR + FF@N@)) & (fb[0] < -(fb[1] * RADIUS_FACTOR + FF@N@));
    return sep ? RULE_SEP : (point ? RULE_POINT : -1);
}

/* One pair, every case: a rule id (>= 0) or -1 (the exact path decides). */
static inline int pair@N@(const double *A, const double *B) {
    double wa[@NN@] = {0}, wb[@NN@] = {0}, c[@N@ + 1], cr[@N@ + 1];
    const int sa = prepare@N@(A, wa), sb = prepare@N@(B, wb);
    if (!sa || !sb) return -1;
    const int code = tree@N@(wa, wb, (sa == 2) | (sb == 2), c, cr, 1);
    if (code != NEEDS_CERT) return code;
    return cert@N@(wa, wb, sa == 2, sb == 2, c, cr, 1);
}

/* The fast path's prepare of one lane (branch-free): both matrices finite, M_00 != 0, largest
 * entry within 2^-1000 .. 2^1000 (scaled by the same power of two as prepare@N@), symmetric or
 * within a cheap sufficient tolerance test. Writes the prepared upper triangles with stride s
 * (the same values as prepare@N@); returns eligibility, and which matrices are rounded. */
static inline __attribute__((always_inline)) int fastprep@N@(const double *restrict a, const double *restrict b, const int64_t si,
                                                           double *restrict wa, double *restrict wb, const int64_t s,
                                                           int *restrict rnd_a, int *restrict rnd_b) {
@FASTPREP@
    *rnd_a = !syma;
    *rnd_b = !symb;
    return eligible;
}

/* count contiguous pairs (count, @N@, @N@) of float64 -> rule ids (int8, -1 undecided). */
void classify@N@(const double *A, const double *B, signed char *out, int64_t count) {
    int64_t i = 0;
    for (; i + BLOCK <= count; i += BLOCK) {
        double sa[@NN@ * BLOCK], sb[@NN@ * BLOCK], wa[@NN@ * BLOCK], wb[@NN@ * BLOCK];
        double c[(@N@ + 1) * BLOCK], cr[(@N@ + 1) * BLOCK];
        int res[BLOCK], ra[BLOCK], rb[BLOCK];
        for (int p = 0; p < BLOCK; p++)
            for (int k = 0; k < @NN@; k++) {
                sa[k * BLOCK + p] = A[(i + p) * @NN@ + k];
                sb[k * BLOCK + p] = B[(i + p) * @NN@ + k];
            }
        for (int p = 0; p < BLOCK; p++) {
            const int ok = fastprep@N@(sa + p, sb + p, BLOCK, wa + p, wb + p, BLOCK, ra + p, rb + p);
            const int code = tree@N@(wa + p, wb + p, ra[p] | rb[p], c + p, cr + p, BLOCK);
            res[p] = ok ? code : NEEDS_PAIR;
            res[p] = res[p] == -1 ? NEEDS_PAIR : res[p]; /* validity not certified here: pair@N@ rescales */
        }
        int need = 0;
        for (int p = 0; p < BLOCK; p++) need |= res[p] == NEEDS_CERT;
        if (need) /* only blocks with undecided lanes pay for the certificates (spheres, copies) */
            for (int p = 0; p < BLOCK; p++) {
                const int cc = cert@N@(wa + p, wb + p, ra[p], rb[p], c + p, cr + p, BLOCK);
                res[p] = res[p] == NEEDS_CERT ? (cc >= 0 ? cc : -1) : res[p];
            }
        for (int p = 0; p < BLOCK; p++) out[i + p] = (signed char)res[p];
    }
    for (; i < count; i++) out[i] = (signed char)pair@N@(A + (int64_t)@NN@ * i, B + (int64_t)@NN@ * i);
    for (int64_t j = 0; j < count; j++)
        if (out[j] == NEEDS_PAIR) out[j] = (signed char)pair@N@(A + (int64_t)@NN@ * j, B + (int64_t)@NN@ * j);
}
"""


def _fast_prep_c(n: int) -> str:
    """C statements of ``fastprep{n}``: the branch-free prepare of both matrices into wa, wb."""
    idx = [(i, j) for i in range(n) for j in range(i, n)]
    off = [(i, j) for i, j in idx if i != j]
    tol_lo = float(SYMMETRY_TOLERANCE) * (1 - 2.0**-50)  # exact: 2^-20 - 2^-70
    assert Fraction(tol_lo) == SYMMETRY_TOLERANCE * (1 - Fraction(1, 2**50))
    L = []
    for M, w in (("a", "a"), ("b", "b")):
        xs = [f"{M}x{i}{j}" for i, j in idx] + [f"{M}y{i}{j}" for i, j in off]
        L += [f"    const double {M}x{i}{j} = {M}[{i * n + j} * si];" for i, j in idx]
        L += [f"    const double {M}y{i}{j} = {M}[{j * n + i} * si];" for i, j in off]
        L.append(f"    const double {M}f = {M}x00 < 0.0 ? -1.0 : 1.0, {M}h = 0.5 * {M}f;")
        L.append(f"    double {M}mx = 0.0;")
        L += [f"    {M}mx = fabs({x}) > {M}mx ? fabs({x}) : {M}mx;" for x in xs]
        # the power of two of prepare (2^(1 - e), e the frexp exponent of the largest entry)
        # built from the bits, so that no branch remains; 1 when already in range, as prepare
        L.append(f"    uint64_t {M}mb;")
        L.append(f"    memcpy(&{M}mb, &{M}mx, 8);")
        L.append(f"    const uint64_t {M}sb = (uint64_t)(1 - ((int64_t)(({M}mb >> 52) & 0x7ff) - 1022) + 1023) << 52;")
        L.append(f"    double {M}g;")
        L.append(f"    memcpy(&{M}g, &{M}sb, 8);")
        L.append(f"    const double {M}sc = ({float(NO_SCALE_MIN)!r} <= {M}mx) & ({M}mx <= {float(LEAF_MAX)!r}) ? 1.0 : {M}g;")
        # finite entries (NaN fails every comparison), M_00 != 0, largest entry normal and far
        # from both ends of the range (the scale factor is then a normal power of two)
        L.append(
            f"    const int {M}ok = ({M}x00 != 0.0) & ({M}mx >= 0x1p-1000) & ({M}mx <= 0x1p+1000) & "
            + " & ".join(f"({x} == {x})" for x in xs)
            + ";"
        )
        L.append(f"    const int sym{w} = " + " & ".join(f"({M}x{i}{j} == {M}y{i}{j})" for i, j in off) + ";")
        # a cheaper sufficient test than prepare's: |x - y| <= tol max(|x|, |y|) implies
        # (x - y)^2 <= tol^2 m_i m_j (both m_i and m_j are >= max(|x|, |y|)); rounding covered
        conds = []
        for i, j in off:
            x, y = f"{M}x{i}{j}", f"{M}y{i}{j}"
            L.append(f"    const double {M}e{i}{j} = fabs({x}) > fabs({y}) ? fabs({x}) : fabs({y});")
            conds.append(
                f"(({x} == {y}) | (({M}e{i}{j} >= 1e-270) & "
                f"(fabs({x} - {y}) * {1 + 2.0**-50!r} <= {M}e{i}{j} * {tol_lo!r})))"
            )
        L.append(f"    const int near{w} = " + " & ".join(conds) + ";")
        L += [f"    w{w}[{i * n + i} * s] = ({M}x{i}{i} * {M}sc) * {M}f;" for i in range(n)]
        L += [
            f"    w{w}[{i * n + j} * s] = sym{w} ? ({M}x{i}{j} * {M}sc) * {M}f : ({M}x{i}{j} * {M}sc) * {M}h + ({M}y{i}{j} * {M}sc) * {M}h;"
            for i, j in off
        ]
    L.append("    const int eligible = aok & bok & (syma | neara) & (symb | nearb);")
    return "\n".join(L)


def _bounds_c(n: int, nout: int) -> str:
    """C statements of ``tree{n}``: certified bounds, validity and the table index, unrolled."""
    L = []
    for k in range(0, nout, 2):
        L.append(f"    const double C{k} = rounded ? PCR{n}[{k}] : PC{n}[{k}];")
    valid = []
    for k in range(2 * (n + 1), nout, 2):
        valid.append(f"(r[{k}] > C{k} * r[{k + 1}] + F)")
    for i in range(n + 1):
        L.append(f"    c[{i} * s] = r[{2 * i}];")
        L.append(f"    cr[{i} * s] = C{2 * i} * r[{2 * i + 1}] + F;")
    valid += [f"(c[{n} * s] < -cr[{n} * s])", "(c[0] < -cr[0])"]
    L.append("    const int valid = " + " & ".join(valid) + ";")
    idx = "0"
    for i in range(n - 1, 0, -1):
        idx = f"({idx}) * 5 + sign_digit(c[{i} * s], cr[{i} * s])"
    L.append(f"    const int idx = {idx};")
    return "\n".join(L)


def _centre_c(n: int) -> str:
    """C body of ``centre{n}`` (explicit adjugate: the numpy filter does the same operations)."""
    w = lambda i, j: f"w[{min(i, j) * n + max(i, j)} * s]"  # noqa: E731
    d = n - 1
    L = []
    if d == 2:
        L.append(f"    const double a00 = {w(1, 1)}, a01 = -{w(0, 1)}, a11 = {w(0, 0)};")
        L.append(f"    const double det = {w(0, 0)} * {w(1, 1)} - {w(0, 1)} * {w(0, 1)};")
        L.append(f"    const double m0 = {w(0, 2)}, m1 = {w(1, 2)};")
        L.append("    ctr[0] = -(a00 * m0 + a01 * m1) / det;")
        L.append("    ctr[1] = -(a01 * m0 + a11 * m1) / det;")
        L.append(f"    *k = -(m0 * ctr[0] + m1 * ctr[1]) - {w(2, 2)};")
    else:
        L.append(f"    const double a00 = {w(1, 1)} * {w(2, 2)} - {w(1, 2)} * {w(1, 2)};")
        L.append(f"    const double a01 = {w(0, 2)} * {w(1, 2)} - {w(0, 1)} * {w(2, 2)};")
        L.append(f"    const double a02 = {w(0, 1)} * {w(1, 2)} - {w(0, 2)} * {w(1, 1)};")
        L.append(f"    const double a11 = {w(0, 0)} * {w(2, 2)} - {w(0, 2)} * {w(0, 2)};")
        L.append(f"    const double a12 = {w(0, 1)} * {w(0, 2)} - {w(0, 0)} * {w(1, 2)};")
        L.append(f"    const double a22 = {w(0, 0)} * {w(1, 1)} - {w(0, 1)} * {w(0, 1)};")
        L.append(f"    const double det = {w(0, 0)} * a00 + {w(0, 1)} * a01 + {w(0, 2)} * a02;")
        L.append(f"    const double m0 = {w(0, 3)}, m1 = {w(1, 3)}, m2 = {w(2, 3)};")
        L.append("    ctr[0] = -(a00 * m0 + a01 * m1 + a02 * m2) / det;")
        L.append("    ctr[1] = -(a01 * m0 + a11 * m1 + a12 * m2) / det;")
        L.append("    ctr[2] = -(a02 * m0 + a12 * m1 + a22 * m2) / det;")
        L.append(f"    *k = -(m0 * ctr[0] + m1 * ctr[1] + m2 * ctr[2]) - {w(3, 3)};")
    L.append("    return det > 0.0;")
    return "\n".join(L)


def _quad_c(n: int) -> str:
    """C body of ``quad{n}``: u^T Q u with w strided (stride s), u this lane's own."""
    w = lambda i, j: f"w[{min(i, j) * n + max(i, j)} * s]"  # noqa: E731
    d = n - 1
    terms = [f"{w(i, i)} * u[{i}] * u[{i}]" for i in range(d)]
    terms += [f"2.0 * {w(i, j)} * u[{i}] * u[{j}]" for i in range(d) for j in range(i + 1, d)]
    return "    return " + " + ".join(terms) + ";"


def generate_c() -> str:
    """Source text of ``core/fixed/_kernels.c``."""
    from ..formulae.decision import NEED_S0, TABLE3, TABLE4, rule_by_key

    head = (
        _C_HEADER.replace("@RF@", repr(RADIUS_FACTOR))
        .replace("@NEED_S0@", str(NEED_S0))
        .replace("@RULE_SEP@", str(rule_by_key("sep-witness").id))
        .replace("@RULE_POINT@", str(rule_by_key("common-point").id))
        .replace("@TMIN@", repr(float(CERT_T_MIN)))
        .replace("@TMAX@", repr(float(CERT_T_MAX)))
        .replace("@XMAX@", repr(float(TRANSLATE_MAX)))
    )
    parts = [head]
    for n, table in ((3, TABLE3), (4, TABLE4)):
        k, kr = pencil_kernel(n), pencil_kernel(n, leaf_K=1)
        h, pa, fm = subresultant_kernel(n, "s0"), pencil_at_kernel(n), form_kernel(n)
        parts += [c_function(k, n), c_function(h, n), c_function(pa, n, ["T"]), c_function(fm, n, unit=["Mr", "x"]), prepare_c(n)]
        fill = {
            "@N@": str(n),
            "@D@": str(n - 1),
            "@NN@": str(n * n),
            "@NOUT@": str(len(k.outputs)),
            "@PC@": ", ".join(repr(float(c)) for c in k.constants),
            "@PCR@": ", ".join(repr(float(c)) for c in kr.constants),
            "@PF@": repr(k.underflow_floor),
            "@PFR@": repr(kr.underflow_floor),
            "@HF@": repr(h.underflow_floor),
            "@PAF@": repr(pa.underflow_floor),
            "@FF@": repr(fm.underflow_floor),
            "@TABSIZE@": str(table.size),
            "@TAB@": ", ".join(str(int(v)) for v in table),
            "@CENTRE@": _centre_c(n),
            "@QUAD@": _quad_c(n),
            "@FASTPREP@": _fast_prep_c(n),
            "@BOUNDS@": _bounds_c(n, len(k.outputs)),
            "@UVEC@": "\n".join(f"    u[{i}] = cb[{i}] - ca[{i}];" for i in range(n - 1)),
            "@XVEC@": "\n".join(
                [f"    x[{i}] = ca[{i}] + st * u[{i}];" for i in range(n - 1)]
                + ["    const int xin = " + " & ".join(f"(fabs(x[{i}]) <= TRANSLATE_MAX)" for i in range(n - 1)) + ";"]
                + [f"    x[{i}] = xin ? x[{i}] : 0.0;" for i in range(n - 1)]
            ),
            "@RADII@": "\n".join(
                f"    ra[{k}] = fabs(wa[{k} * s]) * ga + ha;\n    rb[{k}] = fabs(wb[{k} * s]) * gb + hb;" for k in range(n * n)
            ),
        }
        text = _C_DRIVER
        for key, val in fill.items():
            text = text.replace(key, val)
        parts.append(text)
    return "\n".join(parts)


GENERATED_C_PATH = Path(__file__).with_name("_kernels.c")


def main(argv: list[str] | None = None) -> int:
    """Write (default) or ``--check`` the generated modules core/fixed/_kernels.py and core/fixed/_kernels.c."""
    args = sys.argv[1:] if argv is None else argv
    outputs = {GENERATED_PATH: generate_module(), GENERATED_C_PATH: generate_c()}
    if "--check" in args:
        stale = [str(p) for p, text in outputs.items() if not p.exists() or p.read_text() != text]
        if stale:
            print(f"stale: {', '.join(stale)}: run python -m core.fixed.kernelgen")
            return 1
        return 0
    for path, text in outputs.items():
        path.write_text(text)
        print(f"wrote {path} ({len(text.splitlines())} lines)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
