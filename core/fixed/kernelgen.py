"""Generate ``core/fixed/_kernels.py`` and ``core/fixed/_kernels.h``: the float filter's kernels.

The straight-line kernels are traced from the ring-generic formulas (numpy source and C); the C
lane functions are the driver's description (:mod:`core.fixed.driver`) written out through
:class:`core.fixed.lanes.CLanes`, with the decision tables. The hand-written C that runs them
over blocks of pairs (``_filter.h``) and the Python extension around it (``_filter.c``) include
the generated header; ``setup.py`` compiles them when the package is installed.

Run ``python -m core.fixed.kernelgen`` after changing :mod:`core.formulae.pencil`,
:mod:`core.formulae.subresultants`, :mod:`core.fixed.errorbound`, :mod:`core.fixed.driver` or
:mod:`core.formulae.decision` (then reinstall: ``pip install -e .``); ``tests/test_filters.py``
fails if the committed files are not what this module generates (``python -m core.generated --check``
checks every generator's files at once). Committing the generated text
(instead of ``exec`` at import) keeps every line of the fast path readable.
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
from ..shapes.quadrics import origin_moved
from .errorbound import (
    CERT_T_MAX,
    LEAF_MAX,
    S0_RHO,
    TRANSLATE_MAX,
    Kernel,
    Perm,
    build_kernel,
    form_constants,
    relative_input_constant,
    round_up,
)
from .lanes import CExpr, CLanes, KernelInfo

__all__ = [
    "pencil_kernel",
    "pencil_radius_kernel",
    "pencil_at_kernel",
    "form_kernel",
    "form_info",
    "hat_s0_relative_kernel",
    "hat_s0_relative_info",
    "translate_kernel",
    "subresultant_kernel",
    "generate_module",
    "generate_c",
    "c_function",
    "generated_files",
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


def _form(M: list[list[Any]], X: list[Any], d: int) -> Any:
    """X^T M X for X = (x, 1), row by row: 2 (m_i + sum_j<i M_ij x_j) x_i + M_ii x_i^2, then M_dd."""
    acc = M[d][d]
    for i in range(d):
        row = M[i][d] * 2
        for j in range(i):
            row = row + M[i][j] * X[j] * 2
        row = row + M[i][i] * X[i]
        acc = acc + row * X[i]
    return acc


@cache
def form_kernel(n: int) -> Kernel:
    """Kernel ``form{n}(M, Mr, x, g)`` (permanent style): X^T M X for X = (x, 1), and its bound.

    M is a prepared matrix whose exact entries lie within the radii Mr (0 for exact entries, a
    rounded half sum, or a translated entry), x exact with |x_i| <= TRANSLATE_MAX: the
    common-point certificate (negative for both shapes means x is inside both). Outputs ``q``
    and ``q_M`` = Q(e, |x|), the program on e_ij = |m_ij| g + r_ij with every ``-`` turned into
    ``+``; with (g, f) = ``form_constants(K_q, K_qM)``, |fl(q) - exact| <= f q_M + 2 floor
    (:func:`core.fixed.errorbound.form_constants`). One value program and one non-negative
    program: a third of the operations of the midpoint-radius form.
    """
    d = n - 1
    mnames = [_leaf("m", i, j) for i in range(n) for j in range(i, n)]
    rnames = [_leaf("r", i, j) for i in range(n) for j in range(i, n)]
    names = mnames + rnames + [f"x{i}" for i in range(d)] + ["g"]

    def formula(L: dict[str, Any]) -> dict[str, Any]:
        M = [[L[_leaf("m", i, j)] for j in range(n)] for i in range(n)]
        X = [L[f"x{i}"] for i in range(d)]
        E = [[Perm(abs(L[_leaf("m", i, j)]) * L["g"] + L[_leaf("r", i, j)]) for j in range(n)] for i in range(n)]
        return {"q": _form(M, X, d), "q_M": _form(E, [Perm(abs(v)) for v in X], d).v}

    exprs = {nm: (f"M[{nm[1]}, {nm[2]}]", "") for nm in mnames}
    exprs.update({nm: (f"Mr[{nm[1]}, {nm[2]}]", "") for nm in rnames})
    exprs.update({f"x{i}": (f"x[{i}]", "") for i in range(d)})
    exprs["g"] = ("g", "")
    leaf_max = {nm: Fraction(LEAF_MAX) for nm in mnames + rnames}
    leaf_max.update({f"x{i}": Fraction(TRANSLATE_MAX) for i in range(d)})
    leaf_max["g"] = Fraction(1)
    return build_kernel(
        f"form{n}", names, formula, style="permanent", leaf_max=leaf_max, leaf_exprs=exprs, params=["M", "Mr", "x", "g"]
    )


def form_info(n: int) -> tuple[float, float, float]:
    """(g, f, floor) of :func:`form_kernel`: |fl(q) - exact| <= f q_M + floor (two underflow floors)."""
    k = form_kernel(n)
    g, f = form_constants(k.error_counts[0], k.error_counts[1])
    return g, f, round_up(Fraction(k.underflow_floor) * 2)


@cache
def hat_s0_relative_kernel(n: int) -> Kernel:
    """Kernel ``hat_s0_rel_{n}(c)`` (permanent style): hs0 and its permanent, for the first s0 test.

    For a_i known to relative accuracy :data:`~core.fixed.errorbound.S0_RHO` (checked by the
    driver): |fl(hs0) - hs0(exact a)| <= C s0_M + floor with C =
    ``relative_input_constant(K, K_M, degree, S0_RHO)``. About a third of the operations of the
    midpoint-radius ``hat_s0_{n}``, which serves the pairs this one cannot decide.
    """
    pk = pencil_kernel(n)
    pr = pencil_radius_kernel(n)
    names = [f"c{i}" for i in range(n + 1)]

    def formula(L: dict[str, Any]) -> dict[str, Any]:
        perm = hat_s0([Perm(abs(L[c])) for c in names])
        return {"s0": hat_s0([L[c] for c in names]), "s0_M": perm.v}

    return build_kernel(
        f"hat_s0_rel_{n}",
        names,
        formula,
        style="permanent",
        leaf_max={c: max(pk.output_max[pk.outputs.index(c)], pr.output_max[pr.outputs.index(c)] * 2) for c in names},
        leaf_exprs={c: (f"c[{i}]", "") for i, c in enumerate(names)},
        params=["c"],
    )


def hat_s0_relative_info(n: int) -> tuple[float, float]:
    """(C, floor) of :func:`hat_s0_relative_kernel`."""
    k = hat_s0_relative_kernel(n)
    degree = hat_s0([Perm(0) for _ in range(n + 1)]).degree
    return relative_input_constant(k.error_counts[0], k.error_counts[1], degree, S0_RHO), k.underflow_floor


# ---------------------------------------------------------------------------------------------
# C: the same traced kernels and the driver's lane functions (core/fixed/_kernels.h)


_C_LOCAL = re.compile(r"^\s*const (?:double|float|int64_t) (\w+) = .*;$")


def _drop_unused(lines: list[str]) -> list[str]:
    """The C lines without the locals nothing reads (repeated until none is left).

    The traced kernels and the driver compute some values that a given C function does not use
    (an output of a shared stage, a flag of the other path); their definitions are pure, so they
    go, and the compiler has no unused variable to warn about. Values and their order stay.
    """
    while True:
        text = "\n".join(lines)
        counts: dict[str, int] = {}
        for word in re.findall(r"\b\w+\b", text):
            counts[word] = counts.get(word, 0) + 1
        kept = [ln for ln in lines if not ((m := _C_LOCAL.match(ln)) and counts.get(m.group(1), 0) == 1)]
        if len(kept) == len(lines):
            return kept
        lines = kept


def c_function(k: Kernel, n: int, scalars: Sequence[str] = ()) -> str:
    """The kernel's straight-line Python source rewritten as a C function.

    The same operations in the same order: the error constants carry over (compiled without
    contraction, -ffp-contract=off). Matrix leaves ``X[i, j]`` read a row-major n x n array (the
    lane functions pass local arrays of one pair); the outputs go to the array ``out``.
    """
    lines = k.source.rstrip().split("\n")
    params = re.match(r"def \w+\((.*)\):", lines[0]).group(1).split(", ")  # type: ignore[union-attr]
    decl = [f"double {p}" if p in scalars else f"const double *restrict {p}" for p in params]
    body = [f"static inline __attribute__((always_inline)) void {k.name}({', '.join(decl)}, double *restrict out) {{"]
    for raw in lines[1:]:
        ln = raw.strip()
        if ln.startswith("return"):
            for i, v in enumerate(ln[len("return (") : -len(",)")].split(", ")):
                body.append(f"    out[{i}] = {v};")
            continue
        name, rhs = ln.split(" = ", 1)
        rhs = re.sub(r"(\w+)\[(\d+), (\d+)\]", lambda m: f"{m.group(1)}[{int(m.group(2)) * n + int(m.group(3))}]", rhs)
        rhs = rhs.replace("abs(", "fabs(")
        body.append(f"    const double {name} = {rhs};")
    body = _drop_unused(body)
    body.append("}")
    return "\n".join(body) + "\n"

def generate_module() -> str:
    """Source text of ``core/fixed/_kernels.py`` (the numpy filter runs these on arrays of pairs)."""
    parts = [
        '"""Float kernels of the certified filter. GENERATED by ``python -m core.fixed.kernelgen``: do not edit.\n\n'
        "Each ``pencil{n}(A, B)`` reads ``A[i, j]`` (a float, or an array of floats for many pairs) and\n"
        "returns the outputs listed in ``PENCIL{n}_OUTPUTS``; |error of x| <= constant * x_M + floor.\n"
        "The midpoint-radius kernels (``hat_{s}_{n}``, ``translate{n}``, ``pencil_radius{n}``,\n"
        "``pencil_at{n}``) return values and radii; |error| <= radius * RADIUS_FACTOR + floor.\n"
        "``hat_s0_rel_{n}(c)`` returns hs0 and its permanent: |error| <= C * s0_M + floor for a_i known to\n"
        "relative accuracy S0_RHO; ``form{n}(M, Mr, x, g)`` returns q and q_M: |error| <= f * q_M + floor\n"
        "with (g, f) = FORM{n}_CONSTANTS.\n"
        'See core/fixed/errorbound.py for the proofs; core/fixed/_kernels.h holds the same kernels in C.\n"""\n',
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
        for extra in (translate_kernel(n), pencil_radius_kernel(n), pencil_at_kernel(n)):
            parts.append(f"{extra.name.upper()}_OUTPUTS = {extra.outputs!r}")
            parts.append(f"{extra.name.upper()}_FLOOR = {extra.underflow_floor!r}")
            parts.append("")
            parts.append(extra.source)
        fm, (g, f, floor) = form_kernel(n), form_info(n)
        parts.append(f"FORM{n}_OUTPUTS = {fm.outputs!r}")
        parts.append(f"FORM{n}_CONSTANTS = {(g, f)!r}")
        parts.append(f"FORM{n}_FLOOR = {floor!r}")
        parts.append("")
        parts.append(fm.source)
        hr, (C, floor) = hat_s0_relative_kernel(n), hat_s0_relative_info(n)
        parts.append(f"HAT_S0_REL_{n}_OUTPUTS = {hr.outputs!r}")
        parts.append(f"HAT_S0_REL_{n}_CONSTANTS = {(C,)!r}")
        parts.append(f"HAT_S0_REL_{n}_FLOOR = {floor!r}")
        parts.append("")
        parts.append(hr.source)
        for which in HATS:
            h = subresultant_kernel(n, which)
            parts.append(f"HAT_{which.upper()}_{n}_FLOOR = {h.underflow_floor!r}")
            parts.append("")
            parts.append(h.source)
    return "\n".join(parts)


_C_HEADER = """/* The certified float filter's lane functions, in C. GENERATED by `python -m core.fixed.kernelgen`: do not edit.
 *
 * Two sources, one description each:
 * - the straight-line kernels (pencil{n}, hat_s0_rel_{n}, hat_s0_{n}, pencil_at{n}, form{n}) are the traced
 *   ring-generic formulas of core/fixed/_kernels.py, the same operations in the same order, so
 *   their proven error constants (core/fixed/errorbound.py) hold;
 * - the lane functions (first{n}_*, full{n}_*, second{n}, third_sep{n}_*, third{n}_*, fourth{n}) are core/fixed/driver.py written out
 *   in C: prepare, pencil with bounds, validity, the tree (tables of
 *   core.formulae.decision.decide_signs), s0 where the tree asks, the certificates. The numpy
 *   filter runs that same description on arrays, and the two agree bit for bit.
 *
 * Compile without contraction or reassociation (-ffp-contract=off, no -ffast-math): every
 * operation must round once, as the bounds assume. -fno-math-errno and -fno-trapping-math only
 * let the compiler vectorise sqrt and the selects; they change no value. Everything is
 * branch-free, so core/fixed/_filter.h runs each lane function over many pairs at once and the
 * compiler turns the loop into SIMD across pairs. A lane reads one pair: its row-major n x n
 * matrices are a[k * s], b[k * s] (k = n i + j; float64, or float32 widened exactly) and its
 * stage values c[r * s]: columns of blocks stored as structure of arrays.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#define NEEDS_S0 @NEEDS_S0@   /* first stage: valid, the tree asks for s0 */
#define NEEDS_CERT @NEEDS_CERT@ /* valid, the tree cannot decide: try the certificates */
#define NEEDS_FULL @NEEDS_FULL@ /* fast pass: a matrix is not exactly symmetric: the full prepare */
#define NEEDS_S0_RADIUS @NEEDS_S0_RADIUS@ /* stage 2 could not tell the sign of s0: the certificates, then stage 4 */
#define NEEDS_SCALE @NEEDS_SCALE@ /* unscaled first try: a matrix outside [2^-8, 2^24] (or not exactly symmetric): the fast pass */

/* Table digit of a certified sign: 0 for -1, 2 for +1, 3 for uncertain (core.formulae.decision.SIGN_CODES). */
static inline int64_t sign_digit(double v, double b) { return v > b ? 2 : (v < -b ? 0 : 3); }

/* e with v in [2^(e-1), 2^e) for a finite v > 0 (frexp's exponent), from the bits: a subnormal
 * v is first scaled by 2^64 (exact). */
static inline int64_t frexp_exponent(double v) {
    const int64_t sub = v < 0x1p-1000;
    const double w = sub ? v * 0x1p64 : v;
    uint64_t bits;
    memcpy(&bits, &w, 8);
    return (int64_t)((bits >> 52) & 0x7ff) - 1022 - (sub ? 64 : 0);
}

static inline double max2(double a, double b) { return a > b ? a : b; }

/* |v| as an integer (its bits without the sign): ordered as the doubles for finite v, above
 * every finite value for inf and NaN; from_bits reads such an integer back as a double. */
static inline int64_t abs_bits(double v) {
    uint64_t bits;
    memcpy(&bits, &v, 8);
    return (int64_t)(bits & 0x7fffffffffffffffULL);
}
static inline double from_bits(int64_t b) {
    double v;
    memcpy(&v, &b, 8);
    return v;
}
static inline int64_t imin2(int64_t a, int64_t b) { return a < b ? a : b; }
static inline int64_t imax2(int64_t a, int64_t b) { return a > b ? a : b; }

/* 2^k for -1022 <= k <= 1023, exact, from the bits. */
static inline double pow2(int64_t k) {
    const uint64_t bits = (uint64_t)(k + 1023) << 52;
    double v;
    memcpy(&v, &bits, 8);
    return v;
}
"""


def _lane_c(name: str, params: str, build: Any, infos: dict[str, KernelInfo], doc: str) -> str:
    """A C lane function: ``build(x)`` runs the driver on :class:`CLanes` and returns the result."""
    x = CLanes(infos, re.findall(r"(\w+)(?:,|$)", params))
    ret = build(x)
    body = _drop_unused([*x.lines, f"    return {ret.text};"])
    lines = [f"/* {doc} */", f"static inline __attribute__((always_inline)) int64_t {name}({params}) {{", *body, "}"]
    return "\n".join(lines) + "\n"


def _lane_functions(n: int, infos: dict[str, KernelInfo]) -> list[str]:
    """first{n}_{f64,f32}, second{n}, third{n}_{f64,f32}: the driver's stages in C."""
    from .driver import (
        NEEDS_FULL,
        NEEDS_SCALE,
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

    out = []
    for suffix, T in (("f64", "double"), ("f32", "float")):
        entry = lambda p: (lambda i, j: CExpr(f"(double){p}[{i * n + j} * s]", "d"))  # noqa: E731

        def first(x: CLanes, entry: Any = entry, fast: bool = True, unscaled: bool = False) -> CExpr:
            Pa = prepare(x, n, entry("a"), "a", exact_only=fast, unscaled=unscaled)
            Pb = prepare(x, n, entry("b"), "b", exact_only=fast, unscaled=unscaled)
            c, cr, minors = pencil_bounds(x, n, Pa, Pb)
            code: CExpr
            code, _, idx = decide(x, n, c, cr, minors, Pa.ok & Pb.ok)
            if unscaled:  # a matrix outside [2^-8, 2^24], not exactly symmetric or not finite
                code = x.where(Pa.open | Pb.open, NEEDS_SCALE, code)
            elif fast:  # a matrix symmetric only up to rounding: the full prepare decides
                code = x.where(((Pa.ok | Pa.open) & (Pb.ok | Pb.open)) & (Pa.open | Pb.open), NEEDS_FULL, code)
            for i in range(n + 1):
                x.lines.append(f"    c[{i} * s] = {c[i].text};")
                x.lines.append(f"    c[{n + 1 + i} * s] = {cr[i].text};")
            x.lines.append(f"    *idx_out = {idx.text};")
            return code

        def third(x: CLanes, entry: Any = entry, fast: bool = False) -> CExpr:
            # fast: the pair passed the fast first pass (both matrices exactly symmetric), whose
            # W is the full prepare's and whose radii are 0
            Pa, Pb = prepare(x, n, entry("a"), "a", exact_only=fast), prepare(x, n, entry("b"), "b", exact_only=fast)
            c = [CExpr(f"c[{i} * s]", "d") for i in range(n + 1)]
            cr = [CExpr(f"c[{n + 1 + i} * s]", "d") for i in range(n + 1)]
            if fast:
                zero = {ij: 0.0 for ij in Pa.W}
                fast_code: CExpr = certify(x, n, Pa.W, zero, Pb.W, zero, c, cr)
                return fast_code
            code: CExpr = certify(x, n, Pa.W, radii(x, Pa.W, Pa.rounded, "a"), Pb.W, radii(x, Pb.W, Pb.rounded, "b"), c, cr)
            return code

        def third_sep(x: CLanes, entry: Any = entry, fast: bool = False, unscaled: bool = False) -> CExpr:
            # the traces of the matrices the pair's a_i were computed from (fast: the fast pass's
            # W; unscaled: the unscaled first pass's, M itself with the sign apart: no scale to find)
            Pa = prepare(x, n, entry("a"), "a", exact_only=fast or unscaled, unscaled=unscaled)
            Pb = prepare(x, n, entry("b"), "b", exact_only=fast or unscaled, unscaled=unscaled)
            c = [CExpr(f"c[{i} * s]", "d") for i in range(n + 1)]
            cr = [CExpr(f"c[{n + 1 + i} * s]", "d") for i in range(n + 1)]
            code: CExpr = certify_sep(x, n, Pa.W, Pb.W, c, cr, (Pa.sign, Pb.sign) if unscaled else None)
            return code

        if n == 4:
            out.append(_lane_c(
                f"skip_s0{n}_{suffix}", f"const {T} *restrict a, const {T} *restrict b, const int64_t s",
                lambda x, entry=entry: skips_s0(x, n, entry("a"), entry("b")), infos,
                "Before stage 2 (driver.skips_s0): 1 where the diagonals of the quadratic blocks are proportional "
                "(s0 of spheres and copies vanishes: stage 2 is skipped), else 0.",
            ))
        params = f"const {T} *restrict a, const {T} *restrict b, double *restrict c, const int64_t s, int64_t *restrict idx_out"
        out.append(_lane_c(
            f"first{n}_{suffix}", params, first, infos,
            "Stage 1, fast pass (driver.prepare for exactly symmetric matrices, pencil_bounds, decide): a rule id, "
            f"NEEDS_S0, NEEDS_CERT, NEEDS_FULL or -1; writes a_0..a_{n} to c[i * s] and their radii to c[({n + 1} + i) * s], "
            "the table index to *idx_out.",
        ))
        out.append(_lane_c(
            f"first{n}_noscale_{suffix}", params, lambda x, first=first: first(x, unscaled=True), infos,
            "Stage 1, first try (driver.prepare unscaled): the outputs of the fast pass, bit for bit, for a pair "
            "of exactly symmetric matrices whose largest entries are in [2^-8, 2^24], without the scaling; "
            "NEEDS_SCALE for the other pairs.",
        ))
        out.append(_lane_c(
            f"full{n}_{suffix}", params, lambda x, first=first: first(x, fast=False), infos,
            "Stage 1 for the pairs the fast pass left to the full prepare (a matrix symmetric only up to rounding): "
            "the same outputs, never NEEDS_FULL.",
        ))
        out.append(_lane_c(
            f"third_sep{n}_{suffix}",
            f"const {T} *restrict a, const {T} *restrict b, const double *restrict c, const int64_t s",
            third_sep, infos,
            "Stage 3a (driver.certify_sep, on the traces of the pair prepared again): sep-witness or -1.",
        ))
        out.append(_lane_c(
            f"third_sep{n}_noscale_{suffix}",
            f"const {T} *restrict a, const {T} *restrict b, const double *restrict c, const int64_t s",
            lambda x, third_sep=third_sep: third_sep(x, unscaled=True), infos,
            "Stage 3a for a pair the unscaled first pass prepared (largest entries in [2^-8, 2^24]: W is M, "
            "the sign apart): the same answer as third_sep, without finding a scale.",
        ))
        out.append(_lane_c(
            f"third_sep{n}_fast_{suffix}",
            f"const {T} *restrict a, const {T} *restrict b, const double *restrict c, const int64_t s",
            lambda x, third_sep=third_sep: third_sep(x, fast=True), infos,
            "Stage 3a for a pair the fast first pass prepared: the same answer as third_sep, cheaper.",
        ))
        out.append(_lane_c(
            f"third{n}_{suffix}",
            f"const {T} *restrict a, const {T} *restrict b, const double *restrict c, const int64_t s",
            third, infos,
            "Stage 3 (driver.certify, on the pair prepared again): sep-witness, common-point or -1.",
        ))
        out.append(_lane_c(
            f"third{n}_fast_{suffix}",
            f"const {T} *restrict a, const {T} *restrict b, const double *restrict c, const int64_t s",
            lambda x, third=third: third(x, fast=True), infos,
            "Stage 3 for a pair the fast first pass prepared (exactly symmetric: exact entries, radii 0): the same "
            "answer as third, cheaper.",
        ))

    def second(x: CLanes) -> CExpr:
        c = [CExpr(f"c[{i} * s]", "d") for i in range(n + 1)]
        cr = [CExpr(f"c[{n + 1 + i} * s]", "d") for i in range(n + 1)]
        code: CExpr = decide_s0(x, n, c, cr, CExpr("idx", "i"))
        return code

    def fourth(x: CLanes) -> CExpr:
        c = [CExpr(f"c[{i} * s]", "d") for i in range(n + 1)]
        cr = [CExpr(f"c[{n + 1 + i} * s]", "d") for i in range(n + 1)]
        code: CExpr = decide_s0_radius(x, n, c, cr, CExpr("idx", "i"))
        return code

    out.append(_lane_c(
        f"second{n}", "const double *restrict c, const int64_t s, const int64_t idx", second, infos,
        "Stage 2 (driver.decide_s0): the tree with the semi-static sign of s0: a rule id, NEEDS_CERT or NEEDS_S0_RADIUS.",
    ))
    out.append(_lane_c(
        f"fourth{n}", "const double *restrict c, const int64_t s, const int64_t idx", fourth, infos,
        "Stage 4 (driver.decide_s0_radius): the tree with the running-error sign of s0: a rule id or NEEDS_CERT.",
    ))
    return out


def _kernel_infos(n: int) -> dict[str, KernelInfo]:
    k, kr = pencil_kernel(n), pencil_kernel(n, leaf_K=1)
    infos = {
        k.name: KernelInfo(k.outputs, len(k.outputs), k.underflow_floor, tuple(k.constants), tuple(kr.constants), kr.underflow_floor)
    }
    for kk in (subresultant_kernel(n, "s0"), pencil_at_kernel(n)):
        infos[kk.name] = KernelInfo(kk.outputs, 2 * len(kk.outputs), kk.underflow_floor)
    fm, (g, f, floor) = form_kernel(n), form_info(n)
    infos[fm.name] = KernelInfo(fm.outputs, len(fm.outputs), floor, (g, f))
    hr, (C, floor) = hat_s0_relative_kernel(n), hat_s0_relative_info(n)
    infos[hr.name] = KernelInfo(hr.outputs, len(hr.outputs), floor, (C,))
    return infos


def generate_c() -> str:
    """Source text of ``core/fixed/_kernels.h``."""
    from .driver import NEEDS_CERT, NEEDS_FULL, NEEDS_S0, NEEDS_S0_RADIUS, NEEDS_SCALE, TABLES

    codes = {"NEEDS_S0": NEEDS_S0, "NEEDS_CERT": NEEDS_CERT, "NEEDS_FULL": NEEDS_FULL, "NEEDS_S0_RADIUS": NEEDS_S0_RADIUS, "NEEDS_SCALE": NEEDS_SCALE}
    header = _C_HEADER
    for name, value in codes.items():
        header = header.replace(f"@{name}@", str(value))
    parts = [header]
    for n in (3, 4):
        parts.append(f"/* ---- {'ellipses' if n == 3 else 'ellipsoids'}: n = {n} {'-' * 70} */\n")
        k = pencil_kernel(n)
        h, pa, fm, hr = subresultant_kernel(n, "s0"), pencil_at_kernel(n), form_kernel(n), hat_s0_relative_kernel(n)
        parts += [c_function(k, n), c_function(hr, n), c_function(h, n), c_function(pa, n, ["T"]), c_function(fm, n, ["g"])]
        table = [str(int(v)) for v in TABLES[n]]
        rows = ",\n    ".join(", ".join(table[i : i + 25]) for i in range(0, len(table), 25))
        parts.append(
            f"/* core.fixed.driver.TABLES[{n}]: decide_signs with s1, s1,0 pending, at 5 idx + digit of s0. */\n"
            f"static const int64_t TAB{n}[{len(table)}] = {{\n    {rows}}};\n"
        )
        parts += _lane_functions(n, _kernel_infos(n))
    return "\n".join(parts)

GENERATED_C_PATH = Path(__file__).with_name("_kernels.h")


def generated_files() -> dict[Path, str]:
    """The files this generator writes, with their text today (:mod:`core.generated` checks them all)."""
    return {GENERATED_PATH: generate_module(), GENERATED_C_PATH: generate_c()}


def main(argv: list[str] | None = None) -> int:
    """Write (default) or ``--check`` the generated files core/fixed/_kernels.py and core/fixed/_kernels.h."""
    from ..generated import write_or_check

    args = sys.argv[1:] if argv is None else argv
    return write_or_check(generated_files(), "python -m core.fixed.kernelgen", check="--check" in args)


if __name__ == "__main__":
    raise SystemExit(main())
