"""The "Roots of P(T)" panel: the paper's picture for the classroom (uPlot plots and its words).

Two plots, computed only while "Show the roots of P(T)" is on, coalesced with the rest of the
panel (never on the drag or t-step hot path):

* **the roots of P(T) at the current t** in the complex plane: the positive real axis T > 0
  highlighted (where two distinct roots mean *separate*), real roots as dots, a double root as
  a large ring (a tangency), complex pairs; what is drawn comes from :mod:`app.scene.pair.roots`
  (certified isolation, or the certified relation where P(t) has no exact form);
* over a motion, **the root locus**: the real roots of P(T) against t, the certified events as
  vertical lines and the double root of each tangency marked, so that "two positive roots merge
  at α1" is visible.

The words under the title name the paper's quantities: Var(a_n, …, a_0), the signs of s0, s1,
s1,0 and the rule that decided (the readout's own data).
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from typing import Any

import numpy as np
import viser
import viser.uplot as uplot

from ..common import wire
from .roots import RootsPicture, locus, roots_at, roots_of_pencil

__all__ = ["RootsView", "plane_data", "locus_data", "roots_words"]

AXIS_COLOUR = "#9ecae1"
"""The highlighted positive real axis."""

ROOT_COLOURS = ["#08519c", "#6a3d9a", "#e6550d", "#636363"]

WINDOW_WIDTH = 420.0
"""Width (CSS px) of the window of the roots' plots, docked on the left (the scene keeps the middle)."""

RING_LABELS = {2: "×2 double root (a ring)", 3: "×3 triple root (a 2nd ring)", 4: "×4 quadruple root (a 3rd ring)"}
"""Legend of the multiplicity rings (:data:`RINGS`)."""

SCALE_WORDS = {
    "linear": "Axes: **Re T and Im T, linear** (what the paper draws).",
    "asinh": "Axes: **asinh(Re T), asinh(Im T)**: like T near 0, like ±log(2|T|) far away, so roots such as "
             "1/4 and 4 (reciprocal) are both readable.",
}
"""What the roots picture's axes show, under the picture (the "Roots axes" dropdown)."""


def _f(v: Any, scale: str) -> Any:
    return np.arcsinh(v) if scale == "asinh" else v


RINGS = (2, 3, 4)
"""Multiplicities drawn as rings: a root of multiplicity m has a ring for each of 2..m (×2: one ring)."""


def plane_data(pic: RootsPicture, scale: str = "linear") -> tuple[tuple[np.ndarray, ...], tuple[float, float], tuple[float, float]]:
    """The uPlot data of the complex-plane picture.

    Columns: x, the positive axis, real roots (a dot), the tangency's positive double root,
    complex roots, then one column per multiplicity of :data:`RINGS`: every real root of
    multiplicity m >= k has a ring in column "×k", positive or negative (a double root is never
    one plain dot: a quartic's four roots are all counted).

    Returns:
        (data arrays, x range, y range). x ascending (uPlot's aligned mode); each row is one
        root (NaN in the columns it is not drawn in); the axis series is 0 on every row with
        x >= 0 so that it draws as one thick segment along T > 0.

    Examples:
        >>> from app.scene.pair.roots import roots_of_pencil
        >>> data, xr, yr = plane_data(roots_of_pencil([-1, 0, 2, 0, -1]), "linear")
        >>> [np.nan_to_num(a, nan=9).tolist() for a in data][:6]   # T = -1 (double), T = 1 (double)
        [[-1.0, 0.0, 1.0, 1.5], [9.0, 0.0, 0.0, 0.0], [0.0, 9.0, 9.0, 9.0], [9.0, 9.0, 0.0, 9.0], [9.0, 9.0, 9.0, 9.0], [0.0, 9.0, 0.0, 9.0]]
    """
    pts: list[tuple[float, float, int, int]] = []
    for r in pic.roots:
        rx, ry = float(_f(r.re, scale)), float(_f(r.im, scale))
        kind = 3 if not r.real else (2 if r.mult >= 2 and r.re > 0 else 1)  # 2: the tangency's positive double root
        pts.append((rx, ry, kind, r.mult if r.real else 1))
    xs = [p[0] for p in pts] or [0.0]
    span = max([1.0, *(abs(v) for v in xs)])
    xmax = max([*xs, 0.0]) + 0.5 * span
    pts += [(0.0, 0.0, 0, 1), (xmax, 0.0, 0, 1)]
    pts.sort(key=lambda p: (p[0], p[2]))
    n = len(pts)
    cols = [np.full(n, np.nan) for _ in range(4 + len(RINGS))]
    x = np.array([p[0] for p in pts])
    for i, (px, py, kind, mult) in enumerate(pts):
        if kind:
            cols[kind][i] = py
        for j, k in enumerate(RINGS):
            if kind and mult >= k:
                cols[4 + j][i] = py
        if px >= 0:
            cols[0][i] = 0.0
    ys = [abs(p[1]) for p in pts]
    lo = min(float(x.min()), -0.25 * span)
    yspan = max(max(ys) * 1.3, 0.35 * (xmax - lo))
    return (x, *cols), (lo - 0.1 * span, xmax), (-yspan, yspan)


def locus_data(
    ts: np.ndarray, real_roots: np.ndarray, events: Sequence[tuple[float, float | None]], t: float, scale: str = "asinh"
) -> tuple[tuple[np.ndarray, ...], tuple[float, float]]:
    """The uPlot data of the root locus: (t, root_1..root_n, T = 0, α_1..α_k, double roots, t now).

    uPlot joins the points of a series across NaN (it only breaks lines at null), so the roots
    are drawn as sample points and each event is a series of its own: a vertical line made of
    the only two values of its series.

    Args:
        ts: sample times (ascending).
        real_roots: (len(ts), n) real roots per sample, NaN-padded (:func:`app.scene.pair.roots.locus`).
        events: (time, double root position or None) of each certified event.
        t: the current time (cursor).
        scale: "asinh" or "linear" (the y axis: T or asinh T; linear: clipped to 1.5 times the
            10th / 90th percentiles of the roots drawn, so that a root running off to 10^4 leaves
            the others readable).
    """
    n_t = len(ts)
    ys = [_f(real_roots[:, k], scale) for k in range(real_roots.shape[1])]
    finite = np.concatenate([y[np.isfinite(y)] for y in ys]) if ys else np.zeros(1)
    top = float(np.max(finite)) if finite.size else 1.0
    bot = float(np.min(finite)) if finite.size else -1.0
    if scale == "linear" and finite.size:  # a root running off to 10^4 must not flatten the others: clipped
        top = min(top, 1.5 * float(np.percentile(finite, 90)))
        bot = max(bot, 1.5 * float(np.percentile(finite, 10)))
    top, bot = max(top, 0.5), min(bot, -0.5)
    pad = 0.08 * (top - bot)
    zero = np.zeros(n_t)
    lines = []
    dbl = np.full(n_t, np.nan)
    for te, pos in events:
        ev = np.full(n_t, np.nan)
        lines.append(ev)
        if not ts[0] <= te <= ts[-1]:
            continue
        i = min(int(np.searchsorted(ts, te)), n_t - 2)
        ev[i], ev[i + 1] = top + pad, bot - pad  # a vertical line (between two samples)
        if pos is not None:
            dbl[i] = float(_f(pos, scale))
    cur = np.full(n_t, np.nan)
    i = min(max(int(np.searchsorted(ts, t)), 0), n_t - 2)
    cur[i], cur[i + 1] = top + pad, bot - pad
    return (ts, *ys, zero, *lines, dbl, cur), (bot - pad, top + pad)


def _sign_word(sign: int | None) -> str:
    return {1: "> 0", -1: "< 0", 0: "= 0"}.get(sign, "not needed") if sign is not None else "not needed"


def roots_words(pic: RootsPicture, expl: dict[str, Any] | None, where: str, *, hidden: bool = False) -> str:
    """The picture in the paper's words: the roots, Var, s0, s1, s1,0, the rule, the relation.

    ``hidden``: a lesson's question is open: the roots and signs (what the class predicts from)
    without the rule and the relation.
    """
    lines = [f"**P(T) = det(T A + B)** {html.escape(where)}: {pic.summary()}."]
    reals = [r for r in pic.roots if r.real]
    if reals:
        parts = []
        for r in reals:
            what = {2: "double root (×2)", 3: "triple root (×3)", 4: "quadruple root (×4)"}.get(r.mult, "root")
            if r.interval is None:
                enc = f" ≈ {r.re:.6g}"
            elif f"{r.interval[0]:.10g}" == f"{r.interval[1]:.10g}":  # a ball of radius 0: exact
                enc = f" = {r.re:.10g}"
            else:
                enc = f" ∈ [{r.interval[0]:.10g}, {r.interval[1]:.10g}]"
            parts.append(f"{what} T{enc}")
        lines.append("Real roots: " + "; ".join(parts) + ".")
    if expl is not None and expl.get("coefficients"):
        signs = "".join({1: "+", -1: "−", 0: "0"}.get(q.get("sign"), "?") if q else "?" for q in reversed(expl["coefficients"]))
        s = {k: (expl.get(k) or {}).get("sign") if expl.get(k) else None for k in ("s0", "s1", "s10")}
        lines.append(
            f"Var({', '.join(signs)}) = **{expl['var']}** (Descartes: at most {expl['var']} positive roots) · "
            f"s0 {_sign_word(s['s0'])} · s1 {_sign_word(s['s1'])} · s1,0 {_sign_word(s['s10'])}"
        )
        if hidden:
            lines.append("Rule ⇒ relation: press *Reveal the answer* (Lesson folder).")
        else:
            lines.append(f"Rule: {html.escape(expl.get('rule_text', ''))} ⇒ **{str(expl.get('relation', '')).upper()}**.")
    lines.append(
        "The paper: two distinct positive roots ⇔ separate; a positive double root ⇔ tangent (Th. 7/19); "
        "otherwise (complex or negative roots) overlap."
    )
    for note in pic.notes:
        if hidden and "(certified)" in note:  # the certified relation, said in the note
            continue
        lines.append(f"*{html.escape(note)}.*")
    lines.append(f"<span style='color:#666;font-size:11px'>How: {html.escape(pic.how)}.</span>")
    return "\n\n".join(lines)


class RootsView:
    """The roots panel of one tab: a switch, the words and two uPlot plots (built when shown)."""

    def __init__(self, gui: viser.GuiApi, *, expand: bool = False) -> None:
        self._gui = gui
        with gui.add_folder("Roots of P(T) (the paper's picture)", expand_by_default=expand) as folder:
            self.folder = folder
            self.show_roots = gui.add_checkbox(
                "Show the roots of P(T)", False, hint="the roots of det(T A + B) at t, and over a motion the real roots against t"
            )
            self.axes = gui.add_dropdown("Roots axes", list(SCALE_WORDS), initial_value="linear",
                                         hint="linear: T itself; asinh: roots near 0 and far from 0 both readable")
            self.axes_words = gui.add_markdown(SCALE_WORDS["linear"])
            gui.add_markdown("<span style='font-size:11px;color:#555'>The plots: in the window “Roots of P(T)” on the "
                             "left of the scene (drag its title to move it).</span>")
            self.words = gui.add_markdown("")
        self.window: Any = None
        """The floating window of the plots (a viser panel), or None while they are off."""
        self.window_tab: Any = None
        self.plane: viser.GuiUplotHandle | None = None
        self.locus_plot: viser.GuiUplotHandle | None = None
        self._plane_key: Any = None
        self._locus_key: Any = None
        self._words = ""
        self._cache: dict[Any, RootsPicture] = {}
        self._locus_cache: dict[Any, tuple[np.ndarray, np.ndarray, list[tuple[float, float | None]]]] = {}
        self._cursor = -1

    def _window(self) -> Any:
        """The floating window the plots are drawn in (made on first use).

        Beside the panel, not at the bottom of it: at 1280x720 the folder's plots were below the
        fold of a long panel (issue 55); the window is docked on the left of the scene (the scene
        keeps the middle), and a teacher can move it.
        """
        if self.window is None:
            self.window = self._gui.add_panel()
            self.window_tab = self.window.add_tab("Roots of P(T)")
            self.window.dock_left()
            self.window.set_width(WINDOW_WIDTH)
        return self.window_tab

    @property
    def scale(self) -> str:
        """The roots picture's axes: "linear" (the default) or "asinh"."""
        return "asinh" if self.axes.value == "asinh" else "linear"

    @property
    def on(self) -> bool:
        """True when the panel is switched on."""
        return bool(self.show_roots.value)

    def clear(self) -> None:
        """Remove the plots (switched off)."""
        for h in (self.plane, self.locus_plot):
            if h is not None:
                h.remove()
        self.plane = self.locus_plot = None
        if self.window is not None:
            self.window.remove()
            self.window = self.window_tab = None
        self._plane_key = self._locus_key = None
        if self._words:
            self._words = ""
            self.words.content = ""

    # ------------------------------------------------------------------ the picture at t
    def picture(self, state: Any) -> tuple[RootsPicture | None, str]:
        """The roots at the tab's instant and where that is ("at t = …", "(static shapes)")."""
        model, an = state.motion, state.analysis
        if model is None:
            key: Any = ("static", repr(state.shapes["A"].quadric()), repr(state.shapes["B"].quadric()))
            if key not in self._cache:
                from core.formulae.pencil import pencil_coefficients

                try:
                    A, B = state.shapes["A"].quadric(), state.shapes["B"].quadric()
                    self._remember(key, roots_of_pencil(_exact(pencil_coefficients(_exact_matrix(A), _exact_matrix(B)))))
                except (ValueError, ArithmeticError):
                    return None, ""
            return self._cache[key], "(static shapes)"
        if an is None:
            return None, ""
        event = state.event
        if event is not None:
            ev = an.events[event - 1]
            t: Any = ev.event.time
            where = f"at t = α{event} {ev.shown}"
        elif state.t_exact is not None:
            t, where = state.t_exact, f"at t = {state.t_text or state.t_exact}"
        else:
            t, where = an.inside(state.t), f"at t = {state.t_text or format(state.t, '.6g')}"
        key = (id(an), repr(t), event)
        if key not in self._cache:
            self._remember(key, roots_at(list(an.result.a), t, state.t, state.relation))
        return self._cache[key], where

    def _remember(self, key: Any, pic: RootsPicture) -> None:
        if len(self._cache) > 512:
            self._cache.clear()
        self._cache[key] = pic

    def show(self, state: Any, expl: dict[str, Any] | None, scale: str) -> None:
        """The panel for the tab's state (removed when switched off)."""
        if not self.on:
            self.clear()
            return
        if self.axes_words.content != SCALE_WORDS[scale]:
            self.axes_words.content = SCALE_WORDS[scale]
        pic, where = self.picture(state)
        if pic is None:
            self._set_words("No certified pair to show (invalid shapes, or the motion is being analysed).")
            return
        self._set_words(roots_words(pic, expl, where, hidden=bool(getattr(state, "answer_hidden", False))))
        data, xr, yr = plane_data(pic, scale)
        if self.plane is None or self._plane_key != (len(data[0]), scale):
            if self.plane is not None:
                self.plane.remove()
            with self._window():
                self.plane = self._gui.add_uplot(
                    data,
                    (
                        uplot.Series(label="Re T" if scale == "linear" else "asinh Re T"),
                        uplot.Series(label="T > 0 (positive real axis)", stroke=AXIS_COLOUR, width=7, points={"show": False}),
                        # a marker in the legend: uPlot draws a series' marker from its points' stroke when the line has no width
                        uplot.Series(label="real root", stroke="rgba(0,0,0,0)", width=0,
                                     points={"show": True, "size": 11, "fill": ROOT_COLOURS[0], "stroke": ROOT_COLOURS[0], "width": 2}),
                        uplot.Series(label="positive double root (tangency)", stroke="rgba(0,0,0,0)", width=0,
                                     points={"show": True, "size": 20, "fill": "#ffbf00", "stroke": "#000", "width": 2}),
                        uplot.Series(label="complex pair", stroke="rgba(0,0,0,0)", width=0,
                                     points={"show": True, "size": 10, "fill": "#d62728", "stroke": "#d62728", "width": 2}),
                        *(uplot.Series(label=RING_LABELS[k], stroke="rgba(0,0,0,0)", width=0,
                                       points={"show": True, "size": 26 + 10 * (k - 2), "fill": "rgba(0,0,0,0)", "stroke": "#222",
                                               "width": 2}) for k in RINGS),
                    ),
                    title="Roots of P(T) in the complex plane",
                    scales={"x": {"time": False, "auto": False, "range": list(xr)}, "y": {"auto": False, "range": list(yr)}},
                    axes=(uplot.Axis(label="Re T" if scale == "linear" else "asinh(Re T)"),
                          uplot.Axis(label="Im T" if scale == "linear" else "asinh(Im T)")),
                    legend={"show": True, "live": False},
                    aspect=1.6,
                )
            self._plane_key = (len(data[0]), scale)
        else:
            wire.set_uplot_data(self.plane, data)
            self.plane.scales = {"x": {"time": False, "auto": False, "range": list(xr)}, "y": {"auto": False, "range": list(yr)}}
        self._show_locus(state, scale)

    def _set_words(self, text: str) -> None:
        if text != self._words:
            self._words = text
            self.words.content = text

    # ------------------------------------------------------------------ the locus over a motion
    def _show_locus(self, state: Any, scale: str) -> None:
        an = state.analysis
        if state.motion is None or an is None:
            if self.locus_plot is not None:
                self.locus_plot.remove()
                self.locus_plot = None
                self._locus_key = None
            return
        lkey = id(an)
        if lkey not in self._locus_cache:
            if len(self._locus_cache) > 16:
                self._locus_cache.clear()
            ts = np.asarray(an.samples_t, dtype=float)
            evs: list[tuple[float, float | None]] = []
            for e in an.events:
                pos = None
                if e.relation == "tangent":
                    pic = roots_at(list(an.result.a), e.event.time, e.t, e.relation)
                    dbl = [r for r in pic.roots if r.real and r.mult >= 2 and r.re > 0]
                    pos = dbl[0].re if dbl else None
                evs.append((e.t, pos))
            self._locus_cache[lkey] = (ts, locus(list(an.result.a), ts), evs)
        ts, real, evs = self._locus_cache[lkey]
        data, yr = locus_data(ts, real, evs, state.t, scale)
        if self.locus_plot is None or self._locus_key != (lkey, scale):
            if self.locus_plot is not None:
                self.locus_plot.remove()
            n = real.shape[1]
            with self._window():
                self.locus_plot = self._gui.add_uplot(
                    data,
                    (
                        uplot.Series(label="t"),
                        *(uplot.Series(label=f"real root {k + 1}", stroke="rgba(0,0,0,0)", width=0,
                                       points={"show": True, "size": 3, "fill": ROOT_COLOURS[k % 4], "stroke": ROOT_COLOURS[k % 4],
                                               "width": 2})
                          for k in range(n)),
                        uplot.Series(label="T = 0", stroke="#999", width=1, points={"show": False}),
                        *(uplot.Series(label=f"α{k + 1} (certified)", stroke="#000", width=1.5,
                                       points={"show": False}) for k in range(len(evs))),
                        uplot.Series(label="double root", stroke="rgba(0,0,0,0)", width=0,
                                     points={"show": True, "size": 14, "fill": "#ffbf00", "stroke": "#000", "width": 2}),
                        uplot.Series(label="t now", stroke="#1f4e9c", width=2, points={"show": False}),
                    ),
                    title="Root locus: real roots of P(T) against t",
                    scales={"x": {"time": False, "auto": False, "range": [float(ts[0]), float(ts[-1])]},
                            "y": {"auto": False, "range": list(yr)}},
                    axes=(uplot.Axis(label="t"), uplot.Axis(label="T" if scale == "linear" else "asinh(T)")),
                    legend={"show": True, "live": False},
                    aspect=1.6,
                )
            self._locus_key = (lkey, scale)
            self._cursor = -1
            return
        index = int(np.searchsorted(ts, state.t))
        if index != self._cursor:
            self._cursor = index
            wire.set_uplot_data(self.locus_plot, data)


def _exact_matrix(M: Any) -> list[list[Any]]:
    from core.shapes.numbers import to_fmpq

    return [[to_fmpq(v) for v in row] for row in M]


def _exact(coeffs: Any) -> list[Any]:
    return list(coeffs)

