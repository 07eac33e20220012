"""Benchmarks as data: write ``bench/results/<name>.json``, render them as the Benchmarks page.

The benchmark commands write their numbers with :func:`write_result` (the command, the CPU, the
cores, the date and one or more tables); this module renders every result file as one short
section per question, the anchor it is measured against beside it, and the command that produced
it. The documentation's Benchmarks page is this rendering (``docs/_ext/generated.py``), and
``bench/REPORT.md`` is the same text, generated only::

    python -m bench.render              # print the page
    python -m bench.render --write      # write bench/REPORT.md from bench/results/*.json

A result file::

    {"command": "python -m bench.throughput --write", "cpu": "AMD EPYC", "cores": 2,
     "date": "2026-12-05 07:24 UTC", "question": "...", "anchor": "...",
     "tables": [{"title": "...", "columns": ["data", "..."], "rows": [["random 3D", "52.28 M/s"]]}]}

Files in a nested form of their own (``bench/results/audit*.json`` of ``python -m bench.bench_audit``,
``scene_memory.json``) are flattened into tables of their figures here. The CPU, the cores and the
results folder come from :mod:`bench.machine`.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import re
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any, TextIO

from .machine import RESULTS, cores, cpu_model

ROOT = Path(__file__).resolve().parents[1]
REPORT = ROOT / "bench" / "REPORT.md"

__all__ = ["RESULTS", "REPORT", "QUESTIONS", "tables_from_markdown", "write_result", "publish", "render",
           "published", "write_report", "main"]

QUESTIONS: dict[str, tuple[str, str]] = {
    "targets": ("Does each target hold?", "the target beside each measurement"),
    "throughput": ("How fast is the certified filter, on one core and on every core?",
                   "the paper's tree in plain C (bench/baseline_tree.c, gcc -O3 -march=native, no error bound) and a "
                   "memory read of the inputs"),
    "static": ("Static pairs: how fast, and how many wrong labels?",
               "numpy eigenvalues with a tolerance; GJK from coal and python-fcl (3D, boolean)"),
    "near-tangent": ("Near-tangent pairs: wrong labels per gap decade", "numpy eigenvalues; GJK from coal and python-fcl"),
    "moving": ("Moving shapes: the exact analysis against uniform sampling",
               "uniform sampling of t with the certified static classifier at each sample"),
    "sweep": ("Moving many bodies: certified first contact times", "the exact analysis of each pair, and uniform sampling of t"),
    "bodies": ("Contacts among N ellipsoids: how long?",
               "the uncertified pipeline a user would write: scipy cKDTree on bounding spheres + the paper's tree in plain C"),
    "index": ("An index asked about new bodies (BodyIndex): one query, a batch, an update",
              "core.contacts on the union (differences must be 0)"),
    "audit": ("Auditing a trajectory: how long, and how many labels are right, against the uncertified pipeline?",
              "scipy cKDTree on bounding spheres + Perram-Wertheim in numpy (float tolerances 0 and 1e-10)"),
    "audit-command": ("Auditing a trajectory: the command alone (100 frames of 100,000 ellipsoids; target 60 s)",
                      "python -m bench.bench_audit's full run (the float pipeline beside it)"),
    "scales": ("Bodies at any float scale: which arithmetic certifies them, how long?", "the same pairs at scale 1"),
    "witness": ("Witnesses: contact scale, planes, points, distance", "the relation alone (classify) on the same pairs"),
    "stages": ("Where the filter's time goes: cycles per pair in each stage", "random 3D pairs (the ratio column)"),
    "api": ("The HTTP API: a batch, concurrent requests, bursts of large bodies",
            "the targets (p99 < 100 ms at concurrency 32, /healthz while bodies are read)"),
    "api-line": ("The HTTP API under load: large bodies through the one bounded line",
                 "the same load on an earlier checkout (--against)"),
    "scene": ("The scene: server cost of one update, presets and bodies in a browser",
              "the targets: a drag < 2 ms, a t-step < 1 ms of server time; a preset on screen < 300 ms"),
    "scene_memory": ("The scene's memory: what a hostile or a full upload and 400 tabs leave behind (resident MB)",
                     "the server's memory before (it must come back)"),
}
"""The question each result file answers and the anchor it is measured against, by file name."""

ORDER = list(QUESTIONS)
"""The order of the questions on the page (files not named here come after, by name)."""


def tables_from_markdown(text: str, default_title: str = "") -> list[dict[str, Any]]:
    """Every pipe table of a Markdown text, titled by the heading or bold line before it.

    What the benchmark commands print is Markdown; this turns it into the tables of a result
    file, so each command keeps one formatter for its terminal and its data.
    """
    tables: list[dict[str, Any]] = []
    title = default_title
    lines = text.splitlines()
    k = 0
    while k < len(lines):
        line = lines[k].strip()
        if line.startswith("#"):
            title = line.lstrip("#").strip()
        elif line.startswith("**") and line.count("**") >= 2:
            title = line.split("**")[1].strip()
        elif line.startswith("|") and k + 1 < len(lines) and re.fullmatch(r"\|?[\s:|-]+\|?", lines[k + 1].strip()):
            columns = _cells(line)
            rows = []
            k += 2
            while k < len(lines) and lines[k].strip().startswith("|"):
                rows.append(_cells(lines[k].strip()))
                k += 1
            tables.append({"title": title, "columns": columns, "rows": rows})
            continue
        k += 1
    return tables


def _cells(line: str) -> list[str]:
    """The cells of one Markdown table row (escaped pipes kept)."""
    inner = line.strip().removeprefix("|").removesuffix("|")
    return [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", inner)]


def write_result(name: str, *, command: str, tables: list[dict[str, Any]], results: Path = RESULTS, **extra: Any) -> Path:
    """Write ``results/<name>.json``: the command, the machine, the date, the question and the tables."""
    question, anchor = QUESTIONS.get(name, QUESTIONS.get(name.split("-")[0], (name, "")))
    data = {"command": command, "cpu": cpu_model(), "cores": cores(),
            "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "question": question, "anchor": anchor,
            **extra, "tables": tables}
    results.mkdir(parents=True, exist_ok=True)
    path = results / f"{name}.json"
    path.write_text(json.dumps(data, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return path


def publish(name: str, *, command: str, markdown: str, results: Path = RESULTS, report: Path | None = REPORT,
            **extra: Any) -> Path:
    """What a benchmark command does with its numbers: the tables of its Markdown into
    ``results/<name>.json`` (with ``extra`` fields: the load average, the seconds), then bench/REPORT.md
    rendered again (None: not rendered)."""
    path = write_result(name, command=command, tables=tables_from_markdown(markdown), results=results, **extra)
    if report is not None:
        write_report(results, report)
    return path


class _Tee(io.TextIOBase):
    """A text stream that writes to the terminal and keeps a copy."""

    def __init__(self, out: TextIO) -> None:
        self.out, self.copy = out, io.StringIO()

    def write(self, s: str) -> int:
        """Write to both."""
        self.copy.write(s)
        return self.out.write(s)

    def flush(self) -> None:
        """Flush the terminal's stream."""
        self.out.flush()


@contextlib.contextmanager
def published(name: str, *, command: str, write: bool = True, results: Path = RESULTS,
              report: Path | None = REPORT) -> Iterator[None]:
    """Print as usual; with ``write``, what was printed inside becomes ``results/<name>.json`` at the end.

    For the benchmark commands that print Markdown tables (``--write`` publishes them).
    """
    if not write:
        yield
        return
    tee = _Tee(sys.stdout)
    with contextlib.redirect_stdout(tee):  # type: ignore[type-var]
        yield
    path = publish(name, command=command, markdown=tee.copy.getvalue(), results=results, report=report)
    print(f"wrote {path}", file=sys.stderr)


def _esc(value: Any) -> str:
    """One table cell: one line, pipes escaped."""
    return " ".join(str(value).split()).replace("|", "\\|")


def _table(t: dict[str, Any]) -> list[str]:
    """A table of a result file as Markdown lines."""
    cols = t["columns"]
    out = [f"**{_esc(t['title'])}**", ""] if t.get("title") else []
    out += ["| " + " | ".join(_esc(c) for c in cols) + " |", "|" + "---|" * len(cols)]
    out += ["| " + " | ".join(_esc(c) for c in row) + " |" for row in t["rows"]]
    return out + [""]


def _flatten(prefix: str, value: Any, rows: list[list[str]]) -> None:
    """Rows (key path, value) of a nested dict."""
    if isinstance(value, dict):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), v, rows)
    elif isinstance(value, list) and all(isinstance(v, int | float) for v in value):
        rows.append([prefix, ", ".join(f"{v:.4g}" for v in value)])
    else:
        rows.append([prefix, f"{value:.4g}" if isinstance(value, float) else str(value)])


_META = {"command", "cpu", "cores", "date", "question", "anchor", "source", "load_average", "seconds"}
"""Fields of a result file that describe the run, not its figures."""


def _figure_tables(data: dict[str, Any]) -> list[dict[str, Any]]:
    """Tables of a result file written in its own nested form (``bench_audit``, ``scene_memory``):
    one (figure, value) table per nested group, one for the loose figures."""
    loose: list[list[str]] = []
    tables = []
    for key, value in data.items():
        if key in _META:
            continue
        if isinstance(value, dict):
            rows: list[list[str]] = []
            _flatten("", value, rows)
            tables.append({"title": key, "columns": ["figure", "value"], "rows": rows})
        else:
            _flatten(key, value, loose)
    return ([{"title": "", "columns": ["figure", "value"], "rows": loose}] if loose else []) + tables


def _load(path: Path) -> dict[str, Any]:
    """One result file; one in its own nested form gets tables of its figures and its question."""
    data: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    if "tables" not in data:
        question, anchor = QUESTIONS.get(path.stem, QUESTIONS.get(path.stem.split("-")[0], (path.stem, "")))
        data = {"question": question, "anchor": anchor, **data, "tables": _figure_tables(data)}
    return data


def _key(path: Path) -> tuple[int, str]:
    """Sort key of a result file: its place in ORDER, then its name."""
    stem = path.stem
    base = next((n for n in ORDER if stem == n or stem.startswith(n + "-")), None)
    return (ORDER.index(base) if base else len(ORDER), stem)


def render(results: Path = RESULTS) -> str:
    """The Benchmarks page: one section per result file, its question, anchor, command and tables."""
    files = sorted(results.glob("*.json"), key=_key)
    out = ["<!-- generated by bench/render.py from bench/results/*.json: do not edit -->", ""]
    if not files:
        return "\n".join(out + ["No results yet: run a benchmark command (each writes bench/results/<name>.json).", ""])
    for path in files:
        data = _load(path)
        load = f"load average {data['load_average']}" if data.get("load_average") else None
        machine = ", ".join(str(x) for x in (data.get("cpu"), f"{data['cores']} cores" if data.get("cores") else None,
                                             data.get("date"), load) if x)
        out += [f"## {data.get('question') or path.stem}", ""]
        if data.get("anchor"):
            out += [f"Against: {data['anchor']}.", ""]
        out += [f"Command: `{data.get('command', '?')}`" + (f" ({machine})" if machine else "") + f"; data: `bench/results/{path.name}`"
                + (f" ({data['source']})" if data.get("source") else "") + ".", ""]
        shown = None
        for t in data["tables"]:
            out += _table(t if t.get("title") != shown else {**t, "title": ""})
            shown = t.get("title")
    return "\n".join(out)


def write_report(results: Path = RESULTS, path: Path = REPORT) -> Path:
    """Write bench/REPORT.md: the rendered page, generated only."""
    head = ("# Benchmark report\n\nGenerated by `python -m bench.render --write` from `bench/results/*.json` (each written "
            "by the benchmark command it names); do not edit: rerun the command, then this one. The same tables are the "
            "documentation's Benchmarks page (`docs/benchmarks.md`). Ground truth of every label: `tests/oracle.py`, never "
            "the code under test.\n\n")
    path.write_text(head + render(results), encoding="utf-8")
    return path


def main(argv: list[str] | None = None) -> None:
    """``python -m bench.render [--write]``: print the page, or write bench/REPORT.md."""
    ap = argparse.ArgumentParser(description="Render bench/results/*.json as Markdown (the Benchmarks page).")
    ap.add_argument("--write", action="store_true", help="write bench/REPORT.md instead of printing")
    ap.add_argument("--results", type=Path, default=RESULTS, help="folder of result files (default: bench/results)")
    a = ap.parse_args(argv)
    if a.write:
        print(f"wrote {write_report(a.results)}", file=sys.stderr)
    else:
        print(render(a.results))


if __name__ == "__main__":
    main()
