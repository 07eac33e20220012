"""Ending a process group and waiting until none of its processes runs (Linux /proc).

Used for what the tests start in a session of its own: the shared Chromium and its helpers
(tests/browser_helpers.py); tests/test_browser.py checks with it that none is left.
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path


def end_group(pgid: int, timeout: float = 10.0) -> None:
    """Kill what is left of the process group ``pgid`` and wait (at most ``timeout`` s) until none runs.

    A killed process is done with its files once it is a zombie; who reaps it (its parent, or the
    init process, ~1 s here) is not waited for.
    """
    try:
        os.killpg(pgid, signal.SIGKILL)
    except ProcessLookupError:
        return
    deadline = time.monotonic() + timeout
    while running_in_group(pgid) and time.monotonic() < deadline:
        time.sleep(0.01)


def running_in_group(pgid: int) -> bool:
    """Whether a process of the group ``pgid`` is alive and not yet a zombie (Linux /proc)."""
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:  # ended meanwhile
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":  # fields after the name: state, ppid, pgrp
            return True
    return False
