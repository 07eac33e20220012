"""NPZ files (numpy's zip archives of arrays), read without ever unpickling anything.

Bodies: arrays ``centers`` (N, d), ``semi_axes`` (N, d), optional ``orientations`` ((N, 4)
quaternions wxyz, or (N,) angles in 2D) and optional ``box`` (2, 3 or 6 numbers, see
:mod:`app.readers.bodyset`); or ``Q``, (N, d+1, d+1) matrices. :func:`npz_arrays` is also the
reader of ``python -m app classify`` (arrays ``A`` and ``B``).

Arrays are loaded with ``allow_pickle=False``: an array of Python objects is refused with a
message (loading pickles runs code from the file; that is never offered).
"""

from __future__ import annotations

import io
import math
import zipfile
import zlib
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .bodyset import BodySet, file_box, from_parameters
from .guard import one_line

__all__ = ["npz_arrays", "read_npz"]

_NPY_MAGIC = b"\x93NUMPY"


def npz_arrays(
    source: str | Path | bytes, name: str, wanted: Sequence[str] | None = None, *, required: Sequence[str] = ()
) -> dict[str, np.ndarray]:
    """The arrays of an .npz file (all, or those of ``wanted`` that it has).

    Each array's header (shape, dtype) is read and checked against the bytes its member of the
    archive holds before the array is made, and the member's size against what its compression
    can give (:func:`_checked_member`): a small file that claims a huge array is refused, never
    allocated.

    Args:
        source: a path, or the bytes of the file.
        name: the file's name, for messages.
        wanted: the arrays to load (others are not read).
        required: arrays that must be there (a message lists those found otherwise).

    Raises:
        ValueError: not an .npz archive (a single .npy array, or not a zip file at all), a
            damaged or truncated archive, an array of Python objects, a member that is no .npy
            array, encrypted or compressed otherwise than numpy writes, an array whose header
            claims more than its member holds.
    """
    try:
        if isinstance(source, bytes):
            head = source[:8]
        else:
            with Path(source).open("rb") as f:
                head = f.read(8)
    except OSError as e:
        raise ValueError(f"cannot read {name}: {e.strerror}") from None
    if head.startswith(_NPY_MAGIC):
        raise ValueError(f"{name}: a single .npy array, not an .npz archive of named arrays (np.savez writes one)")
    if not head.startswith(b"PK"):
        raise ValueError(f"{name}: not an .npz file (a zip archive of .npy arrays, as np.savez writes)")
    out: dict[str, np.ndarray] = {}
    try:
        with zipfile.ZipFile(io.BytesIO(source) if isinstance(source, bytes) else source) as z:
            members = {info.filename: info for info in z.infolist()}
            keys = {m[:-4] if m.endswith(".npy") else m: m for m in sorted(members, key=lambda m: m.endswith(".npy"))}
            missing = [r for r in required if r not in keys]
            if missing:
                raise ValueError(f"{name}: expected arrays {' and '.join(required)}, found {sorted(keys) or 'none'}")
            for key in keys if wanted is None else [w for w in wanted if w in keys]:
                info = members[keys[key]]
                _checked_member(z, info, key, name)
                with z.open(info) as f:
                    try:
                        out[key] = np.lib.format.read_array(f, allow_pickle=False)
                    except ValueError as e:
                        raise ValueError(f"{name}: array {key!r}: damaged .npy data ({one_line(e)})") from None
    except zipfile.BadZipFile as e:
        raise ValueError(f"{name}: damaged or truncated .npz file: not a zip archive ({one_line(e)})") from None
    except (OSError, EOFError, zlib.error, RuntimeError, NotImplementedError) as e:
        raise ValueError(f"{name}: damaged or truncated .npz file ({one_line(e)})") from None
    return out


_DEFLATE_RATIO = 1032
"""Most bytes deflate expands one compressed byte into (RFC 1951's longest match: 258 bytes from 2 bits)."""


def _checked_member(z: zipfile.ZipFile, info: zipfile.ZipInfo, key: str, name: str) -> None:
    """Refuse a member that is not an .npy array numpy could have written, or claims more than it holds.

    Raises:
        ValueError: encrypted; compressed otherwise than stored or deflated (what np.savez and
            np.savez_compressed write); an uncompressed size deflate cannot reach; not an .npy
            array; an array of Python objects; a header whose shape and dtype need more bytes
            than the member holds.
    """
    where = f"{name}: array {key!r}"
    if info.flag_bits & 0x1:
        raise ValueError(f"{where} is encrypted: numpy's archives are not")
    if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
        method = {zipfile.ZIP_BZIP2: "bzip2", zipfile.ZIP_LZMA: "LZMA"}.get(info.compress_type, f"method {info.compress_type}")
        raise ValueError(f"{where} is compressed with {method}: only stored or deflated members (as np.savez and np.savez_compressed write) are read")
    most = info.compress_size if info.compress_type == zipfile.ZIP_STORED else info.compress_size * _DEFLATE_RATIO + 64
    if info.file_size > most:
        raise ValueError(f"{where} claims {info.file_size:,} bytes from {info.compress_size:,} compressed: more than its compression can give")
    if not info.filename.endswith(".npy"):
        raise ValueError(f"{where} is not an .npy array (a member {info.filename!r} of the archive); np.savez writes NAME.npy")
    with z.open(info) as f:
        try:
            version = np.lib.format.read_magic(f)
            if version == (1, 0):
                shape, _, dtype = np.lib.format.read_array_header_1_0(f)
            else:
                shape, _, dtype = np.lib.format.read_array_header_2_0(f)
        except ValueError as e:
            raise ValueError(f"{where} has no valid .npy header ({one_line(e)})") from None
        start = f.tell()
    if dtype.hasobject:
        raise ValueError(f"{where} holds Python objects; only arrays of numbers are read")
    need = math.prod(shape) * dtype.itemsize
    holds = info.file_size - start
    if need > holds:
        raise ValueError(f"{where} claims shape {tuple(shape)} of {dtype} ({need:,} bytes) but holds {max(holds, 0):,} bytes")


def read_npz(source: str | Path | bytes, name: str) -> BodySet:
    """Bodies from an .npz file (module docstring).

    Raises:
        ValueError: see :func:`npz_arrays`; missing arrays, wrong shapes or dtypes.
    """
    arrays = npz_arrays(source, name, ("Q", "centers", "semi_axes", "orientations", "box"))
    box = _box(arrays.get("box"), name)
    if "Q" in arrays:
        Q = np.asarray(arrays["Q"])
        if Q.ndim != 3 or Q.shape[1] != Q.shape[2] or Q.shape[1] not in (3, 4):
            raise ValueError(f"{name}: Q must be (N, 3, 3) or (N, 4, 4), got shape {Q.shape}")
        if Q.dtype.kind not in "fiu":
            raise ValueError(f"{name}: Q must hold numbers, got dtype {Q.dtype}")
        return BodySet.of_matrices(Q.astype(np.float64), source=name, box=None if box is None else box(Q.shape[1] - 1))
    missing = {"centers", "semi_axes"} - set(arrays)
    if missing:
        raise ValueError(f"{name}: expected arrays centers, semi_axes, orientations (or Q); missing {sorted(missing)}")
    for k in ("centers", "semi_axes", "orientations"):
        if k in arrays and arrays[k].dtype.kind not in "fiu":
            raise ValueError(f"{name}: {k} must hold numbers, got dtype {arrays[k].dtype}")
    c = arrays["centers"]
    dim = int(c.shape[1]) if c.ndim == 2 else 3
    return from_parameters(c, arrays["semi_axes"], arrays.get("orientations"), name, box=None if box is None else box(dim))


def _box(values: np.ndarray | None, name: str):  # type: ignore[no-untyped-def]
    """The ``box`` array as a function of the dimension (2, 3 or 6 numbers)."""
    if values is None:
        return None
    v = np.asarray(values)
    if v.dtype.kind not in "fiu" or v.ndim != 1 or v.size not in (2, 3, 6):
        raise ValueError(f"{name}: box must be 2, 3 or 6 numbers (Lx, Ly[, Lz] or Lx, Ly, Lz, xy, xz, yz), got {v.tolist()!r}"[:300])
    f = v.astype(np.float64)
    return lambda dim: file_box(f[:3], f[3:], dim=dim) if f.size == 6 else tuple(float(x) for x in f)
