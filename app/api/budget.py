"""Time budget and cancellation of one request's work, and running it off the event loop.

Work on user input (a batch of exact classifications, an explanation, waiting on an analysis
worker) runs in a thread while the event loop watches the client: if it disconnects, the work
is cancelled at its next check. A :class:`Budget` is checked between steps (e.g. between the
pairs of a batch): over its time, after a disconnect, or once the server is stopping, the work
stops with :class:`BudgetExceeded` / :class:`Cancelled`, which the routes answer with 503.
"""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import Callable
from typing import Any, TypeVar

import anyio
from fastapi import HTTPException, Request

__all__ = ["Budget", "BudgetExceeded", "Cancelled", "STOPPING", "run_off_loop", "budget_error"]

T = TypeVar("T")

STOPPING = threading.Event()
"""Set when the server process is stopping (SIGTERM): every budget check then fails at once."""

_WATCH_S = 0.1
"""How often the event loop checks whether the client has gone."""


class BudgetExceeded(RuntimeError):
    """The request's work went over its time budget (or the server is stopping)."""


class Cancelled(RuntimeError):
    """The client disconnected: nobody will read the answer."""


class Budget:
    """Deadline plus cancel event of one request; call :meth:`check` between steps."""

    def __init__(self, seconds: float, cancel: threading.Event | None = None) -> None:
        self.seconds = seconds
        self.deadline = time.monotonic() + seconds
        self.cancel = cancel or threading.Event()

    def check(self, progress: str = "") -> None:
        """Raise if the time is spent, the client left or the server is stopping.

        Args:
            progress: where the work is, for the message (e.g. "after 12 of 1000 pairs").
        """
        where = f" {progress}" if progress else ""
        if STOPPING.is_set():
            raise BudgetExceeded(f"stopped{where}: the server is shutting down")
        if self.cancel.is_set():
            raise Cancelled(f"stopped{where}: the client disconnected")
        if time.monotonic() > self.deadline:
            raise BudgetExceeded(f"stopped{where}: over the time budget of {self.seconds:g} s per request")


def budget_error(e: BudgetExceeded | Cancelled, hint: str = "") -> HTTPException:
    """The 503 answer for a budget stop (a cancelled request's answer is never read)."""
    return HTTPException(503, f"{e}{'; ' + hint if hint else ''}", headers={"Retry-After": "2"})


async def run_off_loop(request: Request, fn: Callable[[threading.Event], T]) -> T:
    """Run ``fn(cancel)`` in a worker thread; set ``cancel`` if the client disconnects meanwhile.

    The event loop stays free for other requests (and /healthz) while ``fn`` runs.
    """
    cancel = threading.Event()
    work: asyncio.Future[Any] = asyncio.ensure_future(anyio.to_thread.run_sync(fn, cancel))
    try:
        while True:
            done, _ = await asyncio.wait({work}, timeout=_WATCH_S)
            if done:
                return work.result()
            if not cancel.is_set() and await request.is_disconnected():
                cancel.set()  # the thread stops at its next check; we still wait for it to end
    except asyncio.CancelledError:  # the server cancelled this request (shutdown)
        cancel.set()
        raise
