"""Tables of bodies, columns chosen by name: CSV (streamed) and Parquet (pyarrow).

Columns (any order, any case; an ``id`` column gives the bodies their ids, others such as ``type`` are ignored):
3D ``x,y,z,a,b,c,qw,qx,qy,qz`` (centre, semi-axes, quaternion wxyz), 2D ``x,y,a,b,angle``
(radians). A table with every 3D column is read as ellipsoids, else one with every 2D column as
ellipses. Body k is data row k (CSV: line k + 2 of the file).

A CSV file is read in blocks of about :data:`BLOCK_CHARS` characters (numpy's C parser on each
block), so memory grows with the numbers kept (the selected columns), never with the size of
the text: a 2 GB file with extra columns is read without holding its text. The header line is
at most :data:`HEADER_CHARS` characters; NUL bytes and values beyond the csv module's field
limit are one-line errors naming the line (:mod:`app.readers.guard`).
"""

from __future__ import annotations

import csv
import io
import re
from itertools import repeat
from typing import IO, Any

import numpy as np

from core.shapes.numbers import binary64_array

from .bodyset import BodySet, from_parameters
from .guard import clip, one_line

__all__ = ["COLUMNS", "read_csv", "read_parquet", "BLOCK_CHARS", "HEADER_CHARS"]

COLUMNS = {3: ("x", "y", "z", "a", "b", "c", "qw", "qx", "qy", "qz"), 2: ("x", "y", "a", "b", "angle")}
"""Columns of a body, by dimension."""

BLOCK_CHARS = 1 << 23
"""Characters of CSV text parsed at a time (8 MiB: numpy's parser stays fast, memory small)."""

HEADER_CHARS = 1 << 20
"""Longest header line read (1 Mi characters: some 50,000 column names); a longer one is refused."""


def choose_columns(header: list[str], name: str) -> tuple[int, list[int]]:
    """The dimension and the column index of each needed name (``COLUMNS``) in ``header``.

    Raises:
        ValueError: a needed column is missing or named twice.

    Examples:
        >>> choose_columns(["id", "X", "y", "a", "b", "angle", "type"], "f.csv")
        (2, [1, 2, 3, 4, 5])
    """
    names = [h.strip().strip('"').strip().lower() for h in header]
    for dim in (3, 2):
        if all(c in names for c in COLUMNS[dim]):
            twice = sorted({c for c in COLUMNS[dim] if names.count(c) > 1})
            if twice:
                raise ValueError(f"{name}: the column(s) {', '.join(twice)} appear more than once")
            return dim, [names.index(c) for c in COLUMNS[dim]]
    missing = [c for c in COLUMNS[3] if c not in names]
    missing2 = [c for c in COLUMNS[2] if c not in names]
    raise ValueError(
        f"{name}: the header must name the columns {','.join(COLUMNS[3])} (ellipsoids) or "
        f"{','.join(COLUMNS[2])} (ellipses), in any order (other columns are ignored); "
        f"missing {','.join(missing)} (3D) / {','.join(missing2)} (2D); got {','.join(header)[:200]!r}"
    )


def id_column(header: list[str]) -> int | None:
    """The index of an ``id`` column (the bodies' own ids: outputs name them), or None.

    Examples:
        >>> id_column(["x", "ID", "y"]), id_column(["x", "y"])
        (1, None)
    """
    names = [h.strip().strip('"').strip().lower() for h in header]
    return names.index("id") if names.count("id") == 1 else None


def _ids(table: np.ndarray, with_id: bool, name: str, first_line: int | None) -> tuple[np.ndarray, np.ndarray | None]:
    """The table without its last column and that column as int64 ids, when the file has an id column."""
    if not with_id:
        return table, None
    raw = table[:, -1]
    bad = np.flatnonzero(~(np.isfinite(raw) & (raw == np.round(raw)) & (np.abs(raw) < 2.0**53)))
    if bad.size:
        k = int(bad[0])
        where = f"line {k + first_line}" if first_line is not None else f"row {k}"
        raise ValueError(f"{name}: {where}: id {float(raw[k])!r} is not an integer")
    return table[:, :-1], raw.astype(np.int64)


def read_csv(stream: IO[bytes], name: str) -> BodySet:
    """Read a CSV table of bodies from a binary stream, block by block (module docstring).

    Raises:
        ValueError: no header, missing columns, a value that is not a number (the message names
            the line and column), a row with fewer or more values than the header.
    """
    text = io.TextIOWrapper(stream, encoding="utf-8-sig", errors="replace", newline="")
    first = text.readline(HEADER_CHARS + 1)
    if len(first) > HEADER_CHARS:
        raise ValueError(f"{name}: the header (line 1) is longer than {HEADER_CHARS:,} characters: not a table of bodies")
    if not first.strip():
        raise ValueError(f"{name}: empty file: expected a header row naming the columns")
    header = _fields(first, 1, name)
    dim, cols = choose_columns(header, name)
    idc = id_column(header)
    if idc is not None:
        cols = [*cols, idc]
    width = len(header)
    blocks: list[np.ndarray] = []
    line = 2  # the line of the file where the next block starts
    while True:
        lines = text.readlines(BLOCK_CHARS)
        if not lines:
            break
        _check_widths(lines, width, line, name)
        try:
            block = np.loadtxt(lines, delimiter=",", dtype=np.float64, ndmin=2, usecols=cols, quotechar='"')
        except ValueError as e:
            raise ValueError(f"{name}: {_line_of(str(e), line, header, cols, lines)}") from None
        blocks.append(block)
        line += len(lines)
    table = np.concatenate(blocks) if blocks else np.zeros((0, len(cols)))
    table, ids = _ids(table, idc is not None, name, 2)
    return _bodies(table, dim, name, first_line=2, ids=ids)


def _check_widths(lines: list[str], width: int, start: int, name: str) -> None:
    """Every row has as many values as the header (a stray comma shifts every column after it)."""
    commas = np.fromiter(map(str.count, lines, repeat(",")), dtype=np.int64, count=len(lines))
    for k in np.flatnonzero(commas != width - 1).tolist():
        row = lines[k].strip()
        if not row or row.startswith("#"):  # blank lines and comments are skipped by the parser
            continue
        got = len(_fields(row, start + k, name))  # quoted values may hold commas
        if got != width:
            raise ValueError(f"{name}: line {start + k}: {got} values but {width} columns in the header")


def _fields(row: str, line: int, name: str) -> list[str]:
    """The values of one CSV line (quoted values may hold commas); NUL bytes and huge values refused."""
    if "\0" in row:
        raise ValueError(f"{name}: {_nul(line)}")
    try:
        return next(csv.reader([row]))
    except csv.Error as e:
        limit = csv.field_size_limit()
        problem = f"a value longer than {limit:,} characters" if "field larger" in str(e) else str(e)
        raise ValueError(f"{name}: line {line}: {problem}") from None


def _nul(line: int) -> str:
    return f"line {line} holds NUL bytes: not a text table (a binary file?)"


def _line_of(message: str, start: int, header: list[str], cols: list[int], lines: list[str]) -> str:
    """Numpy's "... at row 12, column 3" (row from 0 in the block) as the file's line and column."""
    m = re.search(r"at row (\d+), column (\d+)", message)
    if not m:
        return clip(message)
    row, col = int(m.group(1)), int(m.group(2))
    if 0 <= row < len(lines) and "\0" in lines[row]:
        return _nul(row + start)
    column = cols[col - 1] + 1 if 0 < col <= len(cols) else col
    what = re.sub(r"string '(.*)' to", lambda v: f"string {clip(v.group(1))!r} to", message.split(" at row")[0], flags=re.S)
    return f"line {row + start}, column {column}: {what} (column {clip(header[column - 1].strip(), 60)})"


def _bodies(table: np.ndarray, dim: int, name: str, **extra: Any) -> BodySet:
    centers, axes = table[:, :dim], table[:, dim : 2 * dim]
    orient = table[:, 2 * dim :] if dim == 3 else table[:, 2 * dim]
    return from_parameters(centers, axes, orient, name, **extra)


def read_parquet(path: str, name: str) -> BodySet:
    """Read a Parquet table of bodies (pyarrow), columns by name, one row group at a time.

    Raises:
        ValueError: pyarrow missing, not a Parquet file, missing columns, non-numeric columns.
    """
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise ValueError(f"{name}: reading Parquet needs pyarrow: pip install 'ellipsoid-interference[formats]'") from None
    try:
        f = pq.ParquetFile(path)
    except Exception as e:  # noqa: BLE001 - pyarrow raises its own ArrowInvalid / OSError kinds
        raise ValueError(f"{name}: not a readable Parquet file ({one_line(e)})") from None
    header = list(f.schema_arrow.names)
    dim, cols = choose_columns(header, name)
    idc = id_column(header)
    if idc is not None:
        cols = [*cols, idc]
    wanted = [header[k] for k in cols]
    blocks = []
    try:
        for batch in f.iter_batches(columns=wanted):
            blocks.append(np.column_stack([_numbers(batch.column(k), header[cols[k]], name) for k in range(len(cols))]))
    except ValueError:
        raise
    except Exception as e:  # noqa: BLE001
        raise ValueError(f"{name}: cannot read the Parquet data ({one_line(e)})") from None
    table = np.concatenate(blocks) if blocks else np.zeros((0, len(cols)))
    table, ids = _ids(table, idc is not None, name, None)
    return _bodies(table, dim, name, ids=ids)


def _numbers(column: Any, label: str, name: str) -> np.ndarray:
    import pyarrow as pa

    if not (pa.types.is_floating(column.type) or pa.types.is_integer(column.type)):
        raise ValueError(f"{name}: column {label} holds {column.type}, not numbers")
    if column.null_count:
        raise ValueError(f"{name}: column {label} has {column.null_count} missing values")
    values = binary64_array(column.to_numpy(zero_copy_only=False))
    if values is None:
        raise ValueError(f"{name}: column {label} holds integers that are not float64 values (bodies are float64 numbers)")
    return values
