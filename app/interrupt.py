"""A stop that cannot be lost: Ctrl+C (SIGINT) and SIGTERM recorded as well as raised.

Python runs a signal's handler in the main thread between two bytecodes, so the exception it
raises can land inside Python code that C calls and whose errors C clears: numpy's lookup of a
special attribute on an enum swallowed a KeyboardInterrupt that way (a Ctrl+C during ``contacts
--method exact`` was lost about once in 8 runs: the file written, exit 0). The handlers here also
record the signal, and :func:`check` raises it again where a command must not go on after a stop:
each step of a progress bar and the commit of an output file (:mod:`app.output`).
"""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator

__all__ = ["Terminated", "check", "unwinding"]


class Terminated(BaseException):
    """SIGTERM during a command: unwinds like Ctrl+C (temporary files removed), exit 143."""


_received = [0]
"""The stop signal received while :func:`unwinding` is active (0: none); a list, set in place."""


def _raise(signum: int) -> None:
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise Terminated()


def _handler(signum: int, frame: object) -> None:
    _received[0] = signum
    _raise(signum)


def check() -> None:
    """Raise KeyboardInterrupt or :class:`Terminated` again if a stop signal was received."""
    if _received[0]:
        _raise(_received[0])


@contextlib.contextmanager
def unwinding() -> Iterator[None]:
    """While a command runs, SIGINT and SIGTERM unwind it and are recorded; the caller's handlers after.

    Only the main thread can set handlers (a command run from another thread, a test's, leaves them
    alone and records nothing). The previous handlers come back so that a program that calls the
    command line in its own process (a test runner) keeps its own.
    """
    previous: dict[int, object] = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[sig] = signal.signal(sig, _handler)
    except ValueError:  # not the main thread
        yield
        return
    _received[0] = 0
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]
        _received[0] = 0
