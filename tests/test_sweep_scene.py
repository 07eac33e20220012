"""Moving bodies in the scene (``serve --bodies START --to END``): colours at t, the event list, the
pair opened on its exact motion; and (marked ``browser``, one browser for the module) the page
driven as a user would: scrub the timeline, click an event, the two-body view shows it.

Golden facts are independent of the code under test: every body's colour at a rational t is
checked against the relation of EVERY pair of bodies (not only the pairs the sweep reports) from
``tests/oracle.py`` (exact characteristic polynomial, certified roots) on matrices built here
from the parameters in rationals; event times are closed forms worked out by hand (unit spheres
whose centres come 2 apart: 3 - 4t = 2 gives 1/4, (3 - 4t)^2 + 1 = 4 gives (3 - sqrt 3)/4, a
sphere grazing another at t = 1/2, one leaving another at 1/3).
"""

from __future__ import annotations

import os
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from flint import fmpq

viser = pytest.importorskip("viser")

import browser_helpers  # noqa: E402
from browser_helpers import field_input, text_shown, until  # noqa: E402
from oracle import oracle_relation  # noqa: E402

from app.bodyfiles import write_bodies_csv  # noqa: E402
from app.scene.bodies.bodies_lod import ViewPose  # noqa: E402
from app.scene.bodies.bodies_view import BodiesView  # noqa: E402
from app.scene.bodies.sweep_model import PENDING_COLOUR, SweepModel, compare_times, same_time  # noqa: E402
from app.scene.pair.analysis import AnalysisView  # noqa: E402
from app.sweep_cli import read_moving_bodies  # noqa: E402
from bench.sweep_data import moving_bodies  # noqa: E402
from core import Relation, analyse  # noqa: E402
from core.algebra.algebraic import RealAlgebraic  # noqa: E402

ARTIFACTS = Path(__file__).resolve().parent / "artifacts"
I = [1.0, 0.0, 0.0, 0.0]

# body: centre at t = 0, centre at t = 1, semi-axes, quaternion at 0, quaternion at 1
SCENE = [
    ((0, 0, 0), (0, 0, 0), (1, 1, 1), I, I),  # 0 and 1: 3 - 4t = 2 at t = 1/4, overlap after
    ((3, 0, 0), (-1, 0, 0), (1, 1, 1), I, I),
    ((10, 0, 0), (10, 0, 0), (1, 1, 1), I, I),  # 2 and 3: (3 - 4t)^2 + 1 = 4 at t = (3 - sqrt 3)/4
    ((13, 1, 0), (9, 1, 0), (1, 1, 1), I, I),
    ((20, 0, 0), (20, 0, 0), (1, 1, 1), I, I),  # 4 and 5: 5 passes 4 at distance 2: touch at 1/2 only
    ((22, -3, 0), (22, 3, 0), (1, 1, 1), I, I),
    ((30, 0, 0), (30, 0, 0), (1, 1, 1), I, I),  # 6 and 7: 1 + 3t < 2 until 1/3: overlap, then apart
    ((31, 0, 0), (34, 0, 0), (1, 1, 1), I, I),
    ((50, 5, 5), (50, 6, 5), (0.5, 0.5, 0.5), I, I),  # 8: alone
    ((40, 0, 0), (40, 0, 0), (2, 0.5, 0.5), I, [1.0, 0.0, 0.0, 1.0]),  # 9 turns (q = (1, 0, 0, t)) into 10
    ((40, 1.5, 0), (40, 1.5, 0), (0.5, 0.5, 0.5), I, I),
]
SQRT3_TIME = "(3 − √3)/4"


def write_scene(folder: Path, rows=SCENE) -> tuple[Path, Path]:
    c0 = np.array([r[0] for r in rows], float)
    c1 = np.array([r[1] for r in rows], float)
    ax = np.array([r[2] for r in rows], float)
    write_bodies_csv(folder / "start.csv", c0, ax, np.array([r[3] for r in rows], float))
    write_bodies_csv(folder / "end.csv", c1, ax, np.array([r[4] for r in rows], float))
    return folder / "start.csv", folder / "end.csv"


@pytest.fixture(scope="module")
def scene_files(tmp_path_factory):
    return write_scene(tmp_path_factory.mktemp("sweep"))


@pytest.fixture(scope="module")
def model(scene_files):
    return SweepModel(read_moving_bodies(str(scene_files[0]), str(scene_files[1])))


# ---------------------------------------------------------------------------- the oracle
def body_matrix(c0, c1, r, q0, q1, t: Fraction) -> list[list[Fraction]]:
    """Body's exact matrix at rational t, written out here: centre c0 + t (c1 - c0), rotation of
    q(t) = (1 - t) q0 + t q1 (R = R~(q) / |q|^2, R~ the quaternion rotation numerator)."""
    F = Fraction
    c = [F(a) + t * (F(b) - F(a)) for a, b in zip(c0, c1, strict=True)]
    q = [(1 - t) * F(a) + t * F(b) for a, b in zip(q0, q1, strict=True)]
    d = len(c)
    if d == 3:
        w, x, y, z = q
        Rn = [[w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)],
              [2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)],
              [2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z]]
    else:
        w, s = q
        Rn = [[w * w - s * s, -2 * w * s], [2 * w * s, w * w - s * s]]
    n = sum(v * v for v in q)
    R = [[v / n for v in row] for row in Rn]
    Q = [[sum(R[i][k] * R[j][k] / (F(r[k]) ** 2) for k in range(d)) for j in range(d)] for i in range(d)]
    Qc = [sum(Q[i][j] * c[j] for j in range(d)) for i in range(d)]
    cQc = sum(c[i] * Qc[i] for i in range(d))
    return [[*Q[i], -Qc[i]] for i in range(d)] + [[*(-v for v in Qc), cQc - 1]]


def oracle_worst(params, t: float) -> list[int]:
    """Each body's worst relation at t over ALL pairs of bodies (tests/oracle.py)."""
    tq = Fraction(t)
    mats = [body_matrix(*p, tq) for p in params]
    code = {"separate": 0, "tangent": 1, "overlap": 2}
    worst = [0] * len(mats)
    for a in range(len(mats)):
        for b in range(a + 1, len(mats)):
            rel = code[oracle_relation(mats[a], mats[b])]
            worst[a], worst[b] = max(worst[a], rel), max(worst[b], rel)
    return worst


def params_of(model: SweepModel):
    """(c0, c1, r, q0, q1) of each body as the files give them (2D: half-angle numbers)."""
    b = model.result.bodies
    return [(b.centers0[k].tolist(), b.centers1[k].tolist(), b.semi_axes[k].tolist(), b.q0[k].tolist(), b.q1[k].tolist())
            for k in range(len(b))]


def certified(model: SweepModel, t, **kw):
    m = model.moment(t, **kw)
    assert model.decide(m)
    return m


# ---------------------------------------------------------------------------- model: colours at t
def test_colours_at_t_are_every_pairs_exact_relation(model):
    params = params_of(model)
    for t in (0.0, 0.2, 0.25, 0.3, 1 / 3, 0.4, 0.5, 0.5000001, 0.75, 1.0):
        m = certified(model, t)
        assert model.worst_at(m).tolist() == oracle_worst(params, t), t
        for k in np.flatnonzero(m.relation >= 0):  # every pair relation the moment holds is exact too
            i, j = int(model.result.i[k]), int(model.result.j[k])
            assert m.relation[k] == {"separate": 0, "tangent": 1, "overlap": 2}[
                oracle_relation(body_matrix(*params[i], Fraction(t)), body_matrix(*params[j], Fraction(t)))]


def test_colours_by_hand(model):
    """The scene's facts, by hand: tangent at 1/4 and at the graze 1/2, never before t*."""
    w = lambda t: model.worst_at(certified(model, t)).tolist()  # noqa: E731
    assert w(0.0) == [0, 0, 0, 0, 0, 0, 2, 2, 0, 0, 0]
    assert w(0.25) == [1, 1, 0, 0, 0, 0, 2, 2, 0, 0, 0]
    assert w(0.5) == [2, 2, 2, 2, 1, 1, 0, 0, 0, 2, 2]
    assert w(np.nextafter(0.5, 1.0)) == [2, 2, 2, 2, 0, 0, 0, 0, 0, 2, 2]
    m = model.moment(0.1)  # before every first contact but 6-7's (overlapping from 0 to 1/3)
    assert m.pending == [model.pair_between(6, 7)] and m.by_sweep == len(model.result) - 1


def test_random_rotating_sets_against_the_oracle(tmp_path):
    """Random moving, turning bodies (3D and 2D): colours at t against every pair's exact relation."""
    for dim, n, seed in ((3, 24, 3), (2, 30, 4)):
        mv = moving_bodies(n, fraction=0.25, dim=dim, rotate=True, seed=seed)
        folder = tmp_path / f"d{dim}"
        folder.mkdir()
        write_bodies_csv(folder / "s.csv", mv.centers0, mv.semi_axes, mv.orientations0)
        write_bodies_csv(folder / "e.csv", mv.centers1, mv.semi_axes, mv.orientations1)
        m = SweepModel(read_moving_bodies(str(folder / "s.csv"), str(folder / "e.csv")))
        assert len(m.result) > 5
        params = params_of(m)
        for t in (0.0, 0.37, 0.81, 1.0):
            mo = certified(m, t)
            assert m.worst_at(mo).tolist() == oracle_worst(params, t), (dim, t)
        assert m.moment(0.0).by_sweep == len(m.result)  # the ends are the sweep's alone
        assert m.moment(1.0).by_sweep == len(m.result)


def test_colours_use_the_sweeps_own_exact_matrices():
    """The matrices classified at t are the sweep's motions at t (also moved to a periodic image)."""
    from core.moving.linear import read_linear_motions
    from core.moving.motions import matrix_at_exact

    for dim, seed in ((3, 5), (2, 6)):
        mv = moving_bodies(6, dim=dim, rotate=True, seed=seed)
        b, _ = read_linear_motions(*mv.arguments())
        for k in range(6):
            for t in ("0", "3/7", 0.61803, "1"):
                assert b.matrix_at(k, t) == matrix_at_exact(b.motion(k), t)
            shift = [10.0] * dim
            assert b.matrix_at(k, "2/9", shift) == matrix_at_exact(b.motion(k, shift), "2/9")


def test_a_tilted_box_moves_the_image_by_its_lattice_vector(tmp_path):
    """Box (8, 8, 8, xy = 0.5): a2 = (4, 8, 0). Body 1 crosses the face y = 8 (END stored wrapped by
    a2); its image -a2 comes from y = -0.25 to 0.5 towards body 0 at (1, 1, 4): tangent at t* = 1/3
    exactly, overlapping after. The scene's pair, motion, colours and picture use v(k) = -a2."""
    r = [[0.5, 0.5, 0.5]] * 2
    q = np.tile([1.0, 0.0, 0.0, 0.0], (2, 1))
    write_bodies_csv(tmp_path / "s.csv", np.array([[1.0, 1.0, 4.0], [5.0, 7.75, 4.0]]), np.array(r), q)
    write_bodies_csv(tmp_path / "e.csv", np.array([[1.0, 1.0, 4.0], [1.0, 0.5, 4.0]]), np.array(r), q)
    m = SweepModel(read_moving_bodies(str(tmp_path / "s.csv"), str(tmp_path / "e.csv"), box=(8.0, 8.0, 8.0, 0.5, 0.0, 0.0)))
    assert len(m.result) == 1 and m.result.image[0].tolist() == [0, -1, 0]
    assert same_time(m.time(0), RealAlgebraic.rational(fmpq(1, 3)))
    mm = m.pair_motion(0)
    r2 = analyse(mm.A, mm.B, interval=(0, 1))
    assert same_time(r2.events[0].time, m.time(0)) and r2.events[0].relation == Relation.TANGENT
    cfg, _ = m.pair_config(0)
    assert np.allclose(cfg.B.center, [1.0, -0.25, 4.0])  # body 1 at t = 0 moved by -a2 = (-4, -8, 0)
    assert [m.worst_at(certified(m, t)).tolist() for t in (0.25, 1 / 3, 0.5)] == [[0, 0], [0, 0], [2, 2]]  # float(1/3) < 1/3
    assert m.worst_at(certified(m, m.time(0), event=0)).tolist() == [1, 1]  # at t* itself
    assert "tilted (xy, xz, yz) = (0.5, 0, 0)" in m.summary()
    assert m.pair_label(0).startswith("0 – 1 [-a2]  t* = 1/3")  # the image by box vectors: j moved by -a2


def test_event_time_colours_at_the_exact_irrational_t(model):
    """At t* = (3 - sqrt 3)/4 of pair 2-3: 2, 3 tangent; 0, 1 overlap (3 - 4t = sqrt 3 < 2); 6, 7
    overlap (1 + 3t = (13 - 3 sqrt 3)/4 < 2); the rest separate."""
    k = model.pair_between(2, 3)
    m = certified(model, model.time(k), event=k)
    assert isinstance(m.t, RealAlgebraic) and m.t.value is None
    assert model.worst_at(m).tolist() == [2, 2, 1, 1, 0, 0, 2, 2, 0, 0, 0]
    k9 = model.pair_between(9, 10)  # an event of degree > 2: decided by the analysis at t*
    m = certified(model, model.time(k9), event=k9)
    assert model.worst_at(m).tolist() == [2, 2, 2, 2, 0, 0, 0, 0, 0, 1, 1]


def test_event_at_a_rational_time_that_is_no_float(tmp_path):
    """t* = 1/3 (3 - 3t = 2) is rational but no float: the colours are certified at 1/3 itself."""
    rows = [((0, 0, 0), (0, 0, 0), (1, 1, 1), I, I), ((3, 0, 0), (0, 0, 0), (1, 1, 1), I, I),  # t* = 1/3
            ((10, 0, 0), (10, 0, 0), (1, 1, 1), I, I), ((13, 0, 0), (9, 0, 0), (1, 1, 1), I, I)]  # t* = 1/4
    m = SweepModel(read_moving_bodies(*(str(p) for p in write_scene(tmp_path, rows))))
    k = m.pair_between(0, 1)
    assert m.time_text(k) == "= 1/3" and m.time(k).value == fmpq(1, 3)
    mo = certified(m, m.time(k), event=k)
    assert m.worst_at(mo).tolist() == [1, 1, 2, 2]
    other = m.pair_between(2, 3)
    assert mo.relation[other] == Relation.OVERLAP and m.exact_relation(k, mo) == Relation.TANGENT


def test_pending_bodies_are_never_guessed(model):
    """Before exact arithmetic runs, the bodies of undecided pairs are "deciding" (pale grey)."""
    m = model.moment(0.4100001)
    assert m.pending and not m.done.is_set()
    worst = model.worst_at(m)
    for k in m.pending:
        for b in (model.result.i[k], model.result.j[k]):
            assert worst[b] in (Relation.UNDECIDED, Relation.OVERLAP)
    model.current = m
    assert tuple(model.colours()[int(model.result.i[m.pending[0]])]) == PENDING_COLOUR
    model.current = model.moment(0.0)


# ---------------------------------------------------------------------------- model: events
def test_event_list_in_exact_time_order_with_exact_times(model):
    labels = [model.pair_label(int(k)) for k in model.order]
    assert [lab.split("  ")[0] for lab in labels] == ["6 – 7", "0 – 1", "2 – 3", "9 – 10", "4 – 5"]
    assert model.exact_labels(model.order)
    times = [model.time_text(int(k)) for k in model.order]
    assert times[:3] == ["= 0", "= 1/4", f"= {SQRT3_TIME}"] and times[4] == "= 1/2"
    assert times[3].startswith("≈ 0.495334497") and times[3].endswith("…")  # degree > 2: a marked rounding
    assert [model.pair_label(int(k)).split("  ")[1] for k in model.order][2] == f"t* = {SQRT3_TIME}"
    k = model.pair_between(2, 3)
    alpha = model.time(k)  # (3 - sqrt 3)/4, sqrt 3 / 4 = 0.43301270189...
    assert alpha.compare(fmpq(3, 4) - fmpq(433012702, 10**9)) > 0 and alpha.compare(fmpq(3, 4) - fmpq(433012701, 10**9)) < 0
    assert alpha.poly(fmpq(3, 4) - fmpq(1, 4) * 0) != 0 and alpha.value is None  # irrational
    for a, b in zip(model.order[:-1], model.order[1:], strict=True):
        assert compare_times(model.time(int(a)), model.time(int(b))) <= 0


def test_event_order_is_exact_inside_overlapping_brackets(tmp_path):
    """Two events 2^-40 apart (their float brackets overlap) are listed in their exact order."""
    eps = 2.0**-40
    rows = [((0, 0, 0), (0, 0, 0), (1, 1, 1), I, I), ((3, 0, 0), (-1, 0, 0), (1, 1, 1), I, I),  # t* = 1/4
            ((10, 0, 0), (10, 0, 0), (1, 1, 1), I, I), ((13 - 4 * eps, 0, 0), (9 - 4 * eps, 0, 0), (1, 1, 1), I, I)]  # 1/4 - eps
    m = SweepModel(read_moving_bodies(*(str(p) for p in write_scene(tmp_path, rows))))
    assert [(int(m.result.i[k]), int(m.result.j[k])) for k in m.order] == [(2, 3), (0, 1)]
    assert compare_times(m.time(int(m.order[0])), m.time(int(m.order[1]))) < 0


def test_opened_pair_analysis_finds_the_sweeps_first_time(model):
    """The two-body view's motion is the sweep's own: its analysis' first non-separate time is t*."""
    for k in model.order.tolist():
        mm = model.pair_motion(k)
        i, j = int(model.result.i[k]), int(model.result.j[k])
        assert mm.A is model.motion(i) and mm.B is model.motion(j)  # the very motions the sweep certified
        assert mm.A.matrix() == model.result.bodies.motion(i).matrix()
        r = analyse(mm.A, mm.B, interval=(0, 1))
        first = RealAlgebraic.rational(0) if r.relation_at(0) != Relation.SEPARATE else r.events[0].time
        assert same_time(first, model.time(k)), model.pair_label(k)
        target = model.open_target(k, AnalysisView.of(r))
        if model.result.t_hi[k] == 0.0 and r.relation_at(0) == Relation.OVERLAP:
            assert target == {"t": 0.0}
        else:
            assert same_time(r.events[target["event"] - 1].time, model.time(k))


def test_the_two_body_motion_reads_back_from_its_text(model):
    """A pair opened from the bodies keeps a shareable text: it reads back to the same exact A(t)."""
    from app.scene.pair.motion import load_motion

    mm = model.pair_motion(model.pair_between(9, 10))
    back = load_motion(preset=None, motion=mm.texts())
    assert back.A.matrix() == mm.A.matrix() and back.B.matrix() == mm.B.matrix()


# ---------------------------------------------------------------------------- the view, no browser
@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def test_view_timeline_events_and_the_two_body_view(server, scene_files):
    view = BodiesView(server, SweepModel(read_moving_bodies(str(scene_files[0]), str(scene_files[1]))))
    m = view.model  # the view's own (its time)
    try:
        tl = view.timeline
        assert tl is not None and view.layers is not None and tl.wait_certified(60)
        assert view.list_md.content == "Showing all 5 events"
        assert "t = 0: 2 bodies overlap, 0 touch" in tl.status.content
        tl.set_time(0.5)
        assert tl.wait_certified(60) and not view.settling()
        assert m.worst.tolist() == [2, 2, 2, 2, 1, 1, 0, 0, 0, 2, 2]
        np.testing.assert_array_equal(view.layers.colours, m.colours())  # what is sent is what is certified
        assert tl.slider.value == 0.5 and "t = 0.5: 6 bodies overlap, 2 touch" in tl.status.content
        k = m.pair_between(2, 3)
        assert view.select(2) is None and view.select(3) == k  # click 2, then 3: the pair opens at t*
        s = view.session
        assert s is not None and s.ready.wait(60) and view.pair == k
        an = s.state.analysis
        assert an is not None and s.state.event == 1 and s.state.relation == "tangent"
        assert same_time(an.events[0].event.time, m.time(k)) and an.events[0].exact == SQRT3_TIME
        assert isinstance(m.current.t, RealAlgebraic) and m.current.event == k
        view.show_bodies()
        assert view.pair is None and tl.wait_certified(60)
        assert m.worst.tolist() == [2, 2, 1, 1, 0, 0, 2, 2, 0, 0, 0]
        assert f"t\\* of 2 – 3 = {SQRT3_TIME}" in tl.status.content  # markdown: t* shown
        k0 = m.pair_between(6, 7)  # overlapping at t = 0: the two-body view at t = 0
        view.open_pair(k0)
        assert view.session.ready.wait(60) and view.session.state.relation == "overlap" and view.session.state.t == 0.0
        view.show_bodies()
    finally:
        view.close()


def test_two_tabs_have_their_own_time(server, model):
    """One model serves every tab of a server: each view scrubs its own t (the sweep is shared)."""
    other = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)  # a second tab's own GUI and scene
    a, b = BodiesView(server, model), BodiesView(other, model)
    try:
        a.timeline.set_time(0.5)
        assert a.timeline.wait_certified(60) and b.timeline.wait_certified(60)
        assert a.model.current.tf == 0.5 and b.model.current.tf == 0.0 and model.current.tf == 0.0
        assert a.model.result is b.model.result is model.result
        assert a.model.worst.tolist() != b.model.worst.tolist()
    finally:
        a.close()
        b.close()
        other.stop()


def test_a_closed_view_sends_nothing(server, model, monkeypatch):
    """The tab went away: a moment the worker finishes or a camera timer that fires afterwards
    draws nothing (viser would queue the messages on a closed connection and warn)."""
    view = BodiesView(server, model)
    tl = view.timeline
    assert tl is not None and view.layers is not None and tl.wait_certified(60)
    pose = ViewPose.looking_at([10.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], fov=1.0, aspect=1.5, height_px=720)
    view.close()
    sent: list[str] = []
    monkeypatch.setattr(type(view.layers), "set_bodies", lambda *a, **k: sent.append("set_bodies"))
    monkeypatch.setattr(type(view.layers), "set_pose", lambda *a, **k: sent.append("set_pose"))
    tl._draw(model.current)
    view.set_pose(pose)
    assert sent == []


def test_cli_to_needs_bodies_and_matching_files(scene_files, tmp_path, capsys):
    from app.cli import main

    assert main(["screenshot", "--to", str(scene_files[1]), "--out", str(tmp_path / "x.png")]) == 2
    assert "--to END needs --bodies START" in capsys.readouterr().err
    other = tmp_path / "other.csv"
    write_bodies_csv(other, np.zeros((2, 3)), np.ones((2, 3)), np.tile(I, (2, 1)))
    assert main(["screenshot", "--bodies", str(scene_files[0]), "--to", str(other), "--out", str(tmp_path / "x.png")]) == 2
    assert "END must hold the same bodies" in capsys.readouterr().err
    assert main(["screenshot", "--bodies", str(scene_files[0]), "--to", str(scene_files[1]), "--t", "1.5",
                 "--out", str(tmp_path / "x.png")]) == 2
    assert "over the step t in [0, 1]" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


# ---------------------------------------------------------------------------- browser
needs_chromium = pytest.mark.skipif(not os.path.exists("/usr/bin/chromium"), reason="needs Debian chromium at /usr/bin/chromium")


@pytest.mark.browser
@needs_chromium
def test_screenshot_command_with_moving_bodies(scene_files, tmp_path):
    """The command draws in a tab of the test process's Chromium (``--browser``); it runs before the
    module's tab is opened (Playwright's sync API cannot nest)."""
    from app.cli import main

    out = tmp_path / "shots"
    argv = ["screenshot", "--bodies", str(scene_files[0]), "--to", str(scene_files[1]), "--t", "0.5", "--event", "3",
            "--out", str(out), "--width", "900", "--height", "600", "--browser", browser_helpers.CHROMIUM_OF_THIS_PROCESS.get()]
    assert main(argv) == 0
    for name in ("t-0.5.png", "event-3.png"):
        data = (out / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


POINT_COLOURS_JS = """() => {
  const m = window.__viserMutable?.nodeRefFromName;
  if (!m) return null;
  const out = new Set();
  for (const [name, r] of Object.entries(m)) {
    if (!name.startsWith('/bodies/points/') || !r || !r.visible) continue;
    r.traverse((o) => {
      const c = o.isPoints ? o.geometry.attributes.color : null;
      if (!c) return;
      const k = c.normalized || !(c.array instanceof Uint8Array) ? 255 : 1;
      for (let i = 0; i < c.count; i++) out.add([c.getX(i), c.getY(i), c.getZ(i)].map((v) => Math.round(v * k)).join(','));
    });
  }
  return Array.from(out).sort();
}"""
"""The distinct colours of the bodies' points as three.js has them ("r,g,b")."""


@pytest.fixture(scope="module")
def sweep_page(scene_files):
    """One browser and one server for the browser tests of this module, on the moving scene."""
    yield from browser_helpers.bodies_page(SweepModel(read_moving_bodies(str(scene_files[0]), str(scene_files[1]))))


def set_slider(page, label: str, value: str) -> None:
    """Type ``value`` into the number box of the slider labelled ``label`` and press Enter."""
    box = field_input(page, label, 'input[inputmode="decimal"]')
    box.fill(value)
    box.press("Enter")


def rgb(colour) -> str:
    return ",".join(str(int(v)) for v in colour)


@pytest.mark.browser
@needs_chromium
def test_browser_scrub_the_timeline(sweep_page):
    """Moving t in the page moves the bodies and recolours them with their certified relation."""
    from app.scene.common.shapes import RELATION_COLORS

    hs, _ = sweep_page
    view = hs.goto("/")
    m = view.model  # the tab's own time on the shared sweep
    page = hs.page
    text_shown(page, "Showing all 5 events")
    amber, red = rgb(RELATION_COLORS["tangent"]), rgb(RELATION_COLORS["overlap"])
    assert amber not in page.evaluate(POINT_COLOURS_JS)  # t = 0: nothing touches
    set_slider(page, "t", "0.5")
    until(lambda: m.current.tf == 0.5, what="t = 0.5 on the server")
    hs.wait_settled()
    text_shown(page, "t = 0.5: 6 bodies overlap, 2 touch")
    colours = page.evaluate(POINT_COLOURS_JS)
    assert amber in colours and red in colours  # the graze 4-5 is tangent at exactly 1/2
    pos = page.evaluate("(n) => { const r = window.__viserMutable.nodeRefFromName[n]; return r ? [r.position.x] : null; }", "/bodies")
    assert pos is not None
    set_slider(page, "t", "0.6")
    until(lambda: m.current.tf == 0.6, what="t = 0.6 on the server")
    hs.wait_settled()
    text_shown(page, "t = 0.6: 6 bodies overlap, 0 touch")
    assert amber not in page.evaluate(POINT_COLOURS_JS)
    assert view.layers.colours.tolist() == m.colours().tolist()
    ARTIFACTS.mkdir(exist_ok=True)
    hs.save(ARTIFACTS / "sweep-scene.png")


@pytest.mark.browser
@needs_chromium
def test_browser_click_an_event_the_two_body_view_shows_it(sweep_page):
    """Clicking an event opens its pair in the two-body view at the analysis' event equal to t*."""
    hs, _ = sweep_page
    view = hs.goto("/")
    m = view.model  # the tab's own time on the shared sweep
    page = hs.page
    k = m.pair_between(2, 3)
    until(lambda: not view.timeline.busy(), what="exact event labels")
    label = m.pair_label(k)
    assert f"t* = {SQRT3_TIME}" in label
    page.get_by_text("Event", exact=True).click()
    page.get_by_role("option", name=" ".join(label.split()), exact=True).click()
    until(lambda: view.pair == k and view.ready.is_set(), what="the event opened")
    hs.wait_settled()
    s = view.session
    assert s.state.event == 1 and s.state.relation == "tangent"
    assert same_time(s.state.analysis.events[0].event.time, m.time(k))
    text_shown(page, "TANGENT")
    text_shown(page, SQRT3_TIME)  # the two-body view's event, exactly
    assert hs.mesh_color("A") == hs.mesh_color("B") == "#ffbf00"
    ARTIFACTS.mkdir(exist_ok=True)
    hs.save(ARTIFACTS / "sweep-event.png")
    page.get_by_role("button", name="← All bodies").click()
    until(lambda: view.pair is None and view.ready.is_set(), what="back to all bodies")
    hs.wait_settled()
    text_shown(page, f"t = t* of 2 – 3 = {SQRT3_TIME}")
    assert m.worst.tolist() == [2, 2, 1, 1, 0, 0, 2, 2, 0, 0, 0]
