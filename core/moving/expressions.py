"""A small safe parser for expressions in t, and exact rational functions over Q(sqrt d).

Users type motion entries as text (scene and HTTP API), e.g. ``"(8*t^2 - 8*t + 3)/2"`` or
``"sqrt(2)*(t - 1)*(3*t - 1)/(-6*t^2 + 6*t - 2)"``. The text is tokenised and parsed by
recursive descent (never ``eval``) into a :class:`RationalFunction`: a numerator in
Q(sqrt d)[t] (:class:`core.algebra.algebraic.QSqrtPoly`) over a monic denominator in Q[t] (a sqrt(d) in
a denominator is moved up by multiplying with the conjugate).

Grammar (whitespace ignored)::

    expr   := term (("+" | "-") term)*
    term   := unary (("*" | "/") unary)*
    unary  := ("+" | "-") unary | power
    power  := atom (("^" | "**") INTEGER)?
    atom   := NUMBER | "t" | "sqrt" "(" expr ")" | "(" expr ")"

NUMBER is an integer or decimal with optional exponent (``12``, ``0.25``, ``.5``, ``1e-3``), read
exactly (``0.1`` is 1/10). ``sqrt`` takes a positive rational constant. Anything else is a
ValueError naming the offending text and its 0-based position.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

from flint import fmpq, fmpq_poly

from ..algebra.qsqrt import QSqrtPoly, squarefree_decomposition
from ..shapes.limits import (
    LIBRARY,
    LimitExceeded,
    Limits,
    check_bits,
    check_degree,
    current,
    log2_ceil,
    using,
)
from ..shapes.numbers import parse_number, to_fmpq

__all__ = [
    "RationalFunction",
    "parse_expression",
    "MAX_EXPRESSION_CHARS",
    "MAX_DEGREE",
    "MAX_EXPONENT",
    "MAX_DEPTH",
]

MAX_EXPRESSION_CHARS = LIBRARY.expression_chars
"""Longest accepted expression text (library default; all limits: :mod:`core.shapes.limits`)."""
MAX_DEGREE = LIBRARY.degree
"""Largest degree in t of the numerator or denominator of one entry, after simplification."""
MAX_EXPONENT = LIBRARY.exponent
"""Largest integer exponent after ``^``."""
MAX_DEPTH = LIBRARY.depth
"""Deepest nesting of parentheses / unary signs (guards the recursion)."""


class RationalFunction:
    """``num / den`` with num in Q(sqrt d)[t] and den a monic polynomial in Q[t], reduced.

    Common factors in Q[t] of num's two parts and den are cancelled (a factor that only splits
    over Q(sqrt d) is not: ``(t - sqrt 2) / (t^2 - 2)`` keeps its denominator).

    Every operation first bounds the size of its result from the sizes of its operands (bits
    of a coefficient, degree) and raises :class:`core.shapes.limits.LimitExceeded` when that bound is
    over :func:`core.shapes.limits.current` (the work is never started), then checks the actual result.

    Examples:
        >>> t = RationalFunction.variable()
        >>> f = (t * t - 1) / (t - 1)
        >>> str(f), f.is_polynomial()
        ('t + 1', True)
        >>> str(1 / (RationalFunction.constant(1) + RationalFunction.sqrt(2)))
        '-1 + sqrt(2)'
    """

    __slots__ = ("num", "den", "_bits")

    def __init__(self, num: QSqrtPoly, den: fmpq_poly | None = None) -> None:
        den = fmpq_poly([1]) if den is None else den
        self._bits: int | None = None
        if den.is_zero():
            raise ValueError("division by zero")
        if num.is_zero():
            self.num, self.den = QSqrtPoly(0, 0, num.d), fmpq_poly([1])
            return
        if den.degree() > 0:
            g = den.gcd(num.p) if num.q.is_zero() else den.gcd(num.p.gcd(num.q))
            if g.degree() > 0:
                den = den // g
                num = QSqrtPoly(num.p // g, num.q // g, num.d)
        lc = den.coeffs()[-1]
        if lc != 1:
            den = den / lc
            num = QSqrtPoly(num.p / lc, num.q / lc, num.d)
        self.num, self.den = num, den
        check_bits(self.bits())

    @classmethod
    def constant(cls, c: Any) -> RationalFunction:
        """The constant rational c."""
        return cls(QSqrtPoly(to_fmpq(c)))

    @classmethod
    def variable(cls) -> RationalFunction:
        """The time variable t."""
        return cls(QSqrtPoly(fmpq_poly([0, 1])))

    @classmethod
    def sqrt(cls, c: Any) -> RationalFunction:
        """The square root of a positive rational c, as k*sqrt(d) (d = 1 or d > 1 not a square)."""
        c = to_fmpq(c)
        if c <= 0:
            raise ValueError(f"sqrt needs a positive number, got {c}")
        k, d = squarefree_decomposition(int(c.p * c.q), current().sqrt_trial_primes)
        # sqrt(p/q) = sqrt(p q) / q
        if d == 1:
            return cls(QSqrtPoly(fmpq(k, int(c.q))))
        return cls(QSqrtPoly(0, fmpq(k, int(c.q)), d))

    # sizes -----------------------------------------------------------------------------------
    def bits(self) -> int:
        """Size of the largest coefficient: bits of numerator plus denominator (sqrt(d) included)."""
        if self._bits is None:
            b = max(_poly_bits(self.num.p), _poly_bits(self.den))
            if not self.num.q.is_zero():
                b = max(b, _poly_bits(self.num.q), self.num.d.bit_length())
            self._bits = b
        return self._bits

    def _dbits(self, other: RationalFunction) -> int:
        """Bits added by ``sqrt(d)^2 = d`` when two irrational parts are multiplied."""
        if self.num.q.is_zero() or other.num.q.is_zero():
            return 0
        return self.num.d.bit_length()

    @staticmethod
    def _plan(bits: int, degree: int) -> None:
        """Refuse an operation whose result may exceed the limits (before computing it)."""
        check_degree(degree)
        check_bits(bits)

    # arithmetic ------------------------------------------------------------------------------
    @staticmethod
    def _lift(x: Any) -> RationalFunction:
        if isinstance(x, RationalFunction):
            return x
        if isinstance(x, QSqrtPoly):
            return RationalFunction(x)
        return RationalFunction.constant(x)

    def __add__(self, other: Any) -> RationalFunction:
        o = self._lift(other)
        if self.den == o.den:
            self._plan(max(self.bits(), o.bits()) + 1, max(self.num.degree(), o.num.degree()))
            return RationalFunction(self.num + o.num, self.den)
        terms = log2_ceil(min(self.den.degree(), o.den.degree()) + 1) + 1
        self._plan(
            self.bits() + o.bits() + terms,
            max(self.num.degree() + o.den.degree(), o.num.degree() + self.den.degree(), self.den.degree() + o.den.degree()),
        )
        return RationalFunction(self.num * o.den + o.num * self.den, self.den * o.den)

    __radd__ = __add__

    def __neg__(self) -> RationalFunction:
        return RationalFunction(-self.num, self.den)

    def __sub__(self, other: Any) -> RationalFunction:
        return self + (-self._lift(other))

    def __rsub__(self, other: Any) -> RationalFunction:
        return self._lift(other) - self

    def __mul__(self, other: Any) -> RationalFunction:
        o = self._lift(other)
        terms = log2_ceil(min(max(self.degree(), 0), max(o.degree(), 0)) + 1) + 1
        self._plan(
            self.bits() + o.bits() + self._dbits(o) + terms,
            max(self.num.degree() + o.num.degree(), self.den.degree() + o.den.degree()),
        )
        return RationalFunction(self.num * o.num, self.den * o.den)

    __rmul__ = __mul__

    def inverse(self) -> RationalFunction:
        """1 / self (the sqrt(d) part of the denominator is cleared with the conjugate)."""
        if self.num.is_zero():
            raise ValueError("division by zero (the divisor is identically 0)")
        if self.num.q.is_zero():
            return RationalFunction(QSqrtPoly(self.den), self.num.p)
        terms = log2_ceil(max(self.num.degree(), 0) + 1) + 1
        self._plan(2 * self.bits() + self._dbits(self) + terms, 2 * self.num.degree() + self.den.degree())
        conj = self.num.conj()
        return RationalFunction(conj * self.den, self.num.norm())

    def __truediv__(self, other: Any) -> RationalFunction:
        return self * self._lift(other).inverse()

    def __rtruediv__(self, other: Any) -> RationalFunction:
        return self._lift(other) * self.inverse()

    def __pow__(self, e: int) -> RationalFunction:
        if not isinstance(e, int) or e < 0:
            raise ValueError(f"exponent must be a non-negative integer, got {e!r}")
        if e > 1:
            per_factor = self.bits() + self._dbits(self) + log2_ceil(max(self.degree(), 0) + 1) + 1
            self._plan(e * per_factor, e * max(self.degree(), 0))
        return RationalFunction(self.num**e, self.den**e)

    def __eq__(self, other: object) -> bool:
        o = self._lift(other)
        return self.num == o.num and self.den == o.den

    def __hash__(self) -> int:
        return hash((hash(self.num), str(self.den)))

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        """Pickle as (num, integer pairs of den): worker processes send parsed motions back."""
        from ..algebra.qsqrt import _pairs

        return (_rf_from_parts, (self.num, _pairs(self.den)))

    # structure -------------------------------------------------------------------------------
    @property
    def d(self) -> int:
        """The d of sqrt(d) in use (1 when the function is rational)."""
        return self.num.d if not self.num.q.is_zero() else 1

    def is_polynomial(self) -> bool:
        """True when the denominator is 1."""
        return self.den.degree() == 0

    def is_constant(self) -> bool:
        """True for a constant (no t)."""
        return self.is_polynomial() and self.num.degree() <= 0

    def degree(self) -> int:
        """max(deg num, deg den)."""
        return max(self.num.degree(), self.den.degree())

    def value_float(self, t: float) -> float:
        """Float value at t (display only, never used to decide)."""
        num = _eval_float(self.num.p, t)
        if not self.num.q.is_zero():
            num += _eval_float(self.num.q, t) * math.sqrt(self.num.d)
        return num / _eval_float(self.den, t)

    def __str__(self) -> str:
        if self.is_polynomial():
            return str(self.num)
        from ..algebra.qsqrt import _poly_str

        return f"({self.num})/({_poly_str(self.den)})"

    def __repr__(self) -> str:
        return f"RationalFunction({self})"


def _poly_bits(p: fmpq_poly) -> int:
    """Bits of the largest integer numerator plus bits of the common denominator of p."""
    if p.is_zero():
        return 0
    return int(p.numer().height_bits()) + int(p.denom().bit_length())


def _rf_from_parts(num: QSqrtPoly, den: list[tuple[int, int]]) -> RationalFunction:
    """Rebuild a pickled RationalFunction as it was (already reduced: no gcd, no limit check)."""
    f = RationalFunction.__new__(RationalFunction)
    f.num, f.den, f._bits = num, fmpq_poly([fmpq(a, b) for a, b in den]), None
    return f


def _eval_float(p: fmpq_poly, t: float) -> float:
    acc = 0.0
    for c in reversed(p.coeffs()):
        acc = acc * t + _fmpq_float(c)
    return acc


def _fmpq_float(c: fmpq) -> float:
    try:
        return float(c)
    except OverflowError:
        return math.inf if c > 0 else -math.inf


# -------------------------------------------------------------------------------------------
# tokenizer and parser


@dataclass(frozen=True)
class _Token:
    kind: str  # "num", "t", "sqrt", "op", "(", ")", "end"
    text: str
    pos: int


_OPS = {"+", "-", "*", "/", "^"}
_DIGITS = frozenset("0123456789")  # ASCII only: str.isdigit() also accepts e.g. superscripts


def _tokenize(text: str) -> list[_Token]:
    tokens: list[_Token] = []
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch.isspace():
            i += 1
            continue
        if ch in _DIGITS or (ch == "." and i + 1 < n and text[i + 1] in _DIGITS):
            j = i
            while j < n and text[j] in _DIGITS:
                j += 1
            if j < n and text[j] == ".":
                j += 1
                while j < n and text[j] in _DIGITS:
                    j += 1
            if j < n and text[j] in "eE":
                k = j + 1
                if k < n and text[k] in "+-":
                    k += 1
                if k < n and text[k] in _DIGITS:
                    while k < n and text[k] in _DIGITS:
                        k += 1
                    j = k
            tokens.append(_Token("num", text[i:j], i))
            i = j
            continue
        if (ch.isascii() and ch.isalpha()) or ch == "_":
            j = i
            while j < n and ((text[j].isascii() and text[j].isalnum()) or text[j] == "_"):
                j += 1
            word = text[i:j]
            if word == "t":
                tokens.append(_Token("t", word, i))
            elif word == "sqrt":
                tokens.append(_Token("sqrt", word, i))
            else:
                raise ValueError(
                    f"unexpected {word!r} at position {i}: {text} "
                    "(allowed: numbers, t, + - * / ^, parentheses, sqrt(n))"
                )
            i = j
            continue
        if ch == "*" and i + 1 < n and text[i + 1] == "*":
            tokens.append(_Token("op", "^", i))
            i += 2
            continue
        if ch in _OPS:
            tokens.append(_Token("op", ch, i))
            i += 1
            continue
        if ch in "()":
            tokens.append(_Token(ch, ch, i))
            i += 1
            continue
        raise ValueError(
            f"unexpected {ch!r} at position {i}: {text} "
            "(allowed: numbers, t, + - * / ^, parentheses, sqrt(n))"
        )
    tokens.append(_Token("end", "", n))
    return tokens


class _Parser:
    def __init__(self, text: str, limits: Limits) -> None:
        self.text = text
        self.limits = limits
        self.tokens = _tokenize(text)
        self.i = 0
        self.depth = 0

    def _peek(self) -> _Token:
        return self.tokens[self.i]

    def _next(self) -> _Token:
        tok = self.tokens[self.i]
        self.i += 1
        return tok

    def _error(self, tok: _Token, what: str = "") -> ValueError:
        shown = "end of input" if tok.kind == "end" else repr(tok.text)
        hint = f" ({what})" if what else ""
        return ValueError(f"unexpected {shown} at position {tok.pos}: {self.text}{hint}")

    def _at(self, tok: _Token, op: Callable[[], RationalFunction]) -> RationalFunction:
        """Run one step; a limit it would exceed is reported with the operator's position."""
        try:
            return op()
        except LimitExceeded as e:
            raise LimitExceeded(f"{e} at position {tok.pos}: {self.text}") from None

    def parse(self) -> RationalFunction:
        if self._peek().kind == "end":
            raise ValueError("empty expression")
        f = self._expr()
        tok = self._peek()
        if tok.kind != "end":
            raise self._error(tok, "expected an operator or the end")
        return f

    def _expr(self) -> RationalFunction:
        f = self._term()
        while self._peek().kind == "op" and self._peek().text in "+-":
            tok = self._next()
            g = self._term()
            f = self._at(tok, partial(operator.add if tok.text == "+" else operator.sub, f, g))
        return f

    def _term(self) -> RationalFunction:
        f = self._unary()
        while self._peek().kind == "op" and self._peek().text in "*/":
            tok = self._next()
            g = self._unary()
            if tok.text == "*":
                f = self._at(tok, partial(operator.mul, f, g))
            else:
                if g.num.is_zero():
                    raise ValueError(f"division by zero at position {tok.pos}: {self.text}")
                f = self._at(tok, partial(operator.truediv, f, g))
        return f

    def _unary(self) -> RationalFunction:
        tok = self._peek()
        if tok.kind == "op" and tok.text in "+-":
            self._next()
            self._enter(tok)
            f = self._unary()
            self.depth -= 1
            return -f if tok.text == "-" else f
        return self._power()

    def _enter(self, tok: _Token) -> None:
        self.depth += 1
        if self.depth > self.limits.depth:
            raise LimitExceeded(f"expression nested too deeply (> {self.limits.depth}) at position {tok.pos}")

    def _power(self) -> RationalFunction:
        base = self._atom()
        tok = self._peek()
        if tok.kind == "op" and tok.text == "^":
            self._next()
            e = self._next()
            if e.kind != "num" or not all(c in _DIGITS for c in e.text):
                raise self._error(e, "the exponent must be a non-negative integer")
            top = self.limits.exponent
            k = int(e.text) if len(e.text) <= 6 else top + 1
            if k > top:
                raise LimitExceeded(f"exponent {e.text[:20]} too large (max {top}) at position {e.pos}")
            base = self._at(tok, lambda: base**k)
            nxt = self._peek()
            if nxt.kind == "op" and nxt.text == "^":
                raise self._error(nxt, "write (a^b)^c with parentheses")
        return base

    def _atom(self) -> RationalFunction:
        tok = self._next()
        if tok.kind == "num":
            try:
                value = parse_number(tok.text, self.limits)
            except ValueError as e:
                raise type(e)(f"bad number {tok.text[:40]!r} at position {tok.pos}: {e}") from None
            return self._at(tok, lambda: RationalFunction.constant(value))
        if tok.kind == "t":
            return RationalFunction.variable()
        if tok.kind == "(":
            self._enter(tok)
            f = self._expr()
            close = self._next()
            if close.kind != ")":
                raise self._error(close, "expected ')'")
            self.depth -= 1
            return f
        if tok.kind == "sqrt":
            open_ = self._next()
            if open_.kind != "(":
                raise self._error(open_, "expected '(' after sqrt")
            self._enter(open_)
            inner = self._expr()
            close = self._next()
            if close.kind != ")":
                raise self._error(close, "expected ')'")
            self.depth -= 1
            if not inner.is_constant() or not inner.num.q.is_zero():
                raise ValueError(
                    f"sqrt at position {tok.pos} needs a positive rational constant "
                    f"(no t, no nested sqrt): {self.text}"
                )
            c = inner.num.p.coeffs()[0] if inner.num.p.coeffs() else fmpq(0)
            if c <= 0:
                raise ValueError(f"sqrt at position {tok.pos} of a non-positive number {c}: {self.text}")
            return self._at(tok, lambda: RationalFunction.sqrt(c))
        raise self._error(tok, "expected a number, t, sqrt(...) or '('")


def parse_expression(text: Any, *, max_degree: int | None = None, limits: Limits | None = None) -> RationalFunction:
    """Parse one expression in t into an exact :class:`RationalFunction`.

    Args:
        text: the expression (str); ints, fmpq and Fractions are accepted as constants, and
            floats as the exact binary rationals they are.
        max_degree: largest allowed degree of numerator and denominator after simplification
            (default ``limits.degree``).
        limits: size limits (:mod:`core.shapes.limits`); default: those in force
            (:data:`core.shapes.limits.LIBRARY` unless the caller set others).

    Returns:
        The reduced rational function (coefficients in Q, or Q(sqrt d) if sqrt appears).

    Raises:
        ValueError: empty or too long text, an unexpected character (message gives it and its
            0-based position), unbalanced parentheses, division by zero, an exponent that is not
            a small non-negative integer, sqrt of something other than a positive constant, two
            different square roots, a degree above ``max_degree``, or a size over ``limits``
            (:class:`core.shapes.limits.LimitExceeded`, refused before the work is done: e.g.
            "constant too large: about 2^297664 (297664 bits), limit 20000 bits at position 10").

    Examples:
        >>> str(parse_expression("(-8*t^2 + 8*t - 1)/(8*t^2 - 8*t + 3) * 2"))
        '(-2*t^2 + 2*t - 1/4)/(t^2 - t + 3/8)'
        >>> str(parse_expression("sqrt(8)/2 * t"))
        'sqrt(2)*(t)'
        >>> parse_expression("3*t + x")
        Traceback (most recent call last):
        ...
        ValueError: unexpected 'x' at position 6: 3*t + x (allowed: numbers, t, + - * / ^, parentheses, sqrt(n))
    """
    lim = limits if limits is not None else current()
    top = lim.degree if max_degree is None else max_degree
    with using(lim):
        if isinstance(text, RationalFunction):
            f = text
        elif isinstance(text, str):
            if lim.expression_chars is not None and len(text) > lim.expression_chars:
                raise LimitExceeded(f"expression too long ({len(text)} > {lim.expression_chars} characters)")
            f = _Parser(text, lim).parse()
        else:
            f = RationalFunction.constant(text)
    if f.num.degree() > top or f.den.degree() > top:
        shown = text if not isinstance(text, str) or len(text) <= 80 else text[:80] + "..."
        raise ValueError(
            f"degree in t too high: {max(f.num.degree(), f.den.degree())} > {top} "
            f"after simplification in {shown!r}"
        )
    return f
