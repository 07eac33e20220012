"""The paper's picture: the roots of P(T) = det(T A + B) at one instant, certified where it matters.

The whole argument of the paper is about the real roots of P(T): two distinct positive roots
<=> separate; they merge into a positive double root at a tangency; they leave the real axis
(or become negative) when the shapes overlap (Th. 7/19, Cor. 13/16, Th. 24/28). What this
module draws is decided by certified computations, never by a float root finder:

* rational P(T) (static shapes; a motion with rational entries at a rational t, and a float t is
  one): flint's certified complex root isolation of the exact integer polynomial, with the
  multiplicities of its exact squarefree factorisation; real roots come back with an exactly
  zero imaginary part and an isolating interval;
* P(T) with coefficients in Q(√d) (Example 30 has √2; a closed-form event such as
  (12 − 2√2)/17): the distinct real roots by :func:`core.algebra.realroots.real_roots`
  (isolating intervals, exact), each root's multiplicity by exact signs of P', P'' there;
  the other roots are non-real, counted exactly, placed by floats (display only);
* any other instant (an event with no closed form): the certified relation decides what is
  drawn — at a tangency P(T) HAS a positive double root (Th. 7/19), drawn as one, at the
  position of the float roots; the picture says so.

:func:`locus` gives the real roots of P(T) against t over a motion (floats on the exact
polynomials a_i(t), display only); the events drawn on it are the analysis' certified ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from flint import ctx, fmpq, fmpq_poly

from core.algebra.algebraic import RealAlgebraic, sign_at
from core.algebra.closedform import quadratic_form
from core.algebra.qsqrt import QSqrtPoly
from core.algebra.realroots import real_roots
from core.shapes.numbers import to_float, to_fmpq

__all__ = ["Root", "RootsPicture", "roots_of_pencil", "roots_at", "locus"]


@dataclass(frozen=True)
class Root:
    """One root of P(T) as drawn."""

    re: float
    """Real part (float: display)."""
    im: float
    """Imaginary part (0 exactly for a real root)."""
    mult: int
    """Multiplicity (certified where ``certified``)."""
    interval: tuple[float, float] | None = None
    """A certified enclosure of a real root, rounded outwards (None: not certified)."""

    @property
    def real(self) -> bool:
        """True for a real root."""
        return self.im == 0


@dataclass
class RootsPicture:
    """The roots of P(T) at one instant and how they were certified."""

    roots: list[Root]
    how: str
    """What certified them (shown under the picture)."""
    n: int = 0
    """Degree of P(T) (3: ellipses, 4: ellipsoids)."""
    notes: list[str] = field(default_factory=list)

    @property
    def positive(self) -> list[Root]:
        """The real roots T > 0, ascending."""
        return sorted((r for r in self.roots if r.real and r.re > 0), key=lambda r: r.re)

    def summary(self) -> str:
        """The roots in words: "two distinct positive roots", "a positive double root", ..."""
        pos = self.positive
        if any(r.mult >= 2 for r in pos):
            head = "a positive double root"
        elif len(pos) >= 2:
            head = "two distinct positive roots"
        elif len(pos) == 1:
            head = "one positive root"
        else:
            head = "no positive root"
        pairs = sum(1 for r in self.roots if r.im > 0)
        tail = f", {pairs} complex pair{'s' * (pairs != 1)}" if pairs else ""
        neg = [r for r in self.roots if r.real and r.re < 0]
        if neg:
            tail += f", {sum(r.mult for r in neg)} negative root{'s' * (sum(r.mult for r in neg) != 1)} (with multiplicity)"
        return head + tail


# ---------------------------------------------------------------------------- rational P(T)
def _enclosure(x: Any) -> tuple[float, float]:
    """A float interval containing the real ball x (outward: one ulp beyond each end)."""
    lo = float(x.lower())
    hi = float(x.upper())
    return math.nextafter(lo, -math.inf), math.nextafter(hi, math.inf)


def roots_of_pencil(coeffs: list[Any]) -> RootsPicture:
    """Certified roots of a rational P(T) (ascending coefficients, any exact numbers).

    flint isolates every complex root of the integer polynomial (a ball per root; real roots
    with an exactly zero imaginary part) and gives each its multiplicity from the exact
    squarefree factorisation.

    Examples:
        >>> pic = roots_of_pencil([-1, 0, 2, 0, -1])      # -(T - 1)^2 (T + 1)^2: spheres touching
        >>> [(r.re, r.mult) for r in pic.roots], pic.summary()
        ([(-1.0, 2), (1.0, 2)], 'a positive double root, 2 negative roots (with multiplicity)')
    """
    p = fmpq_poly([to_fmpq(c) for c in coeffs])
    z = p.numer()
    old = ctx.prec
    try:
        ctx.prec = 96
        found: list[tuple[Any, int]] = list(z.complex_roots())  # type: ignore[arg-type]  # flint's stubs type it as one acb
    finally:
        ctx.prec = old
    roots = []
    for r, m in found:
        if r.imag == 0:
            roots.append(Root(float(r.real.mid()), 0.0, int(m), _enclosure(r.real)))
        else:
            roots.append(Root(float(r.real.mid()), float(r.imag.mid()), int(m)))
    return RootsPicture(sorted(roots, key=lambda r: (r.re, r.im)), "exact: flint's certified isolation of the roots of the exact P(T)", p.degree())


# ---------------------------------------------------------------------------- P(T) over Q(√d)
def _float_roots(coeffs: list[float]) -> list[complex]:
    c = np.asarray(coeffs, dtype=float)
    return [complex(v) for v in np.roots(c[::-1])] if np.isfinite(c).all() and c[-1] != 0 else []


def _roots_qsqrt(P: QSqrtPoly) -> RootsPicture:
    """Roots of P(T) in Q(√d)[T]: real ones isolated exactly, with exact multiplicities."""
    reals: list[Root] = []
    derivs = []
    D = P
    for _ in range(P.degree()):
        D = QSqrtPoly(D.p.derivative(), D.q.derivative(), D.d)
        derivs.append(D)
    count = 0
    for r in real_roots(P):
        mult = 1
        for D in derivs:
            if D.is_zero() or sign_at(D, r) != 0:
                break
            mult += 1
        r.refine_to(fmpq(1, 10**12) * (abs(r.lo) if abs(r.lo) > 1 else fmpq(1)))
        reals.append(Root(float(r), 0.0, mult, (math.nextafter(to_float(r.lo), -math.inf), math.nextafter(to_float(r.hi), math.inf))))
        count += mult
    others = [z for z in _float_roots(P.coefficients_float()) if z.imag > 0]
    others.sort(key=lambda z: -abs(z.imag))
    pairs = (P.degree() - count) // 2
    cx = [Root(z.real, abs(z.imag), 1) for z in others[:pairs]]
    cx += [Root(z.real, -abs(z.imag), 1) for z in others[:pairs]]
    field_ = "Q" if P.d == 1 else f"Q(√{P.d})"
    how = f"exact over {field_}: real roots isolated exactly, multiplicities by exact signs of P′, P″; complex pairs counted exactly, placed in floats"
    return RootsPicture(sorted(reals + cx, key=lambda r: (r.re, r.im)), how, P.degree())


def _qe_eval(poly: fmpq_poly, a: fmpq, b: fmpq, e: int) -> tuple[fmpq, fmpq]:
    """poly(a + b√e) as (x, y) meaning x + y√e, exactly (Horner)."""
    x, y = fmpq(0), fmpq(0)
    for c in reversed(poly.coeffs()):
        x, y = x * a + y * b * e + c, x * b + y * a
    return x, y


def _coeffs_at(a_polys: list[QSqrtPoly], t: Any) -> QSqrtPoly | None:
    """P(T) at the exact t as a polynomial in T over Q(√d), or None when that is not one field.

    t rational: a_i(t) = p(t) + q(t)√d. t = a + b√e (a closed form): p(t) and q(t) are in
    Q(√e), so a_i(t) is when d = 1 or d = e.
    """
    if not isinstance(t, RealAlgebraic) or t.value is not None:
        tq = to_fmpq(t if not isinstance(t, RealAlgebraic) else t.value)
        pairs = [p.at(tq) for p in a_polys]
        d = max(p.d for p in a_polys)
        return QSqrtPoly(fmpq_poly([u for u, _ in pairs]), fmpq_poly([v for _, v in pairs]), d)
    form = quadratic_form(t)
    if form is None:
        return None
    a, b, e = form.value()
    d = max(p.d for p in a_polys)
    if d not in (1, e):
        return None
    xs, ys = [], []
    for p in a_polys:
        x, y = _qe_eval(p.p, a, b, e)
        if not p.q.is_zero():  # q(t)·√e with d = e
            qx, qy = _qe_eval(p.q, a, b, e)
            x, y = x + qy * e, y + qx
        xs.append(x)
        ys.append(y)
    return QSqrtPoly(fmpq_poly(xs), fmpq_poly(ys), e)


def roots_at(a_polys: list[QSqrtPoly], t: Any, t_float: float, relation: str | None) -> RootsPicture:
    """The roots of P(T) = Σ a_i(t) T^i of a motion at the exact t (see the module docstring).

    Args:
        a_polys: a_0..a_n as polynomials in t (the analysis' exact ones).
        t: the exact time (float: its binary value; fmpq; RealAlgebraic).
        t_float: t as a float (positions when nothing exact is available).
        relation: the certified relation at t (decides the picture when P(t) is not exact).
    """
    P = _coeffs_at(a_polys, t if not isinstance(t, float) else to_fmpq(t))
    if P is not None:
        if P.is_rational():
            return roots_of_pencil(list(P.p.coeffs()) + [fmpq(0)] * (len(a_polys) - 1 - P.p.degree()))
        return _roots_qsqrt(P)
    # no exact P(T) here (an event of degree > 2): the certified relation decides
    coeffs = [c for p in a_polys for c in [_float_at(p, t_float)]]
    zs = _float_roots(coeffs)
    pic = RootsPicture([], "", len(a_polys) - 1)
    if relation == "tangent":
        pos = sorted((z for z in zs if z.real > 0 and abs(z.imag) <= 1e-6 * max(1.0, abs(z))), key=lambda z: z.real)
        pos = pos or sorted((z for z in zs if z.real > 0), key=lambda z: abs(z.imag))
        if len(pos) >= 2:  # the two closest: the double root's float image
            k = min(range(len(pos) - 1), key=lambda i: abs(pos[i + 1] - pos[i]))
            dbl = (pos[k] + pos[k + 1]).real / 2
            rest = [z for z in zs if z is not pos[k] and z is not pos[k + 1]]
            pic.roots.append(Root(dbl, 0.0, 2))
            zs = rest
        pic.notes.append("tangent (certified) ⇒ P(T) has a positive double root (Th. 7/19): drawn as one, where the floats put it")
    for z in zs:
        pic.roots.append(Root(z.real, 0.0 if abs(z.imag) <= 1e-9 * max(1.0, abs(z)) else z.imag, 1))
    pic.roots.sort(key=lambda r: (r.re, r.im))
    pic.how = "positions in floats (this instant has no closed form); what is drawn at a double root follows the certified relation"
    return pic


def _float_at(p: QSqrtPoly, t: float) -> float:
    c = p.coefficients_float()
    return float(np.polyval(c[::-1], t)) if c else 0.0


def locus(a_polys: list[QSqrtPoly], ts: np.ndarray) -> np.ndarray:
    """Real roots of P(T) at each sample time, sorted, NaN-padded: (len(ts), n) floats (display).

    A root counts as real when its imaginary part is below 1e-7 of its size: the curves are a
    float picture of the exact polynomials; the events drawn across them are certified.
    """
    n = len(a_polys) - 1
    C = np.stack([np.polyval(np.asarray(p.coefficients_float() or [0.0], dtype=float)[::-1], ts) for p in a_polys], axis=1)
    out = np.full((len(ts), n), np.nan)
    ok = np.isfinite(C).all(axis=1) & (C[:, -1] != 0)
    if not ok.any():
        return out
    Cn = C[ok] / C[ok][:, -1:]
    comp = np.zeros((Cn.shape[0], n, n))
    comp[:, 0, :] = -Cn[:, -2::-1]
    comp[:, np.arange(1, n), np.arange(n - 1)] = 1.0
    ev = np.linalg.eigvals(comp)
    real = np.abs(ev.imag) <= 1e-7 * np.maximum(1.0, np.abs(ev))
    vals = np.where(real, ev.real, np.nan)
    vals.sort(axis=1)  # NaN last
    out[ok] = vals
    return out

