"""The suite's time limit per test phase (conftest.py): a hung test fails and the next one runs."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_a_hung_test_fails_with_its_stacks_and_the_next_test_runs(tmp_path):
    shutil.copy(ROOT / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    (tmp_path / "test_h.py").write_text(
        "import threading, time\n"
        "def test_sleeps():\n    time.sleep(600)\n"
        "def test_waits_on_a_lock():\n    lock = threading.Lock(); lock.acquire(); lock.acquire()\n"
        "def test_after():\n    assert True\n")
    env = {**os.environ, "ELLIPSOID_TEST_HANG_SECONDS": "1.5"}
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist", "test_h.py"],
                         check=False, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "2 failed, 1 passed" in run.stdout, run.stdout
    assert run.stdout.count("over 1.5 s (ELLIPSOID_TEST_HANG_SECONDS)") >= 2
    assert "test_h.py::test_sleeps (call) over 1.5 s" in run.stderr and "time.sleep" not in run.stdout
    assert 'File "' in run.stderr  # the stacks
