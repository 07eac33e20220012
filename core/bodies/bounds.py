"""Certified bounding spheres of N ellipses/ellipsoids, read off their matrices (and their validity).

The broad phase (:mod:`core.bodies.broadphase`) may only drop a pair whose bounding spheres are
disjoint, so each sphere must contain its body *as the matrix defines it* (not as the parameters
describe it: the float matrix is what is classified). For a body with matrix
[[Q, m], [m^T, g0]] (interior f(x) = x^T Q x + 2 m.x + g0 < 0), any float point c~ and any
lambda with 0 < lambda <= lambda_min(Q):

    x = c~ + u in the body  =>  u^T Q u + 2 g.u + f0 <= 0,   g = Q c~ + m,  f0 = f(c~)
                            =>  lambda |u|^2 - 2 |g| |u| + f0 <= 0
                            =>  |u| <= rho = (|g| + sqrt(|g|^2 - lambda f0)) / lambda.

So the sphere (c~, rho) contains the body whatever c~ is (a float estimate of the centre makes g
small and rho tight). Everything is computed in float64 with certified bounds:

* lambda: a float estimate of lambda_min(Q) (Newton on det(Q - x I) from the lower bound
  det Q / tr adj Q), shrunk by 2^-10; then Q - lambda I is proven positive definite (Sylvester's
  leading minors, each with a certified error bound) so lambda <= lambda_min(Q) holds;
* |g| from above and f0 within a certified radius (midpoint-radius arithmetic, the "radius"
  style of :mod:`core.fixed.errorbound`: every operation's rounding, and each input entry's own
  radius when the matrix was symmetrised, is carried);
* rho from upper bounds of |g| and -f0, rounded up.

Most matrices are exactly symmetric: their entries are exact (radius 0), so the same proof runs
on contiguous columns of the entries with only the operations' roundings carried
(:func:`_exact_spheres`, the fast path: several times faster than the general one, which also
carries the symmetrisation's radii and scales every matrix by a power of two). The compiled
extension runs that fast path in C, operation for operation (``core/fixed/_spheres.h``, body by
body: a one-body query of :class:`core.BodyIndex` takes microseconds), the numpy code serving
where the extension is not built.

The same proof certifies validity: Q - lambda I > 0 with lambda > 0 makes Q positive definite,
and f0 < 0 (certified) gives det M = det Q * min f <= det Q * f0 < 0. A body the float
computation cannot certify (NaN/inf, asymmetric beyond rounding, very ill-conditioned: axis
ratios beyond ~10^6, entries near the float range's ends) is decided by exact rational
arithmetic: :func:`core.shapes.quadrics.validate_quadric` names what is wrong, and the same
bound is computed exactly (lambda then from the exact Sylvester test, or the exact lower bound
det Q / tr adj Q).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np
from flint import fmpq, fmpq_mat

from ..filtered import predicate
from ..fixed import compiled
from ..fixed.compiled import get_threads
from ..fixed.filters import centres, log2_size, prepared, space_scaled, times_power_of_two
from ..shapes.numbers import to_float
from ..shapes.quadrics import validate_quadric

__all__ = ["BoundingSpheres", "bounding_spheres"]

_U = 2.0**-52
"""U >= u / (1 - u): relative rounding of one operation, as the radius kernels use it."""
_TINY = 2.0**-1074
"""Absolute error of one product in the subnormal range (sums of floats are exact there)."""
_RADIUS_FACTOR = 1.0 + 2.0**-40
"""Covers the rounding of the radius computations themselves (fewer than 2^12 roundings)."""
_UP = 1.0 + 2.0**-40
"""Covers the roundings of the final formula for rho (a handful of operations, each <= u)."""
_SHRINK = (1.0 - 2.0**-10, 1.0 - 2.0**-4, 0.5)
"""lambda = estimate * factor, tried in order: the first keeps spheres tight (radius + 0.05 %),
the others rescue ill-conditioned bodies (radius + 3 %, or up to sqrt(2) larger)."""
_CHUNK = 8192
"""Bodies per vectorised chunk: the (chunk, n, n) temporaries stay in cache (fastest measured)."""

_BOUNDS = predicate("bounding_sphere")
"""The filtered predicate of the spheres: float certificates, exact arithmetic for the rest
(its counters, per body: :func:`core.filter_stats`)."""


@dataclass
class BoundingSpheres:
    """Spheres (circles in 2D) that contain the bodies, and the bodies that are not shapes."""

    centers: np.ndarray
    """(N, d) float64 centres (float estimates of the bodies' centres; NaN for invalid bodies)."""
    radii: np.ndarray
    """(N,) float64: the body lies in the closed ball (centers[k], radii[k]); NaN if invalid."""
    invalid: dict[int, str]
    """Row -> why it is not an ellipse/ellipsoid (its message names the body)."""
    exact: int = 0
    """Bodies whose sphere needed exact arithmetic (the float bound could not certify them)."""

    @property
    def valid(self) -> np.ndarray:
        """(N,) bool mask of the bodies that are ellipses/ellipsoids."""
        out: np.ndarray = np.isfinite(self.radii)
        return out


class _Ball:
    """Midpoint-radius float numbers over arrays: |exact - v| <= r after every operation."""

    __slots__ = ("v", "r")

    def __init__(self, v: Any, r: Any) -> None:
        self.v = v
        self.r = r

    def __add__(self, o: _Ball) -> _Ball:
        z = self.v + o.v
        return _Ball(z, _radius_sum(self.r, o.r, z))

    def __sub__(self, o: _Ball) -> _Ball:
        z = self.v - o.v
        return _Ball(z, _radius_sum(self.r, o.r, z))

    def __mul__(self, o: _Ball) -> _Ball:
        z = self.v * o.v
        if _exact(self.r) and _exact(o.r):  # both factors exact: one rounding
            return _Ball(z, _U * np.abs(z) + _TINY)
        if _exact(self.r):
            return o * self
        if _exact(o.r):  # an exact factor (a float centre coordinate)
            return _Ball(z, self.r * np.abs(o.v) + (_U * np.abs(z) + _TINY))
        return _Ball(z, np.abs(self.v) * o.r + self.r * (np.abs(o.v) + o.r) + (_U * np.abs(z) + _TINY))


def _exact(r: Any) -> bool:
    """A radius that is the float 0.0: the value is exact."""
    return isinstance(r, float) and r == 0.0


def _radius_sum(r1: Any, r2: Any, z: np.ndarray) -> Any:
    """Radius of a sum or difference z of two balls (one rounding, plus the operands' radii)."""
    r = _U * np.abs(z)
    if not _exact(r1):
        r += r1
    if not _exact(r2):
        r += r2
    return r


def bounding_spheres(Q: np.ndarray) -> BoundingSpheres:
    """Certified bounding spheres of the bodies ``Q`` (and which bodies are not shapes).

    Args:
        Q: (N, n, n) float64 matrices, n = 3 (ellipses) or 4 (ellipsoids); signs may be flipped
            (the filter's normalisation: :func:`core.fixed.filters.prepared`).

    Returns:
        :class:`BoundingSpheres`: for every valid body k, every point x of the closed body
        satisfies |x - centers[k]| <= radii[k] (module docstring for the proof).

    Examples:
        >>> from core.shapes.quadrics import quadric_from_axes
        >>> b = bounding_spheres(np.array([quadric_from_axes([1, 2, 3], [2, 1, 0.5], [1, 0, 0, 0])]))
        >>> b.centers[0].tolist(), bool(2 <= b.radii[0] <= 2.002)
        ([1.0, 2.0, 3.0], True)
        >>> bounding_spheres(np.array([np.diag([1.0, 1.0, 1.0])])).invalid
        {0: 'body 0 has an empty interior: no real points (det > 0), not an ellipse'}
    """
    Q = np.asarray(Q, dtype=np.float64)
    N = Q.shape[0]
    invalid: dict[int, str] = {}

    def exact(Q: np.ndarray, spheres: tuple[np.ndarray, np.ndarray], rest: np.ndarray) -> np.ndarray | None:
        """The exact stage: the bodies the floats left, one by one (an invalid one is named)."""
        centers, radii = spheres
        failed = np.zeros(rest.size, dtype=bool)
        for k, b in enumerate(rest.tolist()):
            try:
                centers[b], radii[b] = _exact_sphere(Q[b], f"body {b}")
            except ValueError as e:
                invalid[b] = str(e)
                failed[k] = True
        return failed if invalid else None

    (centers, radii), _, rest = _BOUNDS.run(Q, N, _float_stage, exact)
    return BoundingSpheres(centers, radii, invalid, exact=int(rest.size) - len(invalid))


def _float_stage(Q: np.ndarray) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray | None]:
    """The float stage of :func:`bounding_spheres`: ((centres, radii), mask of the bodies without a sphere).

    The fast closed forms by chunks (threads), then the bodies far from size 1 in their own
    units, then LAPACK's estimates for the ill-conditioned and loose ones: every sphere
    certified in floats; the radius stays NaN where none is.
    """
    N, n = Q.shape[0], Q.shape[-1]
    d = n - 1
    centers = np.full((N, d), np.nan)
    radii = np.full(N, np.nan)

    def chunk(s: int) -> np.ndarray:
        c, rho, loose = _float_spheres(Q[s : s + _CHUNK], fast=True)
        ok = np.isfinite(rho)
        centers[s : s + _CHUNK][ok] = c[ok]
        radii[s : s + _CHUNK][ok] = rho[ok]
        return s + np.flatnonzero(~ok | loose)

    starts = range(0, N, _CHUNK)
    threads = min(get_threads(), len(starts))
    if threads > 1:  # numpy releases the GIL inside each operation: chunks run side by side
        with ThreadPoolExecutor(threads, thread_name_prefix="bounds") as pool:
            todo = list(pool.map(chunk, starts))
    else:
        todo = [chunk(s) for s in starts]
    rest = np.concatenate(todo) if todo else np.zeros(0, dtype=np.int64)

    def in_own_units(rest: np.ndarray, careful: bool) -> np.ndarray:
        """Bodies far from size 1 without a sphere: the same proof in their own units; the rest left."""
        none = rest[~np.isfinite(radii[rest])]
        if none.size:
            c, rho = _scaled_spheres(Q[none], careful=careful)
            ok = np.isfinite(rho)
            centers[none[ok]], radii[none[ok]] = c[ok], rho[ok]
            rest = rest[~np.isin(rest, none[ok])]
        return rest

    rest = in_own_units(rest, careful=False)
    if rest.size:  # ill-conditioned bodies (and loose spheres): LAPACK's estimates, still certified in floats
        c, rho, _ = _float_spheres(Q[rest], careful=True)
        better = np.isfinite(rho) & ~(rho >= radii[rest])  # a loose sphere is kept if not beaten
        centers[rest[better]] = c[better]
        radii[rest[better]] = rho[better]
        rest = in_own_units(rest, careful=True)
    rest = rest[~np.isfinite(radii[rest])]
    if not rest.size:
        return (centers, radii), None
    unsure = np.zeros(N, dtype=bool)
    unsure[rest] = True
    return (centers, radii), unsure


# -------------------------------------------------------------------------------------------
# float path


def _scaled_spheres(M: np.ndarray, *, careful: bool) -> tuple[np.ndarray, np.ndarray]:
    """(centres, radii) of bodies far from size 1, certified in their own units; NaN radius where not.

    A body of size s (1e150, 1e-150) spreads its entries over decades (|Q| ~ 1/s^2, the corner
    ~ |c|^2/s^2) that the float bounds cannot follow. Space scaled by 2^e ~ 1/s
    (:func:`core.fixed.filters.space_scaled`, exact, else no radius here) turns the body into
    2^e times itself; its sphere (c', rho') there gives (2^-e c', 2^-e rho') here: the centre
    where that is exact, the radius rounded up. ``careful``: LAPACK's estimates
    (:func:`_float_spheres`), else the fast closed forms.
    """
    e = np.clip(-np.rint(log2_size(M)), -1000, 1000).astype(np.int64)
    M1, exact = space_scaled(M, e)
    exact &= e != 0
    _, f = np.frexp(np.abs(M1).max(axis=(1, 2)))  # and the matrix by a power of two: largest entry in [1, 2)
    M2, ok = times_power_of_two(M1, (1 - f)[:, None, None])
    exact &= ok.all(axis=(1, 2))
    c = np.full((len(M), M.shape[-1] - 1), np.nan)
    rho = np.full(len(M), np.nan)
    if not exact.any():
        return c, rho
    rows = np.flatnonzero(exact)
    c2, rho2, _ = _float_spheres(M2[rows], careful=careful, fast=not careful)
    cb, c_exact = times_power_of_two(c2, -e[rows][:, None])
    rb, r_exact = times_power_of_two(rho2, -e[rows])
    rb = np.where(r_exact, rb, np.nextafter(rb, np.inf))  # the radius rounded up
    ok = c_exact.all(axis=1) & np.isfinite(rb)
    c[rows[ok]], rho[rows[ok]] = cb[ok], rb[ok]
    return c, rho


def _float_spheres(
    M: np.ndarray, *, careful: bool = False, fast: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(centres, radii, loose) of a chunk of bodies, certified in floats.

    A radius is NaN where the float bound certifies nothing; ``loose`` marks radii that the
    centre estimate or lambda inflate by more than 1 %.

    ``careful``: estimate the centre and lambda_min with LAPACK (backward stable: good up to
    condition numbers ~10^12) instead of the closed forms (fast, but they lose accuracy on
    ill-conditioned bodies); the certification is the same.

    ``fast``: the exactly symmetric bodies (most inputs) by :func:`_exact_spheres` (the same
    proof on the matrices as given, small ones scaled up by a power of two), the others by the
    general path below.
    """
    if fast:
        c, rho, loose, other = _exact_spheres_c(M) if compiled.spheres_available() else _exact_spheres(M)
        if other.any():
            c[other], rho[other], loose[other] = _float_spheres(M[other], careful=careful)
        return c, rho, loose
    n = M.shape[-1]
    d = n - 1
    with np.errstate(all="ignore"):
        S, status, R = prepared(M)
        ok = status > 0
        Qv = S[:, :d, :d]
        if careful:
            c, lam_est = _lapack_estimates(Qv, S[:, :d, d], ok)
        else:
            c = centres(S)[0]
            lam_est = _lambda_min_estimate(Qv)
        ok &= np.isfinite(c).all(axis=1) & np.isfinite(lam_est) & (lam_est > 0)
        c = np.where(ok[:, None], c, 0.0)
        lam = _proven_lambda(lam_est, ok, lambda rows, trial: _definite(S[rows], R[rows], trial))
        ok &= np.isfinite(lam) & (lam > 0)
        lam = np.where(ok, lam, 1.0)
        # g = Q c~ + m and f0 = c~.g + m.c~ + g0 with certified radii (c~ is exact: a float)
        g: list[_Ball] = []
        for i in range(d):
            acc = _entry(S, R, i, d)
            for j in range(d):
                acc = acc + _entry(S, R, i, j) * _Ball(c[:, j], 0.0)
            g.append(acc)
        f0 = _entry(S, R, d, d)
        for i in range(d):
            f0 = f0 + _Ball(c[:, i], 0.0) * (g[i] + _entry(S, R, i, d))
        rho, loose, good = _radius(g, f0, lam, lam_est)  # f0 < 0: with Q > 0, det M < 0
        ok &= good
    return c, np.where(ok, rho, np.nan), loose


def _exact_spheres(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(centres, radii, loose, other) of the exactly symmetric bodies of a chunk.

    The same certificate as the general path (module docstring), on the matrix as given (its
    sign flipped to a positive Q, which is exact): every entry is an exact float (radius 0),
    so the midpoint-radius arithmetic starts from exact values and carries only the roundings
    of the operations. Each entry is read once into a contiguous column (structure of arrays:
    numpy's fastest layout), and the centre and lambda_min estimates are closed forms on the
    columns. The bound holds for any floats (``_TINY`` covers a product in the subnormal range;
    an overflow gives inf/NaN: no radius); a body whose largest entry is below 2^-8 is first
    scaled up by an exact power of two (its largest entry into [1, 2)), so that ``_TINY`` stays
    negligible against its size.

    ``other`` marks the bodies left to the general path (not exactly symmetric or M_00 = 0);
    their radii are NaN here, as are those of non-finite bodies (left to the exact path).
    """
    N, n = M.shape[0], M.shape[-1]
    d = n - 1
    T = M.reshape(N, n * n).T.copy()  # entry (i, j) of every body: row i n + j (a copy: flipped below)
    upper = [(i, j) for i in range(n) for j in range(i, n)]
    with np.errstate(all="ignore"):
        sym = np.ones(N, dtype=bool)
        for i, j in upper:
            if i != j:
                sym &= T[i * n + j] == T[j * n + i]
        ok = sym & np.isfinite(T).all(axis=0) & (T[0] != 0.0)
        other = ~sym | (T[0] == 0.0)
        # a positive Q, and small bodies scaled up by a power of two into [1, 2) (exact: no
        # result is subnormal); large ones stay as they are (an overflow leaves them to the
        # general path, which scales with care)
        mx = np.abs(T).max(axis=0)
        k = np.where((mx > 0) & (mx < 2.0**-8), np.minimum(1 - np.frexp(mx)[1], 1000), 0)
        T *= np.where(T[0] < 0.0, -1.0, 1.0) * np.ldexp(1.0, k)
        col: dict[tuple[int, int], np.ndarray] = {(i, j): T[i * n + j] for i, j in upper}

        def w(i: int, j: int) -> np.ndarray:
            return col[min(i, j), max(i, j)]

        def E(i: int, j: int) -> _Ball:
            return _Ball(w(i, j), 0.0)

        c = _centre_columns(w, d)
        lam_est = _lambda_columns(w, d)
        ok &= np.isfinite(c).all(axis=0) & np.isfinite(lam_est) & (lam_est > 0)
        c = np.where(ok, c, 0.0)
        lam = _proven_lambda(
            lam_est, ok, lambda rows, trial: _definite_minors([[_Ball(w(i, j)[rows], 0.0) for j in range(d)] for i in range(d)], trial)
        )
        ok &= np.isfinite(lam) & (lam > 0)
        lam = np.where(ok, lam, 1.0)
        g: list[_Ball] = []
        for i in range(d):
            acc = E(i, d)
            for j in range(d):
                acc = acc + E(i, j) * _Ball(c[j], 0.0)
            g.append(acc)
        f0 = E(d, d)
        for i in range(d):
            f0 = f0 + _Ball(c[i], 0.0) * (g[i] + E(i, d))
        rho, loose, good = _radius(g, f0, lam, lam_est)
        ok &= good
    return np.ascontiguousarray(c.T), np.where(ok, rho, np.nan), loose & ok, other


def _exact_spheres_c(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_exact_spheres` in C (``core/fixed/_spheres.h``: the same proof, operation for operation)."""
    c, rho, status = compiled.spheres(M)
    return c, rho, status == compiled.SPHERE_LOOSE, status == compiled.SPHERE_OTHER


def _radius(g: list[_Ball], f0: _Ball, lam: np.ndarray, lam_est: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rho, loose, ok) from g = Q c~ + m, f0 = f(c~) (certified balls) and lambda <= lambda_min.

    ok: f0 < 0 certified (the body has interior points) and rho finite.
    """
    f0r = f0.r * _RADIUS_FACTOR
    ok = f0.v + f0r < 0
    G2 = sum((np.abs(gi.v) + gi.r * _RADIUS_FACTOR) ** 2 for gi in g) * _UP  # >= |g|^2
    F = (-f0.v + f0r) * _UP  # >= -f0 > 0
    rho = (np.sqrt(G2) * _UP + np.sqrt((G2 + lam * F) * _UP) * _UP) / lam * _UP
    ok &= np.isfinite(rho)
    # sqrt(F / lam_est) is the radius with an exact centre and lambda_min
    loose = ok & (rho > 1.01 * np.sqrt(F / lam_est))
    return rho, loose, ok


def _centre_columns(w: Callable[[int, int], np.ndarray], d: int) -> np.ndarray:
    """(d, N) float centre estimates -Q^-1 m by the adjugate.

    The formulas of :func:`core.fixed.driver.centre`, on columns (estimates: any float centre
    is certified by the bound).
    """
    if d == 2:
        det = w(0, 0) * w(1, 1) - w(0, 1) * w(0, 1)
        m0, m1 = w(0, 2), w(1, 2)
        return np.stack([-(w(1, 1) * m0 - w(0, 1) * m1) / det, -(-w(0, 1) * m0 + w(0, 0) * m1) / det])
    a00 = w(1, 1) * w(2, 2) - w(1, 2) * w(1, 2)
    a01 = w(0, 2) * w(1, 2) - w(0, 1) * w(2, 2)
    a02 = w(0, 1) * w(1, 2) - w(0, 2) * w(1, 1)
    a11 = w(0, 0) * w(2, 2) - w(0, 2) * w(0, 2)
    a12 = w(0, 1) * w(0, 2) - w(0, 0) * w(1, 2)
    a22 = w(0, 0) * w(1, 1) - w(0, 1) * w(0, 1)
    det = w(0, 0) * a00 + w(0, 1) * a01 + w(0, 2) * a02
    m0, m1, m2 = w(0, 3), w(1, 3), w(2, 3)
    return np.stack([
        -(a00 * m0 + a01 * m1 + a02 * m2) / det,
        -(a01 * m0 + a11 * m1 + a12 * m2) / det,
        -(a02 * m0 + a12 * m1 + a22 * m2) / det,
    ])


def _lambda_columns(w: Callable[[int, int], np.ndarray], d: int) -> np.ndarray:
    """Float estimates of lambda_min(Q) on columns (the closed forms of :func:`_lambda_min_estimate`)."""
    if d == 2:
        two: np.ndarray = (w(0, 0) + w(1, 1)) / 2 - np.hypot((w(0, 0) - w(1, 1)) / 2, w(0, 1))
        return two
    q = (w(0, 0) + w(1, 1) + w(2, 2)) / 3
    b00, b11, b22 = w(0, 0) - q, w(1, 1) - q, w(2, 2) - q
    b01, b02, b12 = w(0, 1), w(0, 2), w(1, 2)
    p = np.sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2 * (b01 * b01 + b02 * b02 + b12 * b12)) / 6)
    safe = np.where(p > 0, p, 1.0)
    det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02)
    half_det = det / (safe * safe * safe) / 2
    phi = np.arccos(np.clip(half_det, -1.0, 1.0)) / 3
    lam: np.ndarray = np.where(p > 0, q + 2 * p * np.cos(phi + 2 * np.pi / 3), q)
    return lam


def _proven_lambda(
    lam_est: np.ndarray, ok: np.ndarray, definite: Callable[[np.ndarray, np.ndarray], np.ndarray]
) -> np.ndarray:
    """Per body, the first lam_est * factor (factors ``_SHRINK``) proven <= lambda_min; NaN where none.

    ``definite(rows, trial)`` says, for the bodies ``rows``, whether Q - trial I is proven
    positive definite; only the bodies marked ``ok`` are tried.
    """
    lam = np.full(lam_est.shape[0], np.nan)
    rows = np.flatnonzero(ok)
    for factor in _SHRINK:
        trial = lam_est[rows] * factor
        good = definite(rows, trial)
        lam[rows[good]] = trial[good]
        rows = rows[~good]
        if not rows.size:
            break
    return lam


def _definite_minors(Q: list[list[_Ball]], lam: np.ndarray) -> np.ndarray:
    """Mask: Q - lam I proven positive definite (leading minors > their certified radius)."""
    d = len(Q)
    L = _Ball(lam, 0.0)
    P = [[Q[i][j] - L if i == j else Q[i][j] for j in range(d)] for i in range(d)]
    minors = [P[0][0], P[0][0] * P[1][1] - P[0][1] * P[0][1]]
    if d == 3:
        minors.append(
            P[0][0] * (P[1][1] * P[2][2] - P[1][2] * P[1][2])
            - P[0][1] * (P[0][1] * P[2][2] - P[1][2] * P[0][2])
            + P[0][2] * (P[0][1] * P[1][2] - P[1][1] * P[0][2])
        )
    ok: np.ndarray = np.isfinite(lam) & (lam > 0)
    for m in minors:
        ok &= m.v > m.r * _RADIUS_FACTOR
    return ok


def _entry(S: np.ndarray, R: np.ndarray, i: int, j: int) -> _Ball:
    i, j = min(i, j), max(i, j)
    return _Ball(S[:, i, j], R[:, i, j])


def _lapack_estimates(Q: np.ndarray, m: np.ndarray, ok: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centres -Q^-1 m and smallest eigenvalues from LAPACK (NaN where it fails)."""
    N, d = m.shape
    c = np.full((N, d), np.nan)
    lam = np.full(N, np.nan)
    for k in np.flatnonzero(ok & np.isfinite(Q).all(axis=(1, 2)) & np.isfinite(m).all(axis=1)):
        try:
            c[k] = -np.linalg.solve(Q[k], m[k])
            lam[k] = np.linalg.eigvalsh(Q[k])[0]
        except np.linalg.LinAlgError:
            pass
    return c, lam


def _lambda_min_estimate(Q: np.ndarray) -> np.ndarray:
    """Float estimate of the smallest eigenvalue of each symmetric Q (2x2 or 3x3).

    Closed forms (2x2: the quadratic formula; 3x3: the trigonometric solution of the
    characteristic cubic, O. K. Smith 1961). Only an estimate: :func:`_definite` proves.
    """
    d = Q.shape[-1]
    if d == 2:
        h = (Q[:, 0, 0] + Q[:, 1, 1]) / 2
        w = np.hypot((Q[:, 0, 0] - Q[:, 1, 1]) / 2, Q[:, 0, 1])
        low: np.ndarray = h - w
        return low
    q = np.trace(Q, axis1=1, axis2=2) / 3
    B = Q - q[:, None, None] * np.eye(3)
    p = np.sqrt((B * B).sum(axis=(1, 2)) / 6)
    safe = np.where(p > 0, p, 1.0)
    Bn = B / safe[:, None, None]
    half_det = np.linalg.det(Bn) / 2
    phi = np.arccos(np.clip(half_det, -1.0, 1.0)) / 3
    out: np.ndarray = np.where(p > 0, q + 2 * p * np.cos(phi + 2 * np.pi / 3), q)
    return out


def _definite(S: np.ndarray, R: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """Mask: Q - lam I proven positive definite (leading minors > their certified radius)."""
    d = S.shape[-1] - 1
    return _definite_minors([[_entry(S, R, i, j) for j in range(d)] for i in range(d)], lam)


# -------------------------------------------------------------------------------------------
# exact path (rare: bodies the float bound could not certify)


def _exact_sphere(M: np.ndarray, name: str) -> tuple[np.ndarray, float]:
    """(float centre, float radius) of one body in exact arithmetic; ValueError if invalid."""
    E = validate_quadric(M, name=name)  # exact, normalised; raises naming the body
    d = len(E) - 1
    Qm = fmpq_mat([[E[i][j] for j in range(d)] for i in range(d)])
    m = [E[i][d] for i in range(d)]
    centre = Qm.solve(fmpq_mat([[-v] for v in m]))
    c_float = np.array([to_float(centre[i, 0]) for i in range(d)])
    if not np.isfinite(c_float).all():
        raise ValueError(f"{name}: its centre is beyond the float range")
    c = [fmpq(*float(v).as_integer_ratio()) for v in c_float]  # the sphere's centre, exactly
    g = [sum((E[i][j] * c[j] for j in range(d)), m[i]) for i in range(d)]
    f0 = sum((c[i] * (g[i] + m[i]) for i in range(d)), E[d][d])
    lam = _exact_lambda(Qm, d)
    # rho = (|g| + sqrt(|g|^2 - lam f0)) / lam, each step rounded up
    G2 = sum((v * v for v in g), fmpq(0))
    G = _sqrt_up(G2)
    inner = _sqrt_up(G2 - lam * f0)
    rho = _up((fmpq(*G.as_integer_ratio()) + fmpq(*inner.as_integer_ratio())) / lam)
    if not math.isfinite(rho):
        raise ValueError(f"{name}: its size is beyond the float range")
    return c_float, rho


def _exact_lambda(Qm: fmpq_mat, d: int) -> fmpq:
    """A positive rational <= lambda_min(Q), Q positive definite (exact)."""
    Qf = np.array([[to_float(Qm[i, j]) for j in range(d)] for i in range(d)])
    try:
        est = float(np.linalg.eigvalsh(Qf)[0]) if np.isfinite(Qf).all() else math.nan
    except np.linalg.LinAlgError:
        est = math.nan
    for factor in _SHRINK:
        lam = est * factor
        if math.isfinite(lam) and lam > 0:
            q = fmpq(*lam.as_integer_ratio())
            P = [[Qm[i, j] - (q if i == j else 0) for j in range(d)] for i in range(d)]
            if all(fmpq_mat([row[:k] for row in P[:k]]).det() > 0 for k in range(1, d + 1)):
                return q
    # tr adj Q / det Q = sum 1 / lambda_i >= 1 / lambda_min
    adj_trace = sum((_principal_minor(Qm, i, d) for i in range(d)), fmpq(0))
    return Qm.det() / adj_trace


def _principal_minor(Qm: fmpq_mat, i: int, d: int) -> fmpq:
    """Determinant of Q without row and column i (a diagonal entry of adj Q)."""
    keep = [k for k in range(d) if k != i]
    return fmpq_mat([[Qm[r, s] for s in keep] for r in keep]).det()


def _up(q: fmpq) -> float:
    """The smallest float >= q (inf beyond the range)."""
    f = to_float(q)
    if math.isfinite(f) and fmpq(*f.as_integer_ratio()) < q:
        f = math.nextafter(f, math.inf)
    return f


def _sqrt_up(q: fmpq) -> float:
    """A float >= sqrt(q), q >= 0."""
    s = math.sqrt(_up(q))
    while math.isfinite(s) and fmpq(*s.as_integer_ratio()) ** 2 < q:
        s = math.nextafter(s, math.inf)
    return s
