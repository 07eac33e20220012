"""Issue 55 in a real browser: a lesson step by step (links, Previous/Next, Reveal, reload) and undo by the keyboard.

The relations checked are the paper's and hand arithmetic's (tests/test_classroom.py): step 3 of the
paper lesson is separate, step 4 tangent (unit circle at (3, 0) against x²/4 + y² = 1).
"""

from __future__ import annotations

import os

import pytest
from browser_helpers import text_shown, until

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists("/usr/bin/chromium"), reason="needs Debian chromium at /usr/bin/chromium"),
]

UPLOT_TITLES_JS = """() => Object.values(window.__viserTestpoints?.uplots ?? {})
  .filter(u => document.body.contains(u.chart.root)).map(u => u.chart.root.querySelector('.u-title')?.textContent ?? '')"""


def lesson_session(hs, k: int, *, after: int | None = None):
    """The tab's session once it shows step ``k`` (a step starts the tab's session again).

    ``after``: only a tab opened after the client with this id (a reload opens a new tab while
    the old one, on the same step, may not be closed yet)."""
    from app.scene.pair.lesson_view import view_of

    found = []

    def shown() -> bool:
        found[:] = [s for c, s in list(hs.scene.sessions.items())
                    if (after is None or c > after) and (v := view_of(s)) is not None and v.k == k]
        return bool(found)

    until(shown, what=f"a session on step {k}")
    hs.session = found[0]
    hs.wait_settled()
    return found[0]


def test_lesson_link_steps_reveal_and_reload(headless_scene):
    hs = headless_scene
    page = hs.page
    hs.goto("/?lesson=paper&step=3")
    s = lesson_session(hs, 3)
    text_shown(page, "step 3 of 11: Separate ⇔ Var = 2 and s0 > 0 (Descartes)")
    assert s.state.relation == "separate" and s.state.dim == 2
    page.wait_for_function(f"() => ({UPLOT_TITLES_JS})().some(t => t.startsWith('Roots of P(T) in the complex plane'))")
    page.get_by_role("button", name="Next ▶").click()
    s = lesson_session(hs, 4)
    text_shown(page, "step 4 of 11: External tangency")
    assert s.state.relation == "tangent"
    assert page.get_by_text("Tangent at (2, 0)").count() == 0  # the answer waits for Reveal
    page.get_by_role("button", name="Reveal the answer").click()
    text_shown(page, "Tangent at (2, 0)")
    href = page.get_by_role("link", name="Link to this step").get_attribute("href")
    assert href is not None and href.endswith("?lesson=paper&step=4")
    before = max(hs.scene.sessions)
    page.reload()  # the tab reopens where the student was: step 4, not the link's step 3
    s = lesson_session(hs, 4, after=before)
    text_shown(page, "step 4 of 11")
    page.get_by_role("button", name="◀ Previous").click()
    lesson_session(hs, 3)
    text_shown(page, "step 3 of 11")


def test_lesson_link_to_a_missing_step_or_lesson_says_so(headless_scene):
    hs = headless_scene
    hs.goto("/?lesson=paper&step=40")
    lesson_session(hs, 11)
    assert "lesson paper: there is no step 40 (steps 1..11)" in hs.session.state.errors["config"]
    s = hs.goto("/?lesson=nosuch&step=1")
    until(lambda: "config" in s.state.errors, what="the error")
    assert "there is no lesson 'nosuch'" in s.state.errors["config"]


def test_undo_redo_by_keyboard(headless_scene):
    hs = headless_scene
    s = hs.open({"dim": 2, "preset": None, "A": {"center": ["0", "0"], "semi_axes": ["1", "1"]},
                 "B": {"center": ["3", "0"], "semi_axes": ["1", "1"]}})
    s.history.note()
    assert s.set_shape("B", center="2, 0") == "tangent"
    until(lambda: s.history.steps[0] >= 1, what="the change kept")
    page = hs.page
    page.mouse.click(150, 150)  # focus the scene, not a field
    page.keyboard.press("Control+z")
    until(lambda: s.state.relation == "separate" and s.history.steps == (0, 1), what="undone")
    page.keyboard.press("Control+Shift+z")
    until(lambda: s.state.relation == "tangent" and s.history.steps == (1, 0), what="redone")
    page.get_by_role("button", name="↶ Undo").click()
    until(lambda: s.state.relation == "separate", what="undone by the button")


def test_screenshot_of_a_lesson_step_from_a_teachers_file(tmp_path):
    """``screenshot --lesson FILE --step K``: the step drawn as its link shows it (a PNG of the page)."""
    import json

    import browser_helpers

    from app.cli import main

    lesson = tmp_path / "circles.json"
    lesson.write_text(json.dumps({"title": "Two circles", "steps": [
        {"title": "apart", "scene": {"dim": 2, "preset": None, "B": {"center": ["3", "0"], "semi_axes": ["1", "1"]}}},
        {"title": "touching", "scene": {"dim": 2, "preset": None, "A": {"center": ["0", "0"], "semi_axes": ["1", "1"]},
                                        "B": {"center": ["2", "0"], "semi_axes": ["1", "1"]}},
         "question": "Predict?", "answer": "Tangent: 2 = 1 + 1.", "roots": True, "open": ["roots"]}]}))
    out = tmp_path / "step2.png"
    assert main(["screenshot", "--lesson", str(lesson), "--step", "2", "--width", "900", "--height", "600", "--out", str(out),
                 "--browser", browser_helpers.CHROMIUM_OF_THIS_PROCESS.get()]) == 0
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and int.from_bytes(data[16:20], "big") == 900


def test_served_lesson_opens_every_new_tab_on_step_one(headless_scene):
    """``serve --lesson paper``: a tab opened on the scene's root starts at step 1 (its own step after)."""
    hs = headless_scene
    hs.scene.lesson = "paper"
    try:
        hs.goto("/")
        s = lesson_session(hs, 1)
        text_shown(hs.page, "step 1 of 11: An ellipse is a matrix")
        assert s.state.relation == "separate" and s.state.shapes["A"].matrix is not None
    finally:
        hs.scene.lesson = None


def test_t_box_in_the_page_widens_the_slider_and_keeps_the_text(headless_scene):
    """The issue's reproducer: Example 33 (I = R), "3" typed showed "at t = 1" and rewrote the box to 1.0."""
    from browser_helpers import field_input, set_field

    hs = headless_scene
    s = hs.open({"preset": "example-33"})
    set_field(hs.page, "t (exact)", "5/2")
    until(lambda: s.state.t == 2.5 and not s.pending(), what="t = 5/2")
    assert s.state.relation == "tangent" and s.state.analysis.window[1] >= 2.5
    text_shown(hs.page, "at t = 5/2")
    until(lambda: field_input(hs.page, "t (exact)").input_value() == "5/2", what="the box keeps 5/2")


MESH_COLOUR_JS = """(n) => { const r = window.__viserMutable?.nodeRefFromName?.[n]; if (!r) return null; let h = null;
  r.traverse(o => { if (h === null && o.material) h = '#' + o.material.color.getHexString(); }); return h; }"""

RELATION_WORDS = ("separate", "tangent", "overlap")


def test_predict_first_the_page_keeps_the_relation_until_reveal(headless_scene):
    """Issue 55: at a question step the shapes are grey and unlabelled; Reveal shows the paper's answer.

    Step 8 of the paper lesson is Example 29 at α1 = (12 − 2√2)/17: externally tangent (the paper's
    Theorem 24(1), P(α1, T) = −¼(T + 1)²(T − 1)²).
    """
    grey, amber = "#969696", "#ffbf00"  # the neutral grey and the tangent colour of the default palette
    hs = headless_scene
    page = hs.page
    hs.goto("/?lesson=paper&step=8")
    s = lesson_session(hs, 8)
    text_shown(page, "step 8 of 11: Example 29 at the event")
    text_shown(page, "press Reveal")
    for name in ("A", "B"):
        page.wait_for_function(f"() => ({MESH_COLOUR_JS})('/shapes/{name}/mesh') === '{grey}'")
    body = page.locator("body").inner_text()
    assert not any(word.upper() in body for word in RELATION_WORDS) and "Certified by" not in body
    assert [v.label.text for v in s.views.values()] == ["A", "B"]  # the labels drawn in the 3D view (no DOM text)
    page.get_by_role("button", name="Reveal the answer").click()
    text_shown(page, "Tangent (externally), exactly at α1")
    for name in ("A", "B"):
        page.wait_for_function(f"() => ({MESH_COLOUR_JS})('/shapes/{name}/mesh') === '{amber}'")
    text_shown(page, "TANGENT")
    assert [v.label.text for v in s.views.values()] == ["A · tangent", "B · tangent"]
    assert s.state.relation == "tangent" and not s.state.answer_hidden


def test_an_edit_at_a_question_step_reveals(headless_scene):
    """The student explores instead of predicting: moving t reveals (step 9: Example 29 at t = 3/4, overlap)."""
    hs = headless_scene
    page = hs.page
    hs.goto("/?lesson=paper&step=9")
    s = lesson_session(hs, 9)
    until(lambda: s.question is not None, what="the question held")
    text_shown(page, "press Reveal")
    assert s.set_t(0.7) == "overlap"  # inside (α1, α2): the paper's overlap interval
    until(lambda: not s.state.answer_hidden, what="revealed by the edit")
    text_shown(page, "OVERLAP")
    page.get_by_text("Overlap: s1(3/4)").wait_for(state="visible")  # the answer shown, the Reveal button gone
    assert page.get_by_role("button", name="Reveal the answer").count() == 0


def test_panel_links_to_the_guide(headless_scene):
    """Issue 56.5: "What am I seeing?" opens the guide's concepts page; the Lesson folder its tutorial."""
    from pathlib import Path

    hs = headless_scene
    hs.scene.guide = "http://127.0.0.1:8000/guide/"
    try:
        hs.goto("/?lesson=paper&step=2")
        lesson_session(hs, 2)
        page = hs.page
        concepts = page.get_by_role("link", name="What am I seeing?").get_attribute("href")
        tutorial = page.get_by_role("link", name="Teaching with lessons: the tutorial").get_attribute("href")
    finally:
        hs.scene.guide = None
    assert concepts == "http://127.0.0.1:8000/guide/concepts.html"
    assert tutorial == "http://127.0.0.1:8000/guide/tutorials/paper-class.html"
    docs = Path(__file__).resolve().parents[1] / "docs"  # the pages Sphinx builds them from
    assert (docs / "concepts.md").is_file() and (docs / "tutorials" / "paper-class.md").is_file()


def test_a_steps_camera_is_the_view_drawn(tmp_path):
    """A step's ``camera`` is where the tab looks, also after the page first reports its view's shape
    (that report frames the shapes again, unless a camera was given): a top-down camera draws another
    picture than the default framing of the same step."""
    import json

    import browser_helpers
    import numpy as np
    from PIL import Image

    from app.cli import main

    step = {"title": "two ellipsoids", "scene": {"dim": 3, "preset": None, "B": {"center": ["3", "0", "0"], "semi_axes": ["1", "1", "1"]}}}
    shots = {}
    for name, camera in (("default", None), ("top", {"position": [0, 0.01, 25], "look_at": [0, 0, 0]})):
        lesson = tmp_path / f"{name}.json"
        lesson.write_text(json.dumps({"title": "camera", "steps": [{**step, **({"camera": camera} if camera else {})}]}))
        out = tmp_path / f"{name}.png"
        assert main(["screenshot", "--lesson", str(lesson), "--step", "1", "--width", "800", "--height", "500", "--out", str(out),
                     "--browser", browser_helpers.CHROMIUM_OF_THIS_PROCESS.get()]) == 0
        shots[name] = np.asarray(Image.open(out).convert("RGB"), dtype=np.int16)[:, :480]  # the scene, left of the panel
    changed = np.any(np.abs(shots["default"] - shots["top"]) > 24, axis=-1).mean()
    assert changed > 0.05, changed
