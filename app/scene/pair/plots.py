"""uPlot plots over I of a_i(t) and of s0(t), s1(t), s1,0(t), with a t cursor and event markers.

The curves span many orders of magnitude (s0 has degree 84 in Example 30), so by default each
is drawn as asinh(y / s) with s a low percentile of its |samples| (:func:`compress`): zeros and
signs stay where they are, large values are compressed logarithmically. The other scale,
"linear", divides each curve by its largest |value|. Only signs and zeros of these curves
carry meaning (each polynomial is known up to a positive factor), and the y axis says which
scale is shown.

:class:`PlotsView` builds a plot per analysis with exactly one series per curve, then the
cursor series and the event series (uPlot shares one x array), with the x range fixed to the
window of I: a new analysis (another preset, 2D <-> 3D) gets fresh plots, never a stale series
layout or x range. A t-step only moves the cursor (one data message, at most 20 per second).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np
import viser
import viser.uplot as uplot

from ..common import wire

__all__ = ["compress", "PlotData", "PlotsView", "SERIES_COLORS", "SCALES"]

SERIES_COLORS = ["#1f77b4", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2"]
"""Colours of the data series (distinct from the relation colours)."""

Scale = Literal["asinh", "linear"]
SCALES: dict[str, str] = {
    "asinh": "asinh(y / s), s = 20th percentile of |y|: sign and zeros kept, large values compressed",
    "linear": "y / max |y| on I: sign and zeros kept",
}
"""Plot scales and what their y axis shows."""


def compress(y: np.ndarray, scale: Scale = "asinh") -> np.ndarray:
    """Sign-preserving compression of one curve for plotting.

    "asinh": asinh(y / s), s = 20th percentile of the nonzero |y| (linear near 0, logarithmic
    for |y| >> s); "linear": y / max |y|.

    Examples:
        >>> compress(np.array([-100.0, -1.0, 0.0, 1.0, 100.0])).round(2).tolist()
        [-5.3, -0.88, 0.0, 0.88, 5.3]
        >>> compress(np.array([-4.0, 0.0, 2.0]), "linear").tolist()
        [-1.0, 0.0, 0.5]
    """
    y = np.asarray(y, dtype=float)
    nz = np.abs(y[np.isfinite(y) & (y != 0)])
    if scale == "linear":
        return y / (float(nz.max()) if nz.size else 1.0)
    s = float(np.percentile(nz, 20)) if nz.size else 1.0
    return np.arcsinh(y / s)


class PlotData:
    """Compressed series of one plot, computed once per analysis (the cursor is all that moves)."""

    def __init__(self, t: np.ndarray, series: Sequence[tuple[str, np.ndarray]], events: Sequence[float], scale: Scale = "asinh") -> None:
        self.t = np.asarray(t, dtype=float)
        self.names = [name for name, _ in series]
        self.ys = [compress(y, scale) for _, y in series]
        finite = np.concatenate([y[np.isfinite(y)] for y in self.ys]) if self.ys else np.zeros(1)
        self.top = float(np.max(finite)) if finite.size else 1.0
        self.bot = float(np.min(finite)) if finite.size else -1.0
        if self.top - self.bot < 1e-9:  # constant curves: give the cursor some height
            self.top, self.bot = self.top + 1.0, self.bot - 1.0
        n = self.t.shape[0]
        self.ev = np.full(n, np.nan)
        for e in events:
            if self.t[0] <= e <= self.t[-1]:
                self.ev[min(int(np.searchsorted(self.t, e)), n - 1)] = 0.0

    def cursor(self, index: int) -> np.ndarray:
        """The cursor series: a near-vertical segment between samples index and index + 1."""
        n = self.t.shape[0]
        cur = np.full(n, np.nan)
        i = min(max(index, 0), n - 2)
        cur[i], cur[i + 1] = self.top, self.bot
        return cur

    def data(self, index: int) -> tuple[np.ndarray, ...]:
        """(t, curves..., cursor, events): the arrays of the plot with the cursor at ``index``."""
        return (self.t, *self.ys, self.cursor(index), self.ev)


def _add_plot(gui: viser.GuiApi, title: str, data: PlotData, index: int, scale: Scale) -> viser.GuiUplotHandle:
    series = (
        uplot.Series(label="t"),
        *(uplot.Series(label=name, stroke=SERIES_COLORS[i % 5], width=1.5) for i, name in enumerate(data.names)),
        uplot.Series(label="t now", stroke="#1f4e9c", width=2, points={"show": False}),
        uplot.Series(label="events", stroke="rgba(0,0,0,0)", width=0, points={"show": True, "size": 7, "fill": "#000"}),
    )
    pad = 0.05 * (data.top - data.bot) or 1.0
    return gui.add_uplot(
        data.data(index),
        series,
        title=title,
        # fixed ranges: uPlot's auto-range does not skip the NaN gaps of the cursor/event series
        scales={
            "x": {"time": False, "auto": False, "range": [float(data.t[0]), float(data.t[-1])]},
            "y": {"auto": False, "range": [data.bot - pad, data.top + pad]},
        },
        axes=(uplot.Axis(label="t"), uplot.Axis(label="asinh(y / s)" if scale == "asinh" else "y / max|y|")),
        legend={"show": True, "live": False},
        aspect=1.6,
    )


class PlotsView:
    """The two plots of a tab inside the Plots folder: rebuilt per analysis, cursor per t."""

    def __init__(self, gui: viser.GuiApi, folder: viser.GuiFolderHandle) -> None:
        self._gui = gui
        self._folder = folder
        self.coeffs: viser.GuiUplotHandle | None = None
        self.subres: viser.GuiUplotHandle | None = None
        self._shown: tuple[object, str] | None = None
        self._data: tuple[PlotData, PlotData] | None = None
        self._index = -2

    def clear(self) -> None:
        """Remove the plots (no analysis, or plots switched off)."""
        for h in (self.coeffs, self.subres):
            if h is not None:
                h.remove()
        self.coeffs = self.subres = None
        self._shown = None
        self._data = None
        self._index = -2

    def show(
        self,
        key: object,
        t_grid: np.ndarray,
        coeffs: Sequence[tuple[str, np.ndarray]],
        subres: Sequence[tuple[str, np.ndarray]],
        events: Sequence[float],
        t: float,
        scale: Scale = "asinh",
    ) -> None:
        """Plots of one analysis (``key``: its identity) with the cursor at t.

        Args:
            key: identifies the analysis; a new key rebuilds the plots.
            t_grid: sample times (ascending; the x range is [first, last]).
            coeffs: (label, samples) of a_n..a_0.
            subres: (label, samples) of s0, s1, s1,0.
            events: event times (floats, markers).
            t: current time (cursor).
            scale: "asinh" or "linear".
        """
        index = int(np.searchsorted(t_grid, t))
        if self._shown != (key, scale):
            self.clear()
            self._data = (PlotData(t_grid, coeffs, events, scale), PlotData(t_grid, subres, events, scale))
            with self._folder:
                what = "asinh" if scale == "asinh" else "linear"
                self.coeffs = _add_plot(self._gui, f"a_i(t) of P(T) ({what})", self._data[0], index, scale)
                self.subres = _add_plot(self._gui, f"s0, s1, s1,0 (t) ({what})", self._data[1], index, scale)
            self._shown = (key, scale)
            self._index = index
            return
        if index == self._index or self._data is None or self.coeffs is None or self.subres is None:
            return
        self._index = index
        wire.set_uplot_data(self.coeffs, self._data[0].data(index))
        wire.set_uplot_data(self.subres, self._data[1].data(index))
