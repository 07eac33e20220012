"""The roots of P(T) in a real browser (issue 22.2): live while scrubbing, the tangency's double root.

Reads the uPlot charts of the page (``window.__viserTestpoints.uplots``): at Example 29's α1 the
complex-plane picture has one positive double root (the paper's Th. 19: tangent), at t = 0.7
(overlap) none and a complex pair; the root locus has a vertical line per certified event.
"""

from __future__ import annotations

import os

import pytest
from browser_helpers import open_folder, set_field, tick, until

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists("/usr/bin/chromium"), reason="needs Debian chromium at /usr/bin/chromium"),
]

SERIES_JS = """(title) => {
  const u = Object.values(window.__viserTestpoints?.uplots ?? {}).find(u => document.body.contains(u.chart.root)
    && (u.chart.root.querySelector('.u-title')?.textContent ?? '').startsWith(title));
  if (!u) return null;
  const out = {};
  u.chart.series.forEach((s, i) => { if (i > 0) out[s.label] = Array.from(u.chart.data[i]).filter(v => v !== null && !Number.isNaN(v)).length; });
  return out;
}"""
"""For the chart whose title starts with ``title``: series label -> number of points drawn."""


def series(page, title: str) -> dict | None:
    return page.evaluate(SERIES_JS, title)


def test_roots_of_p_follow_t_and_mark_the_tangency(headless_scene):
    hs = headless_scene
    s = hs.open({"preset": "example-29", "event": 1, "show_plots": False})
    page = hs.page
    # states, not clicks in a row: a click can be lost while the panel re-renders (a clean-clone run
    # timed out on "roots plots" after both clicks)
    open_folder(page, "Roots of P(T) (the paper's picture)", "Show the roots of P(T)")
    tick(page, "Show the roots of P(T)", lambda: s.ui.roots.show_roots.value)
    until(lambda: s.ui.roots.plane is not None and s.ui.roots.locus_plot is not None, what="roots plots")
    page.wait_for_function(f"() => ({SERIES_JS})('Roots of P(T)') !== null && ({SERIES_JS})('Root locus') !== null")
    plane = series(page, "Roots of P(T)")
    assert plane["positive double root (tangency)"] == 1 and plane["complex pair"] == 0, plane
    locus = series(page, "Root locus")
    assert locus["α1 (certified)"] == 2 and locus["α2 (certified)"] == 2 and locus["double root"] == 2, locus
    page.wait_for_function("() => document.body.innerText.includes('a positive double root')")
    set_field(page, "t (exact)", "0.7")  # overlap: the positive roots have left the real axis
    until(lambda: s.state.t == 0.7 and s.state.event is None, what="t = 0.7")
    page.wait_for_function(f"() => ({SERIES_JS})('Roots of P(T)')['complex pair'] === 2")
    plane = series(page, "Roots of P(T)")
    assert plane["positive double root (tangency)"] == 0 and plane["real root"] == 1, plane  # T = -1 (double)
    page.wait_for_function("() => document.body.innerText.includes('no positive root, 1 complex pair')")
    set_field(page, "t (exact)", "1/5")  # separate: two distinct positive roots
    page.wait_for_function(f"() => ({SERIES_JS})('Roots of P(T)')['complex pair'] === 0")
    assert series(page, "Roots of P(T)")["real root"] == 3  # T1, T2 > 0 and the negative double root
    page.wait_for_function("() => document.body.innerText.includes('two distinct positive roots')")
