"""Every generated file and traced constant of the project, written or checked from one entry point.

    python -m core.generated            # write every generated file (as each generator does)
    python -m core.generated --check    # exit status 1, naming each stale file or unsafe constant

The generators keep their own commands, which share :func:`write_or_check`:

* ``python -m core.fixed.kernelgen [--check]``: core/fixed/_kernels.py and _kernels.h, the static
  filter's kernels with their traced error constants (:mod:`core.fixed.errorbound`);
* ``python -m core.witness.detgen [--check]``: core/witness/_det_kernels.py, the certified float
  determinants.

The sweep filter's C (core/moving/_sweep_filter.c) is hand-written, its error allowances checked
against traces of the operations they cover: ``python -m core.moving.sweepbounds [--check]``, run
here too (it has nothing to write). After writing, rebuild the extensions: ``pip install -e .``.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from pathlib import Path

__all__ = ["GENERATORS", "CHECKS", "write_or_check", "stale", "main"]

GENERATORS: dict[str, str] = {
    "core.fixed.kernelgen": "python -m core.fixed.kernelgen",
    "core.witness.detgen": "python -m core.witness.detgen",
}
"""Module -> command of every generator; each module has ``generated_files()`` (path -> text)."""

CHECKS: dict[str, str] = {"core.moving.sweepbounds": "python -m core.moving.sweepbounds"}
"""Module -> command of every check of hand-written constants; each module has ``problems()``."""


def write_or_check(files: dict[Path, str], command: str, *, check: bool) -> int:
    """Write a generator's files, or with ``check`` compare them with the committed ones.

    Args:
        files: path -> the text the generator produces today.
        command: the command that writes them (named in the message).
        check: compare only.

    Returns:
        0, or 1 when checking found a file that is not what the generator produces (named).
    """
    if check:
        old = [str(p) for p, text in files.items() if not p.exists() or p.read_text() != text]
        if old:
            print(f"stale: {', '.join(old)}: run {command}")
            return 1
        return 0
    for path, text in files.items():
        path.write_text(text)
        print(f"wrote {path} ({len(text.splitlines())} lines)")
    return 0


def stale() -> list[str]:
    """Every generated file that differs from what its generator produces, and every unsafe constant, one line each."""
    out: list[str] = []
    for name, command in GENERATORS.items():
        files: Callable[[], dict[Path, str]] = importlib.import_module(name).generated_files
        out += [f"stale: {p}: run {command}" for p, text in files().items() if not p.exists() or p.read_text() != text]
    for name, command in CHECKS.items():
        problems: Callable[[], list[str]] = importlib.import_module(name).problems
        out += [f"{line} (see {command})" for line in problems()]
    return out


def main(argv: list[str] | None = None) -> int:
    """Write every generated file (default) or ``--check`` them all and the traced constants; 1 on a problem."""
    args = sys.argv[1:] if argv is None else argv
    if "--check" in args:
        found = stale()
        for line in found:
            print(line)
        if not found:
            print(f"{len(GENERATORS)} generators' files current, {len(CHECKS)} traced constants' check passed")
        return 1 if found else 0
    status = 0
    for name, command in GENERATORS.items():
        status |= write_or_check(importlib.import_module(name).generated_files(), command, check=False)
    for name in CHECKS:
        status |= int(importlib.import_module(name).main(["--check"]))
    return status


if __name__ == "__main__":
    raise SystemExit(main())
