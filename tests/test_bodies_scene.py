"""Many bodies in the scene: the model (colours, list, picking, pair configurations), the view on a
ViserServer without a browser, and (marked ``browser``) the headless page and its screenshot.

Golden facts are exact: touching unit-diameter spheres on a lattice are tangent neighbours; the
two-body view opened on a pair rebuilds the very matrices the search classified, so its
certified relation is the pair's.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

viser = pytest.importorskip("viser")

from app.bodyfiles import read_bodies, write_bodies_csv  # noqa: E402
from app.scene.bodies import BodiesModel  # noqa: E402
from app.scene.bodies_view import MESH_NODE, BodiesView, load_model  # noqa: E402
from bench.bodies_data import demo_bodies, random_bodies  # noqa: E402
from core import Relation, bodies_from_axes, classify  # noqa: E402

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


def test_model_colours_list_and_pair_lookup(tmp_path):
    m = lattice_model(tmp_path)
    assert len(m.result) == 24 and set(m.worst.tolist()) == {Relation.TANGENT}
    labels = [e.label for e in m.listed()]
    assert labels[0] == "0 – 1  tangent (exact)" and len(labels) == 24
    assert m.pair_between(5, 1) == m.pair_between(1, 5) is not None and m.pair_between(0, 5) is None
    assert [m.result.i[e.index] for e in m.listed(body=15)] + [m.result.j[e.index] for e in m.listed(body=15)]
    assert "**16 ellipses**" in m.summary() and "24 contacts" in m.summary()


def test_model_periodic_pair_config_and_labels(tmp_path):
    m = lattice_model(tmp_path, box=(4.0, 4.0))
    assert len(m.result) == 32  # every site has 4 neighbours on the torus
    k = next(e.index for e in m.listed() if "[" in e.label)
    cfg, note = m.pair_config(k)
    a, b = cfg.shapes()
    assert "periodic image" in note and "exact translate" in note
    assert abs(float(b.center[0]) - float(a.center[0])) + abs(float(b.center[1]) - float(a.center[1])) == 1.0


def test_two_body_config_rebuilds_the_same_matrices():
    b = random_bodies(300, dim=3, seed=6)
    Q = bodies_from_axes(b.centers, b.semi_axes, b.orientations)
    from app.bodyfiles import BodySet

    m = BodiesModel(BodySet(Q, b.centers, b.semi_axes, b.orientations), None, name="random")
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


def test_view_select_open_pair_and_back(server, demo_file):
    m = load_model(str(demo_file))
    view = BodiesView(server, m)
    assert view.ready.is_set() and view.mesh is not None
    assert view.mesh.batched_colors.shape == (244, 3)
    k = next(e.index for e in m.listed() if "tangent" in e.label)
    i, j = int(m.result.i[k]), int(m.result.j[k])
    assert view.select(i) is None and f"Body **{i}**" in view.body_md.content
    assert view.select(j) == k and view.pair == k
    session = view.session
    assert session is not None and session.ready.wait(30)
    assert session.state.relation == "tangent"  # the same certified relation as in the search
    view.show_bodies()
    assert view.session is None and view.pair is None and view.mesh is not None


def test_view_upload_and_box(server, tmp_path):
    view = BodiesView(server, None)
    assert view.mesh is None
    b = random_bodies(200, dim=2, seed=3)
    path = tmp_path / "up.csv"
    write_bodies_csv(path, b.centers, b.semi_axes, b.orientations)
    assert view.load_bytes("up.csv", path.read_bytes()) is None
    assert view.model is not None and len(view.model.bodies) == 200 and view.mesh is not None
    assert view.load_bytes("bad.csv", b"x,y\n1,2\n").startswith("bad.csv: the header must name the columns")
    assert "⚠" in view.file_md.content and len(view.model.bodies) == 200  # the old set stays
    view.box_text.value = f"{b.side}, {b.side}"  # from Python: no client, so no recompute
    assert view.load_bytes("up.csv", path.read_bytes()) is None and view.model.box == (b.side, b.side)


needs_chromium = pytest.mark.skipif(not os.path.exists("/usr/bin/chromium"), reason="needs Debian chromium at /usr/bin/chromium")


@pytest.mark.browser
@needs_chromium
def test_bodies_scene_in_the_browser_and_its_screenshot(demo_file):
    from app.scene.state import SceneConfig
    from app.screenshot import HeadlessScene

    ARTIFACTS.mkdir(exist_ok=True)
    m = load_model(str(demo_file))
    with HeadlessScene(SceneConfig(), bodies=m, width=1200, height=800, timeout=120) as hs:
        assert hs.page.evaluate("(n) => window.__viserMutable?.nodeRefFromName?.[n] != null", MESH_NODE)
        px = hs.canvas_pixels()
        opaque = px[px[:, 3] > 200][:, :3].astype(int)
        amber = ((opaque[:, 0] > 150) & (opaque[:, 1] > 110) & (opaque[:, 2] < 90)).sum()
        red = ((opaque[:, 0] > 120) & (opaque[:, 1] < 90) & (opaque[:, 2] < 90)).sum()
        assert amber > 100 and red > 100, (amber, red)  # tangent layer and overlapping cloud are drawn
        hs.save(ARTIFACTS / "bodies-scene.png")
        view = hs.session
        k = next(e.index for e in m.listed() if "tangent" in e.label)
        view.open_pair(k)
        hs.wait_settled()
        assert hs.mesh_color("B") == "#ffbf00"  # the two-body view: amber, tangent
        hs.save(ARTIFACTS / "bodies-pair.png")
        view.show_bodies()
        hs.wait_settled()
        assert hs.page.evaluate("(n) => window.__viserMutable?.nodeRefFromName?.[n] != null", MESH_NODE)


@pytest.mark.browser
@needs_chromium
def test_screenshot_command_with_bodies(demo_file, tmp_path):
    from app.cli import main

    out = tmp_path / "shot.png"
    assert main(["screenshot", "--bodies", str(demo_file), "--out", str(out), "--width", "900", "--height", "600"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 20_000
