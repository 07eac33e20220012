"""The bottom of the app: the job the scene and the HTTP API share, and the budget jobs check.

Imports only :mod:`core` (and :mod:`app.workers`, the pool that runs jobs): worker processes load
it without FastAPI or viser. Jobs are module-level functions run by :class:`app.workers.WorkerPool`
(picklable by reference, wherever they live), each in its own process under a time budget and a
memory cap, so a job can be killed when its client leaves, when its budget is spent or when the
server stops. Every text a user typed is read in the worker, by core's readers
(:func:`core.moving.motions.read_motion`, :func:`core.moving.motions.read_interval`: one grammar,
each expression parsed once), never in the process serving the tabs and the requests.

* :func:`analyse_job`: read two motions and I under the server's limits, analyse; the
  :class:`core.moving.result.MotionAnalysis` pickles back as it is (the scene keeps it, the API
  writes its JSON).
* :class:`Budget`: the deadline and cancel event a job (or a server thread) checks between steps;
  :func:`budgeted` reports its stop from a worker as :class:`app.workers.WorkerTimeout` saying where.

The jobs that need the API's models live beside them (:mod:`app.api.jobs`), the scene's beside
the scene (:func:`app.scene.pair.motion.read_motion_job`). Bad input is :class:`core.InvalidInput`
(a ValueError): it crosses the process boundary with its pair and matrix, and the API's one
exception handler answers it 422.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from core.moving.analysis import analyse
from core.moving.motions import read_interval, read_motion
from core.moving.result import MotionAnalysis
from core.shapes.limits import SERVER, Limits

from .workers import WorkerTimeout, job_clock

__all__ = ["analyse_job", "Budget", "BudgetExceeded", "Cancelled", "STOPPING", "budgeted"]

STOPPING = threading.Event()
"""Set when the server process is stopping (SIGTERM): every budget check then fails at once."""


def analyse_job(
    a: Any,
    b: Any,
    interval: Any,
    digits: int = 20,
    limits: Limits = SERVER,
    names: tuple[str, str] = ("a", "b"),
) -> MotionAnalysis:
    """Read both motions and I under ``limits``, then :func:`core.moving.analysis.analyse` them.

    The same contract for the scene and the HTTP API.

    Args:
        a: the first motion: a motion dict, an n x n nested list of expressions, or a
            :class:`core.moving.motions.Motion` already read (the scene's).
        b: the second, likewise.
        interval: I as a pair (lo, hi) or the text "lo, hi" (:func:`core.moving.motions.read_interval`).
        digits: significant digits of the event values.
        limits: size limits of the text (:data:`core.shapes.limits.SERVER`, or the API's
            :meth:`app.api.settings.ApiSettings.text_limits`).
        names: the motions' names in error messages ("a.translation[0]: ...").

    Raises:
        ValueError: unreadable text (its place named), or a motion that cannot be analysed on I
            (core's message).
    """
    ma, mb = read_motion(a, limits=limits, name=names[0]), read_motion(b, limits=limits, name=names[1])
    return analyse(ma, mb, read_interval(interval, limits), digits=digits)


class BudgetExceeded(RuntimeError):
    """The request's work went over its time budget (or the server is stopping)."""


class Cancelled(RuntimeError):
    """The client disconnected: nobody will read the answer."""


class Budget:
    """Deadline plus cancel event of one request; call :meth:`check` between steps.

    In a worker process the deadline counts from when the pool started the job's clock
    (:func:`app.workers.job_clock`), not from when the job got here: the pool kills the job
    :data:`JOB_GRACE_S` after its own deadline, which counts from then, so the job's last check
    comes first and says where it stopped. Was: on a loaded machine the child's start (fork,
    reading its arguments) took long enough that the kill came first, with a message that says less.
    """

    def __init__(self, seconds: float, cancel: threading.Event | None = None) -> None:
        self.seconds = seconds
        now = time.monotonic()
        clock = job_clock()
        self.deadline = (clock if clock is not None and clock <= now else now) + seconds
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


@contextmanager
def budgeted() -> Iterator[None]:
    """A budget stop inside a worker job as the pool reports it: :class:`WorkerTimeout` saying where."""
    try:
        yield
    except BudgetExceeded as e:
        raise WorkerTimeout(str(e)) from None
