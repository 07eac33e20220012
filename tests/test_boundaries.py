"""core/ is pure mathematics in subpackages without import cycles; it imports only numpy,
python-flint (flint) and the standard library, except the Dask path: two modules that are
imported only when Dask is used (``pip install -e ".[dask]"``) may import dask/distributed."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

CORE = Path(__file__).resolve().parent.parent / "core"
ALLOWED = {"numpy", "flint"}
FORBIDDEN = {"viser", "fastapi", "pydantic", "starlette", "uvicorn", "trimesh", "app"}
OPTIONAL = {
    "fixed/lazy.py": {"dask"},  # classify on dask arrays (imports dask inside its functions)
    "bodies/distributed.py": {"dask", "distributed"},  # contacts on a cluster (imported lazily)
}
"""Modules of the optional Dask path and what they may import besides ALLOWED."""


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def _module(path: Path) -> str:
    parts = list(path.relative_to(CORE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _core_edges(path: Path) -> set[str]:
    """Core modules this file imports (top level or inside functions), resolved to module names."""
    mod = _module(path)
    pkg = mod.split(".") if path.name == "__init__.py" else mod.split(".")[:-1]
    out: set[str] = set()
    known = {_module(p) for p in CORE.rglob("*.py")}
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg[: len(pkg) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:  # "from . import x" imports the module x
                sub = f"{target}.{alias.name}"
                out.add(sub if sub in known else target)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return {m for m in out if m in known and m != mod}


def test_core_imports_no_web_packages():
    stdlib = set(sys.stdlib_module_names)
    files = sorted(CORE.rglob("*.py"))
    assert len(files) > 30 and any("/" in str(p.relative_to(CORE)) for p in files)  # subpackages are scanned
    for path in files:
        mods = _imports(path)
        assert not (mods & FORBIDDEN), f"{path} imports {mods & FORBIDDEN}"
        extra = mods - stdlib - ALLOWED - {"__future__", "core"} - OPTIONAL.get(path.relative_to(CORE).as_posix(), set())
        assert not extra, f"{path} imports non-core packages {extra}"


def test_core_imports_dask_only_when_asked():
    """``import core`` (and a contact search on one machine) never loads dask."""
    code = (
        "import sys, numpy as np, core; "
        "core.contacts(core.bodies_from_axes(np.zeros((2, 3)), np.ones((2, 3)))); "
        "core.classify(np.eye(3)[None], np.eye(3)[None] * -1.0, on_invalid='mark'); "
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed')))"
    )
    import subprocess

    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=CORE.parent, check=True)
    assert out.stdout.strip() == "[]"


def test_no_import_cycles_in_core():
    """Between modules (package __init__ files re-export and are left out)."""
    graph = {_module(p): _core_edges(p) for p in CORE.rglob("*.py") if p.name != "__init__.py"}
    graph = {m: {e for e in es if e in graph} for m, es in graph.items()}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for e in sorted(graph[m]):
            if state.get(e) == 1:
                cycle = stack[stack.index(e) :] + [e]
                raise AssertionError("import cycle: " + " -> ".join(cycle))
            if e not in state:
                visit(e)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m)


def test_boundary_check_can_fail(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("import viser\nfrom fastapi import FastAPI\n")
    assert _imports(bad) & FORBIDDEN == {"viser", "fastapi"}
