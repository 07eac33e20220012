"""The project's checks run with the tests (so CI runs them): ruff with the project's config and
mypy, on the code they cover. A finding is a test failure that names it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
RUFF_PATHS = ["core", "app", "tests", "bench"]
"""Ruff-clean (pyproject's [tool.ruff] config)."""
MYPY_PATHS = ["core", "app"]
"""mypy-clean."""


def _run(args: list[str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(args, cwd=ROOT, capture_output=True, text=True, timeout=600, check=False)


def test_ruff_is_clean():
    pytest.importorskip("ruff", reason="ruff is not installed (pip install -e '.[test]')")
    res = _run([sys.executable, "-m", "ruff", "check", *RUFF_PATHS])
    assert res.returncode == 0, res.stdout[-4000:] + res.stderr[-2000:]


def test_mypy_is_clean():
    pytest.importorskip("mypy", reason="mypy is not installed (pip install -e '.[test]')")
    res = _run([sys.executable, "-m", "mypy", *MYPY_PATHS])
    assert res.returncode == 0, res.stdout[-4000:] + res.stderr[-2000:]
