"""Fills the GUI panel from the tab's state: readout, timeline, plots, motion editor, shape fields.

:meth:`PanelView.show` is the panel half of ``Session.refresh``: it is idempotent and sends only
what changed (texts are compared with the last text sent, values with the handle's value), so
it can run at 20 Hz while scrubbing. What belongs to one analysis (event buttons, sign table,
slider range, plots) is rebuilt only when the analysis shown changes; what belongs to one
motion (the editor texts) only when the motion changes, never under the user's typing.
"""

from __future__ import annotations

import html
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import partial
from typing import Any

import viser

from ..common.shapes import PALETTES
from ..common.state import AppState, ShapeState, StatusError
from ..common.texts import APPROX
from .analysis import AnalysisView
from .gui import DIM_LABELS, STATIC, TOUCH, TYPED, Gui, ignoring_event
from .motion_form import form_from_source
from .panels import (
    HIDDEN,
    copy_button,
    events_html,
    intervals_bar_html,
    legend_html,
    readout_markdown,
    sign_table_markdown,
)
from .plots import SCALES, PlotsView
from .words import plain_words

__all__ = ["PanelView", "Syncing", "error_html"]


def error_html(message: str) -> str:
    """A field error in red (typed text is escaped: a shared scene shows it to every tab)."""
    return f'<span style="color:#d62728">⚠ {html.escape(message)}</span>'


class Syncing:
    """Flag raised while Python assigns GUI values.

    viser runs ``on_update`` for those too: controllers ignore the callbacks it raises.
    """

    def __init__(self) -> None:
        self._depth = threading.local()

    @property
    def active(self) -> bool:
        """True inside :meth:`__call__`'s context on this thread."""
        return getattr(self._depth, "n", 0) > 0

    @contextmanager
    def __call__(self) -> Iterator[None]:
        """Raise the flag on this thread for the duration of the ``with`` block."""
        self._depth.n = getattr(self._depth, "n", 0) + 1
        try:
            yield
        finally:
            self._depth.n -= 1


class PanelView:
    """The panel half of the view: shows an :class:`AppState` in a :class:`Gui`.

    Args:
        gui: the typed handles.
        gui_api: where new handles go (event buttons, plots).
        syncing: raised while values are assigned from here.
        on_event: called with k when the "Jump to α_k" button is clicked.
    """

    def __init__(self, gui: Gui, gui_api: viser.GuiApi, syncing: Syncing, on_event: Callable[[int], object]) -> None:
        self.gui = gui
        self._api = gui_api
        self._syncing = syncing
        self._on_event = on_event
        self.plots = PlotsView(gui_api, gui.plots.folder)
        self._last: dict[int, str] = {}
        self._taken: dict[int, Any] = {}
        """Per field the user types into: the value the server last showed in it or read from it.
        A field showing anything else holds an edit its handler has not read yet (see set_field)."""
        self._motion_shown: object = None
        self._analysis_shown: object = None
        self._palette_shown: str | None = None
        self._hidden = False
        """A lesson's question is open (the state's ``answer_hidden`` as last shown)."""
        self.palette: dict[str, str] = next(iter(PALETTES.values()))
        self.expl: dict[str, Any] | None = None
        """The readout's data last shown (the roots panel names the same Var, signs and rule)."""

    # ------------------------------------------------------------------ primitives
    def set_value(self, handle: Any, value: Any) -> None:
        """Assign a GUI value from Python (only if it differs) without running our callbacks."""
        if handle.value == value:
            return
        with self._syncing():
            handle.value = value

    def set_field(self, handle: Any, text: str) -> None:
        """A field the user types into shows ``text``, unless it holds an edit not yet read.

        viser stores a tab's edit in the handle and then calls its handler, which waits for the
        session lock while a deferred draw may hold it: overwriting the field then (the state does
        not have the edit yet) would lose the edit, the handler reading back the old text. The
        handler reads the field with :meth:`take`; its refresh then shows the state's text.
        """
        if handle.value != self._taken.get(id(handle), handle.value):
            return
        self._taken[id(handle)] = text
        self.set_value(handle, text)

    def take(self, handle: Any) -> Any:
        """The value of a field the user typed into, as its handler reads it (see :meth:`set_field`)."""
        value = handle.value
        self._taken[id(handle)] = value
        return value

    def set_text(self, handle: Any, text: str) -> None:
        """Markdown/HTML content, sent only when it changed."""
        if self._last.get(id(handle)) != text:
            self._last[id(handle)] = text
            handle.content = text

    def set_error(self, handle: viser.GuiMarkdownHandle, message: str | None) -> None:
        """Show ``message`` next to a field, or hide the error."""
        if message is None:
            if handle.visible:
                handle.visible = False
        else:
            self.set_text(handle, error_html(message))
            if not handle.visible:
                handle.visible = True

    @staticmethod
    def set_visible(handle: Any, visible: bool) -> None:
        """Visibility, sent only when it changed."""
        if handle.visible != visible:
            handle.visible = visible

    # ------------------------------------------------------------------ the panel
    def show(self, state: AppState, *, plots: bool = True) -> None:
        """Everything of the panel for ``state`` (``plots=False``: the plot cursor waits)."""
        g = self.gui
        self.set_value(g.view.dimension, DIM_LABELS[state.dim])
        self.set_value(g.view.palette, state.palette)
        self.set_value(g.view.gizmos, state.gizmos)
        self.set_visible(g.view.gizmo_note, state.motion is not None and state.gizmos)
        self.set_value(g.view.plane, state.separating_plane)
        self.set_value(g.view.follow, state.follow)
        self.set_value(g.plots.live, state.show_plots)
        self.palette = PALETTES.get(state.palette, next(iter(PALETTES.values())))
        if self._palette_shown != state.palette:  # colours of the analysis panels too
            self._palette_shown = state.palette
            self._analysis_shown = None
            self.set_text(g.legend, legend_html(self.palette))
        if self._hidden != state.answer_hidden:  # the sign table and event list say the relation
            self._hidden = state.answer_hidden
            self._analysis_shown = None
        self._show_readout(state)
        self.set_error(g.share.error, state.errors.get("config"))
        self.set_error(g.touch_error, state.errors.get("touch"))
        self.set_visible(g.share.analysis_json, state.analysis is not None)
        self.set_visible(g.share.analysis_csv, state.analysis is not None)
        self._show_shapes(state)
        self._show_motion(state)
        self._show_timeline(state)
        if plots:
            self.show_plots(state)

    def _show_readout(self, state: AppState) -> None:
        g = self.gui
        model, an = state.motion, state.analysis
        expl: dict[str, Any] | None = None
        if model is None:
            if state.explanation is None:
                text = readout_markdown(None, error=state.errors.get("shapes", "no shapes"))
            else:
                w = state.witness
                expl = state.explanation
                text = readout_markdown(expl, where="(static shapes)", witness=None if w is None else w.readout(), palette=self.palette,
                                        hidden=state.answer_hidden)
        elif an is None:
            text = readout_markdown(None, error="analysing the motion…" if state.analysing else state.status or "no analysis")
        else:
            event = state.event
            if event is not None:
                ev = an.events[event - 1]
                where, at = f"at t = α{event} {ev.shown}", None
            elif state.t_exact is not None:
                where, at = f"at t = {state.t_text or state.t_exact}", state.t_exact
            else:
                where, at = f"at t = {state.t_text or format(state.t, '.6g')}", an.inside(state.t)  # as typed ("3/4")
            expl = an.readout_at(model, at, state.t, event)
            if expl is None:
                expl = {"n": an.n, "relation": state.relation, "certified_by": "exact", "coefficients": [], "var": 0, "rule_text": ""}
            text = readout_markdown(expl, where=where, palette=self.palette, hidden=state.answer_hidden)
        self.set_text(g.readout, text)
        words = plain_words(expl)
        if state.answer_hidden and words:  # the signs in words, not the decision
            words = words.split("\n\n**Decided**", 1)[0] + f"\n\n{HIDDEN}"
        self.set_text(g.words, words)
        self.expl = expl

    def _show_shapes(self, state: AppState) -> None:
        for name, sg in self.gui.shapes.items():
            err = state.errors.get(f"shape {name}")
            self.set_error(sg.error, err)
            if err is not None:
                continue  # keep the text the user is correcting
            texts = state.shapes[name].field_texts()
            for key, text in texts.items():
                self.set_field(sg.fields[key], text)
            self._show_exact(state, name, sg, any(t.startswith(APPROX) for t in texts.values()))

    def _show_exact(self, state: AppState, name: str, sg: Any, rounded: bool) -> None:
        """Under rounded ("≈") fields: what they are rounded from, and the exact value one click away."""
        if not rounded:
            self.set_visible(sg.exact, False)
            return
        model, an = state.motion, state.analysis
        if model is not None and an is not None:
            if state.event is not None:
                t: Any = an.events[state.event - 1].event.time
            else:
                t = state.t_exact if state.t_exact is not None else an.inside(state.t)
            try:
                exact = model.exact_matrix_text(name, t)
            except (ValueError, ArithmeticError):
                exact = None
            why = "≈: the pose drawn at t, rounded; the relation is certified at the exact t."
        elif model is None and state.shapes[name].matrix is not None:
            exact, why = None, "≈: the float decomposition of the typed matrix; the Matrix field is what is certified."
        elif model is None:
            sh = state.shapes[name]
            exact = None if sh.matrix is not None else "; ".join(", ".join(str(v) for v in row) for row in _exact_rows(sh))
            why = "≈: float64 numbers (read as floats); the float64 matrix they give is what is certified."
        else:
            exact, why = None, "≈: the pose drawn at t, rounded (the motion is being analysed)."
        html_ = f'<span style="font-size:11px;color:#555">{html.escape(why)}</span>'
        if exact is not None:
            html_ += copy_button(exact, "copy the exact matrix")
        self.set_text(sg.exact, html_)
        self.set_visible(sg.exact, True)

    def _show_motion(self, state: AppState) -> None:
        mg = self.gui.motion
        model = state.motion
        if model is not self._motion_shown:
            self._motion_shown = model
            # the dropdown says what the tab shows: a preset, a typed motion, Touch's, or static shapes
            if model is None or model.preset:
                label, options = (model.preset if model is not None else STATIC), (STATIC, *mg.presets)
            else:
                label = TOUCH if model.kind == "touch" else TYPED
                options = (STATIC, label, *mg.presets)
            with self._syncing():
                if tuple(mg.preset.options) != options:
                    mg.preset.options = options
            self.set_value(mg.preset, label)
            if model is not None:
                for key, text in model.texts().items():
                    self.set_value(mg.fields[key], text)
                for name in ("A", "B"):  # the form too, when the motion has the "shape" form
                    form = form_from_source(getattr(model, name).source)
                    for key, handle in mg.form[name].items():
                        self.set_value(handle, "" if form is None else form[key])
            self.set_text(mg.description, model.description if model is not None else "")
        for key, md in mg.errors.items():
            self.set_error(md, state.errors.get(key))
        self.set_error(mg.form_error, state.errors.get("form"))
        self.set_visible(mg.progress, state.analysing)
        if state.analysing and mg.progress.value != 10.0:
            mg.progress.value = 10.0  # type: ignore[misc]  # writable: viser defines the setter apart from the getter, mypy sees read-only
        self.set_text(mg.status, error_html(state.status) if isinstance(state.status, StatusError) else state.status)

    def _show_timeline(self, state: AppState) -> None:
        tg = self.gui.timeline
        model, an = state.motion, state.analysis
        self.set_visible(tg.folder, model is not None)
        self.set_visible(self.gui.plots.folder, an is not None)
        if an is not self._analysis_shown:
            self._analysis_shown = an
            self._rebuild_analysis(an)
        if an is None:
            return
        t, event = state.t, state.event
        lo, hi = an.window
        self.set_value(tg.slider, min(max(t, tg.slider.min), tg.slider.max))
        if event is not None:
            self.set_value(tg.t_box, an.events[event - 1].typed)
        elif state.t_exact is not None:
            self.set_value(tg.t_box, state.t_text or str(state.t_exact))
        elif state.t_text is not None:  # a float typed as text ("3/4"): the box keeps the text
            self.set_value(tg.t_box, state.t_text)
        else:
            self.set_value(tg.t_box, repr(t) if len(repr(t)) < 12 else f"{t:.6g}")
        self.set_error(tg.t_error, state.errors.get("t"))
        palette = {} if self._hidden else self.palette  # an open question: grey intervals
        self.set_text(tg.bar, intervals_bar_html(lo, hi, an.segments, [(e.t, e.relation) for e in an.events], t, palette=palette))

    def _rebuild_analysis(self, an: AnalysisView | None) -> None:
        """What belongs to one analysis: slider range, event list and buttons, sign table."""
        tg = self.gui.timeline
        for b in tg.event_buttons:
            b.remove()
        tg.event_buttons = []
        if an is None:
            self.set_text(tg.events_md, "")
            self.set_text(tg.bar, "")
            self.set_text(self.gui.sign_table, "")
            self.plots.clear()
            return
        lo, hi = an.window
        with self._syncing():
            tg.slider.min, tg.slider.max = lo, hi
            tg.slider.step = (hi - lo) / 1000 or 1e-3
        for ev in an.events:
            with tg.events_folder:
                btn = self._api.add_button(f"Jump to α{ev.k} ≈ {ev.t:.6f}")
            btn.on_click(ignoring_event(partial(self._on_event, ev.k)))
            tg.event_buttons.append(btn)
        if self._hidden:  # an open question: the relations of the events and intervals wait for Reveal
            self.set_text(tg.events_md, "")
            self.set_text(self.gui.sign_table, HIDDEN)
            return
        self.set_text(tg.events_md, events_html(an.events, self.palette))
        self.set_text(self.gui.sign_table, sign_table_markdown(an.sign_rows(), an.n, self.palette))

    def show_plots(self, state: AppState) -> None:
        """The plots of the analysis with the cursor at t (removed when off or no analysis).

        Also the roots of P(T) (when switched on): like the plot cursor, never on the hot path of
        a jump or a drag, but with the coalesced part of the refresh (within PANEL_PERIOD).
        """
        self.gui.roots.show(state, self.expl, self.gui.roots.scale)
        an = state.analysis
        self.set_value(self.gui.plots.scale, state.plot_scale)
        self.set_text(self.gui.plots.about, f"y axis: {SCALES[state.plot_scale]}. Only signs and zeros carry meaning "
                      "(each curve is known up to a positive factor); the dots on y = 0 are the events, the "
                      "vertical line is t.")
        if an is None or not state.show_plots:
            self.plots.clear()
            return
        self.plots.show(
            an,
            an.samples_t,
            an.coeff_series(),
            an.subres_series(),
            [e.t for e in an.events],
            state.t,
            scale="linear" if state.plot_scale == "linear" else "asinh",
        )


def _exact_rows(shape: ShapeState) -> list[list[Any]]:
    """The exact matrix a shape with float parameters is certified as (its float64 matrix, exactly)."""
    from core.shapes.numbers import to_fmpq

    return [[to_fmpq(v) for v in row] for row in shape.quadric()]
