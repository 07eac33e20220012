"""A small safe parser for expressions in t, and exact rational functions over Q(sqrt d).

Users type motion entries as text (scene and HTTP API), e.g. ``"(8*t^2 - 8*t + 3)/2"`` or
``"sqrt(2)*(t - 1)*(3*t - 1)/(-6*t^2 + 6*t - 2)"``. The text is tokenised and parsed by
recursive descent (never ``eval``) into a :class:`RationalFunction`: a numerator in
Q(sqrt d)[t] (:class:`core.algebraic.QSqrtPoly`) over a monic denominator in Q[t] (a sqrt(d) in
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
from dataclasses import dataclass
from typing import Any

from flint import fmpq, fmpq_poly

from .qsqrt import QSqrtPoly, squarefree_decomposition
from .rationals import to_fmpq

__all__ = [
    "RationalFunction",
    "parse_expression",
    "MAX_EXPRESSION_CHARS",
    "MAX_DEGREE",
    "MAX_EXPONENT",
    "MAX_DEPTH",
]

MAX_EXPRESSION_CHARS = 2000
"""Longest accepted expression text."""
MAX_DEGREE = 16
"""Largest degree in t of the numerator or denominator of one entry, after simplification."""
MAX_EXPONENT = 64
"""Largest integer exponent after ``^``."""
MAX_DEPTH = 60
"""Deepest nesting of parentheses / unary signs (guards the recursion)."""
_MAX_WORK_DEGREE = 256  # intermediate results (before cancellation) stay below this degree


class RationalFunction:
    """``num / den`` with num in Q(sqrt d)[t] and den a monic polynomial in Q[t], reduced.

    Common factors in Q[t] of num's two parts and den are cancelled (a factor that only splits
    over Q(sqrt d) is not: ``(t - sqrt 2) / (t^2 - 2)`` keeps its denominator).

    Examples:
        >>> t = RationalFunction.variable()
        >>> f = (t * t - 1) / (t - 1)
        >>> str(f), f.is_polynomial()
        ('t + 1', True)
        >>> str(1 / (RationalFunction.constant(1) + RationalFunction.sqrt(2)))
        '-1 + sqrt(2)'
    """

    __slots__ = ("num", "den")

    def __init__(self, num: QSqrtPoly, den: fmpq_poly | None = None) -> None:
        den = fmpq_poly([1]) if den is None else den
        if den.is_zero():
            raise ValueError("division by zero")
        if num.is_zero():
            self.num, self.den = QSqrtPoly(0, 0, num.d), fmpq_poly([1])
            return
        g = den.gcd(num.p) if num.q.is_zero() else den.gcd(num.p.gcd(num.q))
        if g.degree() > 0:
            den = den // g
            num = QSqrtPoly(num.p // g, num.q // g, num.d)
        lc = den.coeffs()[-1]
        if lc != 1:
            den = den / lc
            num = QSqrtPoly(num.p / lc, num.q / lc, num.d)
        self.num, self.den = num, den

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
        """sqrt(c) for a positive rational c, as k*sqrt(d) with d squarefree."""
        c = to_fmpq(c)
        if c <= 0:
            raise ValueError(f"sqrt needs a positive number, got {c}")
        k, d = squarefree_decomposition(int(c.p * c.q))
        # sqrt(p/q) = sqrt(p q) / q
        if d == 1:
            return cls(QSqrtPoly(fmpq(k, int(c.q))))
        return cls(QSqrtPoly(0, fmpq(k, int(c.q)), d))

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
            return RationalFunction(self.num + o.num, self.den)
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
        return RationalFunction(self.num * o.num, self.den * o.den)

    __rmul__ = __mul__

    def inverse(self) -> RationalFunction:
        """1 / self (the sqrt(d) part of the denominator is cleared with the conjugate)."""
        if self.num.is_zero():
            raise ValueError("division by zero (the divisor is identically 0)")
        conj = self.num.conj()
        return RationalFunction(conj * self.den, self.num.norm())

    def __truediv__(self, other: Any) -> RationalFunction:
        return self * self._lift(other).inverse()

    def __rtruediv__(self, other: Any) -> RationalFunction:
        return self._lift(other) * self.inverse()

    def __pow__(self, e: int) -> RationalFunction:
        if not isinstance(e, int) or e < 0:
            raise ValueError(f"exponent must be a non-negative integer, got {e!r}")
        return RationalFunction(self.num**e, self.den**e)

    def __eq__(self, other: object) -> bool:
        o = self._lift(other)
        return self.num == o.num and self.den == o.den

    def __hash__(self) -> int:
        return hash((hash(self.num), str(self.den)))

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
        from .qsqrt import _poly_str

        return f"({self.num})/({_poly_str(self.den)})"

    def __repr__(self) -> str:
        return f"RationalFunction({self})"


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
    def __init__(self, text: str) -> None:
        self.text = text
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

    def _check(self, f: RationalFunction, tok: _Token) -> RationalFunction:
        if f.degree() > _MAX_WORK_DEGREE:
            raise ValueError(
                f"degree in t too high (> {_MAX_WORK_DEGREE}) near position {tok.pos}: {self.text}"
            )
        return f

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
            f = self._check(f + g if tok.text == "+" else f - g, tok)
        return f

    def _term(self) -> RationalFunction:
        f = self._unary()
        while self._peek().kind == "op" and self._peek().text in "*/":
            tok = self._next()
            g = self._unary()
            if tok.text == "*":
                f = f * g
            else:
                if g.num.is_zero():
                    raise ValueError(f"division by zero at position {tok.pos}: {self.text}")
                f = f / g
            f = self._check(f, tok)
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
        if self.depth > MAX_DEPTH:
            raise ValueError(f"expression nested too deeply (> {MAX_DEPTH}) at position {tok.pos}")

    def _power(self) -> RationalFunction:
        base = self._atom()
        tok = self._peek()
        if tok.kind == "op" and tok.text == "^":
            self._next()
            e = self._next()
            if e.kind != "num" or not all(c in _DIGITS for c in e.text):
                raise self._error(e, "the exponent must be a non-negative integer")
            k = int(e.text) if len(e.text) <= 6 else MAX_EXPONENT + 1
            if k > MAX_EXPONENT:
                raise ValueError(f"exponent {e.text} too large (max {MAX_EXPONENT}) at position {e.pos}")
            if base.degree() * k > _MAX_WORK_DEGREE:
                raise ValueError(f"degree in t too high (> {_MAX_WORK_DEGREE}) at position {e.pos}: {self.text}")
            base = base**k
            nxt = self._peek()
            if nxt.kind == "op" and nxt.text == "^":
                raise self._error(nxt, "write (a^b)^c with parentheses")
        return base

    def _atom(self) -> RationalFunction:
        tok = self._next()
        if tok.kind == "num":
            try:
                return RationalFunction.constant(to_fmpq(tok.text))
            except ValueError as e:
                raise ValueError(f"bad number {tok.text!r} at position {tok.pos}: {e}") from None
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
            return RationalFunction.sqrt(c)
        raise self._error(tok, "expected a number, t, sqrt(...) or '('")


def parse_expression(text: Any, *, max_degree: int = MAX_DEGREE) -> RationalFunction:
    """Parse one expression in t into an exact :class:`RationalFunction`.

    Args:
        text: the expression (str); ints, fmpq and Fractions are accepted as constants, and
            floats as the exact binary rationals they are.
        max_degree: largest allowed degree of numerator and denominator after simplification.

    Returns:
        The reduced rational function (coefficients in Q, or Q(sqrt d) if sqrt appears).

    Raises:
        ValueError: empty or too long text, an unexpected character (message gives it and its
            0-based position), unbalanced parentheses, division by zero, an exponent that is not
            a small non-negative integer, sqrt of something other than a positive constant, two
            different square roots, or a degree above ``max_degree``.

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
    if isinstance(text, RationalFunction):
        f = text
    elif isinstance(text, str):
        if len(text) > MAX_EXPRESSION_CHARS:
            raise ValueError(f"expression too long ({len(text)} > {MAX_EXPRESSION_CHARS} characters)")
        f = _Parser(text).parse()
    else:
        f = RationalFunction.constant(text)
    if f.num.degree() > max_degree or f.den.degree() > max_degree:
        raise ValueError(
            f"degree in t too high: {max(f.num.degree(), f.den.degree())} > {max_degree} "
            f"after simplification in {text!r}"
        )
    return f
