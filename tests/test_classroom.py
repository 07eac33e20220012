"""Issue 55, the classroom, without a browser: the t box, undo/redo, Touch-then-edit, the roots view, lessons.

Truth comes from the paper or from hand arithmetic, never from the code under test: Example 33
is tangent for every real t (P(t, T) = -(T + 1)(T + 4)(T - 1)^2 / 576); Example 29 is separate at
t = 0, overlaps at 3/4 and touches at (12 -+ 2 sqrt 2)/17; unit circles whose centres are d apart
touch when d = 2.
"""

from __future__ import annotations

import pytest

viser = pytest.importorskip("viser")

from app.scene.common.state import SceneConfig  # noqa: E402
from app.scene.pair.session import Session  # noqa: E402


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def preset_session(server, preset: str, **cfg) -> Session:
    s = Session(server, SceneConfig.from_dict({"preset": preset, **cfg}))
    assert s.ready.wait(120), "analysis did not finish"
    return s


# ---------------------------------------------------------------------------------------- the t box
@pytest.mark.parametrize("typed", ["-3", "3", "-2", "5/2", "10", "-7/3"])
def test_t_box_widens_the_slider_for_an_unbounded_interval(server, typed):
    """Example 33 (I = R): a t outside the slider's window is shown at that t, never clamped."""
    from fractions import Fraction

    s = preset_session(server, "example-33")
    s.ui.timeline.t_box.value = typed
    want = float(Fraction(typed))
    assert s.state.t == want
    lo, hi = s.state.analysis.window
    assert lo <= want <= hi and (s.ui.timeline.slider.min, s.ui.timeline.slider.max) == (lo, hi)
    assert s.ui.timeline.slider.value == want
    assert s.ui.timeline.t_box.value == typed  # the text as typed
    assert not s.ui.timeline.t_error.visible
    assert s.state.relation == "tangent"  # the paper: tangent for every real t
    s.close()


def test_t_box_keeps_the_text_typed_and_refuses_outside_a_bounded_interval(server):
    s = preset_session(server, "example-29")
    s.ui.timeline.t_box.value = "3/4"
    assert s.state.t == 0.75 and s.ui.timeline.t_box.value == "3/4" and s.state.relation == "overlap"
    assert s.snapshot().t == "3/4"  # a reload or a link shows the same text
    window = s.state.analysis.window
    s.ui.timeline.t_box.value = "2"  # I = [0, 1]: refused with a message, t unchanged
    assert "outside I = [0, 1]" in s.ui.timeline.t_error.content and s.ui.timeline.t_error.visible
    assert s.state.t == 0.75 and s.state.analysis.window == window
    s.ui.timeline.slider.value = 0.25  # the slider's t: the box shows the number again (panel coalesced: drawn now)
    s.show_panel()
    assert s.state.t == 0.25 and s.ui.timeline.t_box.value == "0.25"
    s.close()


def test_configuration_with_t_outside_the_window_is_not_clamped(server):
    s = preset_session(server, "example-33", t=6.5)
    assert s.state.t == 6.5 and s.state.analysis.window[1] >= 6.5 and s.state.relation == "tangent"
    s.close()
    s = preset_session(server, "example-29", t=1.5)
    s.show_panel()
    assert "t = 1.5 is outside I = [0, 1]" in s.ui.timeline.t_error.content
    s.close()


# ---------------------------------------------------------------------------------------- undo / redo
def wait_steps(s: Session, undo: int, timeout: float = 30.0) -> None:
    """Wait (with a deadline) until the tab's history holds ``undo`` steps to undo."""
    import time

    deadline = time.monotonic() + timeout
    while s.history.steps[0] < undo:
        assert time.monotonic() < deadline, f"history has {s.history.steps}, wanted {undo} undo steps"
        time.sleep(0.02)


def wait_ready(s: Session, timeout: float = 60.0) -> None:
    import time

    deadline = time.monotonic() + timeout
    while not s.ready.is_set() or s.pending() or s.state.analysing:
        assert time.monotonic() < deadline, "the tab did not settle"
        time.sleep(0.02)


def unit_circles(dx: str) -> SceneConfig:
    return SceneConfig.from_dict({
        "dim": 2, "preset": None,
        "A": {"center": ["0", "0"], "semi_axes": ["1", "1"], "orientation": ["0"]},
        "B": {"center": [dx, "0"], "semi_axes": ["1", "1"], "orientation": ["0"]},
    })


def test_undo_redo_fields_matrix_and_motion_text(server):
    s = Session(server, unit_circles("3"))
    s.history.note()  # the configuration opened is kept once quiet: now (the test's change comes at once)
    assert s.history.steps == (0, 0)
    s.ui.shapes["B"].fields["center"].value = "2, 0"  # unit circles 2 apart: tangent
    assert s.state.relation == "tangent"
    wait_steps(s, 1)
    s.ui.shapes["A"].fields["matrix"].value = "1, 0, 0; 0, 1, 0; 0, 0, -9"  # a wrong matrix: radius 3
    assert s.state.relation == "overlap"
    wait_steps(s, 2)
    assert s.history.undo()
    wait_ready(s)
    assert s.state.relation == "tangent" and s.ui.shapes["A"].fields["matrix"].value == ""
    assert s.ui.shapes["B"].fields["center"].value == "2, 0"
    assert s.history.undo()
    wait_ready(s)
    assert s.state.relation == "separate" and s.ui.shapes["B"].fields["center"].value == "3, 0"
    assert not s.history.undo()  # nothing before the first configuration
    assert s.history.redo()
    wait_ready(s)
    assert s.state.relation == "tangent" and s.ui.shapes["B"].fields["center"].value == "2, 0"
    # a typed motion, then undo: the static shapes again; redo: the motion text again
    texts = {
        "A": '{"shape": {"center": [0, 0], "semi_axes": [1, 1]}}',
        "B": '{"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["3*t", "0"]}',
        "interval": "0, 1",
    }
    for k, v in texts.items():
        s.ui.motion.fields[k].value = v
    s.motion_ctl.on_analyse()
    wait_ready(s)
    assert s.state.motion is not None
    wait_steps(s, 2)
    assert s.history.steps[1] == 0  # a new step drops what was undone
    assert s.history.undo()
    wait_ready(s)
    assert s.state.motion is None and s.state.relation == "tangent"
    assert s.history.redo()
    wait_ready(s)
    assert s.state.motion is not None and s.ui.motion.fields["B"].value == s.state.motion.texts()["B"]
    assert "3*t" in s.ui.motion.fields["B"].value
    s.close()


def test_undo_touch_and_a_hundred_steps(server):
    s = Session(server, unit_circles("3"))
    s.history.note()
    s.motion_ctl.on_touch()
    wait_ready(s)
    assert s.state.relation == "tangent" and s.state.motion is not None
    wait_steps(s, 1)
    assert s.history.undo()
    wait_ready(s)
    assert s.state.motion is None and s.state.relation == "separate"
    assert s.ui.shapes["B"].fields["center"].value == "3, 0"
    s.close()
    s = Session(server, unit_circles("3"))
    s.history.QUIET = 0.0  # one step per change (the test's changes come faster than a user's)
    for k in range(120):
        s.set_shape("B", center=f"{3 + k}, 0")
        s.history.note()
    assert s.history.steps[0] >= 100
    for _ in range(100):
        assert s.history.undo()
    wait_ready(s)
    assert s.ui.shapes["B"].fields["center"].value == f"{3 + 119 - 100}, 0"
    s.close()


# ---------------------------------------------------------------------------------------- Touch, then edit
def test_touch_then_static_keeps_the_exact_tangency(server):
    """Unit circles at (0, 0) and (3, 0): Touch slides B to (2, 0) exactly (t = 2/3); leaving the motion
    keeps B at exactly (2, 0), so the circles stay tangent (|c_A c_B| = 2 = 1 + 1)."""
    from app.scene.pair.gui import STATIC

    s = Session(server, unit_circles("3"))
    s.motion_ctl.on_touch()
    wait_ready(s)
    assert s.state.relation == "tangent"
    s.ui.motion.preset.value = STATIC
    assert s.state.motion is None and s.state.relation == "tangent"
    s.show_panel()
    assert s.ui.shapes["B"].fields["center"].value == "2, 0"
    s.close()


def test_event_then_edit_keeps_exact_shapes_with_a_rational_event(server):
    """Unit circles at (0, 0) and (3t, 0), t in [0, 1]: tangent at t = 2/3 (B at (2, 0)). At the
    event, editing A's semi-axes leaves the motion: B is exactly (2, 0), and A with semi-axes 1, 1
    typed again is still tangent to it."""
    s = Session(server, SceneConfig(dim=2, preset=None))
    s.load_untrusted({"dim": 2, "preset": None, "event": 1, "motion": {
        "A": '{"shape": {"center": [0, 0], "semi_axes": [1, 1]}}',
        "B": '{"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["3*t", "0"]}',
        "interval": "0, 1"}})
    wait_ready(s)
    assert s.state.event == 1 and s.state.relation == "tangent"
    assert s.set_shape("A", semi_axes="1, 1") == "tangent"
    s.show_panel()
    assert s.ui.shapes["B"].fields["center"].value == "2, 0"
    assert s.ui.shapes["B"].fields["semi_axes"].value == "1, 1"
    s.close()


def test_irrational_event_falls_back_to_the_marked_decimals(server):
    """Unit circles at (0, 0) and (t, t): tangent at t = sqrt(2) (|c| = t sqrt 2 = 2), an irrational
    time: leaving the motion gives the 10-digit decimals (the fields read rationals only), marked as such."""
    from app.scene.pair.gui import STATIC

    s = Session(server, SceneConfig(dim=2, preset=None))
    s.load_untrusted({"dim": 2, "preset": None, "event": 1, "motion": {
        "A": '{"shape": {"center": [0, 0], "semi_axes": [1, 1]}}',
        "B": '{"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["t", "t"]}',
        "interval": "0, 3"}})
    wait_ready(s)
    assert s.state.relation == "tangent"
    s.ui.motion.preset.value = STATIC
    assert s.state.status == s.motion_ctl.FROZEN
    s.show_panel()
    assert s.ui.shapes["B"].fields["center"].value == "1.414213562, 1.414213562"
    s.close()


# ---------------------------------------------------------------------------------------- the lesson
PAPER_RELATIONS = {1: "separate", 2: "separate", 3: "separate", 4: "tangent", 5: "overlap", 6: "separate",
                   7: "separate", 8: "tangent", 9: "overlap", 10: "tangent", 11: "tangent"}
"""Each step's relation: by hand for the static pairs (below), the paper's for Examples 29, 30 and 33."""


def _char_poly(A, B):
    """det(T A + B) as coefficients a_0..a_n, by exact interpolation at n + 1 rational points (no code under test)."""
    from flint import fmpq, fmpq_mat

    n = len(A)
    xs = [fmpq(k) for k in range(n + 1)]
    ys = [fmpq_mat([[x * A[i][j] + B[i][j] for j in range(n)] for i in range(n)]).det() for x in xs]
    coeffs = [fmpq(0)] * (n + 1)  # Lagrange, expanded
    for i, xi in enumerate(xs):
        basis, denom = [fmpq(1)], fmpq(1)
        for j, xj in enumerate(xs):
            if j != i:
                basis = [fmpq(0)] + basis  # multiply by T
                for k in range(len(basis) - 1):
                    basis[k] -= xj * basis[k + 1]
                denom *= xi - xj
        for k in range(n + 1):
            coeffs[k] += ys[i] * basis[k] / denom
    return coeffs


def _poly_mul(*factors):
    from flint import fmpq

    out = [fmpq(1)]
    for f in factors:
        prod = [fmpq(0)] * (len(out) + len(f) - 1)
        for i, a in enumerate(out):
            for j, b in enumerate(f):
                prod[i + j] += a * fmpq(b)
        out = prod
    return out


def _circle_matrix(cx, cy):
    from flint import fmpq

    cx, cy = fmpq(cx), fmpq(cy)
    return [[1, 0, -cx], [0, 1, -cy], [-cx, -cy, cx * cx + cy * cy - 1]]


def test_paper_lesson_static_steps_match_hand_computed_p_of_t():
    """The words of steps 1-6 quote P(T) = det(TA + B): each is checked here by exact interpolation
    on matrices written by hand (x²/4 + y² = 1 and unit circles / the unit sphere)."""
    from flint import fmpq

    from app.scene.common.lesson import load_lesson

    lesson = load_lesson("paper")
    assert len(lesson.steps) == 11
    A = [[fmpq(1, 4), 0, 0], [0, 1, 0], [0, 0, -1]]
    q = fmpq(1, 4)
    # step 1/2: B = (x - 4)² + y² - 1: P = -1/4 (T + 1)(T² - 11T + 4)
    assert _char_poly(A, _circle_matrix(4, 0)) == [-q * c for c in _poly_mul([1, 1], [4, -11, 1])]
    # step 4: B at (3, 0): P = -1/4 (T + 1)(T - 2)²: a positive double root (tangent, Theorem 7.4)
    assert _char_poly(A, _circle_matrix(3, 0)) == [-q * c for c in _poly_mul([1, 1], [-2, 1], [-2, 1])]
    # step 5: B at (5/2, 0): P = -(T + 1)(4T² - 5T + 16)/16, discriminant 25 - 256 < 0: complex pair (overlap)
    assert _char_poly(A, _circle_matrix(fmpq(5, 2), 0)) == [-c / 16 for c in _poly_mul([1, 1], [16, -5, 4])]
    # step 6: ellipsoid (2, 1, 1) and the unit sphere at height 5/2: P = -(T + 4)(T + 1)(T - 4)(T - 1/4)/4
    A3 = [[q, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, -1]]
    h = fmpq(5, 2)
    B3 = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, -h], [0, 0, -h, h * h - 1]]
    assert _char_poly(A3, B3) == [-q * c for c in _poly_mul([4, 1], [1, 1], [-4, 1], [-q, 1])]
    # step 3: the circle at (3, 1) keeps away from x²/4 + y² = 1 (distance > 0.29 on a fine sampling)
    import math

    d = min(math.hypot(2 * math.cos(a) - 3, math.sin(a) - 1) for a in (k * 2 * math.pi / 20000 for k in range(20000)))
    assert d > 1.29
    # the steps say so
    scenes = {k: lesson.step(k).scene for k in range(1, 7)}
    assert scenes[1]["B"]["matrix"] == [["1", "0", "-4"], ["0", "1", "0"], ["-4", "0", "15"]]
    assert scenes[3]["B"]["center"] == ["3", "1"] and scenes[4]["B"]["center"] == ["3", "0"]
    assert scenes[5]["B"]["center"] == ["5/2", "0"] and scenes[6]["B"]["center"] == ["0", "0", "5/2"]
    for k, rel in PAPER_RELATIONS.items():  # the Reveal of each prediction (step 1 asks to read a matrix)
        assert k == 1 or lesson.step(k).answer.lower().startswith(rel), (k, lesson.step(k).answer)


@pytest.mark.parametrize("k", sorted(PAPER_RELATIONS))
def test_paper_lesson_step_shows_the_relation_it_teaches(server, k):
    from app.scene.common.lesson import load_lesson
    from app.scene.common.texts import read_time

    step = load_lesson("paper").step(k)
    s = Session(server, SceneConfig(), defer_load=True)
    s.load_untrusted(dict(step.scene))
    wait_ready(s, 300)
    assert s.state.relation == PAPER_RELATIONS[k]
    if k == 8:  # the paper's alpha_1 = (12 - 2 sqrt 2)/17, exactly
        assert s.state.event == 1 and s.state.analysis.event_at(read_time("(12-2*sqrt(2))/17")) == 1
    if k == 10:  # Example 30: t = 1/2 is an event, exactly tangent
        assert s.state.event is not None and s.state.analysis.event_at(read_time("1/2")) == s.state.event
    s.close()


def test_lesson_files_are_checked_with_one_line_errors(tmp_path):
    from app.scene.common.lesson import lesson_query, load_lesson

    bad = tmp_path / "bad.json"
    bad.write_text('{"title": "x", "steps": [{"title": "a", "scene": {"dim": 4}}]}')
    with pytest.raises(ValueError, match=r"lesson bad: step 1: scene: config: dim must be 2 or 3"):
        load_lesson(str(bad))
    bad.write_text('{"title": "x", "steps": [{"title": "a", "scene": {}, "open": ["nowhere"]}]}')
    with pytest.raises(ValueError, match=r"step 1: open: unknown folders \['nowhere'\]"):
        load_lesson(str(bad))
    bad.write_text("{")
    with pytest.raises(ValueError, match="not valid JSON"):
        load_lesson(str(bad))
    with pytest.raises(ValueError, match="not a lesson name"):
        load_lesson("/etc/passwd")
    good = tmp_path / "circles.json"
    good.write_text('{"title": "Two circles", "steps": [{"title": "apart", "scene": {"dim": 2, "preset": null,'
                    ' "B": {"center": ["3", "0"], "semi_axes": ["1", "1"]}}, "question": "?", "answer": "Separate."}]}')
    lesson = load_lesson(str(good))
    assert lesson.name == "circles" and lesson.step(1).answer == "Separate."
    with pytest.raises(ValueError, match=r"no step 2 \(steps 1..1\)"):
        lesson.step(2)
    assert lesson_query("lesson=../../etc/passwd&step=2") == ("../../etc/passwd", 2)  # a name, looked up, never opened


def test_lesson_export_page_is_offline_and_has_every_step():
    from app.lesson_export import lesson_html
    from app.scene.common.lesson import load_lesson

    lesson = load_lesson("paper")
    page = lesson_html(lesson, {1: b"\x89PNG fake"})
    assert page.count("<section") == 11 and "step 11 of 11: A degenerate motion" in page
    assert "data:image/png;base64," in page and "http://" not in page and "https://" not in page
    assert "<details><summary>Reveal the answer</summary>" in page


def test_landing_page_opens_the_lesson():
    from fastapi.testclient import TestClient

    from app.api import ApiSettings, create_api

    with TestClient(create_api(ApiSettings(scene_url="http://127.0.0.1:8080"))) as c:
        page = c.get("/").text
    assert 'id="lesson-link" class="button" href="http://127.0.0.1:8080/?lesson=paper&amp;step=1"' in page


def test_gizmos_hidden_until_move_is_ticked(server):
    s = Session(server, unit_circles("3"))
    assert not s.state.gizmos and all(v.control.opacity == 0.0 and v.control.disable_axes for v in s.views.values())
    s.ui.view.gizmos.value = True  # "Move the shapes (gizmos)", at the top of the panel
    assert s.state.gizmos and all(v.control.opacity == 1.0 and not v.control.disable_axes for v in s.views.values())
    assert s.ui.view.gizmos.label == "Move the shapes (gizmos)"
    s.close()


# ---------------------------------------------------------------------------------------- predict first
GREY, AMBER, GREEN = (150, 150, 150), (255, 191, 0), (44, 160, 44)
"""The neutral grey and the default palette's tangent and separate colours."""


def shown_relation(s: Session) -> list[str]:
    """The relation words the tab shows: the shapes' labels, the readout's badge, the rule."""
    texts = [v.label.text for v in s.views.values()] + [s.ui.readout.content, s.ui.words.content, s.ui.sign_table.content]
    return [w for w in ("separate", "tangent", "overlap", "SEPARATE", "TANGENT", "OVERLAP", "Certified by", "Decided")
            if any(w in t for t in texts)]


def test_an_open_question_keeps_the_relation_until_reveal(server):
    """Unit circles 2 apart touch (2 = 1 + 1): hidden, the tab knows it but shows grey shapes and no relation."""
    s = Session(server, unit_circles("2"), answer_hidden=True)
    wait_ready(s)
    s.hold_question()
    revealed = []
    s.on_reveal = lambda: revealed.append(True)
    assert s.state.relation == "tangent"  # certified all the same
    assert shown_relation(s) == [] and "press Reveal" in s.ui.readout.content
    assert [tuple(v.mesh.color) for v in s.views.values()] == [GREY, GREY]
    assert [v.label.text for v in s.views.values()] == ["A", "B"]
    s.refresh()  # drawn again, nothing changed: still a question
    assert s.state.answer_hidden and not revealed
    s.reveal()
    wait_ready(s)
    assert revealed == [True] and not s.state.answer_hidden
    assert [tuple(v.mesh.color) for v in s.views.values()] == [AMBER, AMBER]
    assert [v.label.text for v in s.views.values()] == ["A · tangent", "B · tangent"]
    assert "TANGENT" in s.ui.readout.content and "Certified by" in s.ui.readout.content
    s.close()


def test_an_edit_reveals_and_undo_keeps_it_revealed(server):
    """The student moves B to 3 apart instead of predicting: separate (3 > 1 + 1), shown at once."""
    s = Session(server, unit_circles("2"), answer_hidden=True)
    wait_ready(s)
    s.hold_question()
    s.history.note()
    assert s.set_shape("B", center="3, 0") == "separate"
    assert not s.state.answer_hidden
    assert [tuple(v.mesh.color) for v in s.views.values()] == [GREEN, GREEN]
    wait_steps(s, 1)
    assert s.history.undo()
    wait_ready(s)
    assert s.state.relation == "tangent" and not s.state.answer_hidden and "A · tangent" == s.views["A"].label.text
    s.close()


def test_an_open_question_on_a_motion_hides_the_sign_table_and_events(server):
    """Example 29 at t = 3/4 overlaps (the paper's δ2); the sign table and event list say so only after Reveal."""
    s = Session(server, SceneConfig.from_dict({"preset": "example-29", "t": "3/4"}), answer_hidden=True)
    wait_ready(s, 300)
    s.hold_question()
    assert s.state.relation == "overlap"
    assert shown_relation(s) == [] and s.ui.timeline.events_md.content == ""
    assert "#d62728" not in s.ui.timeline.bar.content  # the intervals bar in grey
    s.reveal()
    wait_ready(s)
    assert "overlap" in s.ui.sign_table.content and "OVERLAP" in s.ui.readout.content
    assert "#d62728" in s.ui.timeline.bar.content and "tangent" in s.ui.timeline.events_md.content  # α1, α2 touch
    s.close()


def test_guide_link_beside_the_legend():
    """Issue 56.5: with the guide's address, "What am I seeing?" links to its concepts page; without, no link."""
    from app.scene.pair.panels import GUIDE_CLASS, GUIDE_CONCEPTS, guide_link_html

    link = guide_link_html("http://10.0.0.5:8000/guide/", GUIDE_CONCEPTS, "What am I seeing?")
    assert 'href="http://10.0.0.5:8000/guide/concepts.html"' in link and ">What am I seeing?</a>" in link
    assert 'href="http://h:1/guide/tutorials/paper-class.html"' in guide_link_html("http://h:1/guide", GUIDE_CLASS, "x")


def test_session_with_a_guide_shows_the_link(server):
    s = Session(server, unit_circles("3"), guide="http://127.0.0.1:8000/guide/")
    assert s.ui.guide is not None and 'href="http://127.0.0.1:8000/guide/concepts.html"' in s.ui.guide.content
    s.close()
    s = Session(server, unit_circles("3"))
    assert s.ui.guide is None
    s.close()


def test_lesson_export_folds_the_picture_after_reveal():
    from app.lesson_export import lesson_html
    from app.scene.common.lesson import load_lesson

    lesson = load_lesson("paper")
    page = lesson_html(lesson, {4: b"before", 5: b"same"}, {4: b"after", 5: b"same"})
    fold = page.split('<section id="step-4">')[1].split("</section>")[0]
    before, details = fold.split("<details>")
    assert "YmVmb3Jl" in before and "YWZ0ZXI=" in details  # base64 of b"before" / b"after": the answer's picture in the fold
    fold = page.split('<section id="step-5">')[1].split("</section>")[0]
    assert fold.count("<img") == 1  # the same picture after Reveal (no question hid anything): shown once


def test_screenshot_reveal_needs_a_lesson(tmp_path, capsys):
    from app.cli import main

    assert main(["screenshot", "--reveal", "--out", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert "--reveal draws a lesson's step after Reveal: give --lesson too" in err and "Traceback" not in err
