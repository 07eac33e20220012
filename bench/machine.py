"""The machine a benchmark ran on, for the JSON files in bench/results/ (figures depend on it)."""

from __future__ import annotations

import os
import platform
from pathlib import Path

__all__ = ["cpu_model", "cores", "RESULTS"]

RESULTS = Path(__file__).resolve().parent / "results"
"""Where benchmarks write their data (the docs render their pages from it)."""


def cpu_model() -> str:
    """The CPU's model name from /proc/cpuinfo, or the platform's word for it."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def cores() -> int:
    """Logical CPUs this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
