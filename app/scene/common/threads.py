"""Deferred calls of the scene: run on a few long-lived threads, never on a thread made for each.

A thread that does exact arithmetic keeps FLINT's thread-local caches (~0.2 MB) for the rest of
the process: python-flint does not free them when the thread ends (500 short threads, each
multiplying a few large fmpz, left +113 MB resident; the same work on one thread, nothing). The
scene deferred its panel refreshes with a ``threading.Timer`` each, a new thread per refresh: a
tab opened and closed in a browser left ~0.5 MB, and a drag more, every second. :func:`later`
keeps the timer's cancel but hands the call to :func:`pool`'s threads, which live on: their
caches are reused, so the memory of the calls is bounded by the pool's size; :func:`soon` hands
over a call to make now.
"""

from __future__ import annotations

import threading
import traceback
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

__all__ = ["later", "soon", "pool", "POOL_THREADS"]

POOL_THREADS = 8
"""Threads running the deferred calls of every tab: their work holds the GIL, but a call may also
wait (a tab's typed motion read in a worker process, :meth:`app.scene.pair.session.Session.load_untrusted`)."""

_POOL = ThreadPoolExecutor(max_workers=POOL_THREADS, thread_name_prefix="scene-later")
"""Its threads start on first use and live on."""


def pool() -> ThreadPoolExecutor:
    """The scene's pool of long-lived threads for deferred calls."""
    return _POOL


def later(delay: float, fn: Callable[..., Any], *args: Any) -> threading.Timer:
    """Call ``fn(*args)`` in ``delay`` seconds on :func:`pool` (``cancel()`` the timer returned to drop it).

    The timer's own thread only hands the call over: it does no arithmetic, and so keeps no cache.
    """
    timer = threading.Timer(delay, _hand_over, (fn, args))
    timer.daemon = True
    timer.start()
    return timer


def soon(fn: Callable[..., Any], *args: Any) -> None:
    """Call ``fn(*args)`` on :func:`pool` now, off the calling thread (an error is printed)."""
    _hand_over(fn, args)


def _hand_over(fn: Callable[..., Any], args: tuple[Any, ...]) -> None:
    try:
        pool().submit(fn, *args).add_done_callback(_report)
    except RuntimeError:  # the interpreter is shutting down: nothing runs any more
        pass


def _report(future: Future[Any]) -> None:
    """Print a deferred call's error, as a thread of its own would have (never lost silently)."""
    error = None if future.cancelled() else future.exception()
    if error is not None:
        traceback.print_exception(type(error), error, error.__traceback__)
