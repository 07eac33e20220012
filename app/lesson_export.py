"""A lesson drawn headless: one step's picture, or the whole lesson as one offline HTML page.

``python -m app screenshot --lesson paper --step 3 --out step3.png`` draws step 3 as a tab opened
on its link shows it: as the class sees it before "Reveal the answer" (a step with a question
keeps the relation back: grey shapes, no relation words); ``--reveal`` draws it after Reveal.
``python -m app export --lesson paper --out lesson.html`` writes every step (the picture as the
class sees it, words, question, and behind a "Reveal" fold the answer with the picture after
Reveal) into one HTML file with the pictures inline: it opens without a server and makes no
network request. One headless Chromium (:class:`app.screenshot.HeadlessScene`) draws all the steps.
"""

from __future__ import annotations

import base64
import html
import re
from collections.abc import Iterator, Sequence

from .scene.common.lesson import Lesson, register, step_link

__all__ = ["step_pictures", "step_shots", "lesson_html", "markdown_html"]


def step_pictures(
    lesson: Lesson, steps: Sequence[int], *, width: int = 1280, height: int = 720, timeout: float = 120.0,
    cdp: str | None = None, reveal: bool = False,
) -> Iterator[tuple[int, bytes]]:
    """(step, PNG of the page) for each step, as a tab opened on the step's link shows it.

    ``reveal``: after "Reveal the answer" is pressed (default: before, as the class sees it first).

    Raises:
        ValueError: a step the lesson does not have.
        RuntimeError: no Chromium or Playwright (:data:`app.screenshot.SCREENSHOT_EXTRA`).
    """
    for k, before, after in step_shots(lesson, steps, width=width, height=height, timeout=timeout, cdp=cdp,
                                       before=not reveal, after=reveal):
        png = after if reveal else before
        if png is not None:  # always: the picture asked for
            yield k, png


def step_shots(
    lesson: Lesson, steps: Sequence[int], *, width: int = 1280, height: int = 720, timeout: float = 120.0,
    cdp: str | None = None, before: bool = True, after: bool = False,
) -> Iterator[tuple[int, bytes | None, bytes | None]]:
    """(step, PNG before Reveal, PNG after Reveal) for each step; a picture not asked for is None.

    A step without a question looks the same before and after: its one picture is both.

    Raises:
        ValueError: a step the lesson does not have.
        RuntimeError: no Chromium or Playwright (:data:`app.screenshot.SCREENSHOT_EXTRA`).
    """
    from .scene.common.state import SceneConfig
    from .scene.pair.lesson_view import view_of
    from .screenshot import HeadlessScene

    for k in steps:
        lesson.step(k)  # a missing step is refused before a browser starts
    register(lesson)  # links name it (a lesson file)
    first = f"/{step_link(lesson, steps[0])}" if steps else "/"
    with HeadlessScene(SceneConfig(), width=width, height=height, timeout=timeout, cdp=cdp, start_path=first) as hs:
        for i, k in enumerate(steps):
            if i:
                hs.goto(f"/{step_link(lesson, k)}")
            view = view_of(hs.session)
            if view is None or view.k != k:
                raise RuntimeError(f"the tab did not open step {k} of lesson {lesson.name}")
            if not view.ready.wait(timeout):
                raise TimeoutError(f"step {k} of lesson {lesson.name} did not finish drawing")
            hs.wait_settled()
            hidden = view.session.state.answer_hidden
            seen: bytes | None = hs.page.screenshot() if before or not hidden else None
            revealed = seen
            if after and hidden:
                view.show_answer()
                hs.wait_settled()
                revealed = hs.page.screenshot()
            yield k, seen if before else None, revealed if after else None


_BOLD = re.compile(r"\*\*(.+?)\*\*")
_ITALIC = re.compile(r"(?<![*\w])\*(?!\s)(.+?)(?<!\s)\*(?![*\w])")


def markdown_html(text: str) -> str:
    """The little Markdown a lesson's words use (paragraphs, **bold**, *italic*) as HTML, escaped.

    Examples:
        >>> markdown_html("**P(T)** < 0 and *s0*")
        '<p><b>P(T)</b> &lt; 0 and <i>s0</i></p>'
    """
    out = []
    for para in re.split(r"\n\s*\n", text.strip()):
        if not para.strip():
            continue
        p = html.escape(para.strip(), quote=False)
        p = _ITALIC.sub(r"<i>\1</i>", _BOLD.sub(r"<b>\1</b>", p))
        out.append(f"<p>{p}</p>")
    return "\n".join(out)


_STYLE = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1320px;margin:0 auto;padding:1em 1.5em;color:#222}
h1{font-size:1.6em} h2{font-size:1.25em;margin-top:2em;border-top:1px solid #ddd;padding-top:1em}
img{width:100%;height:auto;border:1px solid #ccc} .q{background:#f4f7fb;border-left:4px solid #1f4e9c;padding:.5em 1em}
details{margin:.5em 0 1em} summary{cursor:pointer;color:#1f4e9c;font-weight:600} nav a{margin-right:.8em}
"""


def _img(png: bytes, alt: str) -> str:
    return f'<img alt="{html.escape(alt, quote=True)}" src="data:image/png;base64,{base64.b64encode(png).decode()}">'


def lesson_html(lesson: Lesson, pictures: dict[int, bytes], answers: dict[int, bytes] | None = None) -> str:
    """The whole lesson as one offline HTML page: every step's picture, words, question and answer.

    ``pictures``: each step as the class sees it first; ``answers``: after "Reveal the answer"
    (shown in the step's fold when it differs from the first picture).
    """
    answers = answers or {}
    n = len(lesson.steps)
    parts = [
        "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\">",
        f"<title>{html.escape(lesson.title)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>{html.escape(lesson.title)}</h1>",
        "<nav>" + "".join(f'<a href="#step-{k}">{k}</a>' for k in range(1, n + 1)) + "</nav>",
    ]
    for k, step in enumerate(lesson.steps, start=1):
        parts.append(f'<section id="step-{k}"><h2>step {k} of {n}: {html.escape(step.title)}</h2>')
        if k in pictures:
            parts.append(_img(pictures[k], f"step {k}: {step.title}"))
        parts.append(markdown_html(step.words))
        if step.question:
            parts.append(f'<div class="q"><b>Question for the class.</b> {markdown_html(step.question)}</div>')
        shown = answers.get(k)
        if shown is not None and shown == pictures.get(k):
            shown = None
        if step.answer or shown is not None:
            picture = "" if shown is None else _img(shown, f"step {k} after Reveal: {step.title}")
            parts.append(f"<details><summary>Reveal the answer</summary>{markdown_html(step.answer)}{picture}</details>")
        parts.append("</section>")
    parts.append("</body></html>")
    return "\n".join(parts)
