"""First contacts among N moving bodies: sweep_contacts, the swept broad phase, the float filter.

References are independent of the code under test: constructions whose contact time is known
exactly by design (bench/sweep_data.py: an ellipsoid turning its tip past another, touching at
t* = s0 / (s0 + s1) only; the same moved 2^-40 outward never touches), the full exact analysis
:func:`core.analyse` of each pair's exact motion, the static exact oracle (tests/oracle.py) at
the rational ends of the brackets, brute force over all pairs (for the broad phase), and exact
rational segment distances (for the relative-motion test).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from flint import fmpq
from oracle import oracle_relation

from bench.sweep_data import SPACING, grazing_pairs, moving_bodies, random_pairs, start_pairs
from core import Certifier, Relation, SweepContacts, analyse, sweep_contacts
from core.algebra.algebraic import RealAlgebraic
from core.bodies.swept import swept_pairs, swept_spheres
from core.moving import sweep_filter
from core.moving.first_contact import first_contacts
from core.moving.linear import read_linear_motions
from core.moving.motions import matrix_at_exact


def q(x: float) -> fmpq:
    return fmpq(*float(x).as_integer_ratio())


def truth_of(bodies, i: int, j: int, shift=None):
    """(t*, relation at t*) of a pair from the full exact analysis; (None, None) if it never meets."""
    A, B = bodies.motion(i), bodies.motion(j, shift)
    r = analyse(A, B, (0, 1))
    rel = r.relation_at(0)
    if rel != Relation.SEPARATE:
        return RealAlgebraic.rational(fmpq(0)), rel
    for e in r.events:
        return e.time, e.relation
    return None, None


def check_against_analysis(m, res: SweepContacts, *, oracle_every: int = 0) -> None:
    """Every pair of a pair set: reported iff it meets, with its exact t* in [t_lo, t_hi]."""
    bodies, _ = read_linear_motions(*m.arguments())
    found = {(int(a), int(b)): k for k, (a, b) in enumerate(zip(res.i, res.j, strict=True))}
    assert all(a % 2 == 0 and b == a + 1 for a, b in found)  # only the designed pairs meet
    for p in range(len(bodies) // 2):
        t, rel = truth_of(bodies, 2 * p, 2 * p + 1)
        k = found.get((2 * p, 2 * p + 1))
        if t is None:
            assert k is None, f"pair {p}: reported but never meets"
            continue
        assert k is not None, f"pair {p}: missed (t* = {t.decimal(12)})"
        lo, hi = q(res.t_lo[k]), q(res.t_hi[k])
        assert t.compare(lo) >= 0 and t.compare(hi) <= 0, f"pair {p}: t* = {t.decimal(15)} outside [{lo}, {hi}]"
        assert res.t_hi[k] - res.t_lo[k] <= 1e-9
        assert res.relation[k] == rel
        if oracle_every and p % oracle_every == 0 and lo > 0:
            # independent static oracle: separate at t_lo (exact matrices of the exact motion)
            A, B = bodies.motion(2 * p), bodies.motion(2 * p + 1)
            assert oracle_relation(matrix_at_exact(A, lo), matrix_at_exact(B, lo)) == "separate"


# ------------------------------------------------------------------------ the contract


def test_contract_shapes_order_and_exact_time():
    m = random_pairs(60, seed=1)
    res = sweep_contacts(*m.arguments())
    assert res.i.dtype == np.int64 and res.j.dtype == np.int64 and res.relation.dtype == np.int8
    assert res.t_lo.dtype == np.float64 and res.t_hi.dtype == np.float64
    assert (res.i < res.j).all()
    keys = list(zip(res.i.tolist(), res.j.tolist(), strict=True))
    assert keys == sorted(keys)
    assert (res.t_lo <= res.t_hi).all() and (res.t_hi - res.t_lo <= 1e-9).all()
    assert ((res.t_lo >= 0) & (res.t_hi <= 1)).all()
    assert set(res.relation.tolist()) <= {Relation.TANGENT, Relation.OVERLAP}
    assert (res.t_hi[res.relation == Relation.OVERLAP] == 0).all()  # overlap only at the start
    assert res.counts["contacts"] == len(res) and res.counts["float"] + res.counts["exact"] == res.counts["candidates"]
    for k in range(0, len(res), 7):
        t = res.time(k)
        assert t.compare(q(res.t_lo[k])) >= 0 and t.compare(q(res.t_hi[k])) <= 0
    with pytest.raises(IndexError):
        res.time(len(res))
    order = res.order()  # the event list of the step: by t_lo
    assert sorted(order.tolist()) == list(range(len(res))) and (np.diff(res.t_lo[order]) >= 0).all()
    first = res.first_time()
    assert first.shape == (res.n_bodies,) and first[res.i[order[0]]] == res.t_lo[order[0]]
    alone = np.setdiff1d(np.arange(res.n_bodies), np.concatenate([res.i, res.j]))
    assert np.isinf(first[alone]).all() and len(res.pairs_of(int(res.i[0]))) >= 1
    rows = res.to_rows()
    assert rows[0][:2] == (int(res.i[0]), int(res.j[0])) and rows[0][4] in ("tangent", "overlap")
    assert "moving bodies" in res.summary()


@pytest.mark.parametrize("dim", [3, 2])
@pytest.mark.parametrize("rotate", [False, True])
def test_random_pairs_against_the_exact_analysis(dim, rotate):
    m = random_pairs(14 if rotate and dim == 3 else 24, dim=dim, rotate=rotate, seed=7 + dim)
    res = sweep_contacts(*m.arguments())
    assert res.counts["contacts"] >= 5  # the set has contacts at t = 0 and later
    check_against_analysis(m, res, oracle_every=3)


@pytest.mark.parametrize("dim", [3, 2])
def test_grazing_contacts_at_known_rational_times(dim):
    m = grazing_pairs(10, dim=dim, seed=3)
    res = sweep_contacts(*m.arguments())
    assert len(res) == 10
    for k in range(10):
        t = m.t_exact[k]
        assert (res.i[k], res.j[k]) == (2 * k, 2 * k + 1)
        assert q(res.t_lo[k]) <= fmpq(t.numerator, t.denominator) <= q(res.t_hi[k])
        assert res.time(k).compare(fmpq(t.numerator, t.denominator)) == 0  # exactly t*
        assert res.relation[k] == Relation.TANGENT
    # touching without crossing: only exact arithmetic can tell
    assert (res.certified_by == Certifier.EXACT).all()


@pytest.mark.parametrize("dim", [3, 2])
def test_tangent_at_the_start_and_near_misses(dim):
    res = sweep_contacts(*start_pairs(5, dim=dim, seed=4).arguments())
    assert len(res) == 5 and (res.t_lo == 0).all() and (res.t_hi == 0).all() and (res.relation == Relation.TANGENT).all()
    miss = grazing_pairs(10, dim=dim, offset=2.0**-40, seed=5)  # 9.1e-13 apart at closest
    res = sweep_contacts(*miss.arguments())
    assert len(res) == 0 and res.counts["candidates"] == 10
    shallow = grazing_pairs(6, dim=dim, offset=-(2.0**-40), seed=6)  # overlap 9.1e-13 deep
    res = sweep_contacts(*shallow.arguments())
    check_against_analysis(shallow, res)
    assert len(res) == 6


def test_filter_and_exact_paths_agree():
    m = random_pairs(12, rotate=True, seed=21)
    bodies, _ = read_linear_motions(*m.arguments())
    i, j = np.arange(0, 24, 2), np.arange(1, 24, 2)
    fast = first_contacts(bodies, i, j)
    slow = first_contacts(bodies, i, j, method="exact")
    assert (slow.certified_by == Certifier.EXACT).all()
    assert (fast.relation == slow.relation).all()
    for k in np.flatnonzero(slow.relation != Relation.SEPARATE):
        t = slow.times[k]
        assert t.compare(q(fast.t_lo[k])) >= 0 and t.compare(q(fast.t_hi[k])) <= 0


def test_without_the_compiled_filter_exact_arithmetic_answers(monkeypatch):
    m = random_pairs(6, seed=2)
    want = sweep_contacts(*m.arguments())
    monkeypatch.setattr(sweep_filter, "_library", lambda: None)
    got = sweep_contacts(*m.arguments())
    assert got.counts["exact"] == got.counts["candidates"] > 0
    assert got.i.tolist() == want.i.tolist() and got.relation.tolist() == want.relation.tolist()
    for k in range(len(got)):
        assert got.time(k).compare(q(want.t_lo[k])) >= 0 and got.time(k).compare(q(want.t_hi[k])) <= 0


def test_the_sweep_kernel_is_built_at_install_and_its_absence_is_loud(monkeypatch):
    # installed package: the extension loads, nothing is compiled at run time
    assert sweep_filter.filter_status().startswith("compiled sweep kernel loaded from ")
    # a copy without the extension: exact arithmetic answers, and a warning names cause and fix
    monkeypatch.setattr(sweep_filter, "_state", {"lib": None, "status": "not built yet", "tried": False})

    def missing(name: str):
        raise ImportError(f"No module named {name!r}")

    monkeypatch.setattr(sweep_filter.importlib, "import_module", missing)
    with pytest.warns(RuntimeWarning, match=r"sweep kernel is missing .*pip install"):
        assert sweep_filter._library() is None
    assert "exact arithmetic answers every pair" in sweep_filter.filter_status()


def test_exact_motions_are_the_parsed_expressions():
    # the directly built A(t) equals the one the motion's own expressions give (parser path)
    from core.moving.motions import motion_from_dict, motion_to_dict

    for m in (random_pairs(3, rotate=True, seed=1), random_pairs(3, dim=2, rotate=True, seed=3), grazing_pairs(2, seed=1)):
        bodies, _ = read_linear_motions(*m.arguments())
        for k in range(len(bodies)):
            for shift in (None, [10.0] * bodies.dim):
                fast = bodies.motion(k, shift)
                parsed = motion_from_dict(motion_to_dict(fast))
                assert all(x == y for a, b in zip(fast.matrix(), parsed.matrix(), strict=True) for x, y in zip(a, b, strict=True))
                assert bodies.matrix_at_start(k, shift) == matrix_at_exact(parsed, 0)


# ------------------------------------------------------------------------ broad phase


def test_broad_phase_drops_no_pair_that_meets():
    m = moving_bodies(70, fraction=0.3, rotate=True, seed=3)
    res = sweep_contacts(*m.arguments())
    bodies, _ = read_linear_motions(*m.arguments())
    i, j = np.triu_indices(70, 1)
    every = first_contacts(bodies, i, j)  # the narrow phase on all 2415 pairs
    meet = np.flatnonzero(every.relation != Relation.SEPARATE)
    assert set(zip(i[meet].tolist(), j[meet].tolist(), strict=True)) == set(zip(res.i.tolist(), res.j.tolist(), strict=True))
    assert len(res) > 20 and res.counts["candidates"] < i.size


def test_relative_motion_test_is_conservative():
    # pairs whose bounding-sphere paths pass at distances around a_i + a_j (exact rationals decide)
    rng = np.random.default_rng(8)
    n = 150
    c0 = rng.uniform(-3, 3, (n, 3))
    c1 = c0 + rng.normal(size=(n, 3)) * 2
    r = rng.uniform(0.2, 1.0, (n, 3))
    bodies, _ = read_linear_motions(c0, c1, r)
    cand, broad = swept_pairs(bodies, swept_spheres(bodies, np.ones(n, bool)), None)
    kept = set(zip(cand.i.tolist(), cand.j.tolist(), strict=True))
    assert broad >= len(cand)
    misses = 0
    for a in range(n):
        for b in range(a + 1, n):
            d0 = [Fraction(x) - Fraction(y) for x, y in zip(c0[b], c0[a], strict=True)]
            e = [Fraction(x) - Fraction(y) - z for x, y, z in zip(c1[b], c1[a], d0, strict=True)]
            ee = sum(x * x for x in e)
            t = min(max(-sum(x * y for x, y in zip(d0, e, strict=True)) / ee, Fraction(0)), Fraction(1)) if ee else Fraction(0)
            dist2 = sum((x + t * y) ** 2 for x, y in zip(d0, e, strict=True))
            reach = Fraction(max(r[a])) + Fraction(max(r[b]))
            if dist2 <= reach * reach and (a, b) not in kept:
                misses += 1
    assert misses == 0


# ------------------------------------------------------------------------ periodic box


def test_periodic_box_equals_explicit_images():
    # bodies near the faces of a box of side 10; the images are placed explicitly in open space
    rng = np.random.default_rng(4)
    n, Lb = 40, 10.0
    c0 = rng.uniform(0.3, Lb - 0.3, (n, 3))
    c0[:10, 0] = rng.uniform(0.3, 0.8, 10)
    c0[10:20, 0] = rng.uniform(9.2, 9.7, 10)
    c1 = c0 + rng.uniform(-0.5, 0.5, (n, 3))  # the midpoints stay in the box
    r = rng.uniform(0.3, 0.8, (n, 3))
    o0 = rng.normal(size=(n, 4))
    o1 = rng.normal(size=(n, 4))
    res = sweep_contacts(c0, c1, r, o0, o1, box=(Lb,) * 3)
    assert res.image is not None and (res.image != 0).any()
    shifts = [np.array(k, dtype=float) * Lb for k in np.ndindex(3, 3, 3)]
    shifts = [s - Lb for s in shifts]
    big = sweep_contacts(
        np.concatenate([c0 + s for s in shifts]), np.concatenate([c1 + s for s in shifts]),
        np.concatenate([r] * 27), np.concatenate([o0] * 27), np.concatenate([o1] * 27),
    )
    home = [k for k, s in enumerate(shifts) if not s.any()][0]
    want = {}
    for a, b, lo in zip(big.i.tolist(), big.j.tolist(), big.t_lo.tolist(), strict=True):
        ia, ka = a % n, a // n
        ib, kb = b % n, b // n
        if ka == home and ia < ib:
            want[(ia, ib)] = lo
        elif kb == home and ib < ia:
            want[(ib, ia)] = lo
    got = dict(zip(zip(res.i.tolist(), res.j.tolist(), strict=True), res.t_lo.tolist(), strict=True))
    assert got.keys() == want.keys()
    for key in got:
        assert abs(got[key] - want[key]) <= 1e-9


def test_periodic_box_limits():
    c0 = np.array([[0.5, 5, 5], [9.5, 5, 5]])
    with pytest.raises(ValueError, match="too large for the periodic box"):
        sweep_contacts(c0, c0 + [[0, 0, 0], [0, 4, 0]], [[1.5, 1, 1]] * 2, box=(10, 10, 10))  # 1.5 + (1.5 + 2) >= 10 / 2
    # bodies anywhere (issue 54): 25 is 5 two boxes on, 4.5 from 0.5; 21 is 1 two boxes on, 0.5 away
    assert len(sweep_contacts([[0.5, 5, 5], [25, 5, 5]], [[0.5, 5, 5], [25, 5, 5]], [[1, 1, 1]] * 2, box=(10, 10, 10))) == 0
    far = sweep_contacts([[0.5, 5, 5], [21, 5, 5]], [[0.5, 5, 5], [21, 5, 5]], [[1, 1, 1]] * 2, box=(10, 10, 10))
    assert far.image.tolist() == [[-2, 0, 0]] and far.relation.tolist() == [Relation.OVERLAP]
    res = sweep_contacts(c0, c0, [[0.5, 0.5, 0.5]] * 2, box=(10, 10, 10))  # 1 apart across the face
    assert len(res) == 1 and res.relation[0] == Relation.TANGENT and res.image[0].tolist() == [-1, 0, 0]


# ------------------------------------------------------------------------ bad input


def test_bad_rows_are_named_or_marked():
    c0 = [[0.0, 0, 0], [3, 0, 0], [6, 0, 0], [9, 0, 0]]
    c1 = [[2.0, 0, 0], [3, 0, 0], [6, 0, 0], [9, 0, 0]]
    r = [[1.0, 1, 1]] * 4
    o0 = [[1.0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0], [1, 0, 0, 0]]
    o1 = [[1.0, 0, 0, 0], [1, 0, 0, 0], [0, -1, 0, 0], [1, 0, 0, 0]]  # row 2 turns through zero
    with pytest.raises(ValueError, match="row 2: the orientation passes through zero"):
        sweep_contacts(c0, c1, r, o0, o1)
    res = sweep_contacts(c0, c1, r, o0, o1, on_invalid="mark")
    assert list(res.invalid) == [2] and (res.i.tolist(), res.j.tolist()) == ([0], [1])
    bad_r = [[1.0, 1, 1], [1, -1, 1], [1, 1, 1], [1, 1, 1]]
    with pytest.raises(ValueError, match=r"row 1: semi-axes must be positive, got \[1.0, -1.0, 1.0\]"):
        sweep_contacts(c0, c1, bad_r)
    nan = [[0.0, 0, 0], [3, 0, 0], [6, math.nan, 0], [9, 0, 0]]
    with pytest.raises(ValueError, match="row 2: centers1 must be finite"):
        sweep_contacts(c0, nan, r)
    with pytest.raises(ValueError, match="row 3: orientations0: the quaternion is zero"):
        sweep_contacts(c0, c1, r, [[1.0, 0, 0, 0]] * 3 + [[0.0, 0, 0, 0]])
    with pytest.raises(ValueError, match="semi_axes must have the shape"):
        sweep_contacts(c0, c1, r[:3])
    with pytest.raises(ValueError, match="orientations1 must be"):
        sweep_contacts(c0, c1, r, o0, [[1.0, 0, 0]] * 4)
    with pytest.raises(ValueError, match="not a float64 value"):
        sweep_contacts(np.array(c0, dtype=object) + Fraction(1, 3), c1, r)
    with pytest.raises(ValueError, match="on_invalid"):
        sweep_contacts(c0, c1, r, on_invalid="skip")  # type: ignore[arg-type]


def test_2d_angles_are_half_angle_numbers():
    # an angle theta is the half-angle number (cos(theta/2), sin(theta/2)), i.e. the quaternion (w, 0, 0, s)
    m = random_pairs(20, dim=2, rotate=True, seed=5)
    a = sweep_contacts(*m.arguments())

    def quat(theta):
        return np.array([[math.cos(v / 2), 0.0, 0.0, math.sin(v / 2)] for v in theta])

    b = sweep_contacts(m.centers0, m.centers1, m.semi_axes, quat(m.orientations0), quat(m.orientations1))
    assert len(a) > 3 and a.i.tolist() == b.i.tolist() and a.t_lo.tolist() == b.t_lo.tolist()


def test_pairs_spacing_keeps_pair_sets_independent():
    m = grazing_pairs(2, seed=1)
    assert m.centers0[2, 0] - m.centers0[0, 0] == SPACING


@pytest.mark.parametrize("exponent", [-990, -700, 0, 700, 990])
def test_sweep_at_any_float_scale(exponent):
    """Was: past about 1e154 the swept ball's |c1 - c0| overflowed ("its swept volume is beyond the
    float range"). Three unit spheres scaled by 2^e: sphere 1 moves from 3 to 1.5 on the x axis, so it
    meets sphere 0 at t = 2/3 exactly, and it overlaps sphere 2 (at 4.5) from the start."""
    s = 2.0**exponent
    c0 = np.array([[0.0, 0, 0], [3.0, 0, 0], [4.5, 0, 0]]) * s
    c1 = c0 + np.array([[0.0, 0, 0], [-1.5, 0, 0], [0.0, 0, 0]]) * s
    res = sweep_contacts(c0, c1, np.full((3, 3), s))
    assert list(zip(res.i.tolist(), res.j.tolist(), res.relation.tolist(), strict=True)) == [
        (0, 1, Relation.TANGENT), (1, 2, Relation.OVERLAP)]
    assert res.time(0).compare(fmpq(2, 3)) == 0 and res.time(1).compare(0) == 0


@pytest.mark.parametrize("scale", [1e150, 2.0**700, 1e-150, 1.0])
def test_sweep_at_any_float_scale_finds_every_pair_that_meets(scale):
    """Was: at 1e150 the relative-motion test squared cross products past the float range (inf, not
    NaN) and dropped pairs that meet: 1,690 of 6,605 contacts of 5,000 moving bodies went missing,
    also with method="exact" (the test runs before the narrow phase). Reference: the narrow phase
    on every pair (no broad phase, no relative-motion test), the bodies as the user scales them."""
    mv = moving_bodies(240, fraction=0.25, dim=3, rotate=True, seed=2)
    c0, c1, r = (np.asarray(x) * scale for x in (mv.centers0, mv.centers1, mv.semi_axes))
    res = sweep_contacts(c0, c1, r, mv.orientations0, mv.orientations1)
    bodies, _ = read_linear_motions(c0, c1, r, mv.orientations0, mv.orientations1)
    i, j = np.triu_indices(len(c0), 1)
    every = first_contacts(bodies, i, j)
    meet = every.relation != Relation.SEPARATE
    assert set(zip(res.i.tolist(), res.j.tolist(), strict=True)) == set(zip(i[meet].tolist(), j[meet].tolist(), strict=True))
    assert meet.sum() > 40


@pytest.mark.parametrize("dim", [3, 2])
def test_sweep_far_from_size_1_is_certified_in_floats_with_the_pairs_of_size_1(dim):
    """Was: bodies of size 2^-1000 or 1e-300 took 82 s for 2,000 bodies instead of 0.05 s: the swept
    balls had an absolute 2^-1000 added (5x the candidates at 2^-1000), the relative-motion test's
    squared cross products underflowed below 2^-400 (12 % more candidates at 1e-100), and the
    moving filter added its underflow term (2^-1022) to the centre offsets before their scaling to
    the bodies' size, so it abstained on every pair that meets during the step and exact arithmetic
    answered them (~90 ms each). Scaled by a power of two, the geometry and so each first contact
    t* are exactly those of size 1: the same candidates, every one certified by the float filter,
    and brackets (t_lo, t_hi] that overlap those of size 1 (both hold t*)."""
    mv = moving_bodies(300, fraction=0.3, dim=dim, rotate=True, seed=4)
    ref = sweep_contacts(*mv.arguments())
    assert ref.counts["exact"] == 0 and (ref.t_lo < ref.t_hi).sum() > 20  # contacts during the step
    for e in (-1000, -700, -330, 700, 1000):
        s = 2.0**e
        res = sweep_contacts(mv.centers0 * s, mv.centers1 * s, mv.semi_axes * s, mv.orientations0, mv.orientations1)
        assert res.counts["candidates"] == ref.counts["candidates"] and res.counts["broad"] == ref.counts["broad"], e
        assert res.counts["exact"] == 0, (e, res.counts)
        assert (res.i == ref.i).all() and (res.j == ref.j).all() and (res.relation == ref.relation).all(), e
        assert ((res.t_lo <= ref.t_hi) & (ref.t_lo <= res.t_hi)).all(), e
    for s in (1e-300, 1e-100):  # not powers of two: the same counts
        res = sweep_contacts(mv.centers0 * s, mv.centers1 * s, mv.semi_axes * s, mv.orientations0, mv.orientations1)
        assert res.counts["exact"] == 0 and res.counts["candidates"] == ref.counts["candidates"], (s, res.counts)
