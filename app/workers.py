"""Run CPU-bound work (motion analysis) in a separate process with a time budget.

Used by both the HTTP API (:mod:`app.api`) and the scene (:mod:`app.scene`): they share one
server process, so a long exact computation on a user's input must neither hold
the GIL nor outlive its budget. Each job runs in a fresh child process (``forkserver``: forked
from a clean single-threaded server, never from the threaded web process); the caller waits on
a pipe and kills the child when the budget is spent. A semaphore bounds the jobs running at once;
a job that finds all slots taken is refused at once (the caller answers 503) instead of queueing.

Children never outlive the server: each asks the kernel for SIGKILL when its parent dies
(``prctl(PR_SET_PDEATHSIG)``; its parent is the fork server, which exits when the server
process goes, even on SIGKILL), with a watchdog thread polling the parent pid as a fallback;
:meth:`WorkerPool.shutdown` kills the running jobs and refuses new ones.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

if TYPE_CHECKING:
    from multiprocessing.context import ForkContext, ForkServerContext, SpawnContext

__all__ = ["WorkerPool", "WorkerBusy", "WorkerTimeout", "WorkerDied", "WorkerFailed", "WorkerCancelled"]

_POLL_S = 0.1
"""How often a waiting caller checks the budget, the child and the cancel event."""


class WorkerBusy(RuntimeError):
    """All worker slots are taken, or the pool is shut down (the server is stopping)."""


class WorkerCancelled(RuntimeError):
    """The caller cancelled the job (its client went away); the child was killed."""


class WorkerTimeout(RuntimeError):
    """The job exceeded its time budget and was killed."""


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


def _child(conn: Any, fn: Callable[..., Any], args: tuple, kwargs: dict, memory_mb: int | None) -> None:
    _die_with_parent()
    if memory_mb is not None:
        try:
            import resource

            limit = memory_mb * 1024 * 1024
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        except (ImportError, ValueError, OSError):  # pragma: no cover - platform without rlimits
            pass
    try:
        result = ("ok", fn(*args, **kwargs))
    except ValueError as e:
        result = ("value_error", str(e))
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
        preload: modules the fork server imports once, so children start warm.

    Examples:
        >>> import math
        >>> pool = WorkerPool(1, start_method="spawn")
        >>> pool.run(math.sqrt, 16.0, timeout=60)
        4.0
        >>> pool.run(math.sqrt, -1.0, timeout=60)
        Traceback (most recent call last):
        ...
        ValueError: math domain error
    """

    def __init__(
        self,
        max_jobs: int = 2,
        *,
        memory_mb: int | None = None,
        start_method: str | None = None,
        preload: tuple[str, ...] = ("core",),
    ) -> None:
        if start_method is None:
            start_method = "forkserver" if "forkserver" in mp.get_all_start_methods() else "spawn"
        # every context get_context returns for a method name has .Process (typeshed's BaseContext has not)
        self._ctx = cast("ForkServerContext | SpawnContext | ForkContext", mp.get_context(start_method))
        if start_method == "forkserver" and preload:
            self._ctx.set_forkserver_preload(list(preload))
        self._slots = threading.BoundedSemaphore(max_jobs)
        self._memory_mb = memory_mb
        self._running: set[Any] = set()
        self._lock = threading.Lock()
        self._closed = False
        self.max_jobs = max_jobs

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
        fn: Callable[..., Any],
        /,
        *args: Any,
        timeout: float,
        cancel: threading.Event | None = None,
        **kwargs: Any,
    ) -> Any:
        """Run ``fn(*args, **kwargs)`` in a child process and return its result.

        ``fn``, its arguments and its result must be picklable (module-level functions). The
        slot is taken before anything else, so a busy pool answers before any input is read.

        Args:
            fn: module-level function run in the child.
            *args: its positional arguments.
            timeout: wall-clock budget in seconds (the child is killed when it is spent).
            cancel: set it (e.g. when the client has disconnected) to kill the job.
            **kwargs: its keyword arguments.

        Raises:
            WorkerBusy: every slot is taken, or the pool is shut down (nothing was started).
            WorkerTimeout: ``timeout`` seconds passed; the child was killed.
            WorkerCancelled: ``cancel`` was set; the child was killed.
            ValueError: the job raised ValueError (bad input): same message.
            WorkerDied: the child process died or ran out of memory.
            WorkerFailed: the job raised another exception.
        """
        if self._closed:
            raise WorkerBusy("the server is shutting down")
        if not self._slots.acquire(blocking=False):
            raise WorkerBusy(f"all {self.max_jobs} analysis workers are busy")
        try:
            return self._run(fn, args, kwargs, timeout, cancel)
        finally:
            self._slots.release()

    def _run(self, fn: Callable[..., Any], args: tuple, kwargs: dict, timeout: float, cancel: threading.Event | None) -> Any:
        recv, send = self._ctx.Pipe(duplex=False)
        proc = self._ctx.Process(target=_child, args=(send, fn, args, kwargs, self._memory_mb), daemon=True)
        try:
            proc.start()
        except Exception as e:
            recv.close()
            send.close()
            raise WorkerFailed(f"could not start a worker process: {type(e).__name__}: {e}") from None
        deadline = time.monotonic() + timeout  # after start: a cold fork server does not eat the budget
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
            return payload
        if status == "value_error":
            raise ValueError(payload)
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

    def shutdown(self) -> None:
        """Kill every running job and refuse new ones (called when the server stops).

        The callers waiting on those jobs get :class:`WorkerBusy` ("shutting down") within
        ``_POLL_S`` seconds.
        """
        with self._lock:
            self._closed = True
            procs = list(self._running)
        for proc in procs:
            try:
                if proc.is_alive():
                    proc.kill()
            except ValueError:  # already closed
                pass
