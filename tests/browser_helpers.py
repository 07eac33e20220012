"""Waiting on a page's state and opening a headless browser on many bodies: shared by the browser tests.

Every wait is on a state (a condition, a text on the page), never a fixed sleep; the timeouts are
upper bounds for a loaded machine, so a passing test never waits for them.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from conftest import TEST_DPR


def until(cond: Callable[[], object], timeout: float = 120.0, what: str = "") -> None:
    """Poll ``cond`` every 20 ms until it is true; fail naming ``what`` after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what or cond}")
        time.sleep(0.02)


def text_shown(page: Any, fragment: str, timeout: float = 120.0) -> None:
    """Wait until the page's text contains ``fragment``."""
    page.wait_for_function("(f) => document.body.innerText.includes(f)", arg=fragment, timeout=timeout * 1000)


def tick(page: Any, label: str, is_on: Callable[[], object], timeout: float = 120.0, patience: float = 15.0) -> None:
    """Tick the checkbox labelled ``label`` until the server says so (``is_on``) and the page shows it.

    Not Playwright's ``check()``: viser ticks the box in the page when the click's update has gone
    round, which under load is later than ``check()`` looks. A click is repeated only when, ``patience``
    seconds after the last one, neither the server nor the page has it ticked (a click lost, never one
    in flight: it is undone only if slower than ``patience``).
    """
    box = page.get_by_label(label, exact=True)
    box.wait_for(state="visible")
    deadline = time.monotonic() + timeout
    last_click = -float("inf")
    while not (is_on() and box.is_checked()):
        now = time.monotonic()
        if now > deadline:
            raise AssertionError(f"timed out ticking {label!r} (server: {bool(is_on())}, page: {box.is_checked()})")
        if now - last_click > patience and not is_on() and not box.is_checked():
            box.click()
            last_click = time.monotonic()
        time.sleep(0.02)


def open_folder(page: Any, folder: str, label: str, timeout: float = 120.0, patience: float = 15.0) -> None:
    """Open the panel folder titled ``folder`` until the control labelled ``label`` in it is visible.

    A click on a folder's title can be lost when the panel re-renders under it (the server's answer
    to the previous action); it is repeated only when the control has not shown ``patience`` s after
    the last click (a second click on a folder that did open would close it).
    """
    control = page.get_by_label(label, exact=True)
    deadline = time.monotonic() + timeout
    last_click = -float("inf")
    while not control.is_visible():
        now = time.monotonic()
        if now > deadline:
            raise AssertionError(f"timed out opening the folder {folder!r} (no {label!r} shown)")
        if now - last_click > patience:
            page.get_by_text(folder, exact=True).click()
            last_click = time.monotonic()
        time.sleep(0.02)


def bodies_page(model: Any) -> Iterator[tuple[Any, Any]]:
    """A scene server on ``model`` (many bodies) and one headless tab on it, for a module fixture."""
    if not os.path.exists("/usr/bin/chromium"):
        pytest.skip("needs Debian chromium at /usr/bin/chromium")
    from app.scene.state import SceneConfig
    from app.screenshot import HeadlessScene

    with HeadlessScene(SceneConfig(), bodies=model, width=1000, height=720, timeout=120, dpr=TEST_DPR) as hs:
        yield hs, model


def field_input(page: Any, label: str, selector: str = "input") -> Any:
    """The visible input (``selector`` inside the row) of the field labelled ``label``."""
    idx = page.evaluate(
        """([l, sel]) => {
          const label = Array.from(document.querySelectorAll('label')).find(e => e.textContent === l && e.offsetParent !== null);
          const input = label?.closest('.mantine-Flex-root')?.querySelector(sel);
          return Array.from(document.querySelectorAll('input')).indexOf(input);
        }""", [label, selector])
    assert idx >= 0, f"no field labelled {label!r}"
    return page.locator("input").nth(idx)


def set_field(page: Any, label: str, text: str, handle: Any = None, patience: float = 15.0) -> None:
    """Type ``text`` into the text field labelled ``label`` and press Enter.

    With the server's ``handle`` of the field: until the server has the text, typing again when it
    has not arrived ``patience`` s after the last try (a panel re-rendered by the previous action's
    answer can drop the keys; the same text twice changes nothing).
    """
    deadline = time.monotonic() + 120
    while True:
        box = field_input(page, label, "input, textarea")
        box.fill(text)
        box.press("Enter")
        if handle is None:
            return
        tried = time.monotonic()
        while handle.value != text and time.monotonic() - tried < patience:
            time.sleep(0.02)
        if handle.value == text:
            return
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out setting {label} to {text!r} (the server has {handle.value!r})")
