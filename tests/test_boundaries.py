"""core/ is pure mathematics: it imports only numpy, python-flint (flint) and the stdlib."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

CORE = Path(__file__).resolve().parent.parent / "core"
ALLOWED = {"numpy", "flint"}
FORBIDDEN = {"viser", "fastapi", "pydantic", "starlette", "uvicorn", "trimesh", "app"}


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_core_imports_no_web_packages():
    stdlib = set(sys.stdlib_module_names)
    for path in sorted(CORE.glob("*.py")):
        mods = _imports(path)
        assert not (mods & FORBIDDEN), f"{path.name} imports {mods & FORBIDDEN}"
        extra = mods - stdlib - ALLOWED - {"__future__"}
        assert not extra, f"{path.name} imports non-core packages {extra}"


def test_boundary_check_can_fail(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("import viser\nfrom fastapi import FastAPI\n")
    assert _imports(bad) & FORBIDDEN == {"viser", "fastapi"}
