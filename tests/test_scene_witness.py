"""The scene shows the witnesses (issue 15): margin, sentence, certified plane, contact / interior point.

Hand-checkable: unit spheres 3 apart must both grow by 50 % to touch and x = 3/2 separates them;
2 apart they touch at (1, 0, 0) with normal (1, 0, 0); 1 apart they overlap by 50 % (mu = 1/2).
"""

from __future__ import annotations

import time
from fractions import Fraction

import numpy as np
import pytest

viser = pytest.importorskip("viser")

from app.scene.common.state import SceneConfig, ShapeState  # noqa: E402
from app.scene.pair.contact import witness_view  # noqa: E402
from app.scene.pair.session import Session  # noqa: E402


def spheres(dim: int, dx: str, plane: bool = False) -> SceneConfig:
    z = ["0"] * dim
    o = ["0"] if dim == 2 else ["1", "0", "0", "0"]
    cfg = SceneConfig.from_dict(
        {
            "dim": dim,
            "preset": None,
            "A": {"center": z, "semi_axes": ["1"] * dim, "orientation": o},
            "B": {"center": [dx] + ["0"] * (dim - 1), "semi_axes": ["1"] * dim, "orientation": o},
        }
    )
    cfg.separating_plane = plane
    return cfg


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


@pytest.mark.parametrize("dim", [2, 3])
def test_separate_margin_sentence_and_certified_plane(server, dim):
    s = Session(server, spheres(dim, "3", plane=True))
    text = s.ui.readout.content
    assert "50 % apart" in text and "separate: this plane separates them" in text
    assert "d = 3/2" in text  # the exact plane x = 3/2
    assert s.markers.plane.visible
    np.testing.assert_allclose(s.markers.plane.position, (1.5, 0.0, 0.0), atol=1e-12)


def test_tangent_contact_point_and_normal(server):
    s = Session(server, spheres(3, "2"))
    text = s.ui.readout.content
    assert "touching" in text and "tangent: they touch here" in text and "(1, 0, 0) (exact)" in text
    assert s.markers.point.visible and s.markers.label.text == "contact"
    np.testing.assert_allclose(s.markers.point.position, (1.0, 0.0, 0.0), atol=0)
    # the normal segment points along +x: its rotation maps z to x
    w, x, y, z = s.markers.normal.wxyz
    R = np.array(
        [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    )
    np.testing.assert_allclose(R @ [0, 0, 1], [1, 0, 0], atol=1e-12)
    assert s.markers.normal.visible


def test_overlap_point_inside_both(server):
    s = Session(server, spheres(3, "1"))
    text = s.ui.readout.content
    assert "overlapping by 50 %" in text and "overlap: this point is inside both" in text
    assert s.markers.point.visible and s.markers.label.text == "inside both"
    p = [Fraction(v) for v in s.markers.point.position]
    assert sum(v * v for v in p) < 1 and (p[0] - 1) ** 2 + p[1] ** 2 + p[2] ** 2 < 1
    assert s.markers.normal is None or not s.markers.normal.visible
    s.set_shape("B", center="3, 0, 0")
    assert not s.markers.point.visible


def _readout_shows(s: Session, text: str) -> bool:
    """A drag recolours at once; the readout follows within the panel period (polled, 2 s cap)."""
    for _ in range(100):
        if text in s.ui.readout.content:
            return True
        time.sleep(0.02)
    return False


def test_drag_updates_the_margin(server):
    s = Session(server, spheres(3, "3"))
    assert s.apply_drag("B", (4.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)) == "separate"
    assert _readout_shows(s, "100 % apart")  # mu = 4 / 2
    assert s.apply_drag("B", (1.5, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)) == "overlap"
    assert _readout_shows(s, "overlapping by 25 %")  # mu = 1.5 / 2


def test_float_shapes_take_the_float_witness():
    # float matrices (a drag of float shapes): certified by floats (core.witness.witness, adaptive), same margin
    A = ShapeState((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (1.0, 0.0, 0.0, 0.0)).quadric()
    B = ShapeState((3.0, 0.0, 0.0), (1.0, 1.0, 1.0), (1.0, 0.0, 0.0, 0.0)).quadric()
    assert isinstance(A, np.ndarray)
    view = witness_view(A, B, "separate")
    assert view.margin == "50 % apart" and view.mu[0] <= 1.5 <= view.mu[1]
    n, d = view.plane
    np.testing.assert_allclose(n, [1, 0, 0], atol=1e-12)
    assert 1.0 < d < 2.0
    view = witness_view(A, ShapeState((1.0, 0.0, 0.0), (1.0, 1.0, 1.0), (1.0, 0.0, 0.0, 0.0)).quadric(), "overlap")
    x = np.array(view.point)
    assert view.point_label == "inside both" and np.sum(x**2) < 1 and np.sum((x - [1, 0, 0]) ** 2) < 1
