"""Time budget and cancellation of one request's work, and running it off the event loop.

No pair is decided on the event loop. Bounded work (a batch of JSON-number pairs) runs in a
thread (:func:`run_off_loop`) while the event loop watches the client: if it disconnects, the
work is cancelled at its next check. Work that grows with the user's numbers (number strings,
explanations, witnesses, contacts, motions) runs in the budgeted worker processes
(:func:`run_job`: :class:`app.workers.WorkerPool`, its queue, its time budget and memory cap; a
disconnect or a stop kills the process). A :class:`Budget` is checked between steps (e.g.
between the pairs of a batch), in the server thread or in the worker: over its time, after a
disconnect, or once the server is stopping, the work stops with :class:`BudgetExceeded` /
:class:`Cancelled`. Every such stop, a busy server and a server stopping are answered 503 with
``Retry-After`` (:func:`unavailable`).
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable
from typing import Any, TypeVar

import anyio
from fastapi import HTTPException, Request

from ..jobs import STOPPING, Budget, BudgetExceeded, Cancelled
from ..workers import (
    WorkerBusy,
    WorkerCancelled,
    WorkerDied,
    WorkerFailed,
    WorkerPool,
    WorkerStopped,
    WorkerTimeout,
)

__all__ = [
    "Budget",
    "BudgetExceeded",
    "Cancelled",
    "STOPPING",
    "RETRY_AFTER_S",
    "JOB_GRACE_S",
    "WAIT_UNTIL",
    "run_off_loop",
    "run_job",
    "budget_error",
    "unavailable",
]

RETRY_AFTER_S = 2
"""Seconds a client is asked to wait (``Retry-After``) after a 503."""
JOB_GRACE_S = 1.0
"""A worker job that checks its own budget gets this long past it to say where it stopped,
before its process is killed."""

T = TypeVar("T")

_WATCH_S = 0.1
"""How often the event loop checks whether the client has gone."""

WAIT_UNTIL = "app.wait_until"
"""Key of the request's ASGI scope: until when (``time.monotonic()``) it may wait for its work to
start, set when its body is whole (:class:`app.api.line.RequestLine`). One wait for the whole
line: the reader of large bodies and then a worker (:func:`run_job`) share it, so a request never
waits longer than ``ApiSettings.queue_wait_s`` in all."""


def unavailable(detail: str) -> HTTPException:
    """503 with ``Retry-After``: busy, stopped by a budget, or shutting down."""
    return HTTPException(503, detail, headers={"Retry-After": str(RETRY_AFTER_S)})


def budget_error(e: BudgetExceeded | Cancelled, hint: str = "") -> HTTPException:
    """The 503 answer for a budget stop (a cancelled request's answer is never read)."""
    return unavailable(f"{e}{'; ' + hint if hint else ''}")


async def run_job(
    request: Request,
    workers: WorkerPool,
    fn: Callable[..., T],
    *args: Any,
    seconds: float,
    checks_budget: bool = False,
    stopped: str = "stopped: ",
    hint: str = "",
    memory_mb: int | None = None,
) -> T:
    """``fn(*args)`` in a worker process (queued, budgeted, killed on disconnect); errors as HTTP.

    Args:
        request: the request (its disconnect cancels the job; its wait in the queue ends at
            :data:`WAIT_UNTIL`, or after the pool's own longest wait).
        workers: the app's pool.
        fn: a module-level job (:mod:`app.jobs`).
        *args: its arguments (picklable).
        seconds: its time budget.
        checks_budget: the job checks a budget of ``seconds`` itself and says where it stopped
            (its process is killed :data:`JOB_GRACE_S` later if it does not).
        stopped: prefix of the message when the job is stopped ("analysis stopped: ").
        hint: what the client can do about a timeout ("send fewer pairs per request").
        memory_mb: the workers' memory cap, named when a job runs out of memory.

    Raises:
        core.InvalidInput: bad input (the job's ValueError, message, pair and matrix kept; the
            app answers 422).
        HTTPException: 503 with
            Retry-After when busy, over the budget, cancelled, out of memory or shutting down,
            500 for a bug in the job.
    """
    wait_until: float | None = request.scope.get(WAIT_UNTIL)

    def work(cancel: threading.Event) -> T:
        return workers.run(fn, *args, timeout=seconds, grace=JOB_GRACE_S if checks_budget else 0.0, cancel=cancel,
                           wait_until=wait_until)

    tail = f"; {hint}" if hint else ""
    try:  # bad input (core.InvalidInput, carried back by the pool) goes up to the app's one handler: 422
        return await run_off_loop(request, work)
    except WorkerBusy as e:
        raise unavailable(f"{e}; retry in a moment") from None
    except WorkerStopped as e:  # the job's own budget check: the message says where
        raise unavailable(f"{e}{tail}") from None
    except WorkerTimeout as e:
        raise unavailable(f"{stopped}{e}{tail}") from None
    except WorkerCancelled as e:
        raise unavailable(f"{stopped}{e}") from None
    except WorkerDied as e:
        cap = f" (memory limit {memory_mb} MB)" if memory_mb is not None else ""
        raise unavailable(f"{stopped}{e}{cap}") from None
    except WorkerFailed as e:
        raise HTTPException(500, f"internal error: {e}") from None


async def run_off_loop(request: Request, fn: Callable[[threading.Event], T]) -> T:
    """Run ``fn(cancel)`` in a worker thread; set ``cancel`` if the client disconnects meanwhile.

    The event loop stays free for other requests (and /healthz) while ``fn`` runs.
    """
    cancel = threading.Event()
    work: asyncio.Future[T] = asyncio.ensure_future(anyio.to_thread.run_sync(fn, cancel))
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
