"""mypy started with the suite at the lowest CPU priority, so that its run fills the moments the
browser tests leave the CPUs idle; ``test_lint`` takes its verdict.

A cold mypy run (a fresh clone: no .mypy_cache) takes ~11 s of CPU, which a worker used to spend
while the other waited; the suite leaves ~40 CPU-s idle (tabs waiting on a server or a frame).
The run starts in the pytest process that schedules the tests (the xdist controller, or the only
process with ``-n 0``) once the mypy test is collected, niced to 19. The test takes its result
if it has ended; otherwise it stops it and runs mypy itself at normal priority (what the stopped
run finished is in mypy's cache), so a loaded machine, where a niced process gets almost no
CPU, never makes the test wait for it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Collection
from pathlib import Path

from process_groups import end_group

ROOT = Path(__file__).resolve().parent.parent
MYPY_PATHS = ["core", "app"]
"""mypy-clean, in one run; core under the flags of ``mypy --strict`` (pyproject's override for
core.*, plus the global ones on the command line): the library is a typed package (core/py.typed).
One run analyses core once (two runs, default and --strict, took 25 + 13 s of the suite)."""
MYPY_GLOBAL_STRICT = ["--warn-redundant-casts", "--warn-unused-configs"]
"""The flags of --strict that mypy takes only for a whole run."""
MYPY_CACHE = ROOT / ".mypy_cache"
MYPY_TEST = "tests/test_lint.py::test_mypy_is_clean_and_core_is_strict"
"""The test that takes the run's verdict (its node id)."""
RESULT_DIR_ENV = "ELLIPSOID_TEST_MYPY_DIR"
"""Where the scheduling process says (to the workers it starts) the run writes: ``pid``, then ``result.json``."""

_WRAPPER = r"""
import json, os, subprocess, sys
os.nice(19)
out = sys.argv[1]
res = subprocess.run(sys.argv[2:], capture_output=True, text=True, check=False)
with open(out + ".tmp", "w") as f:
    json.dump({"returncode": res.returncode, "stdout": res.stdout, "stderr": res.stderr}, f)
os.replace(out + ".tmp", out)
"""

def mypy_command() -> list[str]:
    """The one mypy run of the suite."""
    return [sys.executable, "-m", "mypy", "--cache-dir", str(MYPY_CACHE), *MYPY_GLOBAL_STRICT, *MYPY_PATHS]


def announce() -> None:
    """Scheduling process, before it starts workers: a fresh folder for the run's files."""
    os.environ[RESULT_DIR_ENV] = tempfile.mkdtemp(prefix="ellipsoid-mypy-")


class _Run:
    """The run this process started (the scheduling process only)."""

    proc: subprocess.Popen[bytes] | None = None

    @classmethod
    def start(cls, ids: Collection[str]) -> None:
        """Start the run (once) if the mypy test is among the collected ``ids`` and mypy is installed."""
        folder = os.environ.get(RESULT_DIR_ENV)
        if cls.proc is not None or folder is None or MYPY_TEST not in ids:
            return
        try:
            import mypy  # noqa: F401
        except ImportError:
            return
        cls.proc = subprocess.Popen(
            [sys.executable, "-c", _WRAPPER, os.path.join(folder, "result.json"), *mypy_command()],
            cwd=ROOT, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        Path(folder, "pid").write_text(str(cls.proc.pid))

    @classmethod
    def stop(cls) -> None:
        """At the end: stop a run still going, remove its files."""
        proc, cls.proc = cls.proc, None
        if proc is not None and proc.poll() is None:
            end_group(proc.pid)  # the wrapper and its mypy (a session of their own)
            proc.wait(30)
        folder = os.environ.pop(RESULT_DIR_ENV, None)
        if folder is not None:
            for name in ("pid", "result.json", "result.json.tmp"):
                Path(folder, name).unlink(missing_ok=True)
            os.rmdir(folder)


start = _Run.start
stop = _Run.stop


def verdict() -> subprocess.CompletedProcess[str]:
    """The suite's mypy result: the background run's if it has ended, else a run now (stopping it)."""
    folder = os.environ.get(RESULT_DIR_ENV)
    if folder is not None:
        result = Path(folder, "result.json")
        if result.exists():
            d = json.loads(result.read_text())
            return subprocess.CompletedProcess(mypy_command(), d["returncode"], d["stdout"], d["stderr"])
        pid = Path(folder, "pid")
        if pid.exists():
            end_group(int(pid.read_text()))
            # a result written meanwhile is as good; a cut run left its finished modules in the cache
            if result.exists():
                return verdict()
    return subprocess.run(mypy_command(), cwd=ROOT, capture_output=True, text=True, timeout=600, check=False)
