"""uPlot plots over I of a_i(t) and s0(t), s1(t), s1,0(t), sign-preserving asinh compression.

The curves span many orders of magnitude (s0 is a degree-84 polynomial in Example 30), so each
is drawn as asinh(y / scale) with a per-series scale (a low percentile of its absolute samples):
the sign and the zeros are kept, large values are compressed logarithmically. A cursor series marks the
current t; event times are marked by a second series with points only at the events.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import viser.uplot as uplot

from . import wire

__all__ = ["compress", "add_plot", "update_plot", "PlotData", "SERIES_COLORS"]

SERIES_COLORS = ["#1f77b4", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2"]
"""Colours of the data series (distinct from the relation colours)."""


def compress(y: np.ndarray) -> np.ndarray:
    """Sign-preserving compression asinh(y / s); s = 20th percentile of the nonzero |y|.

    Linear near 0 (zeros and sign changes stay where they are), logarithmic for |y| >> s, so
    one curve spanning many orders of magnitude stays readable.

    Examples:
        >>> compress(np.array([-100.0, -1.0, 0.0, 1.0, 100.0])).round(2).tolist()
        [-5.3, -0.88, 0.0, 0.88, 5.3]
    """
    y = np.asarray(y, dtype=float)
    nz = np.abs(y[np.isfinite(y) & (y != 0)])
    s = float(np.percentile(nz, 20)) if nz.size else 1.0
    return np.arcsinh(y / s)


def add_plot(gui: Any, title: str, n_series: int) -> Any:
    """An empty uPlot with ``n_series`` data series, a cursor and event markers (hidden)."""
    x = np.array([0.0, 1.0])
    data = (x,) + tuple(np.zeros(2) for _ in range(n_series + 2))
    series = (
        uplot.Series(label="t"),
        *(uplot.Series(label=f"y{i}", stroke=SERIES_COLORS[i % 5], width=1.5) for i in range(n_series)),
        uplot.Series(label="t now", stroke="#1f4e9c", width=2, points={"show": False}),
        uplot.Series(label="events", stroke="rgba(0,0,0,0)", width=0, points={"show": True, "size": 7, "fill": "#000"}),
    )
    return gui.add_uplot(
        data,
        series,
        title=title,
        scales={"x": {"time": False, "auto": True}, "y": {"auto": True}},
        legend={"show": True, "live": False},
        aspect=1.6,
        visible=False,
    )


class PlotData:
    """Compressed series of one plot, computed once per analysis (the cursor is all that moves)."""

    def __init__(self, t: np.ndarray, series: Sequence[tuple[str, np.ndarray]], events: Sequence[float]) -> None:
        self.t = np.asarray(t, dtype=float)
        self.names = [name for name, _ in series]
        self.ys = [compress(y) for _, y in series]
        finite = np.concatenate([y[np.isfinite(y)] for y in self.ys]) if self.ys else np.zeros(1)
        self.top = float(np.max(finite)) if finite.size else 1.0
        self.bot = float(np.min(finite)) if finite.size else -1.0
        if self.top - self.bot < 1e-9:  # constant curves: give the cursor some height
            self.top, self.bot = self.top + 1.0, self.bot - 1.0
        n = self.t.shape[0]
        self.ev = np.full(n, np.nan)
        for e in events:
            self.ev[min(int(np.searchsorted(self.t, e)), n - 1)] = 0.0

    def cursor(self, index: int) -> np.ndarray:
        """The cursor series: a near-vertical segment between samples index and index + 1."""
        n = self.t.shape[0]
        cur = np.full(n, np.nan)
        i = min(max(index, 0), n - 2)
        cur[i], cur[i + 1] = self.top, self.bot
        return cur


def update_plot(handle: Any, data: PlotData, cursor_index: int, *, labels: bool = False) -> None:
    """Send the series with the cursor at sample ``cursor_index`` (labels only when asked).

    The cursor is a near-vertical segment between two adjacent samples (uPlot shares one x
    array across series); event markers sit on y = 0 at the sample nearest each event.
    """
    if labels:
        # fixed y range: uPlot's auto-range does not skip the NaN gaps of the cursor/event series
        pad = 0.05 * (data.top - data.bot) or 1.0
        handle.scales = {"x": {"time": False, "auto": True}, "y": {"auto": False, "range": [data.bot - pad, data.top + pad]}}
        cfg = list(handle.series)
        for k, name in enumerate(data.names, start=1):
            cfg[k] = {**cfg[k], "label": name, "show": True}
        for k in range(len(data.names) + 1, len(cfg) - 2):
            cfg[k] = {**cfg[k], "show": False}
        handle.series = tuple(cfg)
    ys = list(data.ys)
    while len(ys) < len(handle.series) - 3:
        ys.append(np.zeros_like(data.t))
    wire.set_uplot_data(handle, (data.t, *ys, data.cursor(cursor_index), data.ev))
    if not handle.visible:
        handle.visible = True
