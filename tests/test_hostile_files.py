"""Hostile files of bodies in every format (issue 52 item 4): one line, exit 2, never a traceback or a signal.

A corpus of malformed files (huge headers and fields, NUL bytes, negative and huge claimed
counts, truncated frames, wrong types, BOMs, CRLF, a "zip" that is none, ...), each generated
here by code (no binary fixtures): CSV, NPZ, Parquet, HOOMD GSD, LAMMPS dump and extended XYZ.
Each file is read

* through the reader API (:func:`app.readers.read_bodies`, and :func:`read_bodies_bytes` as
  the scene's upload and standard input read): a ValueError whose one line names the file and
  says what is wrong, and
* through the command line (``python -m app contacts FILE``) in a subprocess whose address
  space is limited to 2 GB (``RLIMIT_AS``): exit status 2, one line on stderr naming the file
  and what is wrong, no "Traceback", no signal. A reader that allocates what a header claims
  before checking it fails there with MemoryError (exit 1) or a signal (the extended XYZ C
  parser does not check its allocations), so the limit makes such a reader fail the test.

Each case names a fragment of the message it must give (what is wrong), so that a file refused
for the wrong reason fails too.
"""

from __future__ import annotations

import gzip
import io
import json
import os
import resource
import struct
import subprocess
import sys
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from app.readers import read_bodies, read_bodies_bytes

gsd_fl = pytest.importorskip("gsd.fl")
pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
pytest.importorskip("lammpsio")
pytest.importorskip("extxyz")

ROOT = Path(__file__).resolve().parents[1]
ADDRESS_SPACE = 2 << 30
"""RLIMIT_AS of the command's process: 2 GB (a valid small file needs far less; see the last test)."""

CSV3 = "x,y,z,a,b,c,qw,qx,qy,qz"
ROW3 = "0,0,0,1,1,1,1,0,0,0"


@dataclass(frozen=True)
class Case:
    """A hostile file: its name, how to make it, and a fragment of the message it must give."""

    name: str
    make: Callable[[Path], None]
    says: str
    invalid_body: bool = False
    """The file reads, but a body in it is no shape (a value beyond the float range): the reader
    marks it (:attr:`BodySet.errors`, the reason naming the line or body) and the command refuses it."""


def text(content: str | bytes) -> Callable[[Path], None]:
    data = content.encode() if isinstance(content, str) else content
    return lambda p: p.write_bytes(data)


# ----------------------------------------------------------------------------- CSV
def csv_cases() -> list[Case]:
    ok = f"{CSV3}\n{ROW3}\n"
    return [
        Case("empty.csv", text(""), "empty file"),
        Case("huge-header-field.csv", text(f"{CSV3},{'q' * (1 << 20)}\n{ROW3},5\n"), "line 1"),
        Case("huge-header-no-newline.csv", text("x" * (3 << 20)), "the header (line 1) is longer than"),
        Case("huge-header-many-columns.csv", text(",".join(["id"] * 300_000) + "\n1\n"), "the header must name the columns"),
        Case("huge-field-ragged-row.csv", text(f"{CSV3},t\n{ROW3},\"{'9' * 900_000}\",1\n"), "line 2"),
        Case("huge-quoted-number.csv", text(f"{CSV3}\n0,0,0,1,1,1,1,0,0,\"{'9' * 900_000}\"\n"), "line 2", invalid_body=True),
        Case("huge-text-value.csv", text(f"{CSV3}\n0,0,0,1,1,1,1,0,0,{'z' * 900_000}\n"), "line 2, column 10"),
        Case("nuls-after-header.csv", text(f"{CSV3}\n".encode() + b"\0" * (1 << 20)), "line 2 holds NUL"),
        Case("nul-in-number.csv", text(f"{CSV3}\n0,0,0,1\0,1,1,1,0,0,0\n"), "line 2 holds NUL"),
        Case("binary.csv", text(np.random.default_rng(1).bytes(50_000)), "holds NUL bytes: binary data"),
        Case("gzipped.csv", text(gzip.compress(ok.encode())), "gzip-compressed"),
        Case("utf16.csv", text(ok.encode("utf-16")), "UTF-16"),
        Case("double-bom.csv", text("\ufeff\ufeff" + ok), "missing x"),
        Case("text-value.csv", text(f"{CSV3}\n0,0,0,1,1,1,1,0,0,zero\n"), "line 2, column 10"),
        Case("million-commas.csv", text(f"{CSV3}\n{ROW3}{',' * 1_000_000}\n"), "line 2: 1000010 values but 10 columns"),
        Case("missing-column.csv", text("x,y,z,a,b,c\n0,0,0,1,1,1\n"), "missing qw,qx,qy,qz"),
        Case("crlf-bad-value.csv", text(f"{CSV3}\r\n{ROW3}\r\n{ROW3}\r\n0,0,0,1,1,1,1,0,0,zero\r\n"), "line 4, column 10"),
        Case("unterminated-quote.csv", text(f"{CSV3}\n0,0,0,1,1,1,1,0,0,\"0\n{ROW3}\n"), "line 2"),
    ]


# ----------------------------------------------------------------------------- NPZ
def npz_bytes(**arrays: object) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def npy_header(shape: tuple[int, ...], descr: str = "<f8") -> bytes:
    """An .npy file of ``shape`` holding only a few bytes of data (its header claims the rest)."""
    head = repr({"descr": descr, "fortran_order": False, "shape": shape}).encode()
    head += b" " * ((64 - (10 + len(head) + 1) % 64) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(head)) + head + b"\0" * 64


def zipped(members: dict[str, bytes], method: int = zipfile.ZIP_STORED) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", method) as z:
        for name, data in members.items():
            z.writestr(name, data)
    return buf.getvalue()


def patched_zip(data: bytes, field: str, value: int) -> bytes:
    """Patch every local and central header of a zip: "flags" (+ encrypted) or "method"."""
    out = bytearray(data)
    for sig, flags_at, method_at in ((b"PK\x03\x04", 6, 8), (b"PK\x01\x02", 8, 10)):
        at = out.find(sig)
        while at >= 0:
            off = at + (flags_at if field == "flags" else method_at)
            out[off : off + 2] = struct.pack("<H", value)
            at = out.find(sig, at + 4)
    return bytes(out)


def zip_claiming(name: str, data: bytes, file_size: int) -> bytes:
    """A deflated zip member whose directory claims ``file_size`` uncompressed bytes."""
    z = bytearray(zipped({name: data}, zipfile.ZIP_DEFLATED))
    for sig, size_at in ((b"PK\x03\x04", 22), (b"PK\x01\x02", 24)):
        at = z.find(sig)
        z[at + size_at : at + size_at + 4] = struct.pack("<I", file_size)
    return bytes(z)


def npz_cases() -> list[Case]:
    c, r = np.zeros((5, 3)), np.ones((5, 3))
    good = npz_bytes(centers=c, semi_axes=r)
    return [
        Case("pk-zeros.npz", text(b"PK" + b"\0" * 200), "not a zip archive"),
        Case("truncated.npz", text(good[: len(good) // 2]), "damaged or truncated"),
        Case("empty-archive.npz", text(zipped({})), "missing ['centers', 'semi_axes']"),
        Case("objects.npz", text(npz_bytes(centers=np.array([object()] * 3), semi_axes=r)), "holds Python objects"),
        Case("single-array.npz", text(npy_header((2, 3))), "a single .npy array"),
        Case("claims-1e12-rows.npz", text(zipped({"centers.npy": npy_header((10**12, 3)), "semi_axes.npy": npy_header((10**12, 3))})),
             "array 'centers' claims"),
        Case("claims-1e8-rows.npz", text(zipped({"centers.npy": npy_header((10**8, 3)), "semi_axes.npy": npy_header((10**8, 3))})),
             "array 'centers' claims"),
        Case("claims-huge-strings.npz", text(zipped({"centers.npy": npy_header((1,), "<U200000000")})), "array 'centers' claims"),
        Case("deflate-bomb-claim.npz", text(zip_claiming("centers.npy", npy_header((10**8, 3)), 8 * 3 * 10**8 + 128)),
             "array 'centers' claims"),
        Case("lzma-member.npz", text(zipped({"centers.npy": npy_header((1, 3)), "semi_axes.npy": npy_header((1, 3))}, zipfile.ZIP_LZMA)),
             "compressed with"),
        Case("bad-npy-header.npz", text(zipped({"centers.npy": b"\x93NUMPY\x01\x00\x10\x00{'descr': oops}\n" + b"\0" * 32})),
             "array 'centers'"),
        Case("raw-member.npz", text(zipped({"centers": b"1,2,3\n", "semi_axes": b"1,1,1\n"})), "not an .npy array"),
        Case("encrypted.npz", text(patched_zip(good, "flags", 1)), "encrypted"),
        Case("unknown-compression.npz", text(patched_zip(good, "method", 99)), "compressed with"),
        Case("string-values.npz", text(npz_bytes(centers=np.array([["a", "b", "c"]]), semi_axes=np.ones((1, 3)))), "must hold numbers"),
        Case("mismatched-lengths.npz", text(npz_bytes(centers=c, semi_axes=np.ones((4, 3)))), "semi_axes"),
        Case("bad-box.npz", text(npz_bytes(centers=c, semi_axes=r, box=[1.0, 2.0, 3.0, 4.0])), "box must be"),
    ]


# ----------------------------------------------------------------------------- Parquet
def parquet_bytes(columns: dict[str, object]) -> bytes:
    buf = io.BytesIO()
    pq.write_table(pa.table(columns), buf)
    return buf.getvalue()


def parquet_cases() -> list[Case]:
    cols = {k: [0.0, 3.0] if k == "x" else ([1.0, 1.0] if k in "abc" or k == "qw" else [0.0, 0.0]) for k in CSV3.split(",")}
    good = parquet_bytes(cols)
    huge_footer = good[:-8] + struct.pack("<I", 0x7FFFFFFF) + b"PAR1"
    return [
        Case("empty.parquet", text(b""), "not a readable Parquet file"),
        Case("garbage.parquet", text(b"PAR1" + np.random.default_rng(3).bytes(2000) + b"PAR1"), "not a readable Parquet file"),
        Case("truncated.parquet", text(good[: len(good) // 2]), "not a readable Parquet file"),
        Case("footer-claims-2gb.parquet", text(huge_footer), "not a readable Parquet file"),
        Case("strings.parquet", text(parquet_bytes({**cols, "x": ["0", "3"]})), "column x holds string"),
        Case("nulls.parquet", text(parquet_bytes({**cols, "a": [1.0, None]})), "column a has 1 missing values"),
        Case("lists.parquet", text(parquet_bytes({**cols, "y": [[0.0], [1.0]]})), "column y holds list"),
        Case("big-integers.parquet", text(parquet_bytes({**cols, "z": pa.array([2**60 + 1, 0], pa.int64())})), "not float64 values"),
    ]


# ----------------------------------------------------------------------------- GSD
def gsd_file(path: Path, *, N: int = 5, rows: int | None = None, shapes: list[object] | None = None, typeid: list[int] | None = None,
             dims: int = 3) -> None:
    """A HOOMD GSD frame written chunk by chunk (so that its chunks can disagree with particles/N)."""
    rows = min(N, 5) if rows is None else rows  # a claimed N above 5: the chunks hold 5 rows
    shapes = [{"type": "Ellipsoid", "a": 1.0, "b": 0.5, "c": 0.5}] if shapes is None else shapes
    with gsd_fl.open(str(path), mode="w", application="test", schema="hoomd", schema_version=[1, 4]) as f:
        f.write_chunk("configuration/box", np.array([10, 10, 10, 0, 0, 0], np.float32))
        f.write_chunk("configuration/dimensions", np.array([dims], np.uint8))
        f.write_chunk("particles/N", np.array([N], np.uint32))
        f.write_chunk("particles/position", np.arange(3 * rows, dtype=np.float32).reshape(rows, 3))
        f.write_chunk("particles/typeid", np.array(typeid if typeid is not None else [0] * rows, np.uint32))
        f.write_chunk("particles/types", np.array([[ord("A"), 0]], np.int8))
        names = [json.dumps(s).encode() if not isinstance(s, bytes) else s for s in shapes]
        width = max(len(n) for n in names) + 1
        f.write_chunk("particles/type_shapes", np.array([list(n.ljust(width, b"\0")) for n in names], np.int8))
        f.end_frame()


def gsd_patched(path: Path, at: int, value: int, fmt: str = "<Q") -> None:
    data = bytearray(path.read_bytes())
    data[at : at + struct.calcsize(fmt)] = struct.pack(fmt, value)
    path.write_bytes(bytes(data))


def gsd_index_patched(path: Path, chunk_rows: int, chunk_cols: int, N: int) -> None:
    """Patch the index entries of the chunks of (rows, cols) to claim N rows."""
    data = bytearray(path.read_bytes())
    index = struct.unpack_from("<Q", data, 8)[0]
    for k in range(struct.unpack_from("<Q", data, 16)[0]):
        frame, n, location, m = struct.unpack_from("<QQqI", data, index + 32 * k)
        if location and n == chunk_rows and m == chunk_cols:
            struct.pack_into("<Q", data, index + 32 * k + 8, N)
    path.write_bytes(bytes(data))


def gsd_cases() -> list[Case]:
    def then(*steps: Callable[[Path], None]) -> Callable[[Path], None]:
        def make(p: Path) -> None:
            for s in steps:
                s(p)
        return make

    cut = lambda p: p.write_bytes(p.read_bytes()[:300])  # noqa: E731
    return [
        Case("empty.gsd", text(b""), "not a readable GSD file"),
        Case("magic-then-zeros.gsd", text(b"\xdf\x65\xdf\x65\xdf\x65\xdf\x65" + b"\0" * 500), "not a readable GSD file"),
        Case("truncated.gsd", then(gsd_file, cut), "GSD"),
        Case("claims-1e8-bodies.gsd", lambda p: gsd_file(p, N=10**8), "claims 100000000 bodies"),
        Case("claims-4e9-bodies.gsd", lambda p: gsd_file(p, N=2**32 - 1), "claims 4294967295 bodies"),
        Case("fewer-positions.gsd", lambda p: gsd_file(p, N=5, rows=3), "particles/position"),
        Case("index-claims-2e40-entries.gsd", then(gsd_file, lambda p: gsd_patched(p, 16, 2**40)), "not a readable GSD file"),
        Case("chunk-claims-1e8-rows.gsd", then(gsd_file, lambda p: gsd_index_patched(p, 5, 3, 10**8)), "GSD"),
        Case("bad-shape-json.gsd", lambda p: gsd_file(p, shapes=[b"{not json"]), "type_shapes"),
    ]


# ----------------------------------------------------------------------------- LAMMPS dump
def dump(n_atoms: str | int = 2, rows: str | None = None, *, box: str = "0 10\n0 10\n0 10\n", step: str = "0",
         columns: str = "id type x y z shapex shapey shapez") -> str:
    rows = "1 1 0 0 0 2 2 2\n2 1 3 0 0 2 2 2\n" if rows is None else rows
    return f"ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{n_atoms}\nITEM: BOX BOUNDS pp pp pp\n{box}ITEM: ATOMS {columns}\n{rows}"


def lammps_cases() -> list[Case]:
    many = "".join(f"{k} 1 {k} 0 0 2 2 2\n" for k in range(1, 201))
    return [
        Case("empty.dump", text(""), "empty file"),
        Case("negative-count.dump", text(dump(-5)), "NUMBER OF ATOMS is -5"),
        Case("claims-1e8.dump", text(dump(10**8, many)), "100000000 atoms announced"),
        Case("claims-1e21.dump", text(dump(10**21, many)), "atoms announced"),
        Case("count-not-a-number.dump", text(dump("five")), "NUMBER OF ATOMS is 'five'"),
        Case("no-count.dump", text("ITEM: TIMESTEP\n0\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 1\n0 1\nITEM: ATOMS id x y z shapex shapey shapez\n"),
             "no ITEM: NUMBER OF ATOMS"),
        Case("truncated.dump", text(dump(10)), "10 atoms announced"),
        Case("box-not-numbers.dump", text(dump(box="0 ten\n0 10\n0 10\n")), "BOX BOUNDS"),
        Case("text-in-shape.dump", text(dump(rows="1 1 0 0 0 2 two 2\n2 1 3 0 0 2 2 2\n")), "frame 0"),
        Case("short-row.dump", text(dump(rows="1 1 0 0 0 2 2\n2 1 3 0 0 2 2 2\n")), "frame 0"),
        Case("gzipped.dump", text(gzip.compress(dump().encode())), "gzip-compressed"),
        Case("nuls.dump", text(b"ITEM: TIMESTEP\n" + b"\0" * (1 << 20)), "line 2 holds NUL bytes"),
        Case("step-not-a-number.dump", text(dump(step="soon")), "TIMESTEP"),
        Case("huge-value.dump", text(dump(rows=f"1 1 0 0 {'9' * (1 << 20)} 2 2 2\n2 1 3 0 0 2 2 2\n")), "id 1", invalid_body=True),
    ]


# ----------------------------------------------------------------------------- extended XYZ
PROPS = "Properties=species:S:1:pos:R:3:aspherical_shape:R:3"


def xyz(n: str | int = 2, comment: str = PROPS, rows: str = "A 0 0 0 1 1 1\nB 3 0 0 1 1 1\n") -> str:
    return f"{n}\n{comment}\n{rows}"


def xyz_cases() -> list[Case]:
    return [
        Case("empty.xyz", text(""), "no frames"),
        Case("claims-1e8.xyz", text(xyz(10**8, PROPS + ' pbc="F F F"' + " " * 70)), "100000000 atoms announced"),
        Case("claims-1e12.xyz", text(xyz(10**12)), "1000000000000 atoms announced"),
        Case("claims-2e31.xyz", text(xyz(2**31)), "2147483648 atoms announced"),
        Case("negative-count.xyz", text(xyz(-3)), "line 1"),
        Case("count-not-a-number.xyz", text(xyz("two")), "line 1"),
        Case("truncated.xyz", text(xyz(10)), "10 atoms announced"),
        Case("no-comment-line.xyz", text("1\n"), "frame 0"),
        Case("huge-comment.xyz", text(xyz(comment=PROPS + " note=" + "n" * (2 << 20))), "line 2"),
        Case("properties-1e8-columns.xyz", text(xyz(comment="Properties=species:S:1:pos:R:100000000")), "columns"),
        Case("properties-unknown-type.xyz", text(xyz(comment="Properties=species:S:1:pos:Q:3:aspherical_shape:R:3")), "Properties"),
        Case("properties-zero-columns.xyz", text(xyz(comment="Properties=species:S:1:pos:R:0:aspherical_shape:R:3")), "Properties"),
        Case("text-in-pos.xyz", text(xyz(rows="A 0 zero 0 1 1 1\nB 3 0 0 1 1 1\n")), "frame 0"),
        Case("short-row.xyz", text(xyz(rows="A 0 0 0 1 1\nB 3 0 0 1 1 1\n")), "frame 0"),
        Case("nuls.xyz", text(b"2\n" + b"\0" * (1 << 20)), "line 2 holds NUL bytes"),
        Case("lattice-two-numbers.xyz", text(xyz(comment=PROPS + ' Lattice="1 2"')), "Lattice"),
        Case("long-species.xyz", text(xyz(1000, rows=f"{'A' * (1 << 20)} 0 0 0 1 1 1\n" + "B 3 0 0 1 1 1\n" * 999)), "line 3"),
    ]


CASES = csv_cases() + npz_cases() + parquet_cases() + gsd_cases() + lammps_cases() + xyz_cases()


def test_the_corpus_is_large_and_names_are_unique():
    assert len(CASES) >= 76
    assert len({c.name for c in CASES}) == len(CASES)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_the_reader_refuses_with_one_line_naming_the_file(case, tmp_path):
    path = tmp_path / case.name
    case.make(path)
    if case.invalid_body:
        bodies = read_bodies(path)
        k = min(bodies.errors)
        message = f"{bodies.where(k)}: {bodies.errors[k]}"
        assert case.says in message and "finite" in message, message
        return
    with pytest.raises(ValueError) as e:
        read_bodies(path)
    message = str(e.value)
    assert "\n" not in message and case.name in message and case.says in message and len(message) < 1000, message
    with pytest.raises(ValueError) as e:  # the same bytes uploaded to the scene (or piped to stdin)
        read_bodies_bytes(path.read_bytes(), case.name)
    assert str(e.value) == message


def _limited() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))


def contacts_command(path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "app", "contacts", str(path), "--out", str(path.parent / "pairs.csv"), "--quiet"],
        cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"},
        capture_output=True, text=True, timeout=300, preexec_fn=_limited, check=False,
    )


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_the_command_exits_2_with_one_line_under_an_address_space_limit(case, tmp_path):
    path = tmp_path / case.name
    case.make(path)
    r = contacts_command(path)
    assert r.returncode == 2, f"exit {r.returncode}: {r.stderr[-2000:]}"
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr and len(r.stderr) < 1000, r.stderr[-2000:]
    assert case.name in r.stderr and case.says in r.stderr, r.stderr
    assert not (tmp_path / "pairs.csv").exists()


def test_a_valid_file_reads_under_the_same_limit(tmp_path):
    """The limit leaves room for real work: the corpus fails for its files, not for the limit."""
    path = tmp_path / "ok.xyz"
    path.write_text(xyz(comment=PROPS + ' pbc="F F F"', rows="A 0 0 0 1 1 1\nB 2 0 0 1 1 1\n"))
    r = contacts_command(path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "pairs.csv").read_text().splitlines()[1].startswith("0,1,tangent,exact")
