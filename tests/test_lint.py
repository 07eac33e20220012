"""The project's checks run with the tests (so CI runs them): ruff with the project's config and
mypy, on the code they cover. A finding is a test failure that names it."""

from __future__ import annotations

import inspect
import subprocess
import sys
import typing
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
RUFF_PATHS = ["core", "app", "tests", "bench"]
"""Ruff-clean (pyproject's [tool.ruff] config)."""
MYPY_PATHS = ["core", "app"]
"""mypy-clean, in one run, both under the flags of ``mypy --strict`` (pyproject's override for
core.* and app.*, plus the global ones on the command line): the library is a typed package
(core/py.typed), and the app is held to the same bar. One run analyses core once (two runs,
default and --strict, took 25 + 13 s of the suite)."""
STRICT_PACKAGES = ("core", "app")
"""The packages whose override must hold every per-module flag of --strict."""
MYPY_GLOBAL_STRICT = ["--warn-redundant-casts", "--warn-unused-configs"]
"""The flags of --strict that mypy takes only for a whole run."""
MYPY_CACHE = ROOT / ".mypy_cache"


def _run(args: list[str | Path]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(args, cwd=ROOT, capture_output=True, text=True, timeout=600, check=False)


def test_ruff_is_clean():
    pytest.importorskip("ruff", reason="ruff is not installed (pip install -e '.[test]')")
    res = _run([sys.executable, "-m", "ruff", "check", *RUFF_PATHS])
    assert res.returncode == 0, res.stdout[-4000:] + res.stderr[-2000:]


def test_mypy_is_clean_and_core_and_app_are_strict():
    pytest.importorskip("mypy", reason="mypy is not installed (pip install -e '.[test]')")
    res = _run([sys.executable, "-m", "mypy", "--cache-dir", MYPY_CACHE, *MYPY_GLOBAL_STRICT, *MYPY_PATHS])
    assert res.returncode == 0, res.stdout[-4000:] + res.stderr[-2000:]


def _strict_flags() -> list[str]:
    """The flags ``mypy --strict`` turns on, as this mypy's --help lists them."""
    lines = _run([sys.executable, "-m", "mypy", "--help"]).stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if line.lstrip().startswith("--strict "))
    text = lines[start].split("following flags:", 1)[1].strip()
    for line in lines[start + 1:]:
        if len(line) - len(line.lstrip()) <= 4:  # the next option (continuations are indented deeper)
            break
        text += ("" if text.endswith("-") else " ") + line.strip()
    return [f.strip() for f in text.split(",") if f.strip()]


@pytest.mark.parametrize("package", STRICT_PACKAGES)
def test_override_is_every_strict_flag(package):
    """pyproject's [[tool.mypy.overrides]] for core and app holds every per-module flag of --strict (and
    the suite passes the global ones), so the one run above checks them as ``mypy --strict core app`` does."""
    pytest.importorskip("mypy", reason="mypy is not installed (pip install -e '.[test]')")
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["mypy"]
    override = next((o for o in config["overrides"] if f"{package}.*" in o["module"] and package in o["module"]), None)
    assert override is not None, f"pyproject.toml: no [[tool.mypy.overrides]] for {package} and {package}.*"
    flags = _strict_flags()
    assert len(flags) >= 10 and "--disallow-untyped-defs" in flags, flags
    missing = [f for f in flags if f not in MYPY_GLOBAL_STRICT and override.get(f[2:].replace("-", "_")) is not True]
    assert not missing, f"add to the {package} override in pyproject.toml: {missing}"


def test_core_is_a_typed_package():
    """core/py.typed exists and ships (package data and the source distribution)."""
    assert (ROOT / "core" / "py.typed").is_file()
    assert '"core" = ["py.typed"]' in (ROOT / "pyproject.toml").read_text()
    assert "core/py.typed" in (ROOT / "MANIFEST.in").read_text().split()


def _public_callables() -> list[tuple[str, object]]:
    import core

    out: list[tuple[str, object]] = []
    for name in core.__all__:
        obj = getattr(core, name)
        if inspect.isfunction(obj):
            out.append((name, obj))
            out += [(f"{name} (overload {k})", f) for k, f in enumerate(typing.get_overloads(obj))]
        elif inspect.isclass(obj) and obj.__module__.startswith("core."):
            for attr, member in vars(obj).items():
                if attr.startswith("_"):
                    continue
                f = member.fget if isinstance(member, property) else member
                f = f.__func__ if isinstance(f, staticmethod | classmethod) else f
                if inspect.isfunction(f):
                    out.append((f"{name}.{attr}", f))
    return out


def test_public_functions_never_return_any():
    """Every public function and method of core says what it returns, and it is never a bare Any."""
    found = _public_callables()
    assert len(found) > 50  # the walk reaches the API (functions, overloads, methods)
    bad = []
    for name, f in found:
        hints = typing.get_type_hints(f)
        if "return" not in hints:
            bad.append(f"{name}: no return annotation")
        elif hints["return"] is typing.Any:
            bad.append(f"{name}: returns Any")
    assert not bad, bad
