"""Issue 54.1: any periodic step is swept, whatever crosses which face (spheres: closed forms).

Frames are made as a simulation stores them: positions wrapped into the box after every step, so
bodies cross faces between frames and sit near opposite faces. The truth for spheres is exact:
f(t) = |c_j(t) + v(K) - c_i(t)|^2 - (r_i + r_j)^2 is a quadratic in t with rational coefficients
(the floats and the lattice vector as given), checked over every image K near the pair.
"""

from __future__ import annotations

import itertools
from fractions import Fraction as F

import numpy as np
import pytest

from core import Box, Relation, sweep_contacts


def _f(ci0, ci1, cj0, cj1, shift, R):
    """Coefficients (a, b, c) of f(t) = a t^2 + b t + c, exactly."""
    d0 = [F(cj0[a]) + F(shift[a]) - F(ci0[a]) for a in range(len(ci0))]
    e = [(F(cj1[a]) - F(cj0[a])) - (F(ci1[a]) - F(ci0[a])) for a in range(len(ci0))]
    a = sum(x * x for x in e)
    b = 2 * sum(x * y for x, y in zip(d0, e, strict=True))
    c = sum(x * x for x in d0) - F(R) ** 2
    return a, b, c


def _value(coef, t):
    a, b, c = coef
    return a * t * t + b * t + c


def _meets(coef) -> bool:
    """Whether min over [0, 1] of f is <= 0 (exactly)."""
    a, b, c = coef
    candidates = [F(0), F(1)]
    if a > 0 and 0 < -b / (2 * a) < 1:
        candidates.append(-b / (2 * a))
    return min(_value(coef, t) for t in candidates) <= 0


def _frames(box: Box, n: int, radius: float, step: float, seed: int):
    """Two wrapped frames of n spheres (dyadic numbers: every sum below is exact)."""
    rng = np.random.default_rng(seed)
    d = box.dimensions
    dy = lambda x: np.round(x * 2**24) / 2**24  # noqa: E731
    f0 = rng.uniform(-0.5, 0.5, (n, d))
    c0 = box.wrap(dy(f0 @ box.vectors.T))
    c1 = box.wrap(c0 + dy(rng.uniform(-step, step, (n, d))))
    return c0, c1, np.full((n, d), radius)


def _check(box: Box, c0, c1, r):
    ends, _ = box.unwrap(c0, c1)
    res = sweep_contacts(c0, ends, r, box=box)
    d = box.dimensions
    got = {(int(i), int(j)): k for k, (i, j) in enumerate(zip(res.i, res.j, strict=True))}
    n = len(c0)
    checked = 0
    # minimum-image distance of the midpoints (floats: only to skip pairs far apart in every image)
    mid = (c0 + ends) / 2
    reach = 2 * np.abs(ends - c0).max() + 2 * r.max() + 0.5
    for i, j in itertools.combinations(range(n), 2):
        f = box.fractional((mid[j] - mid[i])[None, :])
        near = (f - np.rint(f)) @ box.vectors.T
        if np.linalg.norm(near) > reach:
            continue
        base = -np.rint(box.fractional(((ends[j] + c0[j]) / 2 - (ends[i] + c0[i]) / 2)[None, :]))[0].astype(int)
        meeting = []
        for off in itertools.product((-1, 0, 1), repeat=d):
            K = base + np.array(off)
            shift = box.shifts(K[None, :])[0]
            coef = _f(c0[i], ends[i], c0[j], ends[j], shift, r[i, 0] + r[j, 0])
            if _meets(coef):
                meeting.append((K, shift, coef))
        assert len(meeting) <= 1, (i, j, [m[0] for m in meeting])  # the size rule: one image at most
        if not meeting:
            assert (i, j) not in got, (i, j)
            continue
        checked += 1
        K, shift, coef = meeting[0]
        k = got[(i, j)]
        assert res.image[k].tolist() == K.tolist()
        lo, hi = F(float(res.t_lo[k])), F(float(res.t_hi[k]))
        if coef[2] <= 0:  # touching or overlapping at t = 0
            assert lo == 0 and res.t_hi[k] == 0.0
            assert Relation(int(res.relation[k])) == (Relation.TANGENT if coef[2] == 0 else Relation.OVERLAP)
        else:
            assert Relation(int(res.relation[k])) == Relation.TANGENT
            assert _value(coef, lo) >= 0 >= _value(coef, hi)  # the first root lies in [t_lo, t_hi]
            assert float(hi - lo) <= 1e-9
    return checked, res


@pytest.mark.parametrize(
    "box",
    [Box(10, 10, 10), Box(10, 9, 8, 0.5, -0.25, 0.125), Box(10, 10), Box(10, 8, xy=-0.5)],
    ids=["orthogonal-3d", "tilted-3d", "orthogonal-2d", "tilted-2d"],
)
@pytest.mark.parametrize("step", [0.05, 0.2, 1.0])
def test_every_wrapped_step_is_swept_exactly(box, step):
    c0, c1, r = _frames(box, 150, 0.45 if box.dimensions == 3 else 0.3, step, seed=int(step * 100))
    assert (box.images(c0 + (box.unwrap(c0, c1)[0] - c0)) != 0).any()  # some bodies cross a face
    checked, res = _check(box, c0, c1, r)
    assert checked >= 3 and len(res) == checked


def test_the_issues_two_spheres_across_a_face():
    box = Box(10, 10, 10)
    c0 = np.array([[4.95, 0, 0], [-4.95, 0, 0]])
    c1 = np.array([[-4.85, 0, 0], [4.85, 0, 0]])
    checked, res = _check(box, c0, c1, np.full((2, 3), 0.02))
    assert checked == 1 and res.image[0].tolist() == [1, 0, 0]
    assert abs(float(res.time(0)) - 0.15) < 1e-12  # d(t) = 0.1 - 0.4 t reaches 0.04


def test_an_unwrapped_trajectory_far_from_the_box_is_swept():
    box = Box(10, 10, 10)
    c0 = np.array([[4.95 + 60, 0, 0], [-4.95 - 30, 0, 0]])  # six and three boxes away
    ends = c0 + np.array([[0.2, 0, 0], [-0.2, 0, 0]])
    res = sweep_contacts(c0, ends, np.full((2, 3), 0.02), box=box)
    assert len(res) == 1 and res.image[0].tolist() == [10, 0, 0]
    assert abs(float(res.time(0)) - 0.15) < 1e-9


def test_a_body_that_moves_too_far_in_one_step_is_named():
    box = Box(10, 10, 10)
    c0 = np.array([[0.0, 0, 0], [3.0, 3, 3]])
    ends = c0 + np.array([[6.0, 0, 0], [0, 0, 0]])
    with pytest.raises(ValueError, match=r"row 0 moves 6 in one step, more than half the smallest height"):
        sweep_contacts(c0, ends, np.full((2, 3), 0.1), box=box)
