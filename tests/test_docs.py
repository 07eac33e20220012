"""The documentation site builds with warnings as errors, and every example in it runs (issue 56).

* ``test_the_site_builds``: ``python -m sphinx -W --keep-going -b html docs <tmp>`` (the command of
  docs/develop/docs.md), so a broken link, reference or docstring fails the suite.
* ``test_the_examples_of`` one page: every ```python block of README.md and docs/**/*.md runs, the
  blocks of a page in one namespace, in order (a doctest of the page), in a temporary folder holding
  docs/data/; every ```bash / ```console block runs there with bash (``set -e``, so a pipeline is judged by its last command, as `| head` is; in a console
  block only the ``$ `` lines). A block preceded by ``<!-- no-run: why -->`` or fenced
  ```python no-run is skipped (a server that never returns, an install).
* ``test_the_readme_is_short``: at most 150 lines.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
CHROMIUM = os.path.exists("/usr/bin/chromium")
PAGES = [ROOT / "README.md"] + sorted(
    p for p in DOCS.rglob("*.md") if not {"_build", "_generated", "data"} & set(p.relative_to(DOCS).parts[:-1])
)
_FENCE = re.compile(r"^```([\w-]*)([^\n]*)\n(.*?)^```[ \t]*$", re.M | re.S)
_NO_RUN = re.compile(r"<!--\s*no-run\b[^>]*-->\s*$")
RUN_LANGS = {"python": "python", "bash": "shell", "console": "shell", "sh": "shell", "shell": "shell"}
NEEDS_BROWSER = re.compile(r"HeadlessScene|python -m app screenshot")


@dataclass(frozen=True)
class Block:
    """One fenced code block of a page: its language ("python" or "shell"), text and first line."""

    kind: str
    code: str
    line: int


def blocks(text: str) -> list[Block]:
    """The blocks of a Markdown page that the suite runs, in order (no-run blocks left out)."""
    out = []
    for m in _FENCE.finditer(text):
        lang, info, code = m.group(1).lower(), m.group(2), m.group(3)
        before = text[: m.start()].rstrip("\n").rsplit("\n", 1)[-1]
        if lang not in RUN_LANGS or "no-run" in info or _NO_RUN.search(before):
            continue
        out.append(Block(RUN_LANGS[lang], code, text[: m.start()].count("\n") + 2))
    return out


def _shell_script(block: Block) -> str:
    """A console block's ``$ `` commands (its other lines are output), or a bash block as it is."""
    lines = block.code.splitlines()
    if any(line.startswith("$ ") for line in lines):
        lines = [line[2:] for line in lines if line.startswith("$ ")]
    return "\n".join(lines)


def _param(page: Path) -> object:
    """One page as a test parameter; pages that draw in a browser are marked ``browser``."""
    marks = []
    if NEEDS_BROWSER.search("\n".join(b.code for b in blocks(page.read_text(encoding="utf-8")))):
        marks = [pytest.mark.browser, pytest.mark.skipif(not CHROMIUM, reason="needs Debian chromium at /usr/bin/chromium")]
    return pytest.param(page, id=str(page.relative_to(ROOT)), marks=marks)


def test_the_fences_are_read_as_the_docs_say():
    """The extraction itself: languages, the two no-run forms, console prompts, line numbers."""
    text = ("# t\n\n```python\nx = 1\n```\n\n<!-- no-run: a server -->\n```bash\npython -m app serve\n```\n"
            "```python no-run\nwhile True: pass\n```\n```console\n$ echo hi\nhi\n```\n```json\n{}\n```\n")
    got = blocks(text)
    assert [(b.kind, b.line) for b in got] == [("python", 4), ("shell", 15)]
    assert _shell_script(got[1]) == "echo hi"


RUNNABLE = [p for p in PAGES if blocks(p.read_text(encoding="utf-8"))]


def test_the_docs_have_examples_to_run():
    """The extraction finds the README's and most pages' examples (a broken fence rule would find none)."""
    assert ROOT / "README.md" in RUNNABLE and len(RUNNABLE) >= 15, [str(p.relative_to(ROOT)) for p in RUNNABLE]


@pytest.mark.parametrize("page", [_param(p) for p in RUNNABLE])
def test_the_examples_of(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """Every runnable block of one page runs, in order, in a folder holding docs/data/."""
    found = blocks(page.read_text(encoding="utf-8"))
    for f in (DOCS / "data").iterdir():
        if f.is_file() and f.name != "README.md":
            shutil.copy(f, tmp_path / f.name)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(ROOT))
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}",
           "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    namespace: dict[str, object] = {"__name__": f"docs_page_{page.stem}"}
    where = page.relative_to(ROOT)
    for b in found:
        if b.kind == "python":
            try:
                exec(compile(b.code, f"{where}:{b.line}", "exec"), namespace)  # noqa: S102  (the page's own example)
            except Exception as e:
                raise AssertionError(f"{where}, the python block at line {b.line} failed: {e!r}") from e
        else:
            done = subprocess.run(["bash", "-c", "set -e\n" + _shell_script(b)], cwd=tmp_path, env=env,
                                  capture_output=True, text=True, timeout=240, check=False)
            assert done.returncode == 0, f"{where}, the shell block at line {b.line} exited {done.returncode}:\n{done.stderr[-3000:]}"


def test_the_readme_is_short():
    """The README is a front door (at most 150 lines); the rest lives in docs/."""
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 150, f"README.md has {len(lines)} lines (at most 150: move the rest into docs/)"


def test_the_site_builds(tmp_path: Path):
    """``sphinx-build -W``: every warning (a broken link, a bad docstring) fails the build."""
    pytest.importorskip("sphinx", reason="the docs extra: pip install -e '.[docs]'")
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-j", "auto", "-b", "html",
           "-d", str(tmp_path / "doctrees"), str(DOCS), str(tmp_path / "html")]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600, check=False)
    assert done.returncode == 0, f"the docs build failed:\n{done.stderr[-6000:]}"
    html = tmp_path / "html"
    for page in ("index", "getting-started", "concepts", "reference/python", "reference/cli", "reference/http",
                 "benchmarks", "develop/index", "changelog"):
        assert (html / f"{page}.html").is_file(), page
    python_ref = (html / "reference" / "python.html").read_text(encoding="utf-8")
    import core

    missing = [name for name in core.__all__ if f'id="core.{name}"' not in python_ref]
    assert not missing, f"names of core.__all__ without an entry in the Python reference: {missing}"


def test_the_guide_is_served_at_guide_when_built(tmp_path: Path):
    """``/guide/`` serves the built site (index, pages, assets); a missing file is a 404."""
    from fastapi.testclient import TestClient

    from app.api import ApiSettings, create_api

    site = tmp_path / "html"
    (site / "_static").mkdir(parents=True)
    (site / "index.html").write_text("<h1>the guide's front page</h1>")
    (site / "concepts.html").write_text("<h1>Concepts</h1>")
    (site / "_static" / "furo.css").write_text("body {}")
    with TestClient(create_api(ApiSettings(scene_url=None), guide_dir=site)) as c:
        front = c.get("/guide/")
        assert (front.status_code, front.text) == (200, "<h1>the guide's front page</h1>")
        assert c.get("/guide/concepts.html").text == "<h1>Concepts</h1>"
        assert c.get("/guide/_static/furo.css").status_code == 200
        assert c.get("/guide/no-such-page.html").status_code == 404


def test_an_unbuilt_guide_answers_404_saying_how_to_build_it(tmp_path: Path):
    """Before the site is built: a 404 of one line naming the build command; built later: served."""
    from fastapi.testclient import TestClient

    from app.api import ApiSettings, create_api
    from app.api.factory import GUIDE_BUILD

    site = tmp_path / "html"
    with TestClient(create_api(ApiSettings(scene_url=None), guide_dir=site)) as c:
        r = c.get("/guide/")
        assert r.status_code == 404 and GUIDE_BUILD in r.text and len(r.text.strip().splitlines()) == 1
        assert c.get("/guide/concepts.html").status_code == 404
        site.mkdir()
        (site / "index.html").write_text("built after the start")
        assert c.get("/guide/").text == "built after the start"


def test_the_landing_page_links_to_the_guide():
    """The landing page at / links to the guide and to its concepts page (what the scene shows)."""
    from fastapi.testclient import TestClient

    from app.api import ApiSettings, create_api

    with TestClient(create_api(ApiSettings(scene_url=None))) as c:
        page = c.get("/").text
    assert 'href="/guide/"' in page and 'href="/guide/concepts.html"' in page


def test_benchmark_results_are_data_and_the_report_their_rendering(tmp_path: Path):
    """A benchmark's Markdown tables go into bench/results/<name>.json and come back on the page."""
    from bench import render

    md = "## Throughput\n\n**one core**\n\n| data | pairs/s |\n|---|---:|\n| random 3D | 52.3 M/s |\n| a \\| b | 1 |\n"
    path = render.publish("throughput", command="python -m bench.throughput --write", markdown=md, results=tmp_path,
                          report=tmp_path / "REPORT.md", load_average="1.0 at the start")
    data = json.loads(path.read_text())
    assert path.name == "throughput.json" and data["command"] == "python -m bench.throughput --write"
    assert data["cores"] == os.cpu_count() and data["cpu"] and data["anchor"] == render.QUESTIONS["throughput"][1]
    assert data["tables"] == [{"title": "one core", "columns": ["data", "pairs/s"], "rows": [["random 3D", "52.3 M/s"], ["a | b", "1"]]}]
    page = (tmp_path / "REPORT.md").read_text()
    for text in (render.QUESTIONS["throughput"][0], "python -m bench.throughput --write", "| random 3D | 52.3 M/s |",
                 "| a \\| b | 1 |", "load average 1.0 at the start"):
        assert text in page, text


def test_the_committed_report_is_the_rendering_of_the_results():
    """bench/REPORT.md is generated only: exactly what ``python -m bench.render --write`` writes."""
    from bench import render

    committed = render.REPORT.read_text(encoding="utf-8")
    with_results = render.render(render.RESULTS)
    assert committed.endswith(with_results), "bench/REPORT.md differs from bench/results/*.json: run python -m bench.render --write"
    for path in sorted(render.RESULTS.glob("*.json")):
        data = json.loads(path.read_text(encoding="utf-8"))
        assert data.get("command", "").startswith("python"), f"{path.name}: the command that produced it"


def test_a_printed_benchmark_table_is_published(tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    """``published``: what a command prints still reaches the terminal, and its tables the result file."""
    from bench import render

    with render.published("index", command="python bench/bench_index.py --write", results=tmp_path, report=None):
        print("# BodyIndex: 10 new against 100\n| space | pairs |\n|---|---:|\n| open | 24 |")
    assert "| open | 24 |" in capsys.readouterr().out
    data = json.loads((tmp_path / "index.json").read_text())
    assert data["tables"] == [{"title": "BodyIndex: 10 new against 100", "columns": ["space", "pairs"], "rows": [["open", "24"]]}]
