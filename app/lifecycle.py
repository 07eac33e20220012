"""Serving until SIGTERM/SIGINT, then stopping within a few seconds (``docker stop`` gives 10).

uvicorn, on a signal, stops accepting connections and waits for the requests in flight; a
request waiting on a 20 s analysis would hold the exit that long. :class:`StoppableServer`
first runs ``on_stop`` (kill the analysis workers, fail every request budget: those requests
are answered 503 at once), and the graceful wait is capped at :data:`GRACE_S`.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from types import FrameType
from typing import Any

import uvicorn

__all__ = ["StoppableServer", "serve", "GRACE_S"]

GRACE_S = 2
"""Longest wait for requests in flight after a stop signal (their work is already stopped), in
whole seconds (uvicorn's ``timeout_graceful_shutdown`` is an int)."""


class StoppableServer(uvicorn.Server):
    """uvicorn's server that runs ``on_stop`` (once, off the signal handler) on the first signal."""

    def __init__(self, config: uvicorn.Config, on_stop: Callable[[], None]) -> None:
        super().__init__(config)
        self._on_stop = on_stop
        self._stop_started = False

    def handle_exit(self, sig: int, frame: FrameType | None) -> None:
        """Stop the work in progress, then let uvicorn shut down as usual."""
        if not self._stop_started:
            self._stop_started = True
            # in a thread: the handler may interrupt the main thread while it holds a lock
            # that on_stop needs (e.g. the worker pool's)
            threading.Thread(target=self._on_stop, name="stop-work", daemon=True).start()
        super().handle_exit(sig, frame)


def _exit(sig: int, frame: FrameType | None) -> None:
    raise SystemExit(0)


def serve(app: Any, host: str, port: int, on_stop: Callable[[], None]) -> None:
    """Serve ``app`` until SIGTERM/SIGINT; ``on_stop`` runs as soon as the signal arrives.

    uvicorn re-raises the signal after its shutdown; the handler installed here turns it into
    a normal exit (``SystemExit(0)``) so that the caller's cleanup (``finally``) still runs.

    Raises:
        RuntimeError: the port cannot be bound (taken, or not allowed); nothing was served.
    """
    config = uvicorn.Config(app, host=host, port=port, log_level="warning", timeout_graceful_shutdown=GRACE_S)
    server = StoppableServer(config, on_stop)
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, _exit)
    try:
        server.run()
    except SystemExit:
        if server.started:
            raise
        # uvicorn exits when it cannot listen (it logged the OS error): a message and exit status 1
        raise RuntimeError(f"cannot serve the API on {host}:{port} (the port is taken or not allowed): "
                           "choose another with --api-port") from None
