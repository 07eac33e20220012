"""The fast paths of ``contacts`` (issue 24.5) against independent references.

* Bounding spheres of exactly symmetric bodies (``core.bodies.bounds._exact_spheres``): each
  sphere is checked in exact rational arithmetic (flint) against the containment certificate
  of the module docstring, with an eigenvalue bound found and proven here (not the code's).
* The open-space broad phase by position ranges (``core.bodies.broadphase._forward_ranges``):
  every pair whose spheres meet (exact rational test, touching spheres included) is found.
* ``contacts`` (spheres, ranges, the narrow phase's reused gather buffers) against every pair
  classified in exact arithmetic, with exactly tangent pairs, flipped and scaled matrices and
  matrices symmetric only up to rounding (the general path).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from flint import fmpq, fmpq_mat

from bench.bodies_data import random_bodies
from core import Relation, bodies_from_axes, classify, contacts
from core.bodies import bounds, narrowphase
from core.bodies.bounds import _exact_spheres, bounding_spheres
from core.bodies.broadphase import candidate_pairs


def _q(x: float) -> fmpq:
    return fmpq(*float(x).as_integer_ratio())


def _certified_sphere(M: np.ndarray, c: np.ndarray, rho: float) -> bool:
    """Exact check that the ball (c, rho) contains the body M (independent of the code).

    With Q the leading block, lam <= lambda_min(Q) proven here (Sylvester on Q - lam I, exact),
    g = Q c + m and f0 = f(c): every point c + u of the body has lam |u|^2 - 2 |g| |u| + f0 <= 0,
    so |u| <= (|g| + sqrt(|g|^2 - lam f0)) / lam, which is <= rho iff rho lam >= |g| and
    rho^2 lam + f0 >= 0 and (rho^2 lam + f0)^2 >= 4 rho^2 |g|^2 (all rational).
    """
    n = M.shape[0]
    d = n - 1
    s = -1 if M[0, 0] < 0 else 1
    E = [[_q(s * M[i, j]) for j in range(n)] for i in range(n)]
    lam_f = float(np.linalg.eigvalsh(s * M[:d, :d])[0]) * (1 - 2.0**-20)
    lam = _q(lam_f)
    P = [[E[i][j] - (lam if i == j else 0) for j in range(d)] for i in range(d)]
    assert all(fmpq_mat([row[:k] for row in P[:k]]).det() > 0 for k in range(1, d + 1)), "test's lambda not proven"
    cq = [_q(v) for v in c]
    g = [sum((E[i][j] * cq[j] for j in range(d)), E[i][d]) for i in range(d)]
    f0 = sum((cq[i] * (g[i] + E[i][d]) for i in range(d)), E[d][d])
    G2 = sum((v * v for v in g), fmpq(0))
    r = _q(rho)
    a = r * r * lam + f0
    return f0 < 0 and r * r * lam * lam >= G2 and a >= 0 and a * a >= 4 * r * r * G2


@pytest.mark.parametrize("dim", [2, 3])
def test_exact_spheres_are_certified_in_rational_arithmetic(dim):
    rng = np.random.default_rng(50 + dim)
    b = random_bodies(120, dim=dim, ratio=20.0, seed=dim)
    b.centers *= 10.0 ** rng.integers(-3, 5, (120, 1))  # near and far from the origin
    M = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    M[::3] *= -3.0  # flipped and scaled (not by a power of two): the same body, still symmetric
    M[1::5] *= 2.0**-600  # tiny entries (products near the subnormal range)
    c, rho, loose, other = _exact_spheres(M)
    assert not other.any()
    ok = np.flatnonzero(np.isfinite(rho))
    assert ok.size >= 100  # the rest goes on to the careful or exact path
    for k in ok.tolist():
        assert _certified_sphere(M[k], c[k], rho[k]), k
    # and the whole pipeline (fast, careful, exact) for every body
    s = bounding_spheres(M)
    assert not s.invalid
    for k in range(len(M)):
        assert _certified_sphere(M[k], s.centers[k], s.radii[k]), k


def test_exact_spheres_leave_asymmetric_and_degenerate_rows_to_the_general_path():
    M = bodies_from_axes([[0, 0, 0], [3, 0, 0], [0, 4, 0]], [[1, 2, 0.5]] * 3, [[1, 0.2, 0.3, 0.1]] * 3)
    M[1, 0, 1] = np.nextafter(M[1, 0, 1], 1.0)  # symmetric up to rounding only
    M[2, 0, 0] = 0.0
    _, rho, _, other = _exact_spheres(M)
    assert other.tolist() == [False, True, True] and np.isnan(rho[1:]).all()
    s = bounding_spheres(M)
    assert _certified_sphere(M[1], s.centers[1], s.radii[1])  # certified by the general path
    assert list(s.invalid) == [2]


def test_the_bodies_are_never_written():
    # a chunk of one body whose matrix is flipped must not flip the caller's matrix
    Q = -bodies_from_axes(np.arange(9.0)[:, None] * [1.5, 0, 0], np.full((9, 3), 0.5))
    before = Q.copy()
    old = bounds._CHUNK
    try:
        bounds._CHUNK = 4  # chunks of 4, 4 and 1 bodies
        res = contacts(Q)
    finally:
        bounds._CHUNK = old
    assert np.array_equal(Q, before)
    assert len(res) == 0


def _exact_sphere_pairs(c: np.ndarray, r: np.ndarray) -> set[tuple[int, int]]:
    """Pairs whose closed spheres meet, in exact rational arithmetic."""
    out = set()
    for i, j in itertools.combinations(range(len(c)), 2):
        if not (np.isfinite(r[i]) and np.isfinite(r[j])):
            continue
        d2 = sum(((_q(c[j, a]) - _q(c[i, a])) ** 2 for a in range(c.shape[1])), fmpq(0))
        if d2 <= (_q(r[i]) + _q(r[j])) ** 2:
            out.add((i, j))
    return out


@pytest.mark.parametrize("dim", [2, 3])
def test_forward_ranges_find_every_meeting_pair_touching_included(dim):
    rng = np.random.default_rng(7 * dim)
    for trial in range(6):
        n = 150
        c = rng.integers(0, 12, (n, dim)).astype(float)  # integer centres: exact touching pairs
        r = np.full(n, 0.5)
        if trial % 2:
            r = rng.choice([0.5, 1.0, 1.5], n)  # sums are integers: touching at integer distance
        if trial >= 4:  # two size classes (grid levels: ranges inside, queries across)
            r[: n // 3] *= 4.0
        if trial == 3:
            c[:10] = c[0]  # a crowded cell
        if trial == 5:  # clusters far apart: more cells than bodies (binary search, no table)
            c += rng.choice([-1e4, 0.0, 1e4], (n, 1))
        got = candidate_pairs(c, r)
        pairs = list(zip(got.i.tolist(), got.j.tolist(), strict=True))
        assert len(set(pairs)) == len(pairs)
        want = _exact_sphere_pairs(c, r)
        assert set(pairs) == want, trial
        assert any(np.isclose(np.linalg.norm(c[i] - c[j]), r[i] + r[j]) for i, j in want)  # touching ones exist


def _exact_brute(Q: np.ndarray) -> set[tuple[int, int, int]]:
    i, j = np.triu_indices(len(Q), 1)
    rel = classify(Q[i], Q[j], method="exact")
    keep = rel != Relation.SEPARATE
    return set(zip(i[keep].tolist(), j[keep].tolist(), rel[keep].tolist(), strict=True))


@pytest.mark.parametrize("dim", [2, 3])
def test_contacts_equal_exact_brute_force_with_tangent_pairs(dim, monkeypatch):
    b = random_bodies(90, dim=dim, fraction=0.4, ratio=3.0, seed=17 + dim)
    lattice = np.array(list(itertools.product(range(4), repeat=dim)), dtype=float) + 40.0
    centres = np.concatenate([b.centers, lattice])  # touching unit-diameter spheres: tangent pairs
    axes = np.concatenate([b.semi_axes, np.full((len(lattice), dim), 0.5)])
    if dim == 3:
        orient = np.concatenate([b.orientations, np.tile([1.0, 0, 0, 0], (len(lattice), 1))])
    else:
        orient = np.concatenate([b.orientations, np.zeros(len(lattice))])
    Q = bodies_from_axes(centres, axes, orient)
    Q[::4] *= -0.75  # flipped and scaled copies of the same bodies
    Q[5, 0, 1] = np.nextafter(Q[5, 0, 1], np.inf)  # symmetric up to rounding: the general path
    monkeypatch.setattr(narrowphase, "_GATHER", 7)  # many refills of the gather buffers
    res = contacts(Q, chunk=50)
    got = set(zip(res.i.tolist(), res.j.tolist(), res.relation.tolist(), strict=True))
    want = _exact_brute(Q)
    assert got == want
    assert sum(1 for *_, rel in want if rel == Relation.TANGENT) >= dim * 4 ** (dim - 1) * 3
    assert sum(1 for *_, rel in want if rel == Relation.OVERLAP) > 10
