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


def budget_checks_after_a_slow_start(start_s: float, budget_s: float) -> None:
    """A job whose start takes ``start_s`` (as on a loaded machine), then checks a budget of
    ``budget_s`` every 10 ms until it is spent: it stops with the budget's message, saying where."""
    from app.jobs import Budget, BudgetExceeded
    from app.workers import WorkerTimeout

    time.sleep(start_s)
    budget = Budget(budget_s)
    steps = 0
    try:
        while True:
            budget.check(f"after {steps} steps")
            steps += 1
            time.sleep(0.01)
    except BudgetExceeded as e:
        raise WorkerTimeout(str(e)) from None
