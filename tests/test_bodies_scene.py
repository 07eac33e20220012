"""Many bodies in the scene: the model (colours, the pair list, picking, pair configurations), the
level of detail, the view on a ViserServer without a browser, and (marked ``browser``, one
browser for the module) the page driven as a user would: page the list, search a body, filter
by relation, toggle the contact network, open a pair.

Golden facts are exact: touching unit-diameter spheres (discs) on a lattice are tangent
neighbours; a disc one unit from another of radius 1/2 touches it, 0.8 units overlaps; the
two-body view opened on a pair rebuilds the very matrices the search classified, so its
certified relation is the pair's. Camera rotations are checked against viser's own quaternion
code, not ours.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

viser = pytest.importorskip("viser")

import browser_helpers  # noqa: E402
from browser_helpers import set_field, text_shown, until  # noqa: E402
from test_browser_scene import choose  # noqa: E402

from app.bodyfiles import BodySet, read_bodies, write_bodies_csv  # noqa: E402
from app.scene.bodies.bodies_layers import FINE_NODE, NETWORK_NODE, BodyLayers, points_node  # noqa: E402
from app.scene.bodies.bodies_lod import ViewPose, choose_detail  # noqa: E402
from app.scene.bodies.bodies_view import NO_PAIRS, BodiesView, load_model  # noqa: E402
from app.scene.bodies.model import PAGE_SIZE, BodiesModel  # noqa: E402
from app.scene.common.shapes import NEUTRAL, RELATION_COLORS  # noqa: E402
from bench.bodies_data import demo_bodies, random_bodies  # noqa: E402
from core import Relation, bodies_from_axes, classify, contacts  # noqa: E402

ARTIFACTS = Path(__file__).resolve().parent / "artifacts"


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


@pytest.fixture(scope="module")
def demo_file(tmp_path_factory):
    b = demo_bodies()
    path = tmp_path_factory.mktemp("bodies") / "demo.csv"
    write_bodies_csv(path, b.centers, b.semi_axes, b.orientations)
    return path


def lattice_model(tmp_path, n=4, box=None):
    c = np.array([[x, y] for x in range(n) for y in range(n)], dtype=float)
    path = tmp_path / "lattice.csv"
    write_bodies_csv(path, c, np.full_like(c, 0.5), np.zeros(len(c)))
    return BodiesModel(read_bodies(path), box, name="lattice.csv")


def test_model_colours_every_body_by_its_worst_relation(tmp_path):
    """Discs of radius 1/2: 0 touches 1 (centres 1 apart), 1 overlaps 2 (0.8 apart), 3 is alone."""
    c = np.array([[0.0, 0.0], [1.0, 0.0], [1.8, 0.0], [10.0, 0.0]])
    path = tmp_path / "chain.csv"
    write_bodies_csv(path, c, np.full_like(c, 0.5), np.zeros(4))
    m = BodiesModel(read_bodies(path), None)
    assert m.worst.tolist() == [Relation.TANGENT, Relation.OVERLAP, Relation.OVERLAP, Relation.SEPARATE]
    want = [RELATION_COLORS["tangent"], RELATION_COLORS["overlap"], RELATION_COLORS["overlap"], RELATION_COLORS["separate"]]
    assert [tuple(int(v) for v in row) for row in m.colours()] == want
    Q = np.stack([m.bodies.Q[0], np.full((3, 3), np.nan)])  # a body that is no ellipse: grey
    bad = BodiesModel(BodySet.of_matrices(Q), None)
    assert bad.worst.tolist() == [Relation.SEPARATE, Relation.INVALID]
    assert tuple(int(v) for v in bad.colours()[1]) == NEUTRAL


def test_model_pages_filters_and_pair_lookup(tmp_path):
    m = lattice_model(tmp_path)
    assert len(m.result) == 24 and set(m.worst.tolist()) == {Relation.TANGENT}
    first = m.page()
    assert first.entries[0].label == "0 – 1  tangent (exact)" and first.total == 24 and first.caption() == "showing all 24 pairs"
    p = m.page(size=10, page=2)
    assert (p.start, len(p.entries), p.pages) == (20, 4, 3) and p.caption() == "showing 21–24 of 24 pairs"
    assert m.page(size=10, page=99).page == 2 and m.page(size=10, page=-5).page == 0  # clamped
    pages = [e.index for k in range(3) for e in m.page(size=10, page=k).entries]
    assert sorted(pages) == list(range(24))  # every pair on exactly one page
    assert m.page("overlap").caption() == "no pairs" and m.page("tangent").total == 24
    of5 = m.page(body=5)  # site (1, 1): neighbours (0, 1), (1, 0), (1, 2), (2, 1)
    assert sorted(m.partners(5)) == [1, 4, 6, 9] and of5.total == 4
    assert all(5 in (m.result.i[e.index], m.result.j[e.index]) for e in of5.entries)
    with pytest.raises(ValueError, match="no body 16"):
        m.page(body=16)
    with pytest.raises(ValueError, match="unknown relation"):
        m.page("touching")
    assert m.pair_between(5, 1) == m.pair_between(1, 5) is not None and m.pair_between(0, 5) is None
    assert "**16 ellipses**" in m.summary() and "24 contacts" in m.summary()
    seg = m.contact_segments()
    assert seg.shape == (24, 2, 3) and np.allclose(np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1), 1.0)


def test_model_periodic_pair_config_and_labels(tmp_path):
    m = lattice_model(tmp_path, box=(4.0, 4.0))
    assert len(m.result) == 32  # every site has 4 neighbours on the torus
    k = next(e.index for e in m.page().entries if "[" in e.label)
    cfg, note = m.pair_config(k)
    a, b = cfg.shapes()
    assert "periodic image" in note and "exact translate" in note
    assert abs(float(b.center[0]) - float(a.center[0])) + abs(float(b.center[1]) - float(a.center[1])) == 1.0
    seg = m.contact_segments()  # the network joins j's image: every segment is one lattice step
    assert np.allclose(np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1), 1.0)


def test_two_body_config_rebuilds_the_same_matrices():
    b = random_bodies(300, dim=3, seed=6)
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    m = BodiesModel(BodySet(b.centers, b.semi_axes, b.orientations), None, name="random")
    for k in range(0, len(m.result), max(1, len(m.result) // 20)):
        cfg, _ = m.pair_config(k)
        A, B = (s.quadric() for s in cfg.shapes())
        i, j = int(m.result.i[k]), int(m.result.j[k])
        assert A.tobytes() == Q[i].tobytes() and B.tobytes() == Q[j].tobytes()
        assert classify(A, B) == m.result.relation[k]


def test_picking_hits_the_first_body_on_the_ray(tmp_path):
    m = lattice_model(tmp_path)
    assert m.pick((1.0, 2.0, 10.0), (0.0, 0.0, -1.0)) == 6  # 2D: the disc under the ray
    assert m.pick((1.5, 2.5, 10.0), (0.0, 0.0, -1.0)) is None  # between four discs
    b = demo_bodies()
    m3 = BodiesModel(read_bodies_from(b, tmp_path), None)
    k = m3.pick((3.0, 4.0, 50.0), (0.0, 0.0, -1.0))
    assert k is not None and np.linalg.norm(m3.positions[k, :2] - [3.0, 4.0]) <= m3.scales[k].max()


def read_bodies_from(b, tmp_path):
    path = tmp_path / "b.csv"
    write_bodies_csv(path, b.centers, b.semi_axes, b.orientations)
    return read_bodies(path)


# ---------------------------------------------------------------------------- level of detail
def test_camera_pose_from_a_tab_matches_look_at():
    """A tab reports its camera as a quaternion (OpenCV axes): read back, it is the look-at pose."""
    pose = ViewPose.looking_at((3.0, -4.0, 5.0), (0.5, 1.0, -0.25), (0.0, 0.0, 1.0), fov=0.9, aspect=1.5, height_px=800)
    R = pose.rotation
    assert np.allclose(R.T @ R, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
    forward = np.array([0.5, 1.0, -0.25]) - [3.0, -4.0, 5.0]
    assert np.allclose(R[:, 2], forward / np.linalg.norm(forward))  # looks at the target
    assert R[:, 1] @ [0.0, 0.0, 1.0] < 0  # image down is world down

    class Tab:
        wxyz = viser.transforms.SO3.from_matrix(R).wxyz  # viser's own conversion
        position = (3.0, -4.0, 5.0)
        fov, aspect, image_height = 0.9, 1.5, 800

    got = ViewPose.of_camera(Tab())
    assert got is not None and np.allclose(got.rotation, R, atol=1e-12)

    class Silent:  # a tab that has not reported its camera yet
        @property
        def wxyz(self):
            raise AssertionError("no camera message yet")

    assert ViewPose.of_camera(Silent()) is None


def test_detail_goes_to_the_largest_on_screen_within_the_budget():
    pose = ViewPose.looking_at((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0), fov=math.pi / 2, aspect=1.0, height_px=200)
    # focal length 100 px: a unit sphere at depth d is 100 / d pixels in radius
    depth = np.array([2.0, 5.0, 10.0, 20.0, 50.0, 200.0, 4.0])
    pos = np.stack([np.zeros(7), np.zeros(7), -depth], axis=1)
    pos[6] = [0.0, 0.0, 4.0]  # behind the camera
    reach = np.ones(7)
    fine, coarse = choose_detail(pose, pos, reach, budget=10_000, costs=(320, 80), fine_px=24, coarse_px=3)
    # radii 50, 20, 10, 5, 2, 0.5 px: fine from 24 px, coarse from 3 px, points below
    assert fine.tolist() == [0] and coarse.tolist() == [1, 2, 3]
    fine, coarse = choose_detail(pose, pos, reach, budget=320 + 80, costs=(320, 80), fine_px=24, coarse_px=3)
    assert fine.tolist() == [0] and coarse.tolist() == [1]  # the budget goes to the largest first
    hidden = np.array([False, True, True, True, True, True, True])
    fine, coarse = choose_detail(pose, pos, reach, budget=10_000, costs=(320, 80), eligible=hidden)
    assert fine.tolist() == [] and coarse.tolist() == [1, 2, 3]
    off = pos + [1000.0, 0.0, 0.0]  # far to the right: outside the view
    assert all(len(a) == 0 for a in choose_detail(pose, off, reach, budget=10_000, costs=(320, 80)))
    inside = np.array([[0.0, 0.0, -0.5]])  # the camera inside a body: always a solid
    assert choose_detail(pose, inside, np.ones(1), budget=10_000, costs=(320, 80))[0].tolist() == [0]


def test_layers_points_for_all_solids_for_the_near(server):
    """Every body is a point (by group and size class); solids follow the pose; timeline-ready."""
    scene = server.scene
    scene.reset()
    N = 50
    pos = np.stack([np.arange(N, dtype=float) * 3, np.zeros(N), np.zeros(N)], axis=1)
    scales = np.ones((N, 3))
    scales[25:] *= 4.0  # a second size class
    worst = np.where(np.arange(N) % 2 == 0, Relation.SEPARATE, Relation.OVERLAP).astype(np.int8)
    colours = np.tile(np.array(RELATION_COLORS["overlap"], np.uint8), (N, 1))
    layers = BodyLayers(scene, 3, pos, np.tile([1.0, 0, 0, 0], (N, 1)), scales, colours, worst, separate="shown", budget=4000)
    want = layers.expected_in_browser()
    assert sum(want.values()) == N and {points_node("separate", 0), points_node("contact", 2)} <= set(want)
    assert layers.pose is None and FINE_NODE not in want  # no camera yet: points only
    pose = ViewPose.looking_at((0.0, -10.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), fov=1.0, aspect=1.5, height_px=800)
    layers.set_pose(pose)
    d = layers.drawn()
    assert d["triangles"] <= 4000 and d["fine"] >= 1 and 0 in layers.fine  # the nearest body is fine
    layers.set_separate("hidden")
    assert not any(worst[layers.fine] == Relation.SEPARATE) and not any(worst[layers.coarse] == Relation.SEPARATE)
    assert all(not k.startswith("/bodies/points/separate") for k in layers.expected_in_browser())
    layers.set_separate("faded")
    pale = layers.shown_colours()
    assert (pale[worst == Relation.SEPARATE] > colours[worst == Relation.SEPARATE]).any()
    assert (pale[worst != Relation.SEPARATE] == colours[worst != Relation.SEPARATE]).all()
    moved = pos + [0.0, 1000.0, 0.0]  # a timeline step: new poses, the solids chosen again
    layers.set_bodies(moved, layers.wxyz, scales, colours, worst)
    assert layers.drawn()["fine"] + layers.drawn()["coarse"] == 0  # all far away now
    layers.set_network(True, np.stack([pos[:2], pos[1:3]], axis=1), np.zeros((2, 3), np.uint8))
    assert layers.network is not None and len(layers.network.points) == 2


def test_a_tab_closed_while_a_pair_opens_leaves_no_session_running(server, demo_file):
    """close() waits for a pair being opened and closes its new session; after it nothing opens.

    Was: close() read ``self.session`` while another thread was building the first one, so that
    session (its timers, its analyses) outlived the tab and drew on a closed connection.
    """
    import threading

    m = load_model(str(demo_file))
    view = BodiesView(server, m)
    closer = threading.Thread(target=view.close)
    with view._lock:  # a pair is being opened on a handler's thread (the lock it holds meanwhile)
        closer.start()
        closer.join(0.3)
        assert closer.is_alive(), "close() returned while a pair was being opened"
        session = view.open_pair(0)
        assert session is not None and not session.closed
    closer.join(30)
    assert not closer.is_alive() and session.closed
    assert view.open_pair(1) is None and view.session is session  # closed: nothing new is built


def test_view_pages_filters_selects_opens_and_back(server, demo_file):
    m = load_model(str(demo_file))
    view = BodiesView(server, m)
    assert view.ready.is_set() and view.layers is not None
    assert sum(view.layers.expected_in_browser().values()) == 244  # every body a point
    total = len(m.result)
    assert total > PAGE_SIZE and view.listing is not None and view.listing.total == total
    assert view.list_md.content == f"Showing 1–{PAGE_SIZE} of {total:,} pairs (page 1 of 2)"
    assert len(view.pairs.options) == PAGE_SIZE and not view.next_button.disabled and view.prev_button.disabled
    view.turn_page(+1)
    assert view.list_md.content.startswith(f"Showing {PAGE_SIZE + 1}–{total} of {total:,}") and view.next_button.disabled
    n_overlap = int(np.count_nonzero(m.result.relation == Relation.OVERLAP))
    view.filter_pairs(relation="overlap")
    assert view.listing.total == n_overlap and all("overlap" in o for o in view.pairs.options)
    view.filter_pairs(relation="all", body=10_000)
    assert "no body 10000" in view.list_md.content and view.pairs.options == (NO_PAIRS,)
    k = next(e.index for e in m.page("tangent").entries)
    i, j = int(m.result.i[k]), int(m.result.j[k])
    assert view.select(i) is None and f"Body **{i}**" in view.body_md.content and view.body_text.value == str(i)
    assert all(i in (m.result.i[e.index], m.result.j[e.index]) for e in view.listing.entries)
    assert view.select(j) == k and view.pair == k and not view.layers.frame.visible
    session = view.session
    assert session is not None and session.ready.wait(30)
    assert session.state.relation == "tangent"  # the same certified relation as in the search
    view.show_bodies()
    assert view.pair is None and view.layers is not None and view.layers.frame.visible
    registry = server.scene._handle_from_node_name
    assert not view.pair_folder.visible and view._session_nodes  # the two-body view: hidden, not gone
    assert all(registry[name].visible is False for name in view._session_nodes)
    k2 = next(e.index for e in m.page("overlap").entries)
    assert view.open_pair(k2) is session and session.ready.wait(30)  # the same two-body view, loaded anew
    assert session.state.relation == "overlap" and view.pair_folder.visible and not view.layers.frame.visible
    view.show_bodies()
    view.set_network(True)
    assert view.layers.network is not None and len(view.layers.network.points) == total
    view.set_network(False)
    assert view.layers.network.visible is False


def test_view_upload_and_box(server, tmp_path):
    view = BodiesView(server, None)
    assert view.layers is None
    b = random_bodies(200, dim=2, seed=3)
    path = tmp_path / "up.csv"
    write_bodies_csv(path, b.centers, b.semi_axes, b.orientations)
    assert view.load_bytes("up.csv", path.read_bytes()) is None
    assert view.model is not None and len(view.model.bodies) == 200 and view.layers is not None
    assert view.load_bytes("bad.csv", b"x,y\n1,2\n").startswith("bad.csv: the header must name the columns")
    assert "⚠" in view.file_md.content and len(view.model.bodies) == 200  # the old set stays
    view.box_text.value = f"{b.side}, {b.side}"  # from Python: no client, so no recompute
    assert view.load_bytes("up.csv", path.read_bytes()) is None and view.model.box == (b.side, b.side)


def test_a_tabs_file_is_searched_in_a_budgeted_worker_never_in_the_server(server, tmp_path, monkeypatch):
    """Was: an uploaded file's contacts were found in the process serving every tab, unbounded: 5,000
    bodies at one point (12,497,500 pairs) took seconds and gigabytes there. Now a worker process
    searches it, under a pair limit (refused before any pair is built) and a time budget."""
    import os

    from app.scene.bodies import model as bodies_mod
    from app.scene.pair.analysis import AnalysisCache

    cache = AnalysisCache(processes=True)
    try:
        view = BodiesView(server, None, cache=cache)
        crowd = tmp_path / "crowd.csv"
        write_bodies_csv(crowd, np.zeros((5000, 3)), np.ones((5000, 3)), np.tile([1.0, 0, 0, 0], (5000, 1)))
        searched_in: list[int] = []
        real = bodies_mod.contacts
        monkeypatch.setattr(bodies_mod, "contacts", lambda *a, **k: (searched_in.append(os.getpid()), real(*a, **k))[1])
        err = view.load_bytes("crowd.csv", crowd.read_bytes())
        assert err == ("crowd.csv: 5,000 bodies give 12,497,500 pairs to examine (bodies crowded together), over the scene's "
                       "limit of 5,000,000: find their contacts with `python -m app contacts` or `core.contacts`")
        assert view.model is None and "⚠" in view.file_md.content and searched_in == []  # not in this process
        # a lattice of touching spheres: 10,512 tangencies decided exactly, over a budget made short for the test
        g = np.arange(16, dtype=float) * 2.0
        c = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
        lattice = tmp_path / "lattice.csv"
        write_bodies_csv(lattice, c, np.ones_like(c), np.tile([1.0, 0, 0, 0], (len(c), 1)))
        monkeypatch.setattr("app.scene.bodies.bodies_view.UPLOAD_SECONDS", 0.3)
        assert view.load_bytes("lattice.csv", lattice.read_bytes()) == "finding the contacts of lattice.csv took over 0.3 s and was stopped"
        monkeypatch.setattr("app.scene.bodies.bodies_view.UPLOAD_SECONDS", 60.0)
        assert view.load_bytes("lattice.csv", lattice.read_bytes()) is None and searched_in == []
        assert len(view.model.result) == 3 * 16 * 16 * 15 and set(view.model.result.relation.tolist()) == {Relation.TANGENT}
    finally:
        cache.shutdown()


def test_a_typed_box_is_budgeted_for_a_tabs_file_not_for_the_servers(server, tmp_path, monkeypatch):
    """A box typed for the server's own bodies (--bodies) is searched here without limits; for
    bodies a tab uploaded, in the budgeted worker (AnalysisCache.run)."""
    from types import SimpleNamespace

    from app.scene.pair.analysis import AnalysisCache

    b = random_bodies(200, dim=2, seed=3)
    path = tmp_path / "up.csv"
    write_bodies_csv(path, b.centers, b.semi_axes, b.orientations)
    ran: list[str] = []
    real = AnalysisCache.run
    monkeypatch.setattr(AnalysisCache, "run", lambda self, fn, *a, **k: (ran.append(fn.__name__), real(self, fn, *a, **k))[1])
    view = BodiesView(server, load_model(str(path)))  # the server's file
    view.box_text.value = f"{b.side}, {b.side}"
    view._on_box(SimpleNamespace(client=object()))  # as a tab's edit arrives
    assert view.model.box == (b.side, b.side) and ran == []
    assert view.load_bytes("up.csv", path.read_bytes()) is None and ran == ["tab_bodies_job"]
    view.box_text.value = ""
    view._on_box(SimpleNamespace(client=object()))
    assert view.model.box is None and ran == ["tab_bodies_job"] * 2


def test_a_file_with_its_own_box_is_searched_in_it(server, tmp_path):
    """An extended-XYZ file's Lattice is the periodic box of the view (load_model and upload), shown exactly."""
    side = 7.123456789012345  # more digits than a rounded display keeps
    text = (f'2\nLattice="{side!r} 0 0 0 {side!r} 0 0 0 {side!r}" Properties=species:S:1:pos:R:3:aspherical_shape:R:3\n'
            f"A 0.5 0 0 1 1 1\nB {side - 1.4!r} 0 0 1 1 1\n")  # 1.9 apart through the box face, 5.2 in open space
    path = tmp_path / "box.xyz"
    path.write_text(text)
    want = contacts(read_bodies(path).Q, box=(side, side, side))
    assert want.relation.tolist() == [Relation.OVERLAP] and len(contacts(read_bodies(path).Q)) == 0  # independent of the view
    m = load_model(str(path))
    assert m.box == (side, side, side) and m.result.relation.tolist() == [Relation.OVERLAP]
    assert load_model(str(path), (20.0, 20.0, 20.0)).box == (20.0, 20.0, 20.0)  # --box overrides the file's
    view = BodiesView(server, None)
    assert view.load_bytes("box.xyz", path.read_bytes()) is None
    assert view.model.box == (side, side, side) and view.model.result.relation.tolist() == [Relation.OVERLAP]
    assert tuple(float(v) for v in view.box_text.value.split(",")) == (side, side, side)  # the field holds the box exactly


def test_a_typed_box_is_a_core_box(server, tmp_path):
    """The field's text is read by core.Box.from_any: a tilted 2D box (Lx, Ly, xy) is taken as one and
    searched as core.contacts searches it; a box of the wrong size is core's message, the model kept."""
    from types import SimpleNamespace

    from core import Box

    b = random_bodies(50, dim=2, seed=5)
    box = Box(b.side, b.side, xy=0.25)
    centers = box.wrap(b.centers)  # into the tilted cell: the bodies must lie in one box
    path = tmp_path / "tilted.csv"
    write_bodies_csv(path, centers, b.semi_axes, b.orientations)
    want = contacts(bodies_from_axes(centers, b.semi_axes, b.orientations), box=(b.side, b.side, 0.25))
    view = BodiesView(server, load_model(str(path)))
    view.box_text.value = f"{b.side!r}, {b.side!r}, 0.25"
    view._on_box(SimpleNamespace(client=object()))  # as a tab's edit arrives
    m = view.model
    assert m.box == box and m.box.tilted and "in a periodic box" in m.summary() and "tilted (xy) = (0.25)" in m.summary()
    assert (m.result.i.tolist(), m.result.j.tolist(), m.result.image.tolist()) == (want.i.tolist(), want.j.tolist(), want.image.tolist())
    assert any("[" in m.pair_label(k) and "a" in m.pair_label(k).split("[")[1] for k in range(len(m.result)) if m.result.image[k].any())
    view.box_text.value = f"{b.side}"  # one number for 2D bodies
    view._on_box(SimpleNamespace(client=object()))
    assert view.model is m and "periodic box: expected 2 positive finite sides" in view.file_md.content
    view.box_text.value = f"{b.side}, ten"
    view._on_box(SimpleNamespace(client=object()))
    assert view.model is m and "periodic box: expected 2 numbers" in view.file_md.content


needs_chromium = pytest.mark.skipif(not os.path.exists("/usr/bin/chromium"), reason="needs Debian chromium at /usr/bin/chromium")

@pytest.mark.browser
@needs_chromium
def test_screenshot_command_with_bodies(demo_file, tmp_path):
    """The command draws in a tab of the test process's Chromium (``--browser``; the command that
    launches its own: tests/test_browser.py). It runs before the module's tab is opened (Playwright's
    sync API cannot nest)."""
    from app.cli import main

    out = tmp_path / "shot.png"
    assert main(["screenshot", "--bodies", str(demo_file), "--out", str(out), "--width", "900", "--height", "600",
                 "--browser", browser_helpers.CHROMIUM_OF_THIS_PROCESS.get()]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 20_000


NODE_JS = """(n) => {
  const r = window.__viserMutable?.nodeRefFromName?.[n];
  if (!r) return null;
  let count = null;
  r.traverse((o) => { if (count === null && o.isPoints) count = o.geometry.attributes.position?.count ?? null; });
  return {visible: r.visible, count};
}"""


@pytest.fixture(scope="module")
def bodies_page(demo_file):
    """One browser and one server for the browser tests of this module, on the demo bodies."""
    yield from browser_helpers.bodies_page(load_model(str(demo_file)))


def fresh_tab(hs):
    """A new tab on the bodies (the view as a user first sees it), once it is drawn."""
    return hs.goto("/")


def caption(page_of_pairs, what: str) -> str:
    text = page_of_pairs.caption(what)
    if page_of_pairs.pages > 1:
        text += f" (page {page_of_pairs.page + 1:,} of {page_of_pairs.pages:,})"
    return text[0].upper() + text[1:]


@pytest.mark.browser
@needs_chromium
def test_browser_bodies_drawn_in_the_colour_of_their_worst_relation(bodies_page):
    hs, m = bodies_page
    view = fresh_tab(hs)
    ARTIFACTS.mkdir(exist_ok=True)
    drawn = view.layers.expected_in_browser()
    for name, count in drawn.items():  # every node in three.js with its number of points / instances
        if "/points/" in name:
            assert hs.page.evaluate(NODE_JS, name)["count"] == count
    assert sum(v for k, v in drawn.items() if "/points/" in k) == len(m.bodies)
    assert view.layers.pose is not None and len(view.layers.fine) + len(view.layers.coarse) > 0  # solids for the camera
    px = hs.canvas_pixels()
    opaque = px[px[:, 3] > 200][:, :3].astype(int)
    amber = ((opaque[:, 0] > 150) & (opaque[:, 1] > 110) & (opaque[:, 2] < 90)).sum()
    red = ((opaque[:, 0] > 120) & (opaque[:, 1] < 90) & (opaque[:, 2] < 90)).sum()
    assert amber > 100 and red > 100, (amber, red)  # tangent layer and overlapping cloud are drawn
    hs.save(ARTIFACTS / "bodies-scene.png")


@pytest.mark.browser
@needs_chromium
def test_browser_page_the_list_search_a_body_filter_by_relation(bodies_page):
    """Issue 22: the list says how many pairs there are, pages through them, finds a body's pairs
    and filters by relation."""
    hs, m = bodies_page
    view = fresh_tab(hs)
    page = hs.page
    total = len(m.result)
    assert total > PAGE_SIZE
    text_shown(page, f"Showing 1–{PAGE_SIZE} of {total:,} pairs (page 1 of 2)")
    page.get_by_role("button", name="Next page ▶").click()
    text_shown(page, f"Showing {PAGE_SIZE + 1}–{total} of {total:,} pairs (page 2 of 2)")
    until(lambda: view.listing is not None and view.listing.page == 1, what="page 2")
    assert view.pairs.value == view.listing.entries[0].label
    page.get_by_role("button", name="◀ Previous page").click()
    text_shown(page, f"Showing 1–{PAGE_SIZE} of {total:,} pairs (page 1 of 2)")
    choose(page, "Relation", "overlap")
    text_shown(page, caption(m.page("overlap"), "overlap pairs"))
    until(lambda: view.listing is not None and view.listing.total == m.page("overlap").total, what="overlap filter")
    assert all("overlap" in label for label in view.pairs.options)
    choose(page, "Relation", "all")
    until(lambda: view.relation == "all", what="all pairs")
    body = int(m.result.j[m.order[0]])  # a body of the layer: it has tangent pairs
    set_field(page, "Body", str(body), view.body_text)
    text_shown(page, caption(m.page(body=body), f"pairs of body {body}"))
    until(lambda: view.body == body, what="body filter")
    assert {e.index for e in view.listing.entries} == set(m.result.pairs_of(body).tolist())
    page.wait_for_function("(v) => Array.from(document.querySelectorAll('input')).some(e => e.value === v)",
                           arg=view.pairs.value)  # the list shows the body's first pair
    assert f"Body **{body}** touches" in view.body_md.content
    set_field(page, "Body", "123456")
    text_shown(page, "no body 123456")
    set_field(page, "Body", "x")
    text_shown(page, "body: expected a whole number")


@pytest.mark.browser
@needs_chromium
def test_browser_contact_network_and_separate_bodies(bodies_page):
    hs, m = bodies_page
    view = fresh_tab(hs)
    page = hs.page
    assert hs.page.evaluate(NODE_JS, NETWORK_NODE) is None  # off by default
    page.get_by_text("Contact network", exact=True).click()
    until(lambda: view.layers.network is not None, what="network built")
    page.wait_for_function(f"() => ({NODE_JS})('{NETWORK_NODE}')?.visible === true")
    assert len(view.layers.network.points) == len(m.result)  # one segment per contact pair
    page.get_by_text("Contact network", exact=True).click()
    page.wait_for_function(f"() => ({NODE_JS})('{NETWORK_NODE}')?.visible === false")
    separate = [k for k in view.layers.expected_in_browser() if "/points/separate/" in k]
    assert separate
    choose(page, "Separate bodies", "hidden")
    for name in separate:
        page.wait_for_function(f"() => ({NODE_JS})('{name}')?.visible === false")
    until(lambda: not any(m.worst[view.layers.fine] == Relation.SEPARATE) and not any(m.worst[view.layers.coarse] == Relation.SEPARATE),
          what="no separate solids")
    choose(page, "Separate bodies", "shown")
    for name in separate:
        page.wait_for_function(f"() => ({NODE_JS})('{name}')?.visible === true")


@pytest.mark.browser
@needs_chromium
def test_browser_open_pair_shows_the_label_core_contacts_certified(bodies_page):
    """Picking a pair (from the list, or a body's pair with "Open pair") opens the two-body view,
    whose certified label is the one ``core.contacts`` gave the pair; "← All bodies" comes back."""
    hs, m = bodies_page
    view = fresh_tab(hs)
    page = hs.page
    choose(page, "Relation", "tangent")
    until(lambda: view.relation == "tangent" and view.listing is not None, what="tangent filter")
    entry = view.listing.entries[3]
    choose(page, "Pair", entry.label)
    until(lambda: view.pair == entry.index and view.ready.is_set(), what="the pair opened")
    hs.wait_settled()
    k = entry.index
    assert view.session.state.relation == str(Relation(int(m.result.relation[k]))) == "tangent"
    text_shown(page, "TANGENT")
    assert hs.mesh_color("B") == "#ffbf00"  # amber: tangent
    hs.save(ARTIFACTS / "bodies-pair.png")
    page.get_by_role("button", name="← All bodies").click()
    until(lambda: view.pair is None and view.ready.is_set(), what="back to all bodies")
    hs.wait_settled()
    assert view.relation == "tangent"  # the list kept its filter
    choose(page, "Relation", "all")
    until(lambda: view.relation == "all", what="all pairs")
    k = int(np.flatnonzero(m.result.relation == Relation.OVERLAP)[0])
    body = int(m.result.i[k])
    set_field(page, "Body", str(body), view.body_text)
    until(lambda: view.body == body and view.relation == "all", what="body filter")
    text_shown(page, f"pairs of body {body}")  # the browser has the body's pairs
    label = m.pair_label(k)
    if view.pairs.value == label:  # the body's first pair: "Open pair" opens it
        page.get_by_role("button", name="Open pair").click()
    else:
        choose(page, "Pair", label)
    until(lambda: view.pair == k and view.ready.is_set(), what="the overlap pair opened")
    hs.wait_settled()
    assert view.session.state.relation == str(Relation(int(m.result.relation[k]))) == "overlap"
    text_shown(page, "OVERLAP")
    page.get_by_role("button", name="← All bodies").click()
    until(lambda: view.pair is None and view.ready.is_set(), what="back to all bodies")
    hs.wait_settled()
    assert view.layers is not None and view.body == body  # the list kept its filter
