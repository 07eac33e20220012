"""Run CPU-bound work (motion analysis) in a separate process with a time budget.

Used by both the HTTP API (:mod:`app.api`) and the scene (:mod:`app.scene`): they share one
server process, so a long exact computation on a user's input must neither hold
the GIL nor outlive its budget. Each job runs in a fresh child process (``forkserver``: forked
from a clean single-threaded server, never from the threaded web process); the caller waits on
a pipe and kills the child when the budget is spent. At most ``max_jobs`` run at once; in front of
them a bounded first-come-first-served queue (``max_waiting`` callers, each for at most
``max_wait_s`` seconds, then :class:`WorkerBusy`): a burst of ordinary requests is served in
turn, and only a burst beyond the queue is refused at once (the caller answers 503). A job's time
budget starts when it starts running, not while it waits.

Children never outlive the server: each asks the kernel for SIGKILL when its parent dies
(``prctl(PR_SET_PDEATHSIG)``; its parent is the fork server, which exits when the server
process goes, even on SIGKILL), with a watchdog thread polling the parent pid as a fallback;
:meth:`WorkerPool.shutdown` kills the running jobs and refuses new ones.

Children run under Linux's batch scheduling policy (``SCHED_BATCH``): they keep their fair
share of the CPU (a job's budget means the same on a busy machine), but a server thread that
wakes up (``/healthz``, a short request, the scene's interaction) is not kept waiting behind them.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar, cast

from core.errors import InvalidInput

if TYPE_CHECKING:
    from multiprocessing.context import ForkContext, ForkServerContext, SpawnContext

T = TypeVar("T")

__all__ = ["JOB_MODULES", "job_clock", "WorkerPool", "WorkerBusy", "WorkerTimeout", "WorkerStopped", "WorkerDied", "WorkerFailed", "WorkerCancelled"]

JOB_MODULES: tuple[str, ...] = (
    "core",
    "core.moving.analysis",
    "core.witness",
    "app.jobs",
    "app.api.jobs",
    "app.api.convert",
    "app.api.witness_out",
    "app.api.contacts_schemas",
    "app.api.sweep_schemas",
    "app.api.limits",
    "app.scene.pair.motion",
    "core.moving._sweep_filter",
)
"""What the fork server imports once, for every job of :mod:`app.jobs` and its arguments.

One list for the process, not one per pool: multiprocessing has one fork server per process,
started by the first pool that runs a job, and it ignores a later pool's preload. When the
scene's pool came first, each API job imported FastAPI, pydantic and the witness code again
in its child (~0.7 s of CPU per request). A module that cannot be imported is skipped by the
fork server (the compiled sweep filter of an install without it). tests/test_workers.py runs
every job in a process that imported only these and fails if one needs more."""

_POLL_S = 0.1
"""How often a waiting caller checks the budget, the child and the cancel event."""


class WorkerBusy(RuntimeError):
    """No slot: every slot and the queue are taken, the wait ran out, or the pool is shut down."""


class WorkerCancelled(RuntimeError):
    """The caller cancelled the job (its client went away); the child was killed."""


class WorkerTimeout(RuntimeError):
    """The job exceeded its time budget and was killed.

    A job raises it from its own budget check (it stops where it is; the message says where).
    """


class WorkerStopped(WorkerTimeout):
    """The job stopped itself at its own budget check; the message says where.

    (It raised :class:`WorkerTimeout` in the child.)
    """


class WorkerDied(RuntimeError):
    """The worker process died or ran out of memory (e.g. FLINT aborts when its memory cap is hit)."""


class WorkerFailed(RuntimeError):
    """The job raised something other than ValueError or MemoryError (a bug)."""


def _release_forkserver() -> None:
    """Close this child's copy of the fd that keeps the fork server alive.

    multiprocessing hands it to every child of the fork server, so a running child would keep
    the fork server alive after the server process died, and the fork server (its parent) the
    child: an orphan. Closed, the fork server exits when the server process goes, and the
    child follows by its parent-death signal.
    """
    try:
        from multiprocessing import forkserver

        # ignored: private state of the fork server on purpose (not in typeshed)
        fs = forkserver._forkserver
        fd = fs._forkserver_alive_fd  # type: ignore[attr-defined]
        if fd is not None:
            fs._forkserver_alive_fd = None  # type: ignore[attr-defined]
            os.close(fd)
    except (AttributeError, ImportError, OSError):  # another start method: nothing to release
        pass


def _die_with_parent() -> None:
    """Ask for SIGKILL when the parent process dies (Linux), else watch the parent pid."""
    _release_forkserver()
    parent = os.getppid()
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            PR_SET_PDEATHSIG = 1
            if libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0:
                if os.getppid() != parent:  # the parent died before prctl took effect
                    os._exit(1)
                return
        except (OSError, AttributeError):  # pragma: no cover - no libc / no prctl
            pass

    def watch() -> None:  # pragma: no cover - only where prctl is unavailable
        while True:
            time.sleep(0.5)
            if os.getppid() != parent:
                os.kill(os.getpid(), signal.SIGKILL)

    threading.Thread(target=watch, name="parent-watchdog", daemon=True).start()


def _batch_policy() -> None:
    """This process under ``SCHED_BATCH``: CPU-bound, never preempting a waking server thread.

    Not a lower priority (``nice``): a niced job would get a fraction of its share whenever any
    other process is busy, and run out of its wall-clock budget on a loaded machine.
    """
    try:
        os.sched_setscheduler(0, os.SCHED_BATCH, os.sched_param(0))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        pass


_JOB_CLOCK: list[float] = []
"""In a worker process: when the pool started its job's clock (``time.monotonic()``); empty elsewhere."""


def job_clock() -> float | None:
    """When the pool started the clock of this process's job (``time.monotonic()``), or None outside a worker.

    Read before the child starts: the pool's own deadline counts from just after it, so a budget
    of the same length counted from here (:class:`app.api.budget.Budget`) always ends first.
    ``time.monotonic()`` is Linux's ``CLOCK_MONOTONIC``, one clock for every process of the machine.
    """
    return _JOB_CLOCK[0] if _JOB_CLOCK else None


def _child(
    conn: Any, fn: Callable[..., Any], args: tuple[Any, ...], kwargs: dict[str, Any], memory_mb: int | None, clock: float | None = None
) -> None:
    if clock is not None:
        _JOB_CLOCK[:] = [clock]
    _die_with_parent()
    _batch_policy()
    if memory_mb is not None:
        try:
            import resource

            limit = memory_mb * 1024 * 1024
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        except (ImportError, ValueError, OSError):  # pragma: no cover - platform without rlimits
            pass
    try:
        result = ("ok", fn(*args, **kwargs))
    except ValueError as e:  # bad input: its message, and its pair and matrix when core said (InvalidInput)
        result = ("value_error", (str(e), getattr(e, "pair", None), getattr(e, "matrix", None), getattr(e, "reason", None)))
    except WorkerTimeout as e:  # the job's own budget check: it says where it stopped
        result = ("timeout", str(e))
    except MemoryError:
        result = ("died", f"the job ran out of memory (limit {memory_mb} MB)")
    except BaseException as e:  # report everything: the parent turns it into a clean error
        result = ("failed", f"{type(e).__name__}: {e}")
    try:
        conn.send(result)
    except Exception as e:  # unpicklable result
        conn.send(("failed", f"result could not be sent back: {type(e).__name__}: {e}"))
    finally:
        conn.close()


class WorkerPool:
    """At most ``max_jobs`` child processes at once, each killed when its budget runs out.

    Args:
        max_jobs: jobs that may run at the same time.
        memory_mb: address-space limit of each child (None: none).
        start_method: multiprocessing start method ("forkserver" where available).
        max_waiting: callers that may wait for a slot (first come, first served); one more is
            refused at once. 0: refuse whenever every slot is taken.
        max_wait_s: longest wait in the queue before :class:`WorkerBusy`.

    Examples:
        >>> import math
        >>> pool = WorkerPool(1, start_method="spawn")
        >>> pool.run(math.sqrt, 16.0, timeout=60)
        4.0
        >>> pool.run(math.sqrt, -1.0, timeout=60)
        Traceback (most recent call last):
        ...
        core.errors.InvalidInput: math domain error
    """

    def __init__(
        self,
        max_jobs: int = 2,
        *,
        memory_mb: int | None = None,
        start_method: str | None = None,
        max_waiting: int = 0,
        max_wait_s: float = 10.0,
    ) -> None:
        if start_method is None:
            start_method = "forkserver" if "forkserver" in mp.get_all_start_methods() else "spawn"
        # every context get_context returns for a method name has .Process (typeshed's BaseContext has not)
        self._ctx = cast("ForkServerContext | SpawnContext | ForkContext", mp.get_context(start_method))
        if start_method == "forkserver":  # children start warm: see JOB_MODULES
            self._ctx.set_forkserver_preload(list(JOB_MODULES))
        self._memory_mb = memory_mb
        self._running: set[Any] = set()
        self._lock = threading.Lock()
        self._turn = threading.Condition(self._lock)
        """Signalled when a slot is freed, a waiter leaves the queue, or the pool shuts down."""
        self._queue: deque[object] = deque()
        self._busy = 0
        """Slots taken (a job between taking its slot and ending)."""
        self._closed = False
        self.max_jobs = max_jobs
        self.max_waiting = max_waiting
        self.max_wait_s = max_wait_s

    def start(self) -> None:
        """Accept jobs (again) after :meth:`shutdown`.

        An app's lifespan can run more than once (tests); a new pool accepts jobs already.
        """
        with self._lock:
            self._closed = False

    @property
    def closed(self) -> bool:
        """True once :meth:`shutdown` ran: every new job is refused."""
        return self._closed

    def run(
        self,
        fn: Callable[..., T],
        /,
        *args: Any,
        timeout: float,
        cancel: threading.Event | None = None,
        grace: float = 0.0,
        wait_until: float | None = None,
        **kwargs: Any,
    ) -> T:
        """Run ``fn(*args, **kwargs)`` in a child process and return its result.

        ``fn``, its arguments and its result must be picklable (module-level functions). A
        slot is taken (after waiting in the queue, if any) before anything else, so a busy pool
        answers before any input is read.

        Args:
            fn: module-level function run in the child.
            *args: its positional arguments.
            timeout: wall-clock budget in seconds from the job's start (the child is killed
                when it is spent, plus ``grace``).
            cancel: set it (e.g. when the client has disconnected) to kill the job, or to leave
                the queue.
            grace: extra seconds for a job that checks its own budget of ``timeout`` seconds
                (it then raises :class:`WorkerTimeout` saying where it stopped).
            wait_until: ``time.monotonic()`` after which the caller stops waiting in the queue,
                if sooner than ``max_wait_s`` from now (a request that already waited to be
                read: its wait is one, :data:`app.api.budget.WAIT_UNTIL`). A free slot is taken
                even when it has passed.
            **kwargs: its keyword arguments.

        Raises:
            WorkerBusy: every slot and the queue are taken, the wait ran out, or the pool is
                shut down (nothing was started).
            WorkerTimeout: ``timeout`` seconds passed; the child was killed (or stopped itself).
            WorkerCancelled: ``cancel`` was set; the child was killed (or the caller left the
                queue).
            core.InvalidInput: the job raised ValueError (bad input): same message, and its
                ``pair``, ``matrix`` and ``reason`` when it was an InvalidInput.
            WorkerDied: the child process died or ran out of memory.
            WorkerFailed: the job raised another exception.
        """
        self._acquire(cancel, wait_until)
        try:
            return self._run(fn, args, kwargs, timeout, grace, cancel)
        finally:
            with self._turn:
                self._busy -= 1
                self._turn.notify_all()

    def _acquire(self, cancel: threading.Event | None, wait_until: float | None = None) -> None:
        """Take a slot: at once, or in turn after the callers queued before this one."""
        with self._turn:
            if self._closed:
                raise WorkerBusy("the server is shutting down")
            if self._busy < self.max_jobs and not self._queue:
                self._busy += 1
                return
            if len(self._queue) >= self.max_waiting:
                queued = f" and {len(self._queue)} requests are waiting" if self.max_waiting else ""
                raise WorkerBusy(f"all {self.max_jobs} workers are busy{queued}")
            ticket = object()
            self._queue.append(ticket)
            deadline = time.monotonic() + self.max_wait_s
            if wait_until is not None:
                deadline = min(deadline, wait_until)
            try:
                while not (self._queue[0] is ticket and self._busy < self.max_jobs):
                    if self._closed:
                        raise WorkerBusy("the server is shutting down")
                    if cancel is not None and cancel.is_set():
                        raise WorkerCancelled("the request left the queue (the client went away)")
                    left = deadline - time.monotonic()
                    if left <= 0:
                        raise WorkerBusy(f"waited {self.max_wait_s:g} s in the queue for one of the {self.max_jobs} workers")
                    self._turn.wait(min(left, _POLL_S))
                self._busy += 1
            finally:
                self._queue.remove(ticket)
                self._turn.notify_all()  # the next in line may now be first

    def _run(
        self, fn: Callable[..., T], args: tuple[Any, ...], kwargs: dict[str, Any], timeout: float, grace: float,
        cancel: threading.Event | None,
    ) -> T:
        recv, send = self._ctx.Pipe(duplex=False)
        clock = time.monotonic()  # the job's own budget counts from here (job_clock), the kill from after start
        proc = self._ctx.Process(target=_child, args=(send, fn, args, kwargs, self._memory_mb, clock), daemon=True)
        try:
            proc.start()
        except Exception as e:
            recv.close()
            send.close()
            raise WorkerFailed(f"could not start a worker process: {type(e).__name__}: {e}") from None
        deadline = time.monotonic() + timeout + grace  # after start: a cold fork server does not eat the budget
        with self._lock:
            self._running.add(proc)
            closed = self._closed  # shutdown() ran while this child was starting
        try:
            send.close()  # the child holds the only write end: EOF when it dies
            while True:
                if closed or self._closed:
                    raise WorkerBusy("the server is shutting down")
                if cancel is not None and cancel.is_set():
                    raise WorkerCancelled("the job was cancelled (the client went away)")
                left = deadline - time.monotonic()
                if left <= 0:
                    raise WorkerTimeout(f"the job exceeded its time budget of {timeout:g} s and was stopped")
                if recv.poll(min(left, _POLL_S)):
                    try:
                        status, payload = recv.recv()
                    except EOFError:
                        if self._closed:
                            raise WorkerBusy("the server is shutting down") from None
                        raise WorkerDied(self._died(proc)) from None
                    break
                if not proc.is_alive() and not recv.poll(0):
                    if self._closed:
                        raise WorkerBusy("the server is shutting down")
                    raise WorkerDied(self._died(proc))
        finally:
            if proc.is_alive():
                proc.kill()
            proc.join(timeout=5)
            recv.close()
            with self._lock:
                self._running.discard(proc)
            if proc.exitcode is not None:
                proc.close()
        if status == "ok":
            return cast(T, payload)  # what fn returned, pickled back
        if status == "value_error":
            message, pair, matrix, reason = payload
            raise InvalidInput(message, pair=pair, matrix=matrix, reason=reason)
        if status == "timeout":
            raise WorkerStopped(payload)
        if status == "died":
            raise WorkerDied(payload)
        raise WorkerFailed(payload)

    @staticmethod
    def _died(proc: Any) -> str:
        proc.join(timeout=1)
        return f"the worker process died (exit code {proc.exitcode})"

    @property
    def running(self) -> int:
        """Jobs running now."""
        with self._lock:
            return len(self._running)

    @property
    def waiting(self) -> int:
        """Callers waiting in the queue now."""
        with self._lock:
            return len(self._queue)

    def shutdown(self) -> None:
        """Kill every running job and refuse new ones (called when the server stops).

        The callers waiting on those jobs, and those waiting in the queue, get
        :class:`WorkerBusy` ("shutting down") within ``_POLL_S`` seconds.
        """
        with self._turn:
            self._closed = True
            procs = list(self._running)
            self._turn.notify_all()
        for proc in procs:
            try:
                if proc.is_alive():
                    proc.kill()
            except ValueError:  # already closed
                pass
