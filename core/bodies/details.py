"""Richer pair output: a certified contact-scale bracket and a certified containment flag per pair.

For the pairs a contact search found (:class:`~core.bodies.result.Contacts`), on request
(``python -m app contacts --with scale``):

* **Contact scale** mu* (:func:`core.witness.contact_scale`; > 1 separate, = 1 tangent, < 1
  overlap): a float bracket ``scale_lo <= mu* <= scale_hi``, certified. Pairs in open space (or
  with image 0) go to the vectorised float form in one call; a pair whose second body is a
  periodic image goes to the exact one-pair form on the exact translate of its matrix (the same
  translate the contact search certified), its rational bracket rounded outwards to floats. The
  call sits in :func:`_scale_brackets` only, so a change of the witness API is one edit.
* **Containment**: whether one body lies inside the other (closed sets), certified both ways:

  - *B inside A* is proven by the S-lemma: since B has interior points, B is contained in A
    exactly when some tau >= 0 makes ``tau B - A`` positive semidefinite (then
    X^T A X <= tau X^T B X <= 0 on B). A rational tau between two consecutive real roots of
    det(tau B - A) (float estimates) is tried and ``tau B - A`` is checked positive definite
    exactly (Sylvester's criterion on fmpq minors): a proof of strict containment.
  - *B not inside A* is proven by a point of B outside A: B's centre and points of B towards 26
    directions (cube corners, edges and faces, just inside B's surface), each checked with
    X^T B X <= 0 and X^T A X > 0 certified: in floats with a proven error bound (|error| <=
    2^-48 sum |X_a A_ab X_b| + 2^-1060, far above the 18 roundings of the sum), exactly for
    pairs across a periodic face.
  - Equal shapes (proportional matrices, checked exactly) contain each other.
  - Otherwise (a body inside the other and touching it from within, or sticking out by less
    than the points can show) the flag is ``uncertain``: never a guess.

  Only overlapping pairs can be nested (a body inside another shares its interior); tangent
  pairs are ``no`` by their certified relation.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np
from flint import fmpq, fmpq_mat

from ..relation import Relation
from ..shapes.quadrics import origin_moved
from .result import Contacts

__all__ = ["PairDetails", "pair_details", "CONTAINMENT_NAMES", "NO", "I_IN_J", "J_IN_I", "EQUAL", "UNCERTAIN"]

NO, I_IN_J, J_IN_I, EQUAL, UNCERTAIN = 0, 1, 2, 3, -1
"""Containment codes: neither inside the other, body i inside body j, j inside i, the same set,
not certified either way."""
CONTAINMENT_NAMES = {NO: "no", I_IN_J: "i_in_j", J_IN_I: "j_in_i", EQUAL: "equal", UNCERTAIN: "uncertain"}

_BOUND_REL = 2.0**-48
_BOUND_ABS = 2.0**-1060
_INSIDE = 1.0 - 2.0**-12
"""Candidate points are taken this far towards a body's surface (then checked, not assumed, inside)."""


@dataclass
class PairDetails:
    """Per pair of a :class:`Contacts` (same order): contact-scale bracket and containment."""

    scale_lo: np.ndarray
    """float64 lower ends: scale_lo <= mu*."""
    scale_hi: np.ndarray
    """float64 upper ends: mu* <= scale_hi."""
    contained: np.ndarray
    """int8 containment codes (:data:`CONTAINMENT_NAMES`)."""

    def contained_names(self) -> list[str]:
        """The containment codes as words ("no", "i_in_j", "j_in_i", "equal", "uncertain")."""
        return [CONTAINMENT_NAMES[int(c)] for c in self.contained.tolist()]


def pair_details(Q: np.ndarray, res: Contacts, *, rtol: float = 1e-9) -> PairDetails:
    """Contact-scale brackets and containment flags of the pairs of ``res`` (module docstring).

    Args:
        Q: the (N, n, n) float64 matrices the search ran on.
        res: the search's result (its pairs, images and box).
        rtol: relative width asked of each contact-scale bracket.

    Returns:
        :class:`PairDetails`, one entry per pair of ``res``.

    Examples:
        >>> from core import bodies_from_axes, contacts
        >>> Q = bodies_from_axes([[0, 0], [2, 0], [0.25, 0]], [[1, 1], [1, 1], [0.5, 0.5]])
        >>> c = contacts(Q)   # (0, 1) tangent, (0, 2) overlap: circle 2 lies inside circle 0
        >>> d = pair_details(Q, c)
        >>> d.contained_names()
        ['no', 'j_in_i']
        >>> bool(d.scale_lo[0] == d.scale_hi[0] == 1.0), bool(d.scale_lo[1] <= 0.25 / 1.5 <= d.scale_hi[1])   # mu* = |c1 - c2| / (r1 + r2)
        (True, True)
    """
    Q = np.asarray(Q, dtype=np.float64)
    M = len(res)
    shifts = res.shifts()  # the exact float vectors v(k) the search moved j by
    if shifts is None:
        shifts = np.zeros((M, Q.shape[-1] - 1))
    moved = np.flatnonzero(shifts.any(axis=1))
    lo, hi = _scale_brackets(Q, res.i, res.j, shifts, moved, rtol)
    contained = np.full(M, NO, dtype=np.int8)
    over = np.flatnonzero(res.relation == Relation.OVERLAP)
    plain = np.setdiff1d(over, moved)
    if plain.size:
        contained[plain] = _containment_float(Q[res.i[plain]], Q[res.j[plain]])
    for k in np.intersect1d(over, moved).tolist():
        A, B = _exact(Q[res.i[k]]), _translated(Q[res.j[k]], shifts[k])
        contained[k] = _containment_exact(A, B, Q[res.i[k]], Q[res.j[k]], shifts[k])
    return PairDetails(lo, hi, contained)


# ----------------------------------------------------------------------------- contact scale
def _scale_brackets(
    Q: np.ndarray, i: np.ndarray, j: np.ndarray, shifts: np.ndarray, moved: np.ndarray, rtol: float
) -> tuple[np.ndarray, np.ndarray]:
    """Certified float brackets of mu* (the one place that calls the witness API)."""
    from ..witness import contact_scale

    M = i.size
    lo, hi = np.empty(M), np.empty(M)
    plain = np.setdiff1d(np.arange(M), moved)
    if plain.size:
        batch = contact_scale(Q[i[plain]], Q[j[plain]], rtol=rtol)  # one ContactScale per pair
        lo[plain] = [_down(cs.lo) for cs in batch]
        hi[plain] = [_up(cs.hi) for cs in batch]
    for k in moved.tolist():
        cs = contact_scale(_exact(Q[i[k]]), _translated(Q[j[k]], shifts[k]), rtol=rtol)
        lo[k], hi[k] = _down(cs.lo), _up(cs.hi)
    return lo, hi


def _down(q: Any) -> float:
    """The largest float <= q (q rational)."""
    f = float(q)
    return f if fmpq(*f.as_integer_ratio()) <= q else float(np.nextafter(f, -np.inf))


def _up(q: Any) -> float:
    """The smallest float >= q (q rational)."""
    f = float(q)
    return f if fmpq(*f.as_integer_ratio()) >= q else float(np.nextafter(f, np.inf))


def _exact(M: np.ndarray) -> list[list[fmpq]]:
    return [[fmpq(*float(v).as_integer_ratio()) for v in row] for row in M.tolist()]


def _translated(M: np.ndarray, shift: np.ndarray) -> list[list[fmpq]]:
    """The exact matrix of body M moved by ``shift`` (its periodic image)."""
    return origin_moved(_exact(M), [-fmpq(*float(s).as_integer_ratio()) for s in shift.tolist()])


# ----------------------------------------------------------------------------- containment
def _directions(d: int) -> np.ndarray:
    """Unit vectors to the corners, edges and faces of the cube (26 in 3D, 8 in 2D)."""
    v = np.array([u for u in itertools.product((-1.0, 0.0, 1.0), repeat=d) if any(u)])
    return v / np.linalg.norm(v, axis=1)[:, None]


def _points(B: np.ndarray, A: np.ndarray) -> np.ndarray:
    """Float points of each body B (P, n, n) likely to lie outside A: candidates, checked afterwards.

    B's centre, points towards the 26 cube directions (8 in 2D), and the point of B's surface
    where A's quadratic form is largest, found by a few steps of u <- L^T S_A (c_B + L u - c_A)
    normalised (x = c_B + L u, |u| = 1, parametrises B's surface; the form is convex, so its
    maximum over B is on the surface, where these steps climb). Returns (P, K, d).
    """
    d = B.shape[-1] - 1
    with np.errstate(all="ignore"):
        c, L = _frame(B)
        cA, _ = _frame(A)
        SA = A[:, :d, :d]
        u = _directions(d)
        pts = [c[:, None, :], c[:, None, :] + np.einsum("pab,ub->pua", L, u) * _INSIDE]
        v = np.einsum("pba,pbc,pc->pa", L, SA, c - cA)  # the gradient direction at u = 0
        for _ in range(12):
            v = v / np.linalg.norm(v, axis=1, keepdims=True)
            pts.append((c + np.einsum("pab,pb->pa", L, v) * _INSIDE)[:, None, :])
            v = np.einsum("pba,pbc,pc->pa", L, SA, c + np.einsum("pab,pb->pa", L, v) - cA)
    return np.concatenate(pts, axis=1)


def _frame(B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(centres (P, d), L (P, d, d)) of bodies B: the body is {c + L u : |u| <= 1} (float estimates)."""
    d = B.shape[-1] - 1
    S, m, k = B[:, :d, :d], B[:, :d, d], B[:, d, d]
    c = -np.linalg.solve(S, m[..., None])[..., 0]
    size = -(k + np.einsum("pa,pa->p", m, c))  # -f(c) > 0 inside a valid body
    w, V = np.linalg.eigh(S)
    half = np.sqrt(np.maximum(size, 0)[:, None] / w)  # semi-axes along V's columns
    return c, V * half[:, None, :]


def _form_signs(A: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Certified signs of X^T A X at points X (P, K, d) for matrices A (P, n, n): +1, -1, or 0 unsure."""
    ones = np.ones(X.shape[:-1] + (1,))
    Y = np.concatenate([X, ones], axis=-1)
    with np.errstate(all="ignore"):
        v = np.einsum("pka,pab,pkb->pk", Y, A, Y)
        s = np.einsum("pka,pab,pkb->pk", np.abs(Y), np.abs(A), np.abs(Y))
        bound = _BOUND_REL * s + _BOUND_ABS
        ok = np.isfinite(v) & np.isfinite(bound)
    return np.where(ok & (v > bound), 1, np.where(ok & (v < -bound), -1, 0)).astype(np.int8)


def _sticks_out(inner: np.ndarray, outer: np.ndarray) -> np.ndarray:
    """(P,) bool: a point certified in ``inner`` and certified outside ``outer`` was found."""
    X = _points(inner, outer)
    return np.asarray(((_form_signs(inner, X) < 0) & (_form_signs(outer, X) > 0)).any(axis=1))


def _containment_float(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Containment codes of float pairs (A = body i, B = body j), floats first, exact proofs after."""
    b_out = _sticks_out(B, A)  # B is not inside A
    a_out = _sticks_out(A, B)
    codes = np.full(A.shape[0], NO, dtype=np.int8)
    for k in np.flatnonzero(~(a_out & b_out)).tolist():
        codes[k] = _decide(_exact(A[k]), _exact(B[k]), a_out[k], b_out[k])
    return codes


def _containment_exact(A: list[list[fmpq]], B: list[list[fmpq]], Af: np.ndarray, Bf: np.ndarray, shift: np.ndarray) -> int:
    """Containment of body i and the image of body j (exact matrices; candidate points from floats)."""
    d = len(A) - 1
    t = [fmpq(*float(s).as_integer_ratio()) for s in shift.tolist()]
    Bt = Bf.copy()  # body j near its image (a float estimate: only to aim the candidate points)
    Bt[:-1, -1] -= Bf[:-1, :-1] @ shift
    Bt[-1, :-1] = Bt[:-1, -1]
    Bt[-1, -1] = Bf[-1, -1] - 2 * Bf[-1, :-1] @ shift + shift @ Bf[:-1, :-1] @ shift
    pts_b = _points(Bt[None], Af[None])[0]  # points near the image of body j (exact checks below)
    pts_a = _points(Af[None], Bt[None])[0]

    del t  # the candidate points are world points already

    def out(inner: list[list[fmpq]], outer: list[list[fmpq]], pts: np.ndarray) -> bool:
        for p in pts.tolist():
            if not all(np.isfinite(p)):
                continue
            x = [fmpq(*float(v).as_integer_ratio()) for v in p]
            if _value(inner, x, d) <= 0 and _value(outer, x, d) > 0:
                return True
        return False

    return _decide(A, B, out(A, B, pts_a), out(B, A, pts_b))


def _value(M: list[list[fmpq]], x: list[fmpq], d: int) -> fmpq:
    X = [*x, fmpq(1)]
    return sum((M[a][b] * X[a] * X[b] for a in range(d + 1) for b in range(d + 1)), fmpq(0))


def _decide(A: list[list[fmpq]], B: list[list[fmpq]], a_out: bool, b_out: bool) -> int:
    """The code from the point witnesses found, the exact S-lemma proofs and the equality check."""
    if a_out and b_out:
        return NO
    if _proportional(A, B):
        return EQUAL
    b_in = not b_out and _nested(B, A)  # B inside A
    a_in = not a_out and _nested(A, B)
    if a_in:
        return I_IN_J
    if b_in:
        return J_IN_I
    return UNCERTAIN


def _nested(inner: list[list[fmpq]], outer: list[list[fmpq]]) -> bool:
    """A proof that ``inner`` lies in ``outer``: tau inner - outer positive definite for a rational tau."""
    fi = np.array([[float(v) for v in row] for row in inner])
    fo = np.array([[float(v) for v in row] for row in outer])
    try:
        roots = np.linalg.eigvals(np.linalg.solve(fi, fo))  # det(tau inner - outer) = 0
    except np.linalg.LinAlgError:
        return False
    real = np.sort(roots.real[np.abs(roots.imag) <= 1e-9 * (1 + np.abs(roots.real))])
    n = len(inner)
    for tau in ((real[:-1] + real[1:]) / 2).tolist():
        if not (np.isfinite(tau) and tau > 0):
            continue
        T = fmpq(*float(tau).as_integer_ratio())
        P = fmpq_mat(n, n, [T * inner[a][b] - outer[a][b] for a in range(n) for b in range(n)])
        if all(_minor(P, k) > 0 for k in range(1, n + 1)):
            return True
    return False


def _minor(P: fmpq_mat, k: int) -> fmpq:
    return fmpq_mat(k, k, [P[a, b] for a in range(k) for b in range(k)]).det()


def _proportional(A: list[list[fmpq]], B: list[list[fmpq]]) -> bool:
    """A = c B with c > 0, exactly."""
    n = len(A)
    c = A[0][0] / B[0][0]  # both > 0: diagonal entries of a valid body's positive definite block
    return c > 0 and all(A[a][b] == c * B[a][b] for a in range(n) for b in range(n))
