"""Every script of examples/ runs to its end (issue 56): numbered, a title docstring, a ``main()``.

Each runs in a subprocess from a temporary folder, as a user runs it (``python examples/NN_name.py``);
the scripts assert what they print, so a script whose answer changed fails here. The headless
screenshot needs Debian's chromium (marked ``browser``).
"""

from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("[0-9][0-9]_*.py"))
BROWSER = {"05_headless_screenshot.py"}


def _param(path: Path) -> object:
    """One script as a test parameter; the ones that draw in a browser are marked ``browser``."""
    marks = []
    if path.name in BROWSER:
        marks = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists("/usr/bin/chromium"), reason="needs Debian chromium")]
    return pytest.param(path, id=path.name, marks=marks)


def test_the_examples_are_numbered_with_a_title_and_main():
    """viser's style: NN_name.py, a docstring whose first line is the title, a main() function."""
    assert len(EXAMPLES) >= 5, [p.name for p in EXAMPLES]
    numbers = [int(p.name[:2]) for p in EXAMPLES]
    assert numbers == list(range(1, len(EXAMPLES) + 1)), "examples are numbered 01, 02, ... without gaps"
    for path in EXAMPLES:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        doc = ast.get_docstring(tree)
        assert doc and re.match(r"[A-Z].*\.$|[A-Z].*:", doc.splitlines()[0]), f"{path.name}: a title docstring"
        assert any(isinstance(n, ast.FunctionDef) and n.name == "main" for n in tree.body), f"{path.name}: main()"


@pytest.mark.parametrize("path", [_param(p) for p in EXAMPLES])
def test_the_example_runs(path: Path, tmp_path: Path):
    """The script exits 0 (its own assertions hold) and prints something."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, str(path)], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=300, check=False)
    assert done.returncode == 0, f"{path.name} exited {done.returncode}:\n{done.stderr[-3000:]}"
    assert done.stdout.strip(), f"{path.name} printed nothing"
