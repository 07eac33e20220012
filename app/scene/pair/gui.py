"""The GUI panel of one tab: every viser handle, typed, built once.

Labels are a contract: tests, screenshots and users find the controls by them.

:func:`build_gui` lays out the panel (readout, timeline, plots, motion editor, shapes, sign table,
view options) and returns a :class:`Gui` of typed handle groups. No behaviour here: controllers
(:mod:`app.scene.pair.control_shapes`, :mod:`app.scene.pair.control_motion`,
:mod:`app.scene.pair.control_timeline`) attach the callbacks, :mod:`app.scene.pair.panel_view` fills in the
contents.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import viser

from ..common.shapes import PALETTES
from .panels import GUIDE_CONCEPTS, guide_link_html
from .plots import SCALES
from .roots_view import RootsView

if TYPE_CHECKING:  # what GuiApi.add_progress_bar returns; viser 1.1.1 does not export it at the top level
    from viser._gui_handles import GuiProgressBarHandle

__all__ = ["Gui", "TimelineGui", "PlotsGui", "MotionGui", "ShapeGui", "ViewGui", "ShareGui", "build_gui", "ignoring_event", "STATIC", "TYPED", "TOUCH", "DIM_LABELS"]

FORM_LABELS = (
    ("center", "Body centre", "x, y[, z] (expressions in t allowed)"),
    ("semi_axes", "Body semi-axes", "a, b[, c]"),
    ("orientation", "Body orientation", "2D: w, z or an angle; 3D: quaternion w, x, y, z (empty: none)"),
    ("translation", "Translation x(t), y(t)[, z(t)]", "e.g. 11 - 12*t, 0, 0 (empty: none)"),
    ("rotation", "Rotation quaternion", "2D: w, z (e.g. 1, t); 3D: w, x, y, z (empty: none)"),
    ("scale", "Scale per axis", "e.g. 1 + t, 1, 1 (empty: none)"),
)
"""Fields of the motion form: key, label, hint."""

STATIC = "(static shapes)"
"""Preset dropdown entry for no motion."""

TYPED = "(typed motion)"
"""Preset dropdown entry shown while a typed motion (editor, form, link) runs."""

TOUCH = "(Touch: B slides to A)"
"""Preset dropdown entry shown while the motion of "Touch: slide B to A" runs."""

DIM_LABELS = {3: "3D ellipsoids", 2: "2D ellipses"}
"""Dimension dropdown entries."""


@dataclass(repr=False)
class TimelineGui:
    """Timeline folder: intervals bar, t slider, exact t box, play, speed, events."""

    folder: viser.GuiFolderHandle
    bar: viser.GuiHtmlHandle
    slider: viser.GuiSliderHandle[float]
    t_box: viser.GuiTextHandle
    t_error: viser.GuiMarkdownHandle
    play: viser.GuiCheckboxHandle
    pause_at_events: viser.GuiCheckboxHandle
    speed: viser.GuiSliderHandle[float]
    events_md: viser.GuiHtmlHandle
    """The exact events (closed forms, copy buttons)."""
    events_folder: viser.GuiFolderHandle
    event_buttons: list[viser.GuiButtonHandle] = field(default_factory=list)


@dataclass(repr=False)
class PlotsGui:
    """Plots folder: the live switch and the two uPlot plots (rebuilt per analysis)."""

    folder: viser.GuiFolderHandle
    live: viser.GuiCheckboxHandle
    scale: viser.GuiDropdownHandle[str]
    """"asinh" or "linear" (:data:`app.scene.pair.plots.SCALES`)."""
    about: viser.GuiMarkdownHandle
    """What the y axis shows."""


@dataclass(repr=False)
class MotionGui:
    """Motion folder: preset, description, the editor texts with their errors, Analyse, status."""

    folder: viser.GuiFolderHandle
    preset: viser.GuiDropdownHandle[str]
    presets: list[str]
    """The presets' names (the dropdown also lists STATIC, and TYPED / TOUCH while one runs)."""
    description: viser.GuiMarkdownHandle
    fields: dict[str, viser.GuiTextHandle]
    """"A", "B", "interval"."""
    errors: dict[str, viser.GuiMarkdownHandle]
    analyse: viser.GuiButtonHandle
    progress: GuiProgressBarHandle
    status: viser.GuiMarkdownHandle
    form: dict[str, dict[str, viser.GuiTextHandle]]
    """The motion form: "A", "B" -> field -> text (:mod:`app.scene.pair.motion_form`)."""
    form_analyse: viser.GuiButtonHandle
    form_error: viser.GuiMarkdownHandle


@dataclass(repr=False)
class ShapeGui:
    """One "Shape A/B" folder: centre, semi-axes, orientation and the error next to them."""

    folder: viser.GuiFolderHandle
    fields: dict[str, viser.GuiTextHandle]
    """"center", "semi_axes", "orientation", "matrix"."""
    error: viser.GuiMarkdownHandle
    exact: viser.GuiHtmlHandle
    """Under "≈" fields: what is rounded and a button copying the exact matrix certified."""


@dataclass(repr=False)
class ViewGui:
    """View folder: dimension, gizmos, separating plane, palette."""

    folder: viser.GuiFolderHandle
    dimension: viser.GuiDropdownHandle[str]
    gizmos: viser.GuiCheckboxHandle
    """"Move the shapes (gizmos)": at the top of the panel, not in the folder (off by default)."""
    gizmo_note: viser.GuiMarkdownHandle
    """Shown while a motion runs: the gizmos are hidden, and how to get them back (under "Move")."""
    plane: viser.GuiCheckboxHandle
    palette: viser.GuiDropdownHandle[str]
    follow: viser.GuiCheckboxHandle
    """The camera follows the moving shapes."""
    frame: viser.GuiButtonHandle


@dataclass(repr=False)
class ShareGui:
    """Share and keep: a link to this view, the configuration as a JSON file (download, open)."""

    folder: viser.GuiFolderHandle
    link: viser.GuiButtonHandle
    link_html: viser.GuiHtmlHandle
    download: viser.GuiButtonHandle
    upload: viser.GuiUploadButtonHandle
    error: viser.GuiMarkdownHandle
    analysis_json: viser.GuiButtonHandle
    """The analysis of the motion shown, exact (JSON)."""
    analysis_csv: viser.GuiButtonHandle


@dataclass(repr=False)
class Gui:
    """Every handle of the panel."""

    title: viser.GuiMarkdownHandle
    legend: viser.GuiHtmlHandle
    readout: viser.GuiMarkdownHandle
    touch: viser.GuiButtonHandle
    """Slide B along the line of centres to the exact contact with A."""
    touch_error: viser.GuiMarkdownHandle
    words: viser.GuiMarkdownHandle
    """"What am I seeing?": the decision in plain words."""
    timeline: TimelineGui
    plots: PlotsGui
    roots: RootsView
    """The roots of P(T): the paper's picture (:mod:`app.scene.pair.roots_view`)."""
    motion: MotionGui
    shapes: dict[str, ShapeGui]
    sign_table: viser.GuiMarkdownHandle
    view: ViewGui
    share: ShareGui
    guide: viser.GuiHtmlHandle | None = None
    """"What am I seeing?": the link beside the legend to the guide's concepts page (None: no guide served)."""


def ignoring_event(fn: Callable[[], object]) -> Callable[[object], None]:
    """A viser callback that calls ``fn()`` and drops the event (and what ``fn`` returns).

    ``fn`` is bound when the callback is made: in a loop, pass ``functools.partial(f, name)``
    rather than a lambda over the loop variable.
    """

    def callback(_event: object) -> None:
        fn()

    return callback


def build_gui(
    gui: viser.GuiApi, *, dim: int, presets: list[str], show_plots: bool, gizmos: bool, plane: bool,
    open_folders: Collection[str] | None = None, guide: str | None = None,
) -> Gui:
    """Lay out the panel of one tab (or of the shared scene) and return its handles.

    ``open_folders``: the folders shown open (names of :data:`app.scene.common.lesson.FOLDERS`, a lesson
    step's); None: the usual ones (Timeline, Plots, Motion). A browser opens a folder as the
    panel is built only: a lesson step builds the panel anew. ``guide``: the documentation site's
    address (``http://host:port/guide/``): a "What am I seeing?" link beside the legend opens its
    concepts page.
    """

    def is_open(name: str, default: bool) -> bool:
        return default if open_folders is None else name in open_folders

    gui.configure_theme(control_width="large", show_share_button=False)
    title = gui.add_markdown("**Ellipse / ellipsoid interference** (certified)")
    legend = gui.add_html("")
    guide_link = None if guide is None else gui.add_html(guide_link_html(guide, GUIDE_CONCEPTS, "What am I seeing?"))
    readout = gui.add_markdown("")
    touch = gui.add_button("Touch: slide B to A", hint="B slides along the line of centres to the exact contact (certified)")
    touch_error = gui.add_markdown("", visible=False)
    move = gui.add_checkbox("Move the shapes (gizmos)", gizmos, hint="show the arrows and rings that drag and turn A and B")
    gizmo_note = gui.add_markdown(
        "*A motion drives the shapes: the gizmos are hidden. Pick “(static shapes)” as the Preset to drag them.*",
        visible=False,
    )
    with gui.add_folder("What am I seeing?", expand_by_default=is_open("words", False)):
        words = gui.add_markdown("")
    with gui.add_folder("Timeline", visible=False, expand_by_default=is_open("timeline", True)) as tl_folder:
        timeline = TimelineGui(
            folder=tl_folder,
            bar=gui.add_html(""),
            slider=gui.add_slider("t", min=0.0, max=1.0, step=0.001, initial_value=0.0),
            t_box=gui.add_text("t (exact)", "0", hint="a number, fraction (3/4) or closed form ((12-2*sqrt(2))/17), or α1, α2, … for an event"),
            t_error=gui.add_markdown("", visible=False),
            play=gui.add_checkbox("Play", False, hint="space: play / pause; arrows: step; N / P: next / previous event"),
            pause_at_events=gui.add_checkbox("Pause at each event", False),
            speed=gui.add_slider("Speed (I per 10 s)", min=0.1, max=5.0, step=0.1, initial_value=1.0),
            events_md=gui.add_html(""),
            events_folder=gui.add_folder("Events (jump to)"),
        )
    with gui.add_folder("Plots", visible=False, expand_by_default=is_open("plots", True)) as pl_folder:
        plots = PlotsGui(
            folder=pl_folder,
            live=gui.add_checkbox("Live plots", show_plots),
            scale=gui.add_dropdown("Plot scale", list(SCALES), initial_value="asinh"),
            about=gui.add_markdown(""),
        )
    roots = RootsView(gui, expand=is_open("roots", False))
    with gui.add_folder("Motion", expand_by_default=is_open("motion", True)) as mo_folder:
        preset = gui.add_dropdown("Preset", [STATIC, *presets], initial_value=STATIC)
        description = gui.add_markdown("")
        fields: dict[str, viser.GuiTextHandle] = {}
        errors: dict[str, viser.GuiMarkdownHandle] = {}
        for key, label in (("A", "Motion of A"), ("B", "Motion of B"), ("interval", "Interval I")):
            fields[key] = gui.add_text(label, "", multiline=key != "interval")
            errors[key] = gui.add_markdown("", visible=False)
        analyse = gui.add_button("Analyse motion")
        progress = gui.add_progress_bar(0.0, visible=False, animated=True)
        status = gui.add_markdown("")
        form: dict[str, dict[str, viser.GuiTextHandle]] = {}
        with gui.add_folder("Motion form (instead of JSON)", expand_by_default=False):
            tabs = gui.add_tab_group()
            for name in ("A", "B"):
                with tabs.add_tab(f"Form {name}"):
                    form[name] = {
                        key: gui.add_text(label, "", hint=hint)
                        for key, label, hint in FORM_LABELS
                    }
            form_analyse = gui.add_button("Analyse the form")
            form_error = gui.add_markdown("", visible=False)
        motion = MotionGui(
            folder=mo_folder,
            preset=preset,
            presets=list(presets),
            description=description,
            fields=fields,
            errors=errors,
            analyse=analyse,
            progress=progress,
            status=status,
            form=form,
            form_analyse=form_analyse,
            form_error=form_error,
        )
    shapes: dict[str, ShapeGui] = {}
    for name in ("A", "B"):
        with gui.add_folder(f"Shape {name}", expand_by_default=is_open(f"shape {name}", False)) as folder:
            shapes[name] = ShapeGui(
                folder=folder,
                fields={
                    "center": gui.add_text("Centre", ""),
                    "semi_axes": gui.add_text("Semi-axes", ""),
                    "orientation": gui.add_text("Orientation", ""),
                    "matrix": gui.add_text(
                        "Matrix", "", hint="or the exact matrix: rows separated by ';', e.g. 1, 0, -2; 0, 1, 0; -2, 0, 3"
                    ),
                },
                error=gui.add_markdown("", visible=False),
                exact=gui.add_html("", visible=False),
            )
    with gui.add_folder("Sign table", expand_by_default=is_open("sign table", False)):
        sign_table = gui.add_markdown("")
    with gui.add_folder("View", expand_by_default=is_open("view", False)) as v_folder:
        view = ViewGui(
            folder=v_folder,
            dimension=gui.add_dropdown("Dimension", list(DIM_LABELS.values()), initial_value=DIM_LABELS[dim]),
            gizmos=move,  # at the top of the panel (issue 55: hidden until the user asks to move a shape)
            gizmo_note=gizmo_note,
            plane=gui.add_checkbox("Separating plane (when separate)", plane),
            palette=gui.add_dropdown("Palette", list(PALETTES), initial_value=next(iter(PALETTES))),
            follow=gui.add_checkbox("Camera follows the shapes", False),
            frame=gui.add_button("Frame the shapes (F)"),
        )
    with gui.add_folder("Share and keep", expand_by_default=is_open("share", False)) as sh_folder:
        share = ShareGui(
            folder=sh_folder,
            link=gui.add_button("Link to this view"),
            link_html=gui.add_html("", visible=False),
            download=gui.add_button("Download configuration (JSON)"),
            upload=gui.add_upload_button("Open a configuration (JSON)", mime_type="application/json"),
            error=gui.add_markdown("", visible=False),
            analysis_json=gui.add_button("Download analysis (JSON)", visible=False),
            analysis_csv=gui.add_button("Download analysis (CSV)", visible=False),
        )
    return Gui(title, legend, readout, touch, touch_error, words, timeline, plots, roots, motion, shapes, sign_table, view, share,
               guide_link)
