"""The suite's mypy run in the background (tests/background_mypy.py): started only for the mypy
test, its verdict taken when it has ended, stopped (never waited for at low priority) when not."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import background_mypy
import pytest
from process_groups import running_in_group

FAKE_MYPY = [sys.executable, "-c", "import os, sys; print('fake mypy at nice', os.nice(0)); sys.exit(3)"]
"""A stand-in for mypy: fast, exit code 3, says its CPU priority."""
NOW = f"fake mypy at nice {os.nice(0)}"
"""What it says when the test process runs it."""


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """A run folder of this test's own, and the stand-in for mypy."""
    monkeypatch.setenv(background_mypy.RESULT_DIR_ENV, str(tmp_path))
    monkeypatch.setattr(background_mypy, "mypy_command", lambda: FAKE_MYPY)
    return tmp_path


def test_an_ended_run_gives_its_verdict(folder):
    (folder / "result.json").write_text(json.dumps({"returncode": 1, "stdout": "core/x.py:1: error", "stderr": ""}))
    res = background_mypy.verdict()
    assert (res.returncode, res.stdout) == (1, "core/x.py:1: error")


def test_a_run_still_going_is_stopped_and_mypy_runs_now(folder):
    slow = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"], start_new_session=True)
    try:
        (folder / "pid").write_text(str(slow.pid))
        res = background_mypy.verdict()
        assert (res.returncode, res.stdout.strip()) == (3, NOW)  # the run made now
        assert not running_in_group(slow.pid)
    finally:
        slow.kill()
        slow.wait()


def test_without_a_run_mypy_runs_now(folder):
    res = background_mypy.verdict()
    assert (res.returncode, res.stdout.strip()) == (3, NOW)


def test_started_only_for_the_mypy_test_and_its_files_removed(tmp_path, monkeypatch):
    monkeypatch.delenv(background_mypy.RESULT_DIR_ENV, raising=False)
    monkeypatch.setattr(background_mypy, "mypy_command", lambda: FAKE_MYPY)
    monkeypatch.setattr(background_mypy._Run, "proc", None)
    background_mypy.announce()
    where = os.environ[background_mypy.RESULT_DIR_ENV]
    try:
        background_mypy.start(["tests/test_lint.py::test_ruff_is_clean"])
        assert background_mypy._Run.proc is None and not os.listdir(where)
        background_mypy.start([background_mypy.MYPY_TEST])
        proc = background_mypy._Run.proc
        assert proc is not None
        deadline = time.monotonic() + 60
        while proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        res = background_mypy.verdict()
        assert (res.returncode, res.stdout.strip()) == (3, "fake mypy at nice 19")  # the background run's
    finally:
        background_mypy.stop()
    assert not os.path.exists(where) and background_mypy.RESULT_DIR_ENV not in os.environ
