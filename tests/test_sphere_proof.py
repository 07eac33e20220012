"""The float bounding spheres of core.bodies.bounds (numpy) and core/fixed/_spheres.h (C), against exact arithmetic.

A sphere (c, rho) is checked to contain the body of the float matrix M exactly, by the S-lemma:
the body {X^T M X <= 0} (M normalised to a positive definite quadratic block) lies in the ball
{|x - c|^2 <= rho^2} when tau M - S is positive definite for some tau > 0, S the ball's matrix
(then X^T S X < tau X^T M X <= 0 on the body). tau is a rational between two consecutive real
roots of det(tau M - S) (flint's certified root isolation); the test is Sylvester's criterion on
exact rationals. The checker
itself is checked: a ball shrunk below the body's half extent is refused (a point of the body
outside it, exactly).

Bodies: spheres, needles (axis ratios to 1e6), flattened discs, random orientations, centres
near and far (up to 2^20 semi-axes away), and the same bodies at the scales 2^-500 and 2^500.
"""

from __future__ import annotations

import numpy as np
import pytest
from flint import arb, fmpq, fmpq_mat, fmpz_poly

from core import bodies_from_axes
from core.bodies.bounds import _exact_spheres, bounding_spheres
from core.fixed import compiled

needs_c = pytest.mark.skipif(not compiled.spheres_available(), reason="the compiled extension (with spheres) is not built")


def q(v: float) -> fmpq:
    return fmpq(*float(v).as_integer_ratio())


def ball_contains(M: np.ndarray, c: np.ndarray, rho: float) -> bool:
    """Exact proof that the body of M lies in the closed ball (c, rho) (False: no proof found).

    tau M - S positive definite (Sylvester, exact rationals) for a rational tau between two
    consecutive real roots of det(tau M - S) = det M * charpoly(M^-1 S), isolated by flint.
    """
    n = M.shape[0]
    d = n - 1
    E = [[q(M[i, j]) for j in range(n)] for i in range(n)]
    if E[0][0] < 0:
        E = [[-v for v in row] for row in E]
    r2 = q(rho) ** 2
    cs = [q(v) for v in c]
    S = [[fmpq(1) if i == j else fmpq(0) for j in range(d)] + [-cs[i]] for i in range(d)]
    S.append([-v for v in cs] + [sum((v * v for v in cs), fmpq(0)) - r2])
    Me, Se = fmpq_mat(E), fmpq_mat(S)
    if Me.det() == 0:
        return False
    poly = (Me.inv() * Se).charpoly()
    num = fmpz_poly([int(poly[k] * poly.denom()) for k in range(poly.degree() + 1)])
    real = sorted(_rational(r.real) for r, _ in num.complex_roots() if r.imag == 0)
    for tau in [(a + b) / 2 for a, b in zip(real[:-1], real[1:], strict=False)]:
        if tau <= 0:
            continue
        P = fmpq_mat(n, n, [tau * E[i][j] - S[i][j] for i in range(n) for j in range(n)])
        if all(fmpq_mat(k, k, [P[i, j] for i in range(k) for j in range(k)]).det() > 0 for k in range(1, n + 1)):
            return True
    return False


def _rational(x: arb) -> fmpq:
    """The midpoint of a real ball, exactly."""
    m, e = x.mid().man_exp()
    return fmpq(int(m)) * (fmpq(2) ** int(e) if e >= 0 else fmpq(1, 2 ** int(-e)))


def point_outside(M: np.ndarray, c: np.ndarray, rho: float, centre: np.ndarray, axes: np.ndarray, R: np.ndarray) -> bool:
    """A point of the body (exactly inside M) farther than rho from c: the ball misses part of it."""
    n = M.shape[0]
    E = [[q(M[i, j]) for j in range(n)] for i in range(n)]
    sign = -1 if E[0][0] < 0 else 1
    for k in range(len(axes)):
        for t in (0.999, -0.999):
            x = centre + t * axes[k] * R[:, k]
            X = [q(v) for v in x] + [fmpq(1)]
            inside = sign * sum(X[i] * E[i][j] * X[j] for i in range(n) for j in range(n)) < 0
            far = sum(((X[i] - q(c[i])) ** 2 for i in range(n - 1)), fmpq(0)) > q(rho) ** 2
            if inside and far:
                return True
    return False


def family(d: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(centres, semi-axes, orientations) of spheres, needles, discs and random bodies."""
    rng = np.random.default_rng([seed, d])
    rows = []
    for ratio in (1.0, 1e2, 1e4, 1e6):  # 1: spheres; then needles and discs
        for _ in range(3):
            a = np.ones(d)
            a[rng.integers(d)] = ratio if rng.random() < 0.5 else 1 / ratio
            rows.append(a * rng.uniform(0.5, 2.0))
    for _ in range(8):
        rows.append(rng.uniform(0.2, 3.0, d))
    axes = np.array(rows)
    far = 2.0 ** rng.uniform(-3, 20, (len(rows), 1)) * axes.min(axis=1, keepdims=True)
    u = rng.normal(size=(len(rows), d))
    centres = u / np.linalg.norm(u, axis=1, keepdims=True) * far
    orient = rng.normal(size=(len(rows), 4)) if d == 3 else rng.uniform(0, np.pi, len(rows))
    return centres, axes, orient


def test_the_checker_refuses_a_ball_too_small():
    """The exact containment check can fail: a unit sphere is not in a ball of radius 0.9, nor off-centre."""
    M = bodies_from_axes([[0.5, -0.25, 3.0]], [[1.0, 1.0, 1.0]])[0]
    assert ball_contains(M, np.array([0.5, -0.25, 3.0]), 1.0 + 2.0**-40)
    assert not ball_contains(M, np.array([0.5, -0.25, 3.0]), 0.9)
    assert not ball_contains(M, np.array([0.6, -0.25, 3.0]), 1.05)
    assert point_outside(M, np.array([0.5, -0.25, 3.0]), 0.9, np.array([0.5, -0.25, 3.0]), np.ones(3), np.eye(3))


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("scale", [1.0, 2.0**-500, 2.0**500])
def test_float_spheres_contain_the_exact_bodies(d, scale):
    """Every sphere the float proof gives (numpy, and C where built) contains its body exactly, and is tight."""
    centres, axes, orient = family(d, seed=3)
    Q = bodies_from_axes(centres * scale, axes * scale, orient)
    Q[1::4] *= -1.0  # flipped signs: the same bodies
    results = {"numpy": _exact_spheres(Q)[:2]}
    if compiled.spheres_available():
        c, r, status = compiled.spheres(Q)
        results["C"] = (c, np.where(status <= compiled.SPHERE_LOOSE, r, np.nan))
    full = bounding_spheres(Q)  # every body: the float paths, exact arithmetic for the rest
    ratio = axes.max(axis=1) / axes.min(axis=1)
    # the builder's float matrix of a needle 2^500 long is no ellipsoid (its thin axis' 1/r^2 is
    # subnormal): exact validation says so, and no sphere is given
    assert all(ratio[k] >= 1e4 and scale != 1.0 for k in full.invalid), full.invalid
    assert np.isfinite(full.radii[[k not in full.invalid for k in range(len(Q))]]).all()
    results["bounding_spheres"] = (full.centers, full.radii)
    certified = 0
    tame = (axes.max(axis=1) / axes.min(axis=1) <= 1e2) & (np.linalg.norm(centres, axis=1) <= 2.0**10 * axes.min(axis=1))
    for name, (c, r) in results.items():
        for k in np.flatnonzero(np.isfinite(r)):
            assert ball_contains(Q[k], c[k], r[k]), (name, k, axes[k])
            if tame[k]:  # and tight: the largest semi-axis plus the centre's offset, within 0.2 %
                assert r[k] <= 1.002 * axes[k].max() * scale + np.linalg.norm(c[k] - centres[k] * scale), (name, k)
            certified += 1
    assert full.exact <= np.count_nonzero(ratio >= 1e4)  # floats serve all but the most ill-conditioned
    if scale == 1.0:  # the fast path itself (far from size 1: bounds.py's own-units path)
        for name in ("numpy", "C"):
            if name in results:
                assert np.isfinite(results[name][1][ratio < 1e3]).all(), name
    assert certified >= len(Q) + (2 * len(Q) if scale == 1.0 else 0) - 3 * np.count_nonzero(ratio >= 1e4)


@needs_c
@pytest.mark.parametrize("d", [2, 3])
def test_c_spheres_are_the_numpy_proof(d):
    """The C twin takes the numpy proof's steps: the same status, centres bit for bit, radii to the last bits
    (the 3D eigenvalue estimate uses libm's acos and cos, numpy its own)."""
    centres, axes, orient = family(d, seed=5)
    Q = bodies_from_axes(centres, axes, orient)
    Q = np.concatenate([Q, Q * 2.0**-20, -Q])
    c, r, status = compiled.spheres(Q)
    cn, rn, loose, other = _exact_spheres(Q)
    assert (status == np.where(other, 3, np.where(np.isnan(rn), 2, np.where(loose, 1, 0)))).all()
    ok = np.isfinite(rn)
    assert (c[ok] == cn[ok]).all()
    assert np.allclose(r[ok], rn[ok], rtol=1e-12, atol=0)
    if d == 2:
        assert (r[ok] == rn[ok]).all()
    asym = Q[:3].copy()
    asym[0, 0, 1] += 1e-13  # not exactly symmetric: the general path
    asym[1, 2, 2] = np.nan  # not finite: no sphere here
    asym[2, 0, 0] = 0.0  # M_00 = 0: the general path
    assert compiled.spheres(asym)[2].tolist() == [3, 2, 3]
