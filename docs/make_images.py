"""Regenerate the screenshots of the README (docs/img/) and of the landing page (static/img/).

One browser and one server for all of them (:class:`app.screenshot.HeadlessScene`). Run from the
repository root: ``python -m docs.make_images`` (about half a minute).
"""

from __future__ import annotations

import shutil
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
TO_TOP = "() => document.querySelectorAll('*').forEach((e) => { if (e.scrollTop) e.scrollTop = 0; })"
"""Scroll the GUI panel back to its top (a click on a folder may have scrolled it)."""


ROOTS_TITLE = "Roots of P(T) (the paper's picture)"
SCROLL_TO = """(text) => {
  const e = Array.from(document.querySelectorAll('*')).find(n => n.children.length === 0 && n.textContent === text);
  let n = e && e.parentElement;
  while (n && !(n.scrollHeight > n.clientHeight + 2 && ['auto', 'scroll'].includes(getComputedStyle(n).overflowY))) n = n.parentElement;
  if (n) n.scrollTop += e.getBoundingClientRect().top - n.getBoundingClientRect().top - 8;
}"""
"""Scroll the GUI panel so that the element with this text is at its top."""


def new_views(hs: object) -> None:
    """The views of issue 22: the roots of P(T) with the root locus, and fields that hold what is certified."""
    from app.scene.common.links import link_path

    h: Any = hs
    # the paper's picture: Example 29 at its first tangency, the roots of P(T) and the locus
    s = h.goto(link_path({"preset": "example-29", "event": 1, "show_plots": False}))
    h.page.get_by_text("Timeline", exact=True).click()  # folded: room for the roots
    h.page.get_by_text("Plots", exact=True).click()
    h.page.get_by_text(ROOTS_TITLE, exact=True).click()
    h.page.get_by_text("Show the roots of P(T)", exact=True).click()
    h.page.wait_for_function("() => Object.values(window.__viserTestpoints?.uplots ?? {}).filter(u => document.body.contains(u.chart.root)).length >= 2")
    h.wait_settled()
    h.page.evaluate(SCROLL_TO, ROOTS_TITLE)
    h.save(ROOT / "docs/img/scene-roots.png")
    shutil.copyfile(ROOT / "docs/img/scene-roots.png", ROOT / "static/scene/roots.png")
    # a few steps later: overlap, the positive roots have left the real axis
    s.set_t(0.7)
    h.wait_settled()
    h.page.evaluate(SCROLL_TO, ROOTS_TITLE)
    h.save(ROOT / "docs/img/scene-roots-overlap.png")
    # the fields hold what is certified: 17 digits typed, kept verbatim, certified SEPARATE
    s = h.goto(link_path({"preset": None, "A": {"center": ["0", "0", "0"], "semi_axes": ["1", "1", "1"]},
                          "B": {"center": ["2.00000000000000001", "0", "0"], "semi_axes": ["1", "1", "1"]}}))
    h.page.get_by_text("Shape B", exact=True).click()
    h.wait_settled()
    h.page.evaluate(TO_TOP)
    h.save(ROOT / "docs/img/scene-fields.png")
    shutil.copyfile(ROOT / "docs/img/scene-fields.png", ROOT / "static/scene/fields.png")


def main() -> None:
    """Write every image (README: docs/img/; landing page: static/img/, static/scene/)."""
    from app.scene.common.state import SceneConfig
    from app.screenshot import HeadlessScene

    t0 = time.perf_counter()
    with HeadlessScene(SceneConfig(preset="example-29", event=1), width=1400, height=900) as hs:
        hs.wait_settled()
        hs.save(ROOT / "docs/img/scene-example-29-tangent.png")
        # the teacher's view: colour-blind safe palette, "What am I seeing?" open, Example 32 at alpha_1
        hs.show(SceneConfig.from_dict({"preset": "example-29", "event": 1, "palette": "colour-blind safe", "show_plots": False}))
        hs.page.get_by_text("What am I seeing?", exact=True).click()
        hs.wait_settled()
        hs.page.evaluate(TO_TOP)
        hs.save(ROOT / "docs/img/scene-what-am-i-seeing.png")
        hs.page.get_by_text("What am I seeing?", exact=True).click()
        # snap to contact: an ellipse and a circle, B slid to the exact tangency
        hs.show(SceneConfig.from_dict({"dim": 2, "preset": None, "A": {"center": [0, 0], "semi_axes": [2, 1]},
                                       "B": {"center": [3, "3/2"], "semi_axes": [1, 1]}}))
        hs.session.ready.clear()
        hs.page.get_by_role("button", name="Touch: slide B to A").click()
        hs.session.ready.wait(60)
        hs.wait_settled()
        hs.session.frame_camera()
        hs.wait_settled()
        hs.page.evaluate(TO_TOP)
        hs.save(ROOT / "docs/img/scene-touch.png")
    with HeadlessScene(SceneConfig(preset="ellipse-spin"), width=1400, height=1250) as hs:
        hs.page.get_by_text("Events (jump to)", exact=True).click()  # folded: room for the plots
        hs.wait_settled()
        hs.save(ROOT / "docs/img/scene-2d-plots.png")
    with HeadlessScene(SceneConfig(preset=None), width=1200, height=760) as hs:
        from core.moving.presets import preset_names

        for name in preset_names():
            hs.show(SceneConfig(preset=name, show_plots=False))
            if hs.session.state.analysis.events:
                hs.show(event=1)
            hs.session.frame_camera()
            hs.wait_settled()
            hs.save(ROOT / f"static/img/{name}.png")
    with HeadlessScene(SceneConfig(preset=None), width=1400, height=1300) as hs:
        new_views(hs)
    for src, dst in (("scene-what-am-i-seeing", "what-am-i-seeing"), ("scene-touch", "touch")):
        shutil.copyfile(ROOT / f"docs/img/{src}.png", ROOT / f"static/scene/{dst}.png")
    print(f"images written in {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    if sys.argv[1:] == ["--new"]:  # only the views of issue 22
        from app.scene.common.state import SceneConfig
        from app.screenshot import HeadlessScene

        with HeadlessScene(SceneConfig(preset=None), width=1400, height=1300) as scene:
            new_views(scene)
    else:
        main()
