"""The "Lesson" folder of a tab: step K of N, the paper's words, a question, Reveal, Previous / Next.

A tab is in a lesson when its page was opened with ``?lesson=NAME&step=K`` (a step's link), or
when the server was started with ``--lesson`` (:attr:`SceneServer.lesson
<app.scene.server.SceneServer.lesson>`). Each step sets the whole scene: the tab starts again on
the step's configuration (:meth:`SceneServer.renew <app.scene.server.SceneServer.renew>`, no page
load) with the step's folders open, the roots drawn if the step says so and its camera. A reload
reopens the tab as the student left it, the lesson at the same step. The model and the JSON
format: :mod:`app.scene.common.lesson`.

Predict first: while a step's question is open the scene keeps the relation back
(:attr:`AppState.answer_hidden <app.scene.common.state.AppState.answer_hidden>`: shapes in neutral
grey, labels "A" and "B", no relation, certification or rule in the readout, the sign table and
the events' relations replaced by "press Reveal"). "Reveal the answer" shows all of it; so does
any change of the scene (an edit, a drag, t, Play: the student is exploring). Previous / Next
open the other step with its own question open; a reload opens the step's question again.
"""

from __future__ import annotations

import html
import threading
import weakref
from typing import TYPE_CHECKING

import viser

from ..common.lesson import Lesson, Step, builtin_lessons, find_lesson, step_link
from ..common.state import SceneConfig
from ..common.threads import soon
from .panels import GUIDE_CLASS, copy_button, guide_link_html

if TYPE_CHECKING:
    from ..server import SceneServer
    from .session import Session

__all__ = ["LessonView", "lesson_session", "view_of", "PREVIOUS", "NEXT", "REVEAL", "LESSON_ORDER"]

PREVIOUS = "◀ Previous"
NEXT = "Next ▶"
REVEAL = "Reveal the answer"

LESSON_ORDER = -1000.0
"""The Lesson folder's place in the panel: first (viser orders elements by this number)."""

_VIEWS: weakref.WeakValueDictionary[int, LessonView] = weakref.WeakValueDictionary()
"""id(session) -> its lesson view. Weak values: a view lives as long as its buttons' callbacks (the
tab's panel), and it holds its session, so an id here is never a dead session's."""


def view_of(session: Session) -> LessonView | None:
    """The lesson view of a session, or None (the tab is not in a lesson)."""
    view = _VIEWS.get(id(session))
    return view if view is not None and view.session is session else None


def heading(lesson: Lesson, k: int) -> str:
    """"step K of N: TITLE" (Markdown)."""
    return f"**step {k} of {len(lesson.steps)}: {lesson.step(k).title}**"


class LessonView:
    """The Lesson folder of one session, and the moves between steps.

    Args:
        server: the scene server (a step starts the tab again through it).
        client_id: the tab.
        tab: its address's id (where its step is remembered), or None.
        session: the tab's session.
        lesson: the lesson.
        k: the step shown (1-based).
    """

    def __init__(self, server: SceneServer, client_id: int, tab: str | None, session: Session, lesson: Lesson, k: int) -> None:
        self.server, self.client_id, self.tab, self.session = server, client_id, tab, session
        self.lesson, self.k = lesson, k
        self.ready = threading.Event()
        """Set once the step's extras (roots, camera) are applied."""
        step = lesson.step(k)
        gui = session.gui_api
        with gui.add_folder("Lesson", order=LESSON_ORDER) as folder:
            self.folder = folder
            self.title = gui.add_markdown(f"*{lesson.title}*\n\n{heading(lesson, k)}")
            self.nav = gui.add_button_group("Step", [PREVIOUS, NEXT], hint="the lesson's previous / next step")
            self.words = gui.add_markdown(step.words, visible=bool(step.words))
            self.question = gui.add_markdown(f"**Question for the class.** {step.question}", visible=bool(step.question))
            self.reveal = gui.add_button(REVEAL, visible=bool(step.answer) or session.state.answer_hidden)
            self.answer = gui.add_markdown(f"**Answer.** {step.answer}", visible=False)
            path = "../.." + "/" + step_link(lesson, k)  # relative to the tab's page /s/<id>/
            self.link = gui.add_html(
                f'<div style="font-size:12px"><a href="{html.escape(path, quote=True)}" target="_blank">'
                f"Link to this step</a>{copy_button(path, 'copy link', url=True)}</div>"
            )
            self.tutorial = None if server.guide is None else gui.add_html(
                guide_link_html(server.guide, GUIDE_CLASS, "Teaching with lessons: the tutorial")
            )
        self.nav.on_click(lambda ev: self.on_nav(str(ev.target.value)))
        self.reveal.on_click(lambda _ev: self.show_answer())
        session.on_reveal = self._answer_shown  # an edit reveals too
        _VIEWS[id(session)] = self

    def on_nav(self, which: str) -> None:
        """"◀ Previous" / "Next ▶" clicked."""
        self.go(self.k - 1 if which == PREVIOUS else self.k + 1)

    def show_answer(self) -> None:
        """"Reveal": the answer under the question, and the relation in the scene and the panel."""
        self._answer_shown()
        self.session.reveal()

    def _answer_shown(self) -> None:
        """The answer shown, the Reveal button gone (Reveal pressed, or the scene changed)."""
        self.answer.visible = bool(self.lesson.step(self.k).answer)
        self.reveal.visible = False

    def apply(self, step: Step) -> None:
        """What a step sets besides the configuration: the roots drawn, then its camera; the question held."""
        s = self.session
        if step.roots:
            s.ui.roots.show_roots.value = True  # type: ignore[misc]  # runs its callback: the roots drawn
        if step.camera is None and s.ready.is_set():
            s.hold_question()
            self.ready.set()
            return
        soon(self.settle, step.camera)

    def settle(self, camera: tuple[tuple[float, float, float], tuple[float, float, float]] | None) -> None:
        """Once the step is drawn: its question is about what it shows, and its camera is set."""
        s = self.session
        s.ready.wait(120)  # the analysis frames the camera when it arrives: the step's camera after it
        with s.lock:
            if not s.closed:
                s.hold_question()
                if camera is not None:
                    s.camera_chosen = True
                    for cam in s.cameras():
                        cam.position, cam.look_at = camera
        self.ready.set()

    def go(self, k: int) -> Session | None:
        """Show step ``k``: the tab starts again on its configuration; None if there is no step k."""
        if not 1 <= k <= len(self.lesson.steps):
            return None
        step = self.lesson.step(k)
        if self.tab is not None:
            self.server.store.lessons.set(self.tab, self.lesson.name, k)

        def attach(session: Session) -> None:
            LessonView(self.server, self.client_id, self.tab, session, self.lesson, k).apply(step)

        try:
            return self.server.renew(self.client_id, dict(step.scene), open_folders=step.open, then=attach,
                                     answer_hidden=bool(step.question))
        except (KeyError, ValueError):  # the tab left meanwhile
            return None


def lesson_session(server: SceneServer, client: viser.ClientHandle, tab: str | None) -> Session | None:
    """The session of a tab that opens in a lesson (its link's, or the server's), else None.

    A tab reloaded in a lesson gets its scene as it left it and the lesson at the same step; a
    link to an unknown lesson or step opens with a message (never a file: a link names lessons
    by name only).
    """
    if server.shared is not None or server.bodies is not None or tab is None:
        return None
    marks = server.store.lessons
    mark = marks.get(tab)
    saved = server.store.get(tab)
    if mark is None and server.lesson is not None and saved is None:
        mark = (server.lesson, 1)
        marks.set(tab, *mark)
    if mark is None:
        return None
    name, k = mark
    lesson = find_lesson(name)
    if lesson is None:
        session = server._session(client, saved)
        known = ", ".join(sorted({*builtin_lessons(), *([server.lesson] if server.lesson else [])}))
        session.field_error("config", f"lesson: there is no lesson {name[:40]!r} (lessons: {known})")
        return session
    error = None
    n = len(lesson.steps)
    if not 1 <= k <= n:
        error = f"lesson {lesson.name}: there is no step {k} (steps 1..{n})"
        k = min(max(k, 1), n)
        marks.set(tab, lesson.name, k)
    step = lesson.step(k)
    hidden = bool(step.question)  # predict first: the relation waits for Reveal
    if isinstance(saved, SceneConfig):  # a reload: the scene as the tab left it, the lesson at its step
        session = server._session(client, saved, answer_hidden=hidden)
        view = LessonView(server, client.client_id, tab, session, lesson, k)
        soon(view.settle, None)
    else:
        session = server._session(client, dict(step.scene), step.open, answer_hidden=hidden)
        LessonView(server, client.client_id, tab, session, lesson, k).apply(step)
    if error is not None:
        session.field_error("config", error)
    return session
