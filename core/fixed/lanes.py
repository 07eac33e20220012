"""Two readings of one lane program: numpy arrays (run it) and C statements (write it).

The filter's driver (:mod:`core.fixed.driver`) is written once, as straight-line code on "lanes"
(one value per pair) through a small namespace of operations. :class:`NumpyLanes` runs it on
float64 arrays, one element per pair: that is the numpy filter. :class:`CLanes` runs the same
code on :class:`CExpr` symbols and records one C statement per named value: that is the body of
the C lane functions in ``core/fixed/_kernels.h`` (:mod:`core.fixed.kernelgen` writes them).

Every floating-point operation is one IEEE operation in both readings, in the same order (the C
expressions are fully parenthesised; the C is compiled with ``-ffp-contract=off`` and without
``-ffast-math``), so the two agree bit for bit and the error bounds of :mod:`core.fixed.errorbound`
hold for both. Masks are numpy bool arrays and C ``int`` 0/1 (no short-circuit: ``&``/``|``);
``where`` evaluates both sides in numpy and is a select in C (same value).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

__all__ = ["NumpyLanes", "CLanes", "CExpr", "KernelInfo"]


@dataclass(frozen=True)
class KernelInfo:
    """What the driver needs to know of a straight-line kernel."""

    outputs: tuple[str, ...]
    count: int
    """Numbers it returns: the outputs, then (midpoint-radius kernels) their radii."""
    floor: float
    constants: tuple[float, ...] = ()
    constants_rounded: tuple[float, ...] = ()
    floor_rounded: float = 0.0


@cache
def _numpy_info(name: str) -> KernelInfo:
    from . import _kernels as K

    up = name.upper()
    outputs = tuple(getattr(K, f"{up}_OUTPUTS", ("s",)))
    radius = not hasattr(K, f"{up}_CONSTANTS")
    return KernelInfo(
        outputs=outputs,
        count=len(outputs) * (2 if radius else 1),
        floor=getattr(K, f"{up}_FLOOR"),
        constants=tuple(getattr(K, f"{up}_CONSTANTS", ())),
        constants_rounded=tuple(getattr(K, f"{up}_CONSTANTS_ROUNDED", ())),
        floor_rounded=getattr(K, f"{up}_FLOOR_ROUNDED", 0.0),
    )


class NumpyLanes:
    """Operations of the lane language on numpy arrays (one element per pair)."""

    def let(self, name: str, value: Any) -> Any:
        """Name a value (C: a ``const`` local); numpy: the value itself."""
        return value

    def where(self, m: Any, a: Any, b: Any) -> Any:
        """Select a where m, else b."""
        return np.where(m, a, b)

    def max(self, a: Any, b: Any) -> Any:
        """``a > b ? a : b`` (exact; NaN behaves as in C)."""
        return np.where(a > b, a, b)

    def abs(self, a: Any) -> Any:
        """|a|."""
        return np.abs(a)

    def abs_max_finite(self, name: str, values: list[Any]) -> tuple[Any, Any]:
        """``(max |v|, every v finite)`` over the values (the max chained with :meth:`max`).

        The max is only read where every value is finite (the C reads it from the bits).
        """
        nan_free = values[0] == values[0]
        mx = np.abs(values[0])
        for v in values[1:]:
            nan_free = nan_free & (v == v)
            mx = self.max(mx, np.abs(v))
        return mx, nan_free & (mx <= np.finfo(np.float64).max)

    def sqrt(self, a: Any) -> Any:
        """Correctly rounded square root."""
        return np.sqrt(a)

    def integer(self, v: int, like: Any) -> Any:
        """An integer constant per lane."""
        return np.full(np.shape(like), v, dtype=np.int64)

    def frexp_exponent(self, v: Any) -> Any:
        """E with v in [2^(e-1), 2^e) (v finite and > 0)."""
        return np.frexp(v)[1].astype(np.int64)

    def pow2(self, k: Any) -> Any:
        """2^k as a float64, for integers -1022 <= k <= 1023 (exact)."""
        return np.ldexp(1.0, k)

    def imin(self, a: Any, b: int) -> Any:
        """Min of an integer lane and a constant."""
        return np.minimum(a, b)

    def imax(self, a: Any, b: int) -> Any:
        """Max of an integer lane and a constant."""
        return np.maximum(a, b)

    def digit(self, v: Any, bound: Any) -> Any:
        """Table digit of a certified sign: 0 for -1, 2 for +1, 3 uncertain (never 'zero')."""
        return np.where(v > bound, 2, np.where(v < -bound, 0, 3)).astype(np.int64)

    def table(self, table: np.ndarray, name: str, index: Any) -> Any:
        """``table[index]`` as int64."""
        return table[index].astype(np.int64)

    def info(self, name: str) -> KernelInfo:
        """Outputs, error constants and underflow floor of a generated kernel."""
        return _numpy_info(name)

    def call(self, name: str, args: Sequence[Any], scalars: Sequence[Any] = ()) -> tuple[Any, ...]:
        """Run a generated straight-line kernel of :mod:`core.fixed._kernels`."""
        from . import _kernels

        return tuple(getattr(_kernels, name)(*args, *scalars))

    def matrix(self, entries: dict[tuple[int, int], Any], n: int, name: str) -> Any:
        """A matrix argument of a kernel (entries by (i, j), upper triangle)."""
        return entries

    def vector(self, entries: Sequence[Any], name: str) -> Any:
        """A vector argument of a kernel."""
        return list(entries)


class CExpr:
    """A C expression of type double ("d") or int64_t ("i"), built by Python operators."""

    __slots__ = ("text", "ty")

    def __init__(self, text: str, ty: str) -> None:
        self.text = text
        self.ty = ty

    def _bin(self, other: Any, op: str, ty: str | None = None, rev: bool = False) -> CExpr:
        o = _as_c(other, self.ty)
        res = ty or ("d" if "d" in (self.ty, o.ty) else "i")
        a, b = (o, self) if rev else (self, o)
        return CExpr(f"({a.text} {op} {b.text})", res)

    def __add__(self, o: Any) -> CExpr:
        return self._bin(o, "+")

    def __radd__(self, o: Any) -> CExpr:
        return self._bin(o, "+", rev=True)

    def __sub__(self, o: Any) -> CExpr:
        return self._bin(o, "-")

    def __rsub__(self, o: Any) -> CExpr:
        return self._bin(o, "-", rev=True)

    def __mul__(self, o: Any) -> CExpr:
        return self._bin(o, "*")

    def __rmul__(self, o: Any) -> CExpr:
        return self._bin(o, "*", rev=True)

    def __truediv__(self, o: Any) -> CExpr:
        return self._bin(o, "/")

    def __rtruediv__(self, o: Any) -> CExpr:
        return self._bin(o, "/", rev=True)

    def __neg__(self) -> CExpr:
        return CExpr(f"(-{self.text})", self.ty)

    def __lt__(self, o: Any) -> CExpr:
        return self._bin(o, "<", "i")

    def __le__(self, o: Any) -> CExpr:
        return self._bin(o, "<=", "i")

    def __gt__(self, o: Any) -> CExpr:
        return self._bin(o, ">", "i")

    def __ge__(self, o: Any) -> CExpr:
        return self._bin(o, ">=", "i")

    def __eq__(self, o: Any) -> CExpr:  # type: ignore[override]
        return self._bin(o, "==", "i")

    def __ne__(self, o: Any) -> CExpr:  # type: ignore[override]
        return self._bin(o, "!=", "i")

    def __and__(self, o: Any) -> CExpr:
        return self._bin(o, "&", "i")

    def __rand__(self, o: Any) -> CExpr:
        return self._bin(o, "&", "i", rev=True)

    def __or__(self, o: Any) -> CExpr:
        return self._bin(o, "|", "i")

    def __ror__(self, o: Any) -> CExpr:
        return self._bin(o, "|", "i", rev=True)

    def __invert__(self) -> CExpr:
        return CExpr(f"(!{self.text})", "i")

    __hash__ = None  # type: ignore[assignment]


def _literal(v: float) -> str:
    """A C double literal that parses to exactly v (repr is the shortest round trip)."""
    r = repr(float(v))
    return r if ("e" in r or "." in r or "inf" in r or "nan" in r) else r + ".0"


def _as_c(v: Any, like: str) -> CExpr:
    if isinstance(v, CExpr):
        return v
    if isinstance(v, bool):
        return CExpr(str(int(v)), "i")
    if isinstance(v, int) and like == "i":
        return CExpr(f"INT64_C({v})" if abs(v) > 2**31 - 1 else str(v), "i")
    return CExpr(_literal(float(v)), "d")


class CLanes:
    """Operations of the lane language that write C: each ``let`` becomes one statement."""

    def __init__(self, kernels: dict[str, KernelInfo], params: Sequence[str] = ()) -> None:
        self.lines: list[str] = []
        self._names: dict[str, int] = {p: 1 for p in params}
        """Names in use (the function's parameters): a local of the same name gets a suffix."""
        self._kernels = kernels

    def info(self, name: str) -> KernelInfo:
        """Outputs, error constants and underflow floor of a kernel (from the fresh trace)."""
        return self._kernels[name]

    def _fresh(self, name: str) -> str:
        k = self._names.get(name, 0)
        self._names[name] = k + 1
        return name if k == 0 else f"{name}_{k}"

    def comment(self, text: str) -> None:
        """A C comment line (the description's prose, carried into the C)."""
        self.lines.append(f"    /* {text} */")

    def let(self, name: str, value: Any) -> CExpr:
        """``const double name = value;`` (or ``int64_t``); returns the name."""
        v = _as_c(value, "d")
        nm = self._fresh(name)
        ty = "double" if v.ty == "d" else "int64_t"
        self.lines.append(f"    const {ty} {nm} = {v.text};")
        return CExpr(nm, v.ty)

    def where(self, m: Any, a: Any, b: Any) -> CExpr:
        """``m ? a : b`` (double unless both sides are integers)."""
        ty = "d" if any(isinstance(v, float) or (isinstance(v, CExpr) and v.ty == "d") for v in (a, b)) else "i"
        ac, bc = _as_c(a, ty), _as_c(b, ty)
        return CExpr(f"({_as_c(m, 'i').text} ? {ac.text} : {bc.text})", ty)

    def max(self, a: Any, b: Any) -> CExpr:
        """``max2(a, b)`` = ``a > b ? a : b`` (a function: each argument is written once)."""
        return CExpr(f"max2({_as_c(a, 'd').text}, {_as_c(b, 'd').text})", "d")

    def abs(self, a: Any) -> CExpr:
        """``fabs(a)``."""
        return CExpr(f"fabs({_as_c(a, 'd').text})", "d")

    def abs_max_finite(self, name: str, values: list[Any]) -> tuple[CExpr, CExpr]:
        """``(max |v|, every v finite)`` from the bits.

        |v| as an integer orders the finite values as the doubles and puts inf and NaN above
        them, so one integer max replaces the float max and the NaN tests (fewer vector
        instructions); the same max where every value is finite.
        """
        chain = f"abs_bits({_as_c(values[0], 'd').text})"
        for v in values[1:]:
            chain = f"imax2({chain}, abs_bits({_as_c(v, 'd').text}))"
        bits = self.let(f"{name}bits", CExpr(chain, "i"))
        return CExpr(f"from_bits({bits.text})", "d"), CExpr(f"({bits.text} <= 0x7fefffffffffffffLL)", "i")

    def sqrt(self, a: Any) -> CExpr:
        """``sqrt(a)`` (correctly rounded; vectorises with -fno-math-errno)."""
        return CExpr(f"sqrt({_as_c(a, 'd').text})", "d")

    def integer(self, v: int, like: Any) -> CExpr:
        """An integer constant."""
        return _as_c(int(v), "i")

    def frexp_exponent(self, v: Any) -> CExpr:
        """``frexp_exponent(v)`` (bit arithmetic in the header: vectorises)."""
        return CExpr(f"frexp_exponent({_as_c(v, 'd').text})", "i")

    def pow2(self, k: Any) -> CExpr:
        """``pow2(k)`` (built from the bits)."""
        return CExpr(f"pow2({_as_c(k, 'i').text})", "d")

    def imin(self, a: Any, b: int) -> CExpr:
        """Min of an integer and a constant."""
        return CExpr(f"imin2({_as_c(a, 'i').text}, {_as_c(b, 'i').text})", "i")

    def imax(self, a: Any, b: int) -> CExpr:
        """Max of an integer and a constant."""
        return CExpr(f"imax2({_as_c(a, 'i').text}, {_as_c(b, 'i').text})", "i")

    def digit(self, v: Any, bound: Any) -> CExpr:
        """``sign_digit(v, bound)``."""
        return CExpr(f"sign_digit({_as_c(v, 'd').text}, {_as_c(bound, 'd').text})", "i")

    def table(self, table: np.ndarray, name: str, index: Any) -> CExpr:
        """``name[index]`` (a static table of the header)."""
        return CExpr(f"{name}[{_as_c(index, 'i').text}]", "i")

    def call(self, name: str, args: Sequence[Any], scalars: Sequence[Any] = ()) -> tuple[CExpr, ...]:
        """Call a straight-line kernel; its outputs (values, then radii) go to a local array."""
        count = self._kernels[name].count
        out = self._fresh(f"r_{name}")
        self.lines.append(f"    double {out}[{count}];")
        params = [a.text if isinstance(a, CExpr) else str(a) for a in args] + [_as_c(s, "d").text for s in scalars]
        self.lines.append(f"    {name}({', '.join(params)}, {out});")
        return tuple(CExpr(f"{out}[{k}]", "d") for k in range(count))

    def matrix(self, entries: dict[tuple[int, int], Any], n: int, name: str) -> CExpr:
        """A local ``double name[n * n]`` holding the upper triangle (the kernels read only that)."""
        nm = self._fresh(name)
        self.lines.append(f"    double {nm}[{n * n}];")
        for (i, j), v in sorted(entries.items()):
            self.lines.append(f"    {nm}[{i * n + j}] = {_as_c(v, 'd').text};")
        return CExpr(nm, "p")

    def vector(self, entries: Sequence[Any], name: str) -> CExpr:
        """A local ``double name[len]``."""
        nm = self._fresh(name)
        vals = ", ".join(_as_c(v, "d").text for v in entries)
        self.lines.append(f"    const double {nm}[{len(entries)}] = {{{vals}}};")
        return CExpr(nm, "p")
