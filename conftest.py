"""Repository-level pytest configuration: a time limit per test phase; Dask doctests need their extra."""

from __future__ import annotations

import faulthandler
import importlib.util
import os
import signal
import sys
import threading
from collections.abc import Generator

import pytest

# core/bodies/distributed.py imports dask at import time (it is only imported when Dask is used);
# without ``pip install -e ".[dask]"`` its doctest collection is skipped instead of failing
collect_ignore = [] if importlib.util.find_spec("distributed") else ["core/bodies/distributed.py"]

HANG_SECONDS = float(os.environ.get("ELLIPSOID_TEST_HANG_SECONDS", "480"))
"""A test's setup, call or teardown that runs longer fails: every thread's stack goes to stderr.

A hung test must cost one failure, not the CI's whole time. faulthandler's ``exit`` would end the
worker process, and pytest-xdist 3.8 (``--dist loadfile``) then runs the crashed test again in each
new worker; so the limit raises in the test instead (SIGALRM, main thread only), and the next test runs.
"""

_STDERR: dict[str, int] = {}
"""A copy of the real stderr (capturing replaces fd 2 during tests) for the stack dump."""


def pytest_configure(config: pytest.Config) -> None:
    """Copy the real stderr's file descriptor once."""
    if "fd" not in _STDERR:
        _STDERR["fd"] = os.dup(sys.__stderr__.fileno() if sys.__stderr__ else 2)


class _Hang:
    """SIGALRM after :data:`HANG_SECONDS`: dump every thread's stack, then fail the running phase."""

    def __init__(self, item: pytest.Item, phase: str) -> None:
        self.where = f"{item.nodeid} ({phase})"

    def __call__(self, signum: int, frame: object) -> None:
        fd = _STDERR.get("fd")
        if fd is not None:
            os.write(fd, f"\n--- {self.where} over {HANG_SECONDS:g} s; stacks:\n".encode())
            faulthandler.dump_traceback(file=fd, all_threads=True)
        pytest.fail(f"over {HANG_SECONDS:g} s (ELLIPSOID_TEST_HANG_SECONDS): every thread's stack is on stderr",
                    pytrace=False)


def _limited(item: pytest.Item, phase: str) -> Generator[None, object, object]:
    if HANG_SECONDS <= 0 or threading.current_thread() is not threading.main_thread():
        return (yield)
    previous = signal.signal(signal.SIGALRM, _Hang(item, phase))
    signal.setitimer(signal.ITIMER_REAL, HANG_SECONDS)
    try:
        return (yield)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_runtest_setup(item: pytest.Item) -> Generator[None, object, object]:
    """Setup within :data:`HANG_SECONDS`."""
    return (yield from _limited(item, "setup"))


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_runtest_call(item: pytest.Item) -> Generator[None, object, object]:
    """The test within :data:`HANG_SECONDS`."""
    return (yield from _limited(item, "call"))


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_runtest_teardown(item: pytest.Item, nextitem: pytest.Item | None) -> Generator[None, object, object]:
    """Teardown within :data:`HANG_SECONDS`."""
    return (yield from _limited(item, "teardown"))
