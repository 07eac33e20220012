"""The distributions and the set-up: the sdist holds the suite with its helpers, the wheel carries
the landing page, the licence is declared, the lock covers the test extra, the C builds without
warnings, and the README's two commands are what CI runs."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def _name(requirement: str) -> str:
    """The normalised project name of a requirement string (PEP 503)."""
    return re.sub(r"[-_.]+", "-", re.match(r"\s*([A-Za-z0-9._-]+)", requirement).group(1)).lower()


@pytest.fixture(scope="module")
def sdist(tmp_path_factory) -> tarfile.TarFile:
    out = tmp_path_factory.mktemp("sdist")
    subprocess.run([sys.executable, "-m", "build", "--sdist", "--no-isolation", "--outdir", str(out), str(ROOT)],
                   check=True, capture_output=True, text=True, timeout=300)
    (archive,) = out.glob("*.tar.gz")
    return tarfile.open(archive)


def test_the_sdist_holds_the_suite_and_every_helper_it_imports(sdist):
    names = {n.split("/", 1)[1] for n in sdist.getnames() if "/" in n}
    on_disk = {p.relative_to(ROOT).as_posix() for p in (ROOT / "tests").glob("*.py")}
    assert len(on_disk) > 50 and on_disk <= names, sorted(on_disk - names)
    for helper in ("conftest.py", "tests/conftest.py", "tests/oracle.py", "tests/strategies.py", "tests/cases.py",
                   "tests/browser_helpers.py", "LICENSE", "requirements/test.txt", "static/index.html"):
        assert helper in names, helper
    # every top-level module or package the tests import from the checkout is in it too
    local = {p.stem if p.suffix == ".py" else p.name for p in ROOT.iterdir() if p.suffix == ".py" or (p / "__init__.py").exists()}
    imported = set()
    for path in (ROOT / "tests").glob("*.py"):
        imported |= set(re.findall(r"^\s*(?:from|import) (\w+)", path.read_text(), re.M))
    for package in sorted(imported & local):
        assert f"{package}/__init__.py" in names or f"{package}.py" in names, package
    assert not [n for n in names if "__pycache__" in n or n.endswith((".pyc", ".so"))]


def test_the_sdist_declares_the_licence(sdist):
    (member,) = [m for m in sdist.getmembers() if m.name.count("/") == 1 and m.name.endswith("/PKG-INFO")]
    meta = sdist.extractfile(member).read().decode()
    assert "License-Expression: BSD-3-Clause" in meta
    assert "License-File: LICENSE" in meta
    assert "Redistribution and use in source and binary forms" in (ROOT / "LICENSE").read_text()


def test_a_built_package_serves_the_landing_page(tmp_path):
    """setup.py's build_py copies static/ into app/static: the wheel's tree answers GET / with the page
    (built here without the C: the wheel is this tree plus the compiled filters)."""
    build = tmp_path / "lib"
    subprocess.run([sys.executable, "setup.py", "-q", "build_py", "--build-lib", str(build)], cwd=ROOT,
                   check=True, capture_output=True, text=True, timeout=120)
    assert (build / "app" / "static" / "index.html").is_file()
    probe = (
        "from fastapi.testclient import TestClient\n"
        "from app.api import ApiSettings, create_api\n"
        "from app.api.settings import default_static_dir\n"
        "print(default_static_dir())\n"
        "r = TestClient(create_api(ApiSettings())).get('/')\n"
        "print(r.status_code, 'Ellipse' in r.text or 'ellips' in r.text.lower())\n"
    )
    out = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, env={"PYTHONPATH": str(build), "PATH": "/usr/bin:/bin"},
                         check=True, capture_output=True, text=True, timeout=120).stdout.split("\n")
    assert out[0] == str(build / "app" / "static")
    assert out[1] == "200 True"


def test_the_lock_pins_every_package_the_test_extra_needs():
    lock = (ROOT / "requirements" / "test.txt").read_text()
    pinned = {_name(line) for line in lock.splitlines() if re.match(r"[A-Za-z0-9]", line)}
    assert all("==" in line for line in lock.splitlines() if re.match(r"[A-Za-z0-9]", line))
    extras = PYPROJECT["project"]["optional-dependencies"]
    wanted = set()
    for req in PYPROJECT["project"]["dependencies"] + [r for group in ("test", "screenshot", "formats", "dask") for r in extras[group]]:
        if _name(req) != "ellipsoid-interference":
            wanted.add(_name(req))
    assert wanted <= pinned, sorted(wanted - pinned)


def test_the_test_tools_have_upper_bounds():
    for req in PYPROJECT["project"]["optional-dependencies"]["test"]:
        if _name(req) != "ellipsoid-interference":
            assert "<" in req, f"{req}: bound it by its next major"


def test_ci_runs_the_readme_test_command_with_the_lock():
    readme = (ROOT / "README.md").read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    commands = re.findall(r"```bash\n(.*?)\n```", readme, re.S)
    test_cmd = next(c for c in commands if "pytest" in c and "pip install" in c)
    assert "-c requirements/test.txt" in test_cmd
    assert test_cmd.strip().splitlines()[-1] in ci.splitlines()


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
def test_the_c_sources_compile_without_warnings():
    """-Wall -Wextra on every C file the build compiles (syntax and front-end checks only: quick)."""
    import numpy  # noqa: F401  (the extension includes only Python's headers)

    include = sysconfig.get_paths()["include"]
    sources = sorted((ROOT / "core").glob("*/_*.c"))
    assert len(sources) >= 6
    for src in sources:
        for macros in ([], ["-DBASELINE_ONLY"]):
            done = subprocess.run(["gcc", "-fsyntax-only", "-Wall", "-Wextra", "-Wno-unused-parameter", "-std=c99",
                                   f"-I{include}", *macros, str(src)], capture_output=True, text=True, timeout=120, check=False)
            assert done.returncode == 0 and "warning" not in done.stderr, f"{src.name} {macros}:\n{done.stderr[:2000]}"
