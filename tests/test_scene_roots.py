"""The roots of P(T) (issue 22.2): what is drawn is decided by certified computations.

Golden values are independent of the code under test: tests/oracle.py's P(T) (characteristic
polynomial with flint) and its certified positive roots, and the paper's Example 29 (P(T) at
the tangency α1 = (12 - 2√2)/17 has a positive double root, Th. 19).
"""

from __future__ import annotations

import numpy as np
import pytest
from oracle import pencil_oracle, positive_roots

from app.jobs import analyse_job
from app.scene.pair.motion import load_motion
from app.scene.pair.roots import locus, roots_at, roots_of_pencil
from app.scene.pair.roots_view import locus_data, plane_data, roots_words
from core import quadric_from_axes
from core.formulae.pencil import pencil_coefficients


def circle_pair(dx: str):
    return quadric_from_axes([0, 0], [1, 1], exact=True), quadric_from_axes([dx, 0], ["1/2", 2], exact=True)


@pytest.mark.parametrize("dx, want", [("3/2", [2]), ("1.5000000000000001", [1, 1]), ("1.4999999999999999", [])])
def test_static_roots_match_the_independent_oracle(dx, want):
    """A unit circle and an ellipse (1/2, 2) whose centres are dx apart touch at dx = 3/2: a positive
    double root; 1e-16 farther: two distinct positive roots; nearer: none (overlap)."""
    A, B = circle_pair(dx)
    pic = roots_of_pencil(pencil_coefficients(A, B))
    assert [r.mult for r in pic.positive] == positive_roots(pencil_oracle(A, B)) == want
    for r in pic.positive:  # certified enclosures, disjoint
        assert r.interval[0] < r.re < r.interval[1]
    assert sum(r.mult for r in pic.roots) == 3


@pytest.fixture(scope="module")
def ex29():
    m = load_motion(preset="example-29", motion=None)
    return analyse_job(m.A, m.B, m.interval)


@pytest.fixture(scope="module")
def ex30():
    m = load_motion(preset="example-30", motion=None)
    return analyse_job(m.A, m.B, m.interval)


def test_example_29_tangency_is_an_exact_double_root(ex29):
    """At α1 (a closed form in Q(√2)) P(T) is evaluated exactly: a certified positive double root."""
    ev = ex29.events[0]
    pic = roots_at(list(ex29.a), ev.time, float(ev.time), "tangent")
    assert pic.how.startswith("exact")
    assert [r.mult for r in pic.positive] == [2]
    assert pic.summary().startswith("a positive double root")


def test_example_29_locus_two_positive_roots_merge_at_alpha_1(ex29):
    """Before α1 two distinct positive roots (separate), after it none (overlap): on the locus and
    exactly at rational times on either side."""
    a1 = float(ex29.events[0].time)
    ts = np.array([a1 - 0.02, a1 + 0.02])
    L = locus(list(ex29.a), ts)
    assert (L[0] > 0).sum() == 2 and (np.nan_to_num(L[1], nan=-1) > 0).sum() == 0
    for t, want in ((a1 - 0.02, 2), (a1 + 0.02, 0)):
        pic = roots_at(list(ex29.a), t, t, None)
        assert pic.how.startswith("exact") and len(pic.positive) == want
    data, yr = locus_data(ts, L, [(a1, 1.0)], a1, "asinh")
    assert len(data) == 1 + 4 + 1 + 1 + 2 and yr[0] < 0 < yr[1]  # t, roots, T = 0, one event, double root, t now
    assert np.count_nonzero(~np.isnan(data[6])) == 2  # the event: a vertical line of its own


def test_example_30_over_q_sqrt2_and_at_an_event_without_closed_form(ex30):
    """Example 30 has √2 in its coefficients: at a rational t the real roots are isolated over
    Q(√2) exactly; at α4 (a root of a degree-166 polynomial) the certified tangency decides that a
    double positive root is drawn, and the picture says so."""
    t = -0.3  # separate (the paper: δ1 = -0.3)
    pic = roots_at(list(ex30.a), t, t, None)
    assert pic.how.startswith("exact over Q(√2)") and len(pic.positive) == 2
    ev = ex30.events[-1]
    pic = roots_at(list(ex30.a), ev.time, float(ev.time), "tangent")
    assert [r.mult for r in pic.positive] == [2] and any("Th. 7/19" in n for n in pic.notes)
    words = roots_words(pic, None, "at t = α4")
    assert "positive double root" in words and "Th. 7/19" in words


def test_plane_picture_marks_the_double_root_and_the_positive_axis():
    A, B = circle_pair("3/2")
    pic = roots_of_pencil(pencil_coefficients(A, B))
    data, xr, yr = plane_data(pic, "linear")
    x, axis, simple, double, cplx, ring2, *more_rings = data
    assert list(np.flatnonzero(~np.isnan(double))) == [int(np.flatnonzero(np.isclose(x, pic.positive[0].re))[0])]
    assert np.all(axis[x >= 0] == 0) and np.all(np.isnan(axis[x < 0]))
    assert np.array_equal(~np.isnan(ring2), ~np.isnan(double))  # the double root's ring (×2); no other multiple root
    assert all(np.all(np.isnan(r)) for r in more_rings)
    assert xr[0] < min(x) and xr[1] >= max(x) and yr[0] < 0 < yr[1]


def test_roots_panel_in_a_session_only_when_switched_on():
    """The panel computes nothing while off; on, the words name Var and the rule, and the plots exist
    (the locus only during a motion)."""
    import viser

    from app.scene.common.state import SceneConfig
    from app.scene.pair.session import Session

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        s = Session(server, SceneConfig.from_dict({"preset": "example-29", "event": 1}))
        assert s.ready.wait(120)
        r = s.ui.roots
        s.show_panel()
        assert r.plane is None and r.locus_plot is None and not r._cache
        r.show_roots.value = True
        s.show_panel()
        assert r.plane is not None and r.locus_plot is not None
        assert "a positive double root" in r.words.content and "Var(" in r.words.content and "Rule:" in r.words.content
        r.show_roots.value = False
        s.show_panel()
        assert r.plane is None and r.locus_plot is None
        s.close()
    finally:
        server.stop()


def test_rounded_fields_give_the_exact_matrix_one_click_away():
    """Issue 22.1: during a motion the Shape fields are rounded ("≈") and a button under them copies
    the exact matrix at the exact t: at t = 1/5 it is core's exact A(1/5), entry by entry."""
    import html
    import re
    from fractions import Fraction

    import viser

    from app.scene.common.state import SceneConfig
    from app.scene.pair.session import Session
    from core.moving.motions import matrix_at_exact

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        s = Session(server, SceneConfig.from_dict({"preset": "example-29", "t": "1/5"}))
        assert s.ready.wait(120)
        s.show_panel()
        sg = s.ui.shapes["A"]
        assert sg.fields["center"].value.startswith("≈ ") and sg.exact.visible
        copied = html.unescape(re.search(r'data-copy="([^"]*)"', sg.exact.content).group(1))
        rows = [[Fraction(v) for v in r.split(",")] for r in copied.split(";")]
        want = matrix_at_exact(s.state.motion.A, Fraction(1, 5))
        assert rows == [[Fraction(int(v.p), int(v.q)) for v in r] for r in want]
        s.close()
    finally:
        server.stop()


def test_touch_then_static_shapes_the_controls_say_the_state():
    """Issue 22.1: after Touch the Preset says the Touch motion runs (not "(static shapes)"), the
    event is shown in closed form (two circles: a quadratic), and picking "(static shapes)" leaves
    the motion for the exact decimals the fields show, whose exact relation the readout states."""
    import time

    import viser
    from oracle import oracle_relation

    from app.scene.common.state import SceneConfig
    from app.scene.pair.gui import STATIC, TOUCH
    from app.scene.pair.session import Session

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        s = Session(server, SceneConfig.from_dict({"dim": 2, "preset": None, "A": {"center": [0, 0], "semi_axes": [1, 1]},
                                                   "B": {"center": [3, "1/2"], "semi_axes": ["1/2", "1/2"]},
                                                   "gizmos": True}))  # "Move" on: the motion hides them and says so
        s.motion_ctl.on_touch()
        deadline = time.monotonic() + 60
        while not (s.state.motion is not None and s.state.analysis is not None and s.state.event is not None):
            assert time.monotonic() < deadline, "no touch motion"
            time.sleep(0.02)
        s.show_panel()
        assert s.state.relation == "tangent"
        assert s.ui.motion.preset.value == TOUCH and TOUCH in s.ui.motion.preset.options
        ev = s.state.analysis.events[s.state.event - 1]
        assert ev.closed and "√" in ev.exact  # |c_B(t)| = 3/2: t = 3/sqrt(37) is a closed form
        assert s.ui.view.gizmo_note.visible
        s.ui.motion.preset.value = STATIC  # re-picking "(static shapes)" works
        assert s.state.motion is None and s.ui.motion.preset.value == STATIC
        s.show_panel()
        texts = {n: {k: h.value for k, h in s.ui.shapes[n].fields.items()} for n in "AB"}
        assert not any(v.startswith("≈") for t in texts.values() for k, v in t.items() if k != "matrix"), texts
        from test_browser_fields import shape_matrix

        want = oracle_relation(shape_matrix(texts["A"], 2), shape_matrix(texts["B"], 2))
        assert s.state.relation == want and want in ("separate", "overlap")  # rounded: not exactly tangent
        s.close()
    finally:
        server.stop()
