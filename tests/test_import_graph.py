"""app/ has no import circle at run time: every import, at module level or inside a function,
is an edge of the module graph, and the graph has no cycle (``if TYPE_CHECKING:`` blocks are
left out: they never run). The worker side (:mod:`app.jobs`, :mod:`app.workers`) imports no
FastAPI and nothing of the scene or the API."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
APP = ROOT / "app"


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _is_type_checking(test: ast.expr) -> bool:
    """``if TYPE_CHECKING:`` or ``if typing.TYPE_CHECKING:``."""
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST, module: str, is_package: bool, modules: set[str] | None = None) -> set[str]:
    """Every module ``module`` imports when it runs (absolute names), TYPE_CHECKING blocks left out.

    ``from p import x`` is the module p.x when ``modules`` holds it, else p (x is a name in p);
    without ``modules``, both.
    """
    found: set[str] = set()
    package = module if is_package else module.rpartition(".")[0]

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                stem = ".".join(base + ([node.module] if node.module else []))
            else:
                stem = node.module or ""
            for alias in node.names:
                sub = f"{stem}.{alias.name}"
                if modules is None:
                    found.update((stem, sub))
                else:
                    found.add(sub if sub in modules else stem)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return found


def import_graph(root: Path | None = None) -> dict[str, set[str]]:
    """Module -> the modules of app/ it imports at run time (a package's __init__ is the package).

    The edges are the import statements; a package's own __init__, which Python runs before any of
    its modules, is an edge only where a module imports a name from it.
    """
    root = root or APP
    files = {_module_name(p, root): p for p in sorted(root.rglob("*.py"))}
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        targets = _imports(tree, name, path.name == "__init__.py", set(files))
        graph[name] = {t for t in targets if t in files and t != name}
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as [m0, m1, ..., m0], or None (iterative depth-first search)."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    for start in sorted(graph):
        if state.get(start):
            continue
        path = [start]
        stack = [iter(sorted(graph[start]))]
        state[start] = 1
        while stack:
            nxt = next(stack[-1], None)
            if nxt is None:
                state[path.pop()] = 2
                stack.pop()
            elif state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            elif not state.get(nxt):
                state[nxt] = 1
                path.append(nxt)
                stack.append(iter(sorted(graph.get(nxt, ()))))
    return None


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every cycle found by removing one edge of each found cycle in turn (for a useful message)."""
    g = {k: set(v) for k, v in graph.items()}
    out = []
    while (c := find_cycle(g)) is not None and len(out) < 20:
        out.append(c)
        g[c[-2]].discard(c[-1])
    return out


def test_find_cycle_finds_one():
    """The search can fail: a three-module circle is found, a tree is not."""
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) is None


def test_imports_inside_functions_count_and_type_checking_does_not():
    src = (
        "from typing import TYPE_CHECKING\n"
        "from . import x\n"
        "if TYPE_CHECKING:\n    from .y import Y\n"
        "def f():\n    from ..z import w\n    import app.v\n"
    )
    found = _imports(ast.parse(src), "app.p.m", is_package=False)
    assert {"app.p.x", "app.z", "app.z.w", "app.v"} <= found
    assert "app.p.y" not in found and "app.p.y.Y" not in found


def test_app_has_no_import_circle():
    graph = import_graph()
    assert len(graph) > 50 and sum(map(len, graph.values())) > 100  # the walk reaches app/
    cycles = _cycles(graph)
    assert not cycles, "import circles in app/:\n" + "\n".join(" -> ".join(c) for c in cycles)


def _reach(graph: dict[str, set[str]], start: str) -> set[str]:
    """Every module importing ``start`` runs: what it imports, and the packages they are in."""
    seen, todo = set(), [start]
    while todo:
        m = todo.pop()
        parts = m.split(".")
        for k in range(2, len(parts) + 1):  # importing a.b.c runs a.b's __init__ first
            name = ".".join(parts[:k])
            if name in graph and name not in seen:
                seen.add(name)
                todo.append(name)
        todo.extend(t for t in graph.get(m, ()) if t not in seen)
    return seen


def _third_party(module: str) -> set[str]:
    """The top-level names of what ``module`` (of app/) imports at run time."""
    path = ROOT / (module.replace(".", "/") + ".py")
    if not path.exists():
        path = ROOT / module.replace(".", "/") / "__init__.py"
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return {n.split(".")[0] for n in _imports(tree, module, path.name == "__init__.py")}


def test_app_floors_have_no_import_circle():
    """Between the floors of app/ (app.api, app.scene, app.readers, and each module of app/ itself)
    the imports go one way: was app.jobs -> app.api -> app.jobs and app.jobs -> app.scene -> app.jobs."""
    graph = import_graph()

    def floor(m: str) -> str:
        return ".".join(m.split(".")[:2])

    floors: dict[str, set[str]] = {}
    for m, targets in graph.items():
        floors.setdefault(floor(m), set()).update(floor(t) for t in targets if floor(t) != floor(m))
    assert {"app.api", "app.scene", "app.jobs", "app.cli"} <= set(floors)
    cycles = _cycles(floors)
    assert not cycles, "import circles between the floors of app/:\n" + "\n".join(" -> ".join(c) for c in cycles)


@pytest.mark.parametrize(("start", "may_reach"), [("app.jobs", ()), ("app.api.jobs", ("app.api",)), ("app.scene.pair.motion", ("app.scene",))])
def test_worker_side_imports_no_fastapi_nor_the_other_floors(start, may_reach):
    """What the worker processes run imports only core and app.workers (the API's and the scene's jobs
    also their own floor's models), and no module of it loads FastAPI or viser."""
    graph = import_graph()
    reached = _reach(graph, start)
    assert start in reached
    foreign = {m for m in reached if m.startswith(("app.scene", "app.api")) and not m.startswith(may_reach or ("-",))}
    assert not foreign, f"{start} reaches {sorted(foreign)}"
    heavy = {m: bad for m in reached if (bad := _third_party(m) & {"fastapi", "starlette", "viser", "uvicorn"})}
    assert not heavy, f"{start} reaches modules importing {heavy}"


SCENE_FLOORS = ("app.scene.common", "app.scene.pair", "app.scene.bodies.model", "app.scene.server")
"""The scene's floors, bottom first: each imports only the floors below it (and the rest of app)."""


def test_the_scene_floors_import_downwards():
    """common (tab state, drawing, page, wire) imports neither product; the two-shape scene (pair)
    not the many-bodies one (bodies, which opens a pair); neither imports the server that holds both."""
    graph = import_graph()
    assert all(any(m.startswith(f) for m in graph) for f in SCENE_FLOORS)
    up = []
    for m, targets in graph.items():
        level = next((k for k, f in enumerate(SCENE_FLOORS) if m == f or m.startswith(f + ".")), None)
        if level is None:
            continue
        for t in targets:
            above = [f for f in SCENE_FLOORS[level + 1:] if t == f or t.startswith(f + ".")]
            if above:
                up.append(f"{m} -> {t}")
    assert not up, "imports up the scene's floors:\n" + "\n".join(sorted(up))


def test_controllers_see_the_session_through_its_narrow_face():
    """The controllers import app.scene.pair.session_view (the SessionView protocol: mypy holds them to
    its members), never the session module, not even for type checking (was a circle of six files)."""
    controllers = sorted((APP / "scene" / "pair").glob("control_*.py"))
    assert len(controllers) >= 5
    for path in controllers:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        names = {f"{'.' * n.level}{n.module or ''}" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
        assert ".session_view" in names and ".session" not in names, (path.name, sorted(names))
