"""Regenerate the screenshots of the README (docs/img/) and of the landing page (static/img/).

One browser and one server for all of them (:class:`app.screenshot.HeadlessScene`). Run from the
repository root: ``python -m docs.make_images`` (about half a minute).
"""

from __future__ import annotations

import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TO_TOP = "() => document.querySelectorAll('*').forEach((e) => { if (e.scrollTop) e.scrollTop = 0; })"
"""Scroll the GUI panel back to its top (a click on a folder may have scrolled it)."""


def main() -> None:
    """Write every image (README: docs/img/; landing page: static/img/, static/scene/)."""
    import shutil

    from app.scene.state import SceneConfig
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
    for src, dst in (("scene-what-am-i-seeing", "what-am-i-seeing"), ("scene-touch", "touch")):
        shutil.copyfile(ROOT / f"docs/img/{src}.png", ROOT / f"static/scene/{dst}.png")
    print(f"images written in {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
