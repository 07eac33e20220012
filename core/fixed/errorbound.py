"""Straight-line float kernels with proven forward error bounds, generated from the ring-generic formulas.

The pencil (:mod:`core.formulae.pencil`) and subresultant (:mod:`core.formulae.subresultants`) formulas are traced once
with a symbolic number type (:class:`_Sym`) that records every ``+ - *``; from the trace we emit Python
source that runs unchanged on Python floats (one pair) and on numpy float64 arrays (many pairs), and
we derive each output's error constant from the trace itself (CGAL's ``compute_epsilon`` idea).
Two bound styles, both assuming round-to-nearest, fl(x op y) = (x op y)(1 + d), |d| <= u = 2^-53:

``"permanent"`` (stage 1, matrix entries -> pencil): a node's error count K is 0 for leaves (and
unchanged by negation and ``abs``),
``max(Kx, Ky) + 1`` for ``+``/``-``, ``Kx + Ky + 1`` for ``*``, ``Kx + 1`` for a constant factor that is
not a power of two. Then |fl(v) - v| <= gamma_K * M with gamma_K = K u / (1 - K u) and M the exact value
of the expression on absolute values with every ``-`` turned into ``+`` (Higham, Lemma 3.1, monomial by
monomial). Each output ``x`` has a companion output ``x_M``, an upper bound of M computed in the
same kernel from ``abs`` of the leaves (for instance products of row sums); M <= fl(x_M) / (1 - u)^K_M
since its terms are non-negative, so ``constants[x]`` = gamma_K / (1 - u)^(K_M + 2) rounded up (the
two extra roundings are those of ``C * fl(x_M)`` and of adding the underflow floor).

``"radius"`` (stage 2, uncertain a_i -> s0, s1, s1,0): midpoint-radius (running error) arithmetic;
every node carries r >= |computed - exact|:
``r(x +- y) = rx + ry + U|z|``, ``r(x * y) = |x| ry + rx (|y| + ry) + U|z|``, ``r(c x) = |c| rx (+ U|z|)``
with U = 2^-52 >= u / (1 - u) and z the computed result. Inputs keep their own radii, so the
cancellation already present in the a_i is not compounded (a permanent of a permanent would be).
The computed radius is itself rounded: ``radius_factor`` = 1 + 2^-40 >= (1 - u)^-(#radius ops).

Underflow and overflow (both styles): the filter scales each matrix by a power of two (exact, and
the relation does not change) unless its largest entry already lies in [2^-8, 2^24], so that every
entry is at most LEAF_MAX = 2^24. Then no value can overflow (the largest magnitude every node can
reach is computed here exactly from the leaf bounds, and :func:`build_kernel` refuses a kernel
whose nodes could reach 2^1000), and with gradual underflow each rounding is
fl(x op y) = (x op y)(1 + d) + e with |e| <= 2^-1075 (e = 0 for + and -; Higham, Sec. 2.2).
``underflow_floor`` adds the effect of all the e's on the output: each e is multiplied on its way
to the output by at most the largest magnitudes of the factors it meets (a backward pass over the
trace); it is below 2^-530 for our kernels (2^-850 when LEAF_MAX was 2^8), far under any sign we
certify: the smallest matrices left unscaled (largest entry 2^-8) give s0 around 2^-192.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Literal

__all__ = [
    "Kernel",
    "build_kernel",
    "gamma_constant",
    "round_up",
    "UNIT_ROUNDOFF",
    "LEAF_MAX",
    "NO_SCALE_MIN",
    "TRANSLATE_MAX",
    "RADIUS_FACTOR",
    "CERT_T_MIN",
    "CERT_T_MAX",
    "S0_RHO",
    "relative_input_constant",
    "form_constants",
    "Perm",
]

UNIT_ROUNDOFF = Fraction(1, 2**53)
"""u for float64 round-to-nearest."""

LEAF_MAX = 2**24
"""(Scaled) matrix entries must be <= 2^24: nothing can overflow (degree <= 24, largest node < 2^640).

2^24, not 2^8 as first: bodies a few thousand units from the origin (simulation boxes) have
entries c^T A c up to ~2^22 and skip the per-pair scaling (a scaling by a power of two changes no
relative error, only the overflow and underflow margins, which the generator checks)."""

TRANSLATE_MAX = 2**30
"""The translated second stage of the filter moves the origin by at most 2^30 per coordinate."""

NO_SCALE_MIN = Fraction(1, 256)
"""Matrices whose largest |entry| is already in [2^-8, 2^24] are not rescaled (saves time)."""

CERT_T_MIN, CERT_T_MAX = Fraction(1, 2**20), Fraction(2**20)
"""The separation certificate evaluates P(T*) only for T* in this range (overflow-free bounds)."""

S0_RHO = Fraction(1, 2**20)
"""The first s0 test (stage 2) runs only where every a_i is known to this relative accuracy:
cr_i * 2^20 <= |a_i| (an exact comparison: the product by a power of two is exact, since
cr_i >= the pencil's underflow floor > 2^-1040 keeps it in the normal range). Random pairs pass
(their a_i are accurate to ~1e-14); the others, and every pair whose s0 is too small for this
bound, go to the running-error s0 test after the certificates."""

RADIUS_FACTOR = 1.0 + 2.0**-40
"""Covers the rounding of a computed radius or bound (fewer than 2^12 roundings of nonneg terms)."""

_UNDERFLOW_ABS = Fraction(1, 2**1074)
"""Absolute error of one rounding in the subnormal range (half an ulp there, doubled for safety)."""


def round_up(c: Fraction) -> float:
    """The smallest float >= c (c >= 0)."""
    f = float(c)
    if Fraction(f) < c:
        f = math.nextafter(f, math.inf)
    return f


def gamma_constant(K: int, K_bound: int) -> float:
    """Float C with |fl(v) - v| <= fl(C * fl(M)).

    Args:
        K: error count of the value v.
        K_bound: error count of the computed upper bound M of its permanent (nonneg terms, so
            exact M <= fl(M) / (1 - u)^K_bound); two more roundings: the product C * fl(M) and
            the addition of the underflow floor.

    Examples:
        >>> gamma_constant(0, 0)
        0.0
        >>> 2.0**-53 < gamma_constant(1, 0) < 2.0**-52
        True
    """
    u = UNIT_ROUNDOFF
    if K == 0:
        return 0.0
    if max(K, K_bound) * u >= Fraction(1, 2**20):
        raise ValueError(f"error count {K} too large for float64")
    return round_up(K * u / (1 - K * u) / (1 - u) ** (K_bound + 2))


def relative_input_constant(K: int, K_bound: int, degree: int, rho: Fraction) -> float:
    """Float C with |fl(p(c)) - p(c~)| <= fl(C * fl(M)) + floor for inputs known to relative accuracy rho.

    The s0 test of stage 2 (semi-static, CGAL style: one evaluation of the value and one of its
    permanent, no radius per operation). Proof, for a straight-line polynomial p of degree at
    most ``degree`` evaluated on floats c_i with |c~_i - c_i| <= rho |c_i| (c~ the exact inputs):
    expanded monomial by monomial (with multiplicity, before any cancellation), p = sum_m t_m
    and M = sum_m |t_m| is the value of the program on |c_i| with every ``-`` turned into ``+``
    (:class:`Perm`). Each monomial moves by at most ((1 + rho)^degree - 1) |t_m| when its
    factors move by relative rho, and the rounding of fl(p(c)) is at most gamma_K M (Higham,
    Lemma 3.1, the error count K of the trace). So |fl(p(c)) - p(c~)| <= (gamma_K + (1 + rho)^degree
    - 1) M, and M <= fl(M) / (1 - u)^K_bound (non-negative terms), two more roundings for the
    product C * fl(M) and the floor's addition.

    Examples:
        >>> 6 * 2.0**-20 < relative_input_constant(10, 10, 6, Fraction(1, 2**20)) < 6.001 * 2.0**-20
        True
    """
    u = UNIT_ROUNDOFF
    if max(K, K_bound) * u >= Fraction(1, 2**20):
        raise ValueError(f"error count {K} too large for float64")
    gamma = K * u / (1 - K * u)
    return round_up((gamma + (1 + rho) ** degree - 1) / (1 - u) ** (K_bound + 2))


def form_constants(K: int, K_bound: int) -> tuple[float, float]:
    """(g, f) for the certificates' X^T M X with entries known up to radii r_ij and x exact.

    Proof: q(M, x) = X^T M X is linear in M. With M~ the exact entries (|m~_ij - m_ij| <= r_ij)
    and K the error count of the program, |fl(q) - q(M~, x)| <= gamma_K Q(|M|, |x|) + Q(R, |x|) =
    Q(gamma_K |M| + R, |x|), Q the program on non-negative entries with ``-`` turned into ``+``
    (linear in its matrix too). The kernel computes e_ij = fl(fl(|m_ij| g) + r_ij) with g >=
    gamma_K, then fl(Q(e, |x|)); the two roundings of e are in its error count K_bound (the
    trace sees them), so Q(gamma_K |M| + R, |x|) <= fl(Q(e, |x|)) / (1 - u)^K_bound, and f covers
    two more roundings (f * fl(Q) and the floor's addition). Underflow: the trace's floor,
    added twice (f ~ 1 also scales the companion's own underflow).

    Examples:
        >>> g, f = form_constants(7, 12)
        >>> 7 * 2.0**-53 <= g < 8 * 2.0**-53 and 1 < f < 1 + 2.0**-48
        True
    """
    u = UNIT_ROUNDOFF
    if max(K, K_bound) * u >= Fraction(1, 2**20):
        raise ValueError(f"error count {K} too large for float64")
    return round_up(K * u / (1 - K * u)), round_up(1 / (1 - u) ** (K_bound + 2))


class Perm:
    """The permanent of a traced program: ``-`` becomes ``+``, constant factors their absolute value.

    Wraps the leaves (already non-negative: ``abs`` of inputs, or bound entries) so that a
    ring-generic formula, run on them, traces M = sum of |monomials| (the companion bound of the
    permanent-style kernels); ``degree`` is the largest total degree of a monomial (leaves 1).
    """

    __slots__ = ("v", "degree")

    def __init__(self, v: Any, degree: int = 1) -> None:
        self.v = v
        self.degree = degree

    def __add__(self, o: Any) -> Perm:
        if isinstance(o, Perm):
            return Perm(self.v + o.v, max(self.degree, o.degree))
        return NotImplemented

    __sub__ = __add__

    def __mul__(self, o: Any) -> Perm:
        if isinstance(o, Perm):
            return Perm(self.v * o.v, self.degree + o.degree)
        if isinstance(o, int):
            return Perm(self.v * abs(o), self.degree)
        return NotImplemented

    __rmul__ = __mul__

    def __neg__(self) -> Perm:
        return self


def _is_power_of_two(c: int) -> bool:
    c = abs(c)
    return c > 0 and c & (c - 1) == 0


@dataclass
class _Node:
    op: str  # "leaf", "+", "-", "*", "c*", "neg"
    args: tuple[int, ...]
    const: int = 1
    name: str = ""
    K: int = 0


class _Trace:
    def __init__(self) -> None:
        self.nodes: list[_Node] = []

    def add(self, node: _Node) -> _Sym:
        self.nodes.append(node)
        return _Sym(self, len(self.nodes) - 1)


class _Sym:
    """Symbolic float: supports exactly the operations the formulas use (+, -, *, int factors)."""

    __slots__ = ("t", "i")

    def __init__(self, t: _Trace, i: int) -> None:
        self.t = t
        self.i = i

    def _bin(self, other: Any, op: str) -> _Sym:
        t = self.t
        if isinstance(other, int):
            if op != "*":
                return NotImplemented  # type: ignore[no-any-return]  # the operator passes it on
            if other == 0:
                raise ValueError("multiplication by 0 in a traced formula")
            if other == 1:
                return self
            K = t.nodes[self.i].K + (0 if _is_power_of_two(other) else 1)
            return t.add(_Node("c*", (self.i,), const=other, K=K))
        a, b = t.nodes[self.i], t.nodes[other.i]
        K = a.K + b.K + 1 if op == "*" else max(a.K, b.K) + 1
        return t.add(_Node(op, (self.i, other.i), K=K))

    def __add__(self, o: Any) -> _Sym:
        return self._bin(o, "+")

    def __sub__(self, o: Any) -> _Sym:
        return self._bin(o, "-")

    def __mul__(self, o: Any) -> _Sym:
        return self._bin(o, "*")

    def __rmul__(self, o: Any) -> _Sym:
        return self._bin(o, "*")

    def __neg__(self) -> _Sym:
        return self.t.add(_Node("neg", (self.i,), K=self.t.nodes[self.i].K))

    def __abs__(self) -> _Sym:
        return self.t.add(_Node("abs", (self.i,), K=self.t.nodes[self.i].K))


@dataclass(frozen=True)
class Kernel:
    """A generated kernel and the constants that make its outputs certified."""

    name: str
    """Function name in the generated source (core/fixed/_kernels.py)."""
    style: str
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    constants: tuple[float, ...]
    """permanent style: C_k with |error_k| <= C_k * M_k; radius style: unused (zeros)."""
    error_counts: tuple[int, ...]
    underflow_floor: float
    """Absolute error allowance for underflow (add to every bound)."""
    output_max: tuple[Fraction, ...]
    """Largest |value| of each output given the leaf bounds (exact)."""
    source: str
    n_ops: int


def _magnitudes(nodes: list[_Node], leaf_max: dict[str, Fraction]) -> list[Fraction]:
    """Largest |value| each node can take when every leaf x satisfies |x| <= leaf_max[x]."""
    mag: list[Fraction] = []
    for nd in nodes:
        if nd.op == "leaf":
            mag.append(leaf_max[nd.name])
        elif nd.op in "+-":
            mag.append(mag[nd.args[0]] + mag[nd.args[1]])
        elif nd.op == "*":
            mag.append(mag[nd.args[0]] * mag[nd.args[1]])
        elif nd.op == "c*":
            mag.append(abs(nd.const) * mag[nd.args[0]])
        else:
            mag.append(mag[nd.args[0]])
    return mag


def _underflow_floor(nodes: list[_Node], outputs: list[int], mag: list[Fraction], chains: int) -> float:
    """Bound on the effect at any output of 2^-1074 absolute error at every rounded node."""
    worst = Fraction(0)
    for o in outputs:
        F = [Fraction(0)] * len(nodes)  # propagation factor of a perturbation at each node
        F[o] = Fraction(1)
        for i in range(o, -1, -1):
            nd = nodes[i]
            if F[i] == 0 or nd.op == "leaf":
                continue
            if nd.op == "*":
                x, y = nd.args
                F[x] += F[i] * mag[y]
                F[y] += F[i] * mag[x]
            elif nd.op == "c*":
                F[nd.args[0]] += F[i] * abs(nd.const)
            else:
                for x in nd.args:
                    F[x] += F[i]
        # every node but neg/abs may round in the subnormal range; leaves too (the filter's
        # power-of-two rescaling of an input, or a rounded input, can land there)
        rounded = sum((F[i] for i, nd in enumerate(nodes) if nd.op not in ("neg", "abs")), Fraction(0))
        worst = max(worst, rounded)
    return round_up(chains * _UNDERFLOW_ABS * (worst + 1))


def build_kernel(
    name: str,
    inputs: Sequence[str],
    formula: Callable[[dict[str, _Sym]], dict[str, _Sym]],
    *,
    style: Literal["permanent", "radius"],
    leaf_max: dict[str, Fraction],
    leaf_exprs: dict[str, tuple[str, str]],
    params: Sequence[str],
    leaf_K: int = 0,
) -> Kernel:
    """Trace ``formula`` and emit the source of a float kernel with its certified error constants.

    Args:
        name: function name in the generated source.
        inputs: input variable names (the leaves).
        formula: maps leaf symbols by name to output symbols by name (ring-generic code).
        style: "permanent" (values only; each output ``x`` has a companion bound ``x_M``) or
            "radius" (midpoint-radius arithmetic; inputs carry radii).
        leaf_max: an upper bound of |leaf| for every input (for the underflow floor).
        leaf_exprs: source expressions (value, radius) reading each leaf from the parameters,
            e.g. ``("A[0, 1]", "")`` or ``("c[2]", "cr[2]")``.
        params: parameter names of the generated function.
        leaf_K: error count of every leaf ("permanent" style). 0: the inputs are exact. 1: each
            input is a correctly rounded value of the exact one (relative error <= u), e.g. the
            float sum a_ij + a_ji of a matrix symmetric only up to rounding; Higham's count
            then treats the leaf as one more rounding, in the value and in its bound.

    Returns:
        The :class:`Kernel`: source text (written to core/fixed/_kernels.py by core.fixed.kernelgen; no
        ``del`` so numba can compile it) and certified constants.
    """
    t = _Trace()
    leaves = {nm: t.add(_Node("leaf", (), name=nm, K=leaf_K)) for nm in inputs}
    out = formula(leaves)
    outputs = tuple(out)
    out_idx = [out[k].i for k in outputs]
    nodes = t.nodes
    radius = style == "radius"
    U = "2.220446049250313e-16"  # 2^-52 >= u / (1 - u)
    body = [f"def {name}({', '.join(params)}):"]
    # leaves whose radius is the constant 0 (an exact input, e.g. T of pencil_at): the terms of
    # their radius are left out (each is +0 for a finite value, and adding +0 to a radius >= 0
    # changes no bit; a non-finite value makes the kernel's value non-finite, which the callers'
    # comparisons already refuse)
    exact: set[int] = set()
    for j, nd in enumerate(nodes):
        x = nd.args[0] if nd.args else -1
        y = nd.args[1] if len(nd.args) > 1 else -1
        if nd.op == "leaf":
            vexpr, rexpr = leaf_exprs[nd.name]
            body.append(f"    v{j} = {vexpr}")
            if radius:
                body.append(f"    r{j} = {rexpr}")
                if rexpr == "0.0":
                    exact.add(j)
        elif nd.op in "+-":
            body.append(f"    v{j} = v{x} {nd.op} v{y}")
            if radius:
                terms = [f"r{i}" for i in (x, y) if i not in exact]
                body.append(f"    r{j} = {' + '.join([*terms, f'{U} * abs(v{j})'])}")
        elif nd.op == "*":
            body.append(f"    v{j} = v{x} * v{y}")
            if radius:
                terms = []
                if y not in exact:
                    terms.append(f"abs(v{x}) * r{y}")
                if x not in exact:
                    terms.append(f"r{x} * abs(v{y})" if y in exact else f"r{x} * (abs(v{y}) + r{y})")
                body.append(f"    r{j} = {' + '.join([*terms, f'{U} * abs(v{j})'])}")
        elif nd.op == "c*":
            body.append(f"    v{j} = v{x} * {nd.const}.0")
            if radius:
                extra = "" if _is_power_of_two(nd.const) else f" + {U} * abs(v{j})"
                body.append(f"    r{j} = r{x} * {abs(nd.const)}.0{extra}")
        elif nd.op == "abs":
            body.append(f"    v{j} = abs(v{x})")
            if radius:
                body.append(f"    r{j} = r{x}")
        else:  # neg
            body.append(f"    v{j} = -v{x}")
            if radius:
                body.append(f"    r{j} = r{x}")
    ret = [f"v{o}" for o in out_idx] + ([f"r{o}" for o in out_idx] if radius else [])
    body.append(f"    return ({', '.join(ret)},)")
    source = "\n".join(body) + "\n"
    mag = _magnitudes(nodes, leaf_max)
    if max(mag) >= 2**1000:
        raise ValueError(f"{name}: a node can reach 2^{math.log2(max(mag)):.0f}: leaf bounds too large for float64")
    floor = _underflow_floor(nodes, out_idx, mag, chains=3 if radius else 1)
    # an output "x" is bounded by its companion output "x_M" (an upper bound of its permanent)
    K_of = {k: nodes[out[k].i].K for k in outputs}
    consts = tuple(
        0.0 if radius or k.endswith("_M") else gamma_constant(K_of[k], K_of.get(k + "_M", K_of[k]))
        for k in outputs
    )
    return Kernel(
        name=name,
        style=style,
        inputs=tuple(inputs),
        outputs=outputs,
        constants=consts,
        error_counts=tuple(nodes[o].K for o in out_idx),
        underflow_floor=floor,
        output_max=tuple(mag[o] for o in out_idx),
        source=source,
        n_ops=sum(1 for nd in nodes if nd.op != "leaf"),
    )
