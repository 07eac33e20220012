"""Tiny module-level jobs for the worker-pool tests (a child process imports them by reference)."""

from __future__ import annotations

import time
from pathlib import Path


def wait_for(path: str, seconds: float = 60.0) -> bool:
    """Hold a worker until ``path`` exists (the test creates it); False if it never does."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if Path(path).exists():
            return True
        time.sleep(0.01)
    return False


def log(path: str, name: str) -> str:
    """Append ``name`` to the file ``path`` (the order in which queued jobs ran)."""
    with open(path, "a") as f:
        f.write(name + "\n")
    return name
