"""The sweep filter's error allowances, checked against traces of the operations they cover.

The C kernel (``core/moving/_sweep_filter.c``) evaluates its pencil in midpoint-radius arithmetic;
every constant a radius formula adds is a named allowance there (``#define ADD_U U``,
``#define DOT_U(m) ((m) * U)``, ...). This module reads their values from the C source, traces each
primitive's float operations, written here as the C writes them, with the tracer of the static
filter's generated kernels (:mod:`core.fixed.errorbound`: its rounding counts K and its
:func:`~core.fixed.errorbound.gamma_constant`), and derives the least value each allowance must
have. A drift check: the allowances stay readable hand-written C (several are generous on purpose:
U = 2^-52 is twice u, one ETA = 2^-1022 covers 2^53 underflows) and the answers stay bit for bit
what they were; the check fails when an allowance is below what its trace requires, when one is
unused, when a ``#define`` mentions U or ETA without a derivation here, and when U or ETA is used
outside the allowances (an unnamed constant nothing would check).

Requirements (u = 2^-53; a rounding is fl(a) = a (1 + d) = a / (1 + d'), |d|, |d'| <= u; Higham,
Lemma 3.1, counts quotients as products):

* ``c |z|`` (the computed result z of a program with K roundings):
  c >= gamma_K / (1 - gamma_K), since |z - exact| <= gamma_K |exact| <= gamma_K |z| / (1 - gamma_K);
* ``c M`` (M the float companion the C computes, on non-negative terms, K_M roundings):
  c >= ``gamma_constant(K, K_M)`` = gamma_K / (1 - u)^(K_M + 2), errorbound's proof;
* ``c ETA``: each product or quotient of the value, its companion or its radius may lose 2^-1074 in
  the subnormal range (errorbound's allowance per rounding there): c ETA >= their number times that;
* ``RF`` = 1 + 2^-30 >= 1 / (1 - 2^22 u) >= (1 - u)^-(2^22): a radius, evaluated on non-negative
  terms, loses at most a factor 1 - u per dependent rounding; that the chains are shorter than
  2^22 roundings is argued in the C, not traced here;
* ``CERTIFY_STEPS_UP``: the fewest steps k with (1 - u)^2 (1 + u)^(k - 1) >= 1 (certify_prefix);
* ``BRACKET`` + 2^-53 <= 1e-9, the documented width t_hi - t_lo (the rounding of t_a + BRACKET);
* the binomials C(n, k), n < MAXF, are exact as the C computes them (C (n - k) / (k + 1)).

``python -m core.moving.sweepbounds`` prints the table; ``--check`` prints only the problems (exit
status 1 if any); ``python -m core.generated --check`` runs it with the generated files' checks.
"""

from __future__ import annotations

import ast
import math
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

# the tracer itself (its nodes carry Higham's rounding count K), as core.fixed.kernelgen uses it
# through build_kernel; here leaves need their own K (a weight 1 - t rounded once)
from ..fixed.errorbound import _UNDERFLOW_ABS, UNIT_ROUNDOFF, _Node, _Sym, _Trace, gamma_constant

__all__ = ["SOURCE", "Row", "read_defines", "rows", "problems", "main"]

SOURCE = Path(__file__).with_name("_sweep_filter.c")
"""The C kernel whose allowances are checked."""

WIDTH = Fraction(1, 10**9)
"""The documented bracket width: t_hi - t_lo <= 1e-9 (:class:`core.moving.sweep_filter.FilterResult`)."""

CHAIN = 2**22
"""Dependent roundings of a radius that RF must make up for (the C's own bound, argued there)."""

_HEX_FLOAT = re.compile(r"\b0[xX][0-9a-fA-F]*\.?[0-9a-fA-F]*[pP][+-]?\d+\b")
_DEFINE = re.compile(r"^[ \t]*#[ \t]*define[ \t]+(\w+)(?:\((\w+)\))?[ \t]+(.+?)[ \t]*$", re.M)
_COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)


@dataclass(frozen=True)
class Row:
    """One allowance of the C (at one argument for a macro of m) and what its trace requires."""

    name: str
    """The allowance, e.g. ``DOT_U(7)``."""
    allowance: Fraction
    """Its value in the C (exact)."""
    required: Fraction
    """The least safe value (or, with ``at_most``, the largest)."""
    why: str
    """The derivation in a few words (the trace's counts)."""
    at_most: bool = False

    @property
    def ok(self) -> bool:
        """Whether the allowance covers its requirement."""
        return self.allowance <= self.required if self.at_most else self.allowance >= self.required


# ----------------------------------------------------------------------------- reading the C


def _strip_comments(text: str) -> str:
    """The C text without comments (newlines kept, so line numbers stay)."""
    return _COMMENT.sub(lambda m: "\n" * m.group(0).count("\n"), text)


def read_defines(text: str) -> dict[str, tuple[str | None, str]]:
    """Every ``#define NAME body`` or ``#define NAME(p) body`` of the C text: name -> (parameter, body)."""
    return {m.group(1): (m.group(2), m.group(3)) for m in _DEFINE.finditer(_strip_comments(text))}


def _evaluate(name: str, defines: dict[str, tuple[str | None, str]], arg: int | None = None, depth: int = 0) -> int | float:
    """The value of a macro as C computes it (ints and doubles: + - * /, parentheses, other macros)."""
    if name not in defines:
        raise ValueError(f"{SOURCE.name} defines no {name}")
    if depth > 20:
        raise ValueError(f"{name}: macros nested too deeply")
    param, body = defines[name]
    if (param is None) != (arg is None):
        raise ValueError(f"{name} is {'a macro of ' + param if param else 'a constant'} in {SOURCE.name}")
    hexes: dict[str, float] = {}

    def hex_name(m: re.Match[str]) -> str:
        hexes[f"_hex{len(hexes)}"] = float.fromhex(m.group(0))
        return f"_hex{len(hexes) - 1}"

    tree = ast.parse(_HEX_FLOAT.sub(hex_name, body), mode="eval")

    def ev(node: ast.AST) -> int | float:
        if isinstance(node, ast.Constant) and isinstance(node.value, int | float) and not isinstance(node.value, bool):
            return node.value
        if isinstance(node, ast.Name):
            if node.id in hexes:
                return hexes[node.id]
            if node.id == param and arg is not None:
                return arg
            return _evaluate(node.id, defines, None, depth + 1)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
            x = ev(node.operand)
            return -x if isinstance(node.op, ast.USub) else x
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add | ast.Sub | ast.Mult | ast.Div):
            x, y = ev(node.left), ev(node.right)
            if isinstance(node.op, ast.Add):
                return x + y
            if isinstance(node.op, ast.Sub):
                return x - y
            if isinstance(node.op, ast.Mult):
                return x * y
            if isinstance(x, int) and isinstance(y, int):
                raise ValueError(f"{name}: integer division in {body!r}")
            return x / y
        raise ValueError(f"{name}: cannot evaluate {body!r}")

    return ev(tree.body)


# ----------------------------------------------------------------------------- traces


@dataclass(frozen=True)
class _Traced:
    K: dict[str, int]
    """Rounding count of each output (value z, companion M)."""
    products: int
    """Products and quotients anywhere in the trace (value, companion, radius): underflows."""


def _trace(formula: Callable[[dict[str, _Sym]], dict[str, _Sym]], leaves: dict[str, int]) -> _Traced:
    """Trace a primitive written as the C writes it; leaves: name -> rounding count of that input."""
    t = _Trace()
    L = {name: t.add(_Node("leaf", (), name=name, K=k)) for name, k in leaves.items()}
    out = formula(L)
    return _Traced({k: t.nodes[s.i].K for k, s in out.items()}, sum(1 for nd in t.nodes if nd.op == "*"))


def _leaves(*names: str, rounded: tuple[str, ...] = ()) -> dict[str, int]:
    """Exact float inputs (K = 0), and inputs rounded once from an exact value (K = 1)."""
    return {**{n: 0 for n in names}, **{n: 1 for n in rounded}}


def _add(L: dict[str, _Sym]) -> dict[str, _Sym]:
    """badd, bsub, lf_addsub, lf_elevate: z = x + y, r = rx + ry + ADD_U |z| (+ ADD_ETA)."""
    z = L["x"] + L["y"]
    return {"z": z, "r": L["rx"] + L["ry"] + L["ADD_U"] * abs(z)}


def _mul(L: dict[str, _Sym]) -> dict[str, _Sym]:
    """bmul, lf_scale: z = x y, r = |x| ry + rx (|y| + ry) + MUL_U |z| (+ MUL_ETA)."""
    z = L["x"] * L["y"]
    return {"z": z, "r": abs(L["x"]) * L["ry"] + L["rx"] * (abs(L["y"]) + L["ry"]) + L["MUL_U"] * abs(z)}


def _div(L: dict[str, _Sym]) -> dict[str, _Sym]:
    """lf_bernstein: z = x / C, r = rx / C + DIV_U |z| (+ DIV_ETA); a quotient rounds once, as a product."""
    z = L["x"] * L["1/C"]
    return {"z": z, "r": L["rx"] * L["1/C"] + L["DIV_U"] * abs(z)}


def _inv_square(L: dict[str, _Sym]) -> dict[str, _Sym]:
    """load_body: s2 = s s, D = 1 / s2 (the quotient's rounding traced as a product's), r = INV_SQUARE_U D."""
    s2 = L["s"] * L["s"]
    D = L["1/"] * s2
    return {"z": D, "r": L["INV_SQUARE_U"] * D}


def _times(c: int) -> Callable[[dict[str, _Sym]], dict[str, _Sym]]:
    """lf_times: z = c x, r = |c| rx (+ TIMES_ETA), c in {-2, -1, 2}: exact."""

    def formula(L: dict[str, _Sym]) -> dict[str, _Sym]:
        return {"z": L["x"] * c, "r": L["rx"] * abs(c)}

    return formula


def _rescale(L: dict[str, _Sym]) -> dict[str, _Sym]:
    """load_pair: z = x 2^-e, r = rx 2^-e (+ RESCALE_ETA): exact but for underflow (the count only)."""
    return {"r": L["rx"] * L["2^-e"], "underflow": L["x"] * L["2^-e"]}


def _lerp(L: dict[str, _Sym]) -> dict[str, _Sym]:
    """blerp: al = fl(1 - t) (rounded once), z = al x0 + t x1, mag = al (|x0| + r0) + t |x1|."""
    al, t = L["al"], L["t"]
    z = al * L["x0"] + t * L["x1"]
    mag = al * (abs(L["x0"]) + L["r0"]) + t * abs(L["x1"])
    r = al * L["r0"] + t * L["r1"] + L["LERP_MAG_U"] * mag + L["LERP_Z_U"] * abs(z)
    return {"z": z, "M": mag, "r": r}


def _split(L: dict[str, _Sym]) -> dict[str, _Sym]:
    """f_split, one step: al = fl(1 - tau), x = al v0 + tau v1, mag = al (|v0| + r0) + tau |v1|."""
    al, tau = L["al"], L["tau"]
    x = al * L["v0"] + tau * L["v1"]
    mag = al * (abs(L["v0"]) + L["r0"]) + tau * abs(L["v1"])
    return {"z": x, "M": mag, "r": al * L["r0"] + tau * L["r1"] + L["SPLIT_MAG_U"] * mag}


def _dot(m: int) -> Callable[[dict[str, _Sym]], dict[str, _Sym]]:
    """lf_mul, one coefficient: m products summed in order (from 0: the first sum is exact)."""

    def formula(L: dict[str, _Sym]) -> dict[str, _Sym]:
        terms = []
        for i in range(m):
            x, y, rx, ry = L[f"x{i}"], L[f"y{i}"], L[f"rx{i}"], L[f"ry{i}"]
            ax, ay = abs(x), abs(y)
            terms.append((x * y, ax * ay, ax * ry + rx * (ay + ry)))
        sv, S, R = terms[0]
        for p, q, w in terms[1:]:
            sv, S, R = sv + p, S + q, R + w
        return {"z": sv, "M": S, "r": R + L["DOT_U(m)"] * S}

    return formula


def _combine(m: int) -> Callable[[dict[str, _Sym]], dict[str, _Sym]]:
    """combine, one coefficient: sum of the m = n + 1 terms T^k b_k (T^k a ball), in order."""

    def formula(L: dict[str, _Sym]) -> dict[str, _Sym]:
        terms = []
        for k in range(m):
            T, Tr, y, ry = L[f"T{k}"], L[f"Tr{k}"], L[f"y{k}"], L[f"ry{k}"]
            x = T * y
            terms.append((x, abs(x), T * ry + Tr * (abs(y) + ry)))
        s, S, R = terms[0]
        for p, q, w in terms[1:]:
            s, S, R = s + p, S + q, R + w
        return {"z": s, "M": S, "r": R + L["COMBINE_U(m)"] * S}

    return formula


def _dot_leaves(m: int, a: str, b: str, ra: str, rb: str, constant: str) -> dict[str, int]:
    return _leaves(*(f"{p}{i}" for i in range(m) for p in (a, b, ra, rb)), constant)


# ----------------------------------------------------------------------------- requirements


def _gamma(K: int) -> Fraction:
    u = UNIT_ROUNDOFF
    return K * u / (1 - K * u)


def _on_result(K: int) -> Fraction:
    """Least c with |z - exact| <= c |z| after K roundings."""
    return _gamma(K) / (1 - _gamma(K))


def _underflow(tr: _Traced) -> Fraction:
    return tr.products * _UNDERFLOW_ABS


def rows(text: str | None = None) -> list[Row]:
    """Every allowance of the C text (default: :data:`SOURCE`) with the requirement its trace gives.

    Raises:
        ValueError: an allowance is missing or its ``#define`` cannot be evaluated.
    """
    defines = read_defines(SOURCE.read_text() if text is None else text)

    def value(name: str, arg: int | None = None) -> Fraction:
        return Fraction(_evaluate(name, defines, arg))

    out: list[Row] = []

    def single(kind: str, tr: _Traced, what: str) -> None:
        out.append(Row(f"{kind}_U", value(f"{kind}_U"), _on_result(tr.K["z"]), f"{what}: c |z|, K = {tr.K['z']}"))

    def eta(name: str, tr: _Traced, what: str, arg: int | None = None) -> None:
        label = name if arg is None else f"{name}({arg})"
        out.append(Row(label, value(name, arg), _underflow(tr), f"{what}: may underflow {tr.products} times (products, quotients)"))

    add = _trace(_add, _leaves("x", "y", "rx", "ry", "ADD_U"))
    single("ADD", add, "x +- y")
    eta("ADD_ETA", add, "x +- y")
    mul = _trace(_mul, _leaves("x", "y", "rx", "ry", "MUL_U"))
    single("MUL", mul, "x y")
    eta("MUL_ETA", mul, "x y")
    div = _trace(_div, _leaves("x", "rx", "1/C", "DIV_U"))
    single("DIV", div, "x / C")
    eta("DIV_ETA", div, "x / C")
    inv = _trace(_inv_square, _leaves("s", "1/", "INV_SQUARE_U"))
    single("INV_SQUARE", inv, "1 / (s s), s in [2^-60, 1]: never underflows")
    times = [_trace(_times(c), _leaves("x", "rx")) for c in (-2, -1, 2)]
    worst = max(times, key=lambda tr: tr.products)
    if any(tr.K["z"] for tr in times):
        raise ValueError("c x rounds for some c in {-2, -1, 2}: TIMES needs a rounding allowance")
    eta("TIMES_ETA", worst, "c x, c in {-2, -1, 2}, exact")
    eta("RESCALE_ETA", _trace(_rescale, _leaves("x", "rx", "2^-e")), "x 2^-e, exact")
    for kind, formula, leaves, what in (
        ("LERP", _lerp, _leaves("t", "x0", "x1", "r0", "r1", "LERP_MAG_U", "LERP_Z_U", rounded=("al",)), "(1 - t) x0 + t x1"),
        ("SPLIT", _split, _leaves("tau", "v0", "v1", "r0", "r1", "SPLIT_MAG_U", rounded=("al",)), "de Casteljau step"),
    ):
        tr = _trace(formula, leaves)
        K, KM = tr.K["z"], tr.K["M"]
        out.append(Row(f"{kind}_MAG_U", value(f"{kind}_MAG_U"), Fraction(gamma_constant(K, KM)),
                       f"{what}: c M, K = {K} (1 - t rounded), K_M = {KM}"))
        if kind == "LERP":
            out.append(Row("LERP_Z_U", value("LERP_Z_U"), Fraction(0), f"{what}: c |z|, not needed (c M covers the rounding)"))
        eta(f"{kind}_ETA", tr, what)
    maxf = int(_evaluate("MAXF", defines))
    for name, build, count, args in (("DOT", _dot, range(1, maxf + 1), ("x", "y", "rx", "ry")),
                                     ("COMBINE", _combine, range(1, 6), ("T", "y", "Tr", "ry"))):
        for m in count:
            tr = _trace(build(m), _dot_leaves(m, *args, f"{name}_U(m)"))
            K, KM = tr.K["z"], tr.K["M"]
            out.append(Row(f"{name}_U({m})", value(f"{name}_U", m), Fraction(gamma_constant(K, KM)),
                           f"sum of {m} products: c M, K = {K}, K_M = {KM}"))
            eta(f"{name}_ETA", tr, f"sum of {m} products", m)
    u = UNIT_ROUNDOFF
    out.append(Row("RF", value("RF"), 1 / (1 - CHAIN * u), f"radius factor: (1 - u)^-k for k <= 2^{CHAIN.bit_length() - 1} roundings"))
    k = 1
    while (1 - u) ** 2 * (1 + u) ** (k - 1) < 1:
        k += 1
    out.append(Row("CERTIFY_STEPS_UP", value("CERTIFY_STEPS_UP"), Fraction(k), "fewest k with (1 - u)^2 (1 + u)^(k - 1) >= 1"))
    out.append(Row("BRACKET", value("BRACKET"), WIDTH - Fraction(1, 2**53), "t_a + BRACKET rounded (< 2: <= 2^-53) within 1e-9", at_most=True))
    return out


def _binomials_exact(maxf: int) -> list[str]:
    """C(n, k) for n < maxf as lf_bernstein computes it (C = C (n - k) / (k + 1) in doubles) vs the exact one."""
    bad = []
    for n in range(maxf):
        C = 1.0
        for k in range(n + 1):
            if C != math.comb(n, k):
                bad.append(f"C({n}, {k}) computed as {C!r} is not exact")
            C = C * (n - k) / (k + 1)
    return bad


def _unnamed_uses(text: str, names: set[str]) -> list[str]:
    """Uses of U or ETA outside the allowances' definitions, and allowances never used."""
    bad = []
    code = _strip_comments(text)
    used: set[str] = set()
    for number, line in enumerate(code.splitlines(), 1):
        if re.match(r"[ \t]*#[ \t]*define\b", line):
            continue
        used.update(re.findall(r"\b[A-Z_]+\b", line))
        for token in re.findall(r"\b(?:U|ETA)\b", line):
            bad.append(f"line {number} of {SOURCE.name} uses {token} outside a named allowance: name it and derive it here")
    bad += [f"{n} is defined but not used in {SOURCE.name}: remove it or use it" for n in sorted(names - used)]
    return bad


def problems(text: str | None = None) -> list[str]:
    """Everything wrong with the C's allowances (empty when each covers its trace), one line each."""
    text = SOURCE.read_text() if text is None else text
    try:
        table = rows(text)
    except ValueError as e:
        return [str(e)]
    defines = read_defines(text)
    names = {r.name.split("(")[0] for r in table}
    out = [
        f"{r.name} = {float(r.allowance)!r} is {'above' if r.at_most else 'below'} {float(r.required)!r} ({r.why}): "
        f"unsafe, fix {SOURCE.name}"
        for r in table
        if not r.ok
    ]
    out += [
        f"{name} mentions U or ETA but has no derivation: add one to core/moving/sweepbounds.py"
        for name, (_, body) in defines.items()
        if name not in names | {"U", "ETA"} and re.search(r"\b(?:U|ETA)\b", body)
    ]
    out += _unnamed_uses(text, names)
    out += _binomials_exact(int(_evaluate("MAXF", defines)))
    return out


def _units(r: Row) -> str:
    """The allowance in units of U or ETA, where it is a multiple of one."""
    for unit, size in (("U", Fraction(1, 2**52)), ("ETA", Fraction(1, 2**1022))):
        if r.name.split("(")[0].endswith(unit) and r.allowance:
            return f"{float(r.allowance / size):g} {unit}"
    return str(r.allowance) if r.allowance.denominator == 1 else repr(float(r.allowance))


def _ratio(r: Row) -> Fraction:
    """How many times the requirement the allowance is (its inverse for a largest value)."""
    if not r.required or not r.allowance:
        return Fraction(10**30)
    return r.required / r.allowance if r.at_most else r.allowance / r.required


def main(argv: list[str] | None = None) -> int:
    """Print the table of allowances (default) or, with ``--check``, only the problems; 1 if any."""
    args = sys.argv[1:] if argv is None else argv
    found = problems()
    if "--check" not in args:
        tightest: dict[str, Row] = {}  # a macro of m: the row with the least margin
        for r in rows():
            base = r.name.split("(")[0]
            if base not in tightest or _ratio(r) < _ratio(tightest[base]):
                tightest[base] = r
        print(f"{'allowance':20s} {'in the C':>14s} {'required':>24s} {'margin':>9s}  derivation (a macro of m: its tightest m)")
        for r in tightest.values():
            margin = f"{float(_ratio(r)):.3g}" if r.required and r.allowance else "-"
            print(f"{r.name:20s} {_units(r):>14s} {float(r.required):>24.17g} {margin:>9s}  {r.why}")
    for line in found:
        print(f"{SOURCE}: {line}")
    return 1 if found else 0


if __name__ == "__main__":
    raise SystemExit(main())
