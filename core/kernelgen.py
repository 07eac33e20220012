"""Generate ``core/_kernels.py``: the float kernels of the filter, traced from the generic formulas.

Run ``python -m core.kernelgen`` after changing :mod:`core.pencil`, :mod:`core.subresultants` or
:mod:`core.errorbound`; ``tests/test_filters.py`` fails if the committed file is not what this
module generates (and ``KERNELS_SHA`` in core/fastpath.py, which keys numba's disk cache). Committing the generated text (instead of ``exec`` at import) lets numba cache
its compiled code and keeps every line of the fast path readable.
"""

from __future__ import annotations

import hashlib
import re
import sys
from fractions import Fraction
from functools import cache
from pathlib import Path
from typing import Any

from .errorbound import LEAF_MAX, NO_SCALE_MIN, TRANSLATE_MAX, Kernel, build_kernel
from .pencil import determinant, pencil_coefficients, poly_mul
from .quadrics import SYMMETRY_TOLERANCE
from .subresultants import hat_s0, hat_s1, hat_s10

__all__ = [
    "pencil_kernel",
    "pencil_radius_kernel",
    "translate_kernel",
    "subresultant_kernel",
    "generate_module",
    "GENERATED_PATH",
    "HATS",
]

GENERATED_PATH = Path(__file__).with_name("_kernels.py")
FASTPATH_PATH = Path(__file__).with_name("fastpath.py")
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
    is at most ``constant * x_M`` (see :mod:`core.errorbound`). ``leaf_K = 1`` gives the
    constants for entries that are correctly rounded values (a matrix symmetrised in floats);
    the source is the same.
    """

    def formula(L: dict[str, Any]) -> dict[str, Any]:
        A = [[L[_leaf("a", i, j)] for j in range(n)] for i in range(n)]
        B = [[L[_leaf("b", i, j)] for j in range(n)] for i in range(n)]
        out: dict[str, Any] = {}
        for i, (c, m) in enumerate(zip(pencil_coefficients(A, B), _row_bound_poly(A, B))):
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
        t = [L[f"t{i}"] for i in range(d)]
        out: dict[str, Any] = {}
        for i in range(d):
            for j in range(i, d):
                out[_leaf("m", i, j)] = M[i][j] * 1  # unchanged (exact)
        Qt = []
        for i in range(d):
            acc = M[i][d]
            for j in range(d):
                acc = acc + M[i][j] * t[j]
            Qt.append(acc)
            out[_leaf("m", i, d)] = acc  # (Q t + m)_i
        last = M[d][d]
        for i in range(d):
            last = last + t[i] * (Qt[i] + M[i][d])  # t^T Q t + 2 m.t + m_nn
        out[_leaf("m", d, d)] = last
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
    """Kernel ``pencil_radius{n}(A, Ar, B, Br)`` (midpoint-radius): a_0..a_n and the validity
    minors from entries that carry radii (the translated matrices, rescaled to |entry| + radius <= 2).
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


def prepare_source(n: int) -> str:
    """Unrolled ``prepare{n}(M, out)``: validate cheaply, flip to a negative interior, scale.

    Writes the upper triangle of ``f * S`` into ``out``, S the symmetric part of M and f = +-1
    when max|M_ij| already lies in [NO_SCALE_MIN, LEAF_MAX], else f = +-2^k (exact) bringing it
    into [1, 2), so that every entry is at most LEAF_MAX as :mod:`core.errorbound`'s bounds
    assume. Returns 1 when M is exactly symmetric (exact entries), 2 when it is symmetric up to
    rounding (entries are the correctly rounded half sums: use the ``leaf_K = 1`` constants),
    0 to abstain: NaN/inf, M_00 = 0, or an asymmetry that is not clearly within
    :data:`core.quadrics.SYMMETRY_TOLERANCE` (the exact path then decides or reports the error).
    The tolerance test is conservative: (d^2 (1 + 2^-48) <= tol^2 m_i m_j (1 - 2^-48), with
    tol^2 m_i m_j >= 2^-1000) on the scaled values implies the exact rule.
    """
    idx = [(i, j) for i in range(n) for j in range(i, n)]
    off = [(i, j) for i, j in idx if i != j]
    xs = [f"x{i}{j}" for i, j in idx] + [f"y{i}{j}" for i, j in off]
    tol2 = float(SYMMETRY_TOLERANCE) ** 2
    L = [f"def prepare{n}(M, out):"]
    L += [f"    x{i}{j} = M[{i}, {j}]" for i, j in idx]
    L += [f"    y{i}{j} = M[{j}, {i}]" for i, j in off]
    L.append("    if (x00 == 0.0) | " + " | ".join(f"({x} != {x})" for x in xs) + ":")
    L.append("        return 0")
    L.append("    mx = max(" + ", ".join(f"abs({x})" for x in xs) + ")")
    L.append("    if not mx <= 1.7976931348623157e308:")
    L.append("        return 0")
    L.append("    f = -1.0 if x00 < 0.0 else 1.0")
    L.append(f"    if not ({float(NO_SCALE_MIN)!r} <= mx <= {float(LEAF_MAX)!r}):")
    L.append("        _, e = math.frexp(mx)")
    L.append("        k = 1 - e  # up to 1075 for subnormal entries: 2^k is no float, use two factors")
    L.append("        g = math.ldexp(1.0, k - k // 2)")
    L += [f"        {x} = {x} * g" for x in xs]
    L.append("        f = math.ldexp(f, k // 2)")
    L.append("    if " + " & ".join(f"(x{i}{j} == y{i}{j})" for i, j in off) + ":")
    L += [f"        out[{i}, {j}] = x{i}{j} * f" for i, j in idx]
    L.append("        return 1")
    # symmetric up to rounding? row scales m_i of the scaled matrix (rows and columns)
    for i in range(n):
        row = [f"x{min(i, k)}{max(i, k)}" for k in range(n)] + [f"y{min(i, k)}{max(i, k)}" for k in range(n) if k != i]
        L.append(f"    m{i} = max(" + ", ".join(f"abs({v})" for v in row) + ") * abs(f)")
    conds = []
    for i, j in off:
        L.append(f"    d{i}{j} = abs(x{i}{j} * f - y{i}{j} * f)")
        L.append(f"    r{i}{j} = {tol2!r} * m{i} * m{j}")
        conds.append(
            f"((x{i}{j} == y{i}{j}) | ((r{i}{j} >= 9.332636185032189e-302) & "
            f"(d{i}{j} * d{i}{j} * 1.0000000000000036 <= r{i}{j} * 0.9999999999999964)))"
        )
    L.append("    if not (" + " & ".join(conds) + "):")
    L.append("        return 0")
    L.append("    h = 0.5 * f")
    L += [f"    out[{i}, {i}] = x{i}{i} * f" for i in range(n)]
    L += [f"    out[{i}, {j}] = x{i}{j} * h + y{i}{j} * h" for i, j in off]
    L.append("    return 2")
    return "\n".join(L) + "\n"


def generate_module() -> str:
    """Source text of ``core/_kernels.py``."""
    parts = [
        '"""Float kernels of the certified filter. GENERATED by ``python -m core.kernelgen``: do not edit.\n\n'
        "Each ``pencil{n}(A, B)`` reads ``A[i, j]`` (a float, or an array of floats for many pairs) and\n"
        "returns the outputs listed in ``PENCIL{n}_OUTPUTS``; |error of x| <= constant * x_M + floor.\n"
        "Each ``hat_{s}_{n}(c, cr)`` takes values and error radii of a_0..a_n and returns (value, radius);\n"
        '|error| <= radius * RADIUS_FACTOR + floor. See core/errorbound.py for the proofs.\n"""\n',
        "# ruff: noqa",
        "import math",
        "",
    ]
    for n in (3, 4):
        k = pencil_kernel(n)
        parts.append(prepare_source(n))
        parts.append(f"PENCIL{n}_OUTPUTS = {k.outputs!r}")
        parts.append(f"PENCIL{n}_CONSTANTS = {tuple(float(c) for c in k.constants)!r}")
        kr = pencil_kernel(n, leaf_K=1)
        parts.append(f"PENCIL{n}_CONSTANTS_ROUNDED = {tuple(float(c) for c in kr.constants)!r}")
        parts.append(f"PENCIL{n}_FLOOR_ROUNDED = {kr.underflow_floor!r}")
        parts.append(f"PENCIL{n}_FLOOR = {k.underflow_floor!r}")
        parts.append("")
        parts.append(k.source)
        for extra in (translate_kernel(n), pencil_radius_kernel(n)):
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


def _kernels_sha(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _stamp_fastpath(text: str) -> tuple[str, str]:
    """(current, updated) source of core/fastpath.py with KERNELS_SHA set for ``text``."""
    current = FASTPATH_PATH.read_text()
    updated = re.sub(r'^KERNELS_SHA = "[0-9a-f]*"', f'KERNELS_SHA = "{_kernels_sha(text)}"', current, flags=re.M)
    return current, updated


def main(argv: list[str] | None = None) -> int:
    """Write (default) or ``--check`` the generated module and the stamp in core/fastpath.py."""
    args = sys.argv[1:] if argv is None else argv
    text = generate_module()
    current_fp, updated_fp = _stamp_fastpath(text)
    if "--check" in args:
        current = GENERATED_PATH.read_text() if GENERATED_PATH.exists() else ""
        if current != text or current_fp != updated_fp:
            print(f"{GENERATED_PATH} or its stamp in {FASTPATH_PATH} is stale: run python -m core.kernelgen")
            return 1
        return 0
    GENERATED_PATH.write_text(text)
    if updated_fp != current_fp:
        # numba's disk cache of core.fastpath is keyed on fastpath.py: changing the stamp there
        # makes every checkout (not only this one) recompile the new kernels
        FASTPATH_PATH.write_text(updated_fp)
    print(f"wrote {GENERATED_PATH} ({len(text.splitlines())} lines), KERNELS_SHA = {_kernels_sha(text)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
