"""Lessons: a scene played step by step, each step in the paper's words with a question for the class.

A lesson is a list of steps; each step sets the whole scene and says a few sentences. The
built-in lesson ``paper`` (:mod:`app.scene.common.lesson_paper`) walks through Caravantes et al. from an
ellipse as a matrix to Examples 29, 30 and 33. A teacher writes a lesson of their own as a JSON
file and opens it the same way (``python -m app serve --lesson FILE``, ``screenshot --lesson FILE
--step K``, ``export --lesson FILE``).

The JSON format of a lesson file (UTF-8, at most :data:`MAX_LESSON_BYTES` bytes)::

    {
      "title": "Two circles",                      # the lesson's title (required, a string)
      "steps": [                                   # 1 .. MAX_STEPS steps, shown in this order
        {
          "title": "Apart",                        # required: "step K of N: TITLE"
          "scene": {"dim": 2, "preset": null,      # required: a scene configuration, exactly the
                    "A": {"center": ["0", "0"], "semi_axes": ["1", "1"]},   # JSON of --config and of
                    "B": {"center": ["3", "0"], "semi_axes": ["1", "1"]}},  # "Download configuration"
          "words": "Two unit circles whose centres are 3 apart.",           # Markdown (optional)
          "question": "Predict: separate, tangent or overlap?",             # optional
          "answer": "Separate: 3 > 1 + 1.",                                 # shown by "Reveal" (optional)
          "open": ["shape A", "roots"],            # folders open in this step (optional; default:
                                                   # the scene's usual ones); any of FOLDERS
          "roots": true,                           # draw the roots of P(T) (optional, default false)
          "camera": {"position": [0, -6, 4],       # optional; default: framed on the shapes
                     "look_at": [1.5, 0, 0]}
        }
      ]
    }

``scene`` takes every key of a scene configuration (:meth:`app.scene.common.state.SceneConfig.from_dict`):
static shapes (centre/semi-axes/orientation or an exact ``matrix``), a ``preset`` or a typed
``motion``, ``t`` (a number or exact text such as ``"3/4"``) or ``event`` (1-based). Unknown keys
are refused with a message that names the step and the key. A lesson's step has a link of its
own: ``?lesson=NAME&step=K`` on the scene's address (NAME: ``paper`` or the lesson the server
was started with, by its file name without ``.json``); a link never names a file.
"""

from __future__ import annotations

import json
import threading
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs

from .state import SceneConfig

__all__ = [
    "Lesson", "Step", "FOLDERS", "MAX_LESSON_BYTES", "MAX_STEPS", "lesson_from_dict", "load_lesson",
    "builtin_lessons", "register", "find_lesson", "lesson_query", "LessonMarks", "step_link",
]

MAX_LESSON_BYTES = 1 << 20
"""Largest lesson file read (1 MiB: a hundred steps with typed motions fit)."""

MAX_STEPS = 200
"""Most steps in a lesson."""

MAX_TEXT_CHARS = 4000
"""Longest words, question or answer of one step."""

FOLDERS = ("words", "timeline", "plots", "roots", "motion", "shape A", "shape B", "sign table", "view", "share")
"""Names of the panel's folders a step may open (:func:`app.scene.pair.gui.build_gui`'s ``open_folders``)."""

_STEP_KEYS = {"title", "scene", "words", "question", "answer", "open", "roots", "camera"}


@dataclass(frozen=True)
class Step:
    """One step of a lesson: the scene it sets and what it says."""

    title: str
    scene: dict[str, Any]
    """The scene configuration (JSON object, checked by :meth:`SceneConfig.from_dict`)."""
    words: str = ""
    question: str = ""
    answer: str = ""
    open: tuple[str, ...] | None = None
    """Folders open in this step (names of :data:`FOLDERS`), or None: the panel's defaults."""
    roots: bool = False
    """Draw the roots of P(T)."""
    camera: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None
    """(position, look_at), or None: framed on the shapes."""


@dataclass(frozen=True)
class Lesson:
    """A named list of steps."""

    name: str
    """How links name it (``?lesson=NAME``)."""
    title: str
    steps: tuple[Step, ...] = field(default_factory=tuple)

    def step(self, k: int) -> Step:
        """The K-th step (1-based).

        Raises:
            ValueError: no such step (the message gives the range).
        """
        if not 1 <= k <= len(self.steps):
            raise ValueError(f"lesson {self.name}: there is no step {k} (steps 1..{len(self.steps)})")
        return self.steps[k - 1]


def _text(d: dict[str, Any], key: str, where: str, *, required: bool = False) -> str:
    value = d.get(key)
    if value is None:
        if required:
            raise ValueError(f"{where}: {key} is required")
        return ""
    if not isinstance(value, str):
        raise ValueError(f"{where}: {key} must be a string")
    if len(value) > MAX_TEXT_CHARS:
        raise ValueError(f"{where}: {key} is too long ({len(value)} > {MAX_TEXT_CHARS} characters)")
    return value


def _point(value: Any, where: str) -> tuple[float, float, float]:
    import math

    if not isinstance(value, list | tuple) or len(value) != 3 or not all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) and abs(v) <= 1e6 for v in value
    ):
        raise ValueError(f"{where}: expected 3 finite numbers (|x| <= 1e6)")
    return (float(value[0]), float(value[1]), float(value[2]))


def _step(d: Any, k: int) -> Step:
    where = f"step {k}"
    if not isinstance(d, dict):
        raise ValueError(f"{where}: expected an object with title, scene, words, question, answer")
    unknown = set(d) - _STEP_KEYS
    if unknown:
        raise ValueError(f"{where}: unknown keys {sorted(unknown)}; allowed: {', '.join(sorted(_STEP_KEYS))}")
    scene = d.get("scene")
    if not isinstance(scene, dict):
        raise ValueError(f"{where}: scene must be a scene configuration (a JSON object)")
    try:
        SceneConfig.from_dict(scene)  # checked now: a bad step is named when the lesson is read
    except ValueError as e:
        raise ValueError(f"{where}: scene: {e}") from None
    open_ = d.get("open")
    if open_ is not None:
        if not isinstance(open_, list) or not all(isinstance(f, str) for f in open_):
            raise ValueError(f"{where}: open must be a list of folder names ({', '.join(FOLDERS)})")
        bad = [f for f in open_ if f not in FOLDERS]
        if bad:
            raise ValueError(f"{where}: open: unknown folders {bad}; known: {', '.join(FOLDERS)}")
    roots = d.get("roots", False)
    if not isinstance(roots, bool):
        raise ValueError(f"{where}: roots must be true or false")
    camera = None
    if d.get("camera") is not None:
        cam = d["camera"]
        if not isinstance(cam, dict) or set(cam) != {"position", "look_at"}:
            raise ValueError(f"{where}: camera must be {{\"position\": [x, y, z], \"look_at\": [x, y, z]}}")
        camera = (_point(cam["position"], f"{where}: camera.position"), _point(cam["look_at"], f"{where}: camera.look_at"))
    return Step(
        title=_text(d, "title", where, required=True),
        scene=dict(scene),
        words=_text(d, "words", where),
        question=_text(d, "question", where),
        answer=_text(d, "answer", where),
        open=None if open_ is None else tuple(open_),
        roots=roots,
        camera=camera,
    )


def lesson_from_dict(d: Any, name: str) -> Lesson:
    """Read and check a lesson (the JSON format of the module's docstring).

    Raises:
        ValueError: a missing or bad key (the message names the step and the key).

    Examples:
        >>> two = {"title": "t", "steps": [{"title": "apart", "scene": {"dim": 2, "preset": None}}]}
        >>> lesson_from_dict(two, "mine").step(1).title
        'apart'
        >>> lesson_from_dict({"title": "t", "steps": [{"title": "x", "scene": {"dimension": 2}}]}, "mine")
        Traceback (most recent call last):
        ...
        ValueError: lesson mine: step 1: scene: config: unknown keys ['dimension']; allowed: A, B, dim, event, gizmos, motion, palette, preset, separating_plane, show_plots, t
    """
    try:
        if not isinstance(d, dict):
            raise ValueError("expected a JSON object with title and steps")
        unknown = set(d) - {"title", "steps"}
        if unknown:
            raise ValueError(f"unknown keys {sorted(unknown)}; allowed: steps, title")
        title = _text(d, "title", "lesson", required=True)
        steps = d.get("steps")
        if not isinstance(steps, list) or not steps:
            raise ValueError("steps must be a non-empty list of steps")
        if len(steps) > MAX_STEPS:
            raise ValueError(f"too many steps ({len(steps)} > {MAX_STEPS})")
        return Lesson(name=name, title=title, steps=tuple(_step(s, k) for k, s in enumerate(steps, start=1)))
    except ValueError as e:
        raise ValueError(f"lesson {name}: {e}") from None


def builtin_lessons() -> dict[str, Lesson]:
    """The lessons that come with the scene, by name (``paper``)."""
    from .lesson_paper import PAPER

    return {"paper": lesson_from_dict(PAPER, "paper")}


_REGISTERED: dict[str, Lesson] = {}
_LOCK = threading.Lock()


def load_lesson(spec: str) -> Lesson:
    """A built-in lesson by name (``paper``) or a lesson file (a path ending in ``.json``).

    Raises:
        ValueError: unknown name, unreadable or too large file, or a bad lesson (one line).
    """
    builtin = builtin_lessons()
    if spec in builtin:
        return builtin[spec]
    path = Path(spec)
    if path.suffix.lower() != ".json":
        raise ValueError(f"--lesson {spec}: not a lesson name ({', '.join(builtin)}) nor a .json lesson file")
    try:
        with path.open("rb") as f:
            raw = f.read(MAX_LESSON_BYTES + 1)
    except OSError as e:
        raise ValueError(f"cannot read lesson file {spec}: {e.strerror}") from None
    if len(raw) > MAX_LESSON_BYTES:
        raise ValueError(f"lesson file {spec} is too large (> {MAX_LESSON_BYTES} bytes)")
    try:
        data = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as e:
        raise ValueError(f"lesson file {spec} is not valid JSON: {e}") from None
    name = path.stem
    if name in builtin:
        name = f"{name}-file"
    return lesson_from_dict(data, name)


def register(lesson: Lesson) -> None:
    """Make ``lesson`` reachable by links (``?lesson=NAME``) in this process (a lesson file the server serves)."""
    with _LOCK:
        _REGISTERED[lesson.name] = lesson


def find_lesson(name: str) -> Lesson | None:
    """The lesson a link names: a built-in one or a registered one (never a file named by the link)."""
    with _LOCK:
        if name in _REGISTERED:
            return _REGISTERED[name]
    return builtin_lessons().get(name)


def lesson_query(query: str) -> tuple[str, int] | None:
    """(lesson name, step) of a page query ``lesson=NAME&step=K`` (step 1 when absent or unreadable).

    Examples:
        >>> lesson_query("lesson=paper&step=3"), lesson_query("fixedDpr=1"), lesson_query("lesson=paper&step=x")
        (('paper', 3), None, ('paper', 1))
    """
    q = parse_qs(query)
    names = q.get("lesson")
    if not names or not names[0] or len(names[0]) > 100:
        return None
    try:
        step = int(q.get("step", ["1"])[0])
    except ValueError:
        step = 1
    return names[0], step


def step_link(lesson: Lesson, k: int) -> str:
    """The query of the link to step K (``?lesson=NAME&step=K``), relative to the scene's root."""
    from urllib.parse import quote

    return f"?lesson={quote(lesson.name)}&step={k}"


class LessonMarks:
    """Which lesson and step each tab is at (its first page's query, then the steps it moved to).

    Bounded like :class:`app.scene.common.links.TabStore`: the newest ``size`` tabs.
    """

    def __init__(self, size: int = 2000) -> None:
        self._items: OrderedDict[str, tuple[str, int]] = OrderedDict()
        self._lock = threading.Lock()
        self.size = size

    def note_query(self, tab: str, query: str) -> None:
        """The tab's page was opened with ``query``: remember its lesson, unless the tab is in one already."""
        mark = lesson_query(query)
        if mark is None:
            return
        with self._lock:
            if tab not in self._items:
                self._put(tab, mark)

    def set(self, tab: str, name: str, k: int) -> None:
        """The tab moved to step ``k`` of lesson ``name``."""
        with self._lock:
            self._put(tab, (name, k))

    def _put(self, tab: str, mark: tuple[str, int]) -> None:
        self._items[tab] = mark
        self._items.move_to_end(tab)
        while len(self._items) > self.size:
            self._items.popitem(last=False)

    def get(self, tab: str) -> tuple[str, int] | None:
        """The tab's lesson and step, or None."""
        with self._lock:
            return self._items.get(tab)
