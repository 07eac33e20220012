"""Data sets shared by the benchmarks: stacks of float ellipse/ellipsoid pairs with exact labels.

Every generator returns a :class:`Dataset`: float64 stacks ``A``, ``B`` of shape (N, n, n)
(n = 3 ellipses, n = 4 ellipsoids), the shape parameters they were built from (for the GJK
baselines, which need centre / semi-axes / rotation), and ``truth``: Relation codes
(0 separate, 1 tangent, 2 overlap) from :func:`oracle.oracle_relation` in ``tests/`` (exact
characteristic polynomial with flint's ``fmpq_mat`` and certified root isolation), applied to the
float matrices as they are (a float is the exact binary rational it is). The code under test
(``core.classify``) never labels a data set.

Families:

* ``random``: centres in [-4, 4]^d, semi-axes in [0.2, 3], uniform random orientation.
* ``near``: a generic pair (random axes and orientations) externally tangent at a random point,
  then B translated along the common normal by ``sign * gap * |cA - cB|``: sign +1 moves it
  away (separate), -1 into A (overlap), for gap = 1e-3 ... 1e-16. Rounding to floats may move a
  pair across; the oracle labels the rounded pair.
* ``tangent``: exactly tangent pairs whose float entries are exact (powers of two).
* ``extreme``: ``scale-1e-6..1e6`` (random pairs at a common scale 10^U(-6, 6)),
  ``mixed-sizes`` (semi-axes log-uniform in [1e-6, 1e6] for each axis, B placed near A's
  surface), ``aspect-1e6`` (axes (1e6 s, s, s) next to a moderate shape), ``centres-1e6``
  (random pairs shifted by 1e6), ``scaled-1e-150`` / ``scaled-1e150`` (A multiplied by 1e-150 or
  1e150, B by 1, 1e-150 or 1e150). Pairs whose rounded matrices are not valid ellipses/ellipsoids
  (exact check) are dropped and counted.

Examples:
    >>> ds = random_pairs(2, 5, seed=1)
    >>> ds.A.shape, ds.truth.shape
    ((5, 3, 3), (5,))
    >>> near_tangent_pairs(3, 4, gap=1e-3, sign=1, seed=2).truth.tolist()   # moved apart
    [0, 0, 0, 0]
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from flint import fmpq, fmpq_mat

_ROOT = Path(__file__).resolve().parents[1]
for _p in (str(_ROOT), str(_ROOT / "tests")):
    if _p not in sys.path:
        sys.path.insert(0, _p)

from oracle import oracle_relation  # noqa: E402  (tests/oracle.py: independent ground truth)

from core.shapes.numbers import to_fmpq  # noqa: E402
from core.shapes.rotation import rotation_numerator  # noqa: E402

__all__ = [
    "Dataset",
    "GAP_EXPONENTS",
    "EXTREME_KINDS",
    "CODES",
    "random_pairs",
    "near_tangent_pairs",
    "tangent_pairs",
    "extreme_pairs",
    "quadrics",
    "rotations",
    "label",
    "is_valid_exact",
    "random_motion",
    "grazing_motion",
    "almost_tangent_motion",
]

CODES = {"separate": 0, "tangent": 1, "overlap": 2}
"""Relation codes (core.Relation values) of the oracle's labels."""

GAP_EXPONENTS = tuple(range(3, 17))
"""Near-tangent relative gaps 10^-3 ... 10^-16."""

EXTREME_KINDS = ("scale-1e-6..1e6", "mixed-sizes", "aspect-1e6", "centres-1e6", "scaled-1e-150", "scaled-1e150")


@dataclass
class Dataset:
    """One benchmark data set of float pairs with exact labels."""

    name: str
    """Row name, e.g. "random 3D" or "near +1e-08 3D"."""
    family: str
    """"random", "near" or "extreme"."""
    dim: int
    """2 (ellipses, 3x3) or 3 (ellipsoids, 4x4)."""
    A: np.ndarray
    """(N, n, n) float64."""
    B: np.ndarray
    """(N, n, n) float64."""
    truth: np.ndarray
    """(N,) int8 Relation codes from the independent oracle."""
    shapes: list[tuple[Any, ...]] = field(default_factory=list, repr=False)
    """Per pair (cA, axesA, RA, cB, axesB, RB) before rounding (for GJK baselines), if known."""
    dropped: int = 0
    """Generated pairs dropped because rounding made a matrix invalid."""

    def __len__(self) -> int:
        return int(self.A.shape[0])

    def counts(self) -> dict[str, int]:
        """Number of pairs of each true relation."""
        return {k: int((self.truth == v).sum()) for k, v in CODES.items()}


# ------------------------------------------------------------------------------------ shapes
def rotations(rng: np.random.Generator, dim: int, N: int) -> np.ndarray:
    """(N, dim, dim) uniformly random rotations (2D: angle; 3D: normalised Gaussian quaternion)."""
    if dim == 2:
        th = rng.uniform(0, 2 * math.pi, N)
        c, s = np.cos(th), np.sin(th)
        return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
    q = rng.normal(size=(N, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    R, _ = rotation_numerator(list(q.T))  # |q| = 1 (to rounding): the numerator is the rotation
    return np.stack([np.stack(row, -1) for row in R], -2)


def quadrics(centers: np.ndarray, axes: np.ndarray, R: np.ndarray) -> np.ndarray:
    """(N, d+1, d+1) homogeneous matrices of ellipsoids x = R diag(axes) u + c, |u| = 1.

    Q = R diag(axes^-2) R^T; M = [[Q, -Q c], [-c^T Q, c^T Q c - 1]] (interior negative).

    Examples:
        >>> quadrics(np.array([[2.0, 0.0]]), np.array([[1.0, 1.0]]), np.eye(2)[None])[0].tolist()
        [[1.0, 0.0, -2.0], [0.0, 1.0, 0.0], [-2.0, 0.0, 3.0]]
    """
    N, d = centers.shape
    Q = np.einsum("nij,nj,nkj->nik", R, axes**-2.0, R)
    Q = (Q + np.swapaxes(Q, 1, 2)) / 2  # exactly symmetric
    Qc = np.einsum("nij,nj->ni", Q, centers)
    M = np.empty((N, d + 1, d + 1))
    M[:, :d, :d] = Q
    M[:, :d, d] = -Qc
    M[:, d, :d] = -Qc
    M[:, d, d] = np.einsum("ni,ni->n", centers, Qc) - 1.0
    return M + 0.0  # no -0.0 entries


# ------------------------------------------------------------------------------------ labels
def is_valid_exact(M: np.ndarray) -> bool:
    """Exact check (flint) that a float matrix is a valid ellipse/ellipsoid up to sign.

    The exact symmetric part has a positive definite quadratic block (leading minors > 0 after
    normalising the sign of M[0, 0]) and det < 0. Independent of ``core.shapes.quadrics`` (its
    asymmetry tolerance is not checked here: the generators only round).
    """
    n = M.shape[0]
    if not np.isfinite(M).all() or M[0, 0] == 0:
        return False
    s = 1 if M[0, 0] > 0 else -1
    # the shape is the exact symmetric part (numpy-built matrices are symmetric up to rounding)
    E = fmpq_mat([[(to_fmpq(float(s * M[i, j])) + to_fmpq(float(s * M[j, i]))) / 2 for j in range(n)] for i in range(n)])
    for k in range(1, n):
        if not fmpq_mat([[E[i, j] for j in range(k)] for i in range(k)]).det() > 0:
            return False
    return bool(E.det() < 0)


def label(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """(N,) int8 oracle codes of stacked float pairs (exact; about 1 ms per pair)."""
    return np.array([CODES[oracle_relation(a, b)] for a, b in zip(A, B, strict=False)], dtype=np.int8)


def _finish(name: str, family: str, dim: int, A: np.ndarray, B: np.ndarray, shapes: list[tuple[Any, ...]]) -> Dataset:
    keep = [i for i in range(len(A)) if is_valid_exact(A[i]) and is_valid_exact(B[i])]
    A, B = A[keep], B[keep]
    shapes = [shapes[i] for i in keep] if shapes else []
    return Dataset(name, family, dim, A, B, label(A, B), shapes, dropped=0)


def _params(cA: np.ndarray, aA: np.ndarray, RA: np.ndarray, cB: np.ndarray, aB: np.ndarray, RB: np.ndarray) -> list[tuple[Any, ...]]:
    return [(cA[i], aA[i], RA[i], cB[i], aB[i], RB[i]) for i in range(len(cA))]


def _with_dropped(ds: Dataset, generated: int) -> Dataset:
    ds.dropped = generated - len(ds)
    return ds


# ------------------------------------------------------------------------------------ families
def random_pairs(dim: int, N: int, *, seed: int = 0) -> Dataset:
    """Random pairs: centres U[-4, 4]^d, semi-axes U[0.2, 3], random orientations."""
    _check(dim, N)
    rng = np.random.default_rng([seed, dim, 1])
    cA, cB = rng.uniform(-4, 4, (2, N, dim))
    aA, aB = rng.uniform(0.2, 3.0, (2, N, dim))
    RA, RB = rotations(rng, dim, N), rotations(rng, dim, N)
    A, B = quadrics(cA, aA, RA), quadrics(cB, aB, RB)
    ds = _finish(f"random {dim}D", "random", dim, A, B, _params(cA, aA, RA, cB, aB, RB))
    return _with_dropped(ds, N)


def _surface_point(rng: np.random.Generator, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Random body-frame points on the ellipsoids |diag(axes)^-1 x| = 1 and their unit normals."""
    u = rng.normal(size=axes.shape)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    p = axes * u
    nrm = p / axes**2
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    return p, nrm


def _align(m: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(N, d, d) rotations taking unit vectors m to unit vectors target (Rodrigues / 2D angle)."""
    N, d = m.shape
    if d == 2:
        th = np.arctan2(target[:, 1], target[:, 0]) - np.arctan2(m[:, 1], m[:, 0])
        c, s = np.cos(th), np.sin(th)
        return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
    v = np.cross(m, target)
    c = np.einsum("ni,ni->n", m, target)
    K = np.zeros((N, 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    K = K - np.swapaxes(K, 1, 2)
    f = 1.0 / (1.0 + np.where(c > -1 + 1e-9, c, np.nan))
    R = np.eye(3)[None] + K + np.einsum("nij,njk->nik", K, K) * f[:, None, None]
    bad = ~np.isfinite(R).all(axis=(1, 2))  # antiparallel: rotate by pi about a perpendicular axis
    if bad.any():
        for i in np.flatnonzero(bad):
            w = np.cross(m[i], [1.0, 0.0, 0.0] if abs(m[i, 0]) < 0.9 else [0.0, 1.0, 0.0])
            w /= np.linalg.norm(w)
            R[i] = 2 * np.outer(w, w) - np.eye(3)
    return R


def tangent_pairs(dim: int, N: int, *, seed: int = 0) -> Dataset:
    """Exactly tangent float pairs (every entry exact): an axis-aligned ellipsoid with power-of-two
    semi-axes and a ball of power-of-two radius touching it at the end of a random axis, from a
    random side, both shifted by multiples of 1/8 (the oracle confirms TANGENT)."""
    _check(dim, N)
    rng = np.random.default_rng([seed, dim, 4])
    aA = 2.0 ** rng.integers(-2, 3, (N, dim))
    r = 2.0 ** rng.integers(-2, 3, N)
    axis = rng.integers(0, dim, N)
    side = rng.choice([-1.0, 1.0], N)
    shift = rng.integers(-32, 33, (N, dim)) / 8.0
    cB = np.zeros((N, dim))
    cB[np.arange(N), axis] = side * (aA[np.arange(N), axis] + r)
    cA, cB = shift, cB + shift
    I = np.broadcast_to(np.eye(dim), (N, dim, dim)).copy()
    aB = np.repeat(r[:, None], dim, axis=1)
    A, B = quadrics(cA, aA, I), quadrics(cB, aB, I)
    ds = _finish(f"tangent {dim}D", "tangent", dim, A, B, _params(cA, aA, I, cB, aB, I))
    return _with_dropped(ds, N)


def near_tangent_pairs(dim: int, N: int, *, gap: float, sign: int, seed: int = 0) -> Dataset:
    """Generic pairs externally tangent at a random point, then moved by ``sign * gap`` (relative).

    A: random centre, axes U[0.3, 3], orientation; p a random point of its surface with outward
    normal n. B: random axes and orientation, rotated so that its outward normal at a random
    surface point q is -n, translated so that q = p (the tangent plane separates them: exactly
    tangent before rounding); then B moves by ``sign * gap * |cA - cB| * n``.
    """
    _check(dim, N)
    if sign not in (1, -1) or not gap > 0:
        raise ValueError(f"near_tangent_pairs needs sign +1/-1 and gap > 0, got {sign}, {gap}")
    rng = np.random.default_rng([seed, dim, 2, int(round(-math.log10(gap) * 10)), sign + 1])
    cA = rng.uniform(-4, 4, (N, dim))
    aA, aB = rng.uniform(0.3, 3.0, (2, N, dim))
    RA = rotations(rng, dim, N)
    p_body, n_body = _surface_point(rng, aA)
    p = cA + np.einsum("nij,nj->ni", RA, p_body)
    n = np.einsum("nij,nj->ni", RA, n_body)
    q_body, m_body = _surface_point(rng, aB)
    R0 = rotations(rng, dim, N)
    m = np.einsum("nij,nj->ni", R0, m_body)
    RB = np.einsum("nij,njk->nik", _align(m, -n), R0)
    cB = p - np.einsum("nij,nj->ni", RB, q_body)
    dist = np.linalg.norm(cB - cA, axis=1, keepdims=True)
    cB = cB + sign * gap * dist * n
    A, B = quadrics(cA, aA, RA), quadrics(cB, aB, RB)
    name = f"near {'+' if sign > 0 else '-'}1e-{round(-math.log10(gap)):02d} {dim}D"
    ds = _finish(name, "near", dim, A, B, _params(cA, aA, RA, cB, aB, RB))
    return _with_dropped(ds, N)


def extreme_pairs(dim: int, N: int, *, kind: str, seed: int = 0) -> Dataset:
    """Extreme but valid inputs (see the module docstring for the kinds)."""
    _check(dim, N)
    if kind not in EXTREME_KINDS:
        raise ValueError(f"unknown extreme kind {kind!r}; valid: {', '.join(EXTREME_KINDS)}")
    rng = np.random.default_rng([seed, dim, 3, EXTREME_KINDS.index(kind)])
    cA, cB = rng.uniform(-4, 4, (2, N, dim))
    aA, aB = rng.uniform(0.2, 3.0, (2, N, dim))
    RA, RB = rotations(rng, dim, N), rotations(rng, dim, N)
    sA = np.ones(N)
    sB = np.ones(N)
    if kind == "scale-1e-6..1e6":
        s = 10.0 ** rng.uniform(-6, 6, (N, 1))
        cA, cB, aA, aB = cA * s, cB * s, aA * s, aB * s
    elif kind == "mixed-sizes":
        aA = 10.0 ** rng.uniform(-6, 6, (N, dim))
        aB = 10.0 ** rng.uniform(-6, 6, (N, dim))
        u = rng.normal(size=(N, dim))
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        cB = cA + np.einsum("nij,nj->ni", RA, aA * u) * rng.uniform(0.5, 1.5, (N, 1))
    elif kind == "aspect-1e6":
        s = 10.0 ** rng.uniform(-2, 2, (N, 1))
        aA = np.concatenate([1e6 * s, s * np.ones((N, dim - 1))], axis=1)
        u = rng.normal(size=(N, dim))
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        cB = cA + np.einsum("nij,nj->ni", RA, aA * u) * rng.uniform(0.7, 1.3, (N, 1))
        aB = aB * s
    elif kind == "centres-1e6":
        cA, cB = cA + 1e6, cB + 1e6
    elif kind == "scaled-1e-150":
        sA[:] = 1e-150
        sB = rng.choice([1.0, 1e-150, 1e150], N)
    elif kind == "scaled-1e150":
        sA[:] = 1e150
        sB = rng.choice([1.0, 1e-150, 1e150], N)
    A = quadrics(cA, aA, RA) * sA[:, None, None]
    B = quadrics(cB, aB, RB) * sB[:, None, None]
    ds = _finish(f"{kind} {dim}D", "extreme", dim, A, B, _params(cA, aA, RA, cB, aB, RB))
    return _with_dropped(ds, N)


STRUCTURED_KINDS = ("spheres", "translated copies", "homothetic copies", "numpy-built")
"""Inputs users bring: s0 vanishes identically for the first three (a structural double root)."""


def structured_pairs(dim: int, N: int, *, kind: str, seed: int = 0) -> Dataset:
    """Spheres/circles, translated copies of one shape, homothetic copies (same orientation,
    scaled), or generic pairs built the numpy way (``R @ diag(1/a^2) @ R.T``, symmetric only up
    to rounding). Centres U[-4, 4]^d; B's centre at a random distance up to 8 from A's."""
    _check(dim, N)
    if kind not in STRUCTURED_KINDS:
        raise ValueError(f"unknown structured kind {kind!r}; valid: {', '.join(STRUCTURED_KINDS)}")
    rng = np.random.default_rng([seed, dim, 5, STRUCTURED_KINDS.index(kind)])
    cA = rng.uniform(-4, 4, (N, dim))
    u = rng.normal(size=(N, dim))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    cB = cA + u * rng.uniform(0.0, 8.0, (N, 1))
    aA = rng.uniform(0.2, 3.0, (N, dim))
    RA = rotations(rng, dim, N)
    if kind == "spheres":
        aA = np.repeat(aA[:, :1], dim, axis=1)
        aB = np.repeat(rng.uniform(0.2, 3.0, (N, 1)), dim, axis=1)
        RA = np.broadcast_to(np.eye(dim), (N, dim, dim)).copy()
        RB = RA
    elif kind == "translated copies":
        aB, RB = aA, RA
    elif kind == "homothetic copies":
        aB, RB = aA * rng.uniform(0.3, 3.0, (N, 1)), RA
    else:
        aB, RB = rng.uniform(0.2, 3.0, (N, dim)), rotations(rng, dim, N)
    if kind == "numpy-built":
        A, B = (_numpy_quadrics(c, a, R) for c, a, R in ((cA, aA, RA), (cB, aB, RB)))
    else:
        A, B = quadrics(cA, aA, RA), quadrics(cB, aB, RB)
    ds = _finish(f"{kind} {dim}D", "structured", dim, A, B, _params(cA, aA, RA, cB, aB, RB))
    return _with_dropped(ds, N)


def _numpy_quadrics(c: np.ndarray, a: np.ndarray, R: np.ndarray) -> np.ndarray:
    """The matrices as user code computes them: Q = R @ diag(a^-2) @ R.T, no symmetrisation."""
    N, d = c.shape
    Q = R @ (a[:, :, None] ** -2.0 * np.swapaxes(R, 1, 2))
    M = np.empty((N, d + 1, d + 1))
    M[:, :d, :d] = Q
    M[:, :d, d] = -np.einsum("nij,nj->ni", Q, c)
    M[:, d, :d] = -np.einsum("ni,nij->nj", c, Q)
    M[:, d, d] = np.einsum("ni,nij,nj->n", c, Q, c) - 1.0
    return M


def big_small_pairs(dim: int, N: int, *, gap: float, sign: int, seed: int = 0) -> Dataset:
    """A large ellipsoid (axes 1e2..1e3) beside a small sphere (radius 1e-2..1), externally tangent
    at a random point, then moved by ``sign * gap * radius`` along the normal (sign +1 apart)."""
    _check(dim, N)
    rng = np.random.default_rng([seed, dim, 6, int(round(-math.log10(gap) * 10)), sign + 1])
    cA = rng.uniform(-4, 4, (N, dim))
    aA = 10.0 ** rng.uniform(2, 3, (N, dim))
    RA = rotations(rng, dim, N)
    r = 10.0 ** rng.uniform(-2, 0, (N, 1))
    p_body, n_body = _surface_point(rng, aA)
    p = cA + np.einsum("nij,nj->ni", RA, p_body)
    n = np.einsum("nij,nj->ni", RA, n_body)
    cB = p + n * r * (1 + sign * gap)
    aB = np.repeat(r, dim, axis=1)
    I = np.broadcast_to(np.eye(dim), (N, dim, dim)).copy()
    A, B = quadrics(cA, aA, RA), quadrics(cB, aB, I)
    name = f"big-small {'+' if sign > 0 else '-'}{gap:g} {dim}D"
    ds = _finish(name, "big-small", dim, A, B, _params(cA, aA, RA, cB, aB, I))
    return _with_dropped(ds, N)


def _check(dim: int, N: int) -> None:
    if dim not in (2, 3):
        raise ValueError(f"dim must be 2 (ellipses) or 3 (ellipsoids), got {dim!r}")
    if not (isinstance(N, int) and N >= 1):
        raise ValueError(f"N must be a positive int, got {N!r}")



# ------------------------------------------------------------------------------------ motions
# Moving pairs in the JSON motion format of core.moving.motions (exact strings), with an interval.


def _q(x: Any) -> str:
    v = to_fmpq(x)
    return f"({v.p}/{v.q})" if v.q != 1 else f"({v.p})"


def _poly_text(coeffs: list[int]) -> str:
    return " + ".join(f"({c})*t^{k}" for k, c in enumerate(coeffs))


def random_motion(dim: int, trans_deg: int, rot_deg: int, *, seed: int = 0) -> dict[str, Any]:
    """Two shapes with integer semi-axes, random polynomial translations of degree ``trans_deg``
    (integer coefficients in [-3, 3], constant terms chosen so that the shapes meet on [-1, 1]
    often) and, for ``rot_deg > 0``, rational rotations from polynomial quaternions of that degree.

    Returns:
        {"A_t": motion, "B_t": motion, "interval": ("-1", "1"), "name": ...}.
    """
    import random

    rng = random.Random(f"{seed}-{dim}-{trans_deg}-{rot_deg}")

    def poly(deg: int) -> list[int]:
        c = [rng.randint(-3, 3) for _ in range(deg + 1)]
        if c[-1] == 0:
            c[-1] = rng.choice([-2, -1, 1, 2])
        return c

    def motion() -> dict[str, Any]:
        m: dict[str, Any] = {
            "shape": {"center": [0] * dim, "semi_axes": [rng.randint(1, 4) for _ in range(dim)]},
            "translation": [_poly_text(poly(trans_deg)) for _ in range(dim)],
        }
        if rot_deg > 0:
            k = 4 if dim == 3 else 2
            q = [_poly_text(poly(rot_deg)) for _ in range(k)]
            q[0] = "3 + " + q[0]  # keeps |q| away from 0 on [-1, 1] most of the time
            m["rotation"] = {"quaternion": q}
        return m

    return {"A_t": motion(), "B_t": motion(), "interval": ("-1", "1"), "name": f"random {dim}D trans {trans_deg} rot {rot_deg}"}


def _rotation_exact(q: list[int], dim: int) -> list[list[fmpq]]:
    R, n = rotation_numerator([fmpq(v) for v in q])  # 2D: q = (w, z)
    return [[v / n for v in r] for r in R]


def grazing_motion(dim: int, *, depth: Any = 0, seed: int = 0) -> dict[str, Any]:
    """A ball sliding past a rotated ellipse/ellipsoid along a line tangent to its offset surface.

    A: integer centre and semi-axes, rational orientation quaternion; p = end of one body axis
    (world), n its outward normal. B: ball of radius r centred at p + (r - depth) n + t v with v a
    rational vector orthogonal to n. Exactly:

    * ``depth = 0``: a grazing touch: one event at t = 0, kind "touch" (separate on both sides);
    * ``depth > 0`` (small): a double event: overlap on a short interval around 0 (two "change"
      events at about -+ sqrt(2 depth rho) / |v|, rho a curvature radius);
    * ``depth < 0``: a near miss: separate on the whole interval, no event.

    Returns:
        {"A_t", "B_t", "interval": ("-1", "1"), "name", "expect"} where ``expect`` is the known
        event pattern for depth 0 ("touch at 0") or depth < 0 ("none"), else None.
    """
    import random

    rng = random.Random(f"graze-{seed}-{dim}")
    cA = [fmpq(rng.randint(-3, 3)) for _ in range(dim)]
    axes = [fmpq(rng.randint(1, 4)) for _ in range(dim)]
    q = [rng.randint(-2, 2) for _ in range(4 if dim == 3 else 2)]
    if not any(q):
        q[0] = 1
    R = _rotation_exact(q, dim)
    k = rng.randrange(dim)
    j = (k + 1 + rng.randrange(dim - 1)) % dim
    side = rng.choice([-1, 1])
    col = [R[i][k] for i in range(dim)]
    n = [side * v for v in col]
    p = [cA[i] + axes[k] * n[i] for i in range(dim)]
    r = fmpq(rng.randint(1, 3), rng.choice([1, 2]))
    speed = fmpq(rng.randint(1, 4))
    v = [speed * R[i][j] for i in range(dim)]
    d = fmpq(0) + to_fmpq(depth)
    c0 = [p[i] + (r - d) * n[i] for i in range(dim)]
    A = {"shape": {"center": [str(x) for x in cA], "semi_axes": [str(x) for x in axes], "orientation": [str(x) for x in q]}}
    B = {"shape": {"center": [0] * dim, "semi_axes": [str(r)] * dim}, "translation": [f"{_q(c0[i])} + {_q(v[i])}*t" for i in range(dim)]}
    kind = "graze" if d == 0 else ("double" if d > 0 else "near miss")
    expect = "touch at 0" if d == 0 else ("none" if d < 0 else None)
    name = f"{kind} {dim}D depth {float(d):.0e}" if d else f"{kind} {dim}D"
    return {"A_t": A, "B_t": B, "interval": ("-1", "1"), "name": f"{name} #{seed}", "expect": expect}


def almost_tangent_motion(eps: Any) -> dict[str, Any]:
    """Paper Example 33 (externally tangent for every t: s0 = 0 identically) with B moved by eps
    along x: the shapes stay within |eps| of tangency for all t (eps > 0 apart, < 0 into A)."""
    e = _q(eps)
    A = {"shape": {"center": [0, 0, 0], "semi_axes": [2, 3, 4]}, "translation": ["2*(t^2 - 1)/(t^2 + 1)", "-6*t/(t^2 + 1)", "0"]}
    B = {"shape": {"center": [0, 0, 0], "semi_axes": [2, 3, 2]}, "translation": [f"-2*(t^2 - 1)/(t^2 + 1) + {e}", "6*t/(t^2 + 1)", "0"]}
    return {"A_t": A, "B_t": B, "interval": ("-3", "3"), "name": f"ex-33 moved {float(to_fmpq(eps)):+.0e}", "expect": None}
