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
import zipfile
import zlib
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .bodyset import BodySet, file_box, from_parameters

__all__ = ["npz_arrays", "read_npz"]

_NPY_MAGIC = b"\x93NUMPY"


def npz_arrays(
    source: str | Path | bytes, name: str, wanted: Sequence[str] | None = None, *, required: Sequence[str] = ()
) -> dict[str, np.ndarray]:
    """The arrays of an .npz file (all, or those of ``wanted`` that it has).

    Args:
        source: a path, or the bytes of the file.
        name: the file's name, for messages.
        wanted: the arrays to load (others are not read).
        required: arrays that must be there (a message lists those found otherwise).

    Raises:
        ValueError: not an .npz archive (a single .npy array, or not a zip file at all), a
            damaged or truncated archive, an array of Python objects.
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
    key = ""
    try:
        with np.load(io.BytesIO(source) if isinstance(source, bytes) else source, allow_pickle=False) as z:
            missing = [r for r in required if r not in z.files]
            if missing:
                raise _Missing(f"{name}: expected arrays {' and '.join(required)}, found {sorted(z.files) or 'none'}")
            for key in z.files if wanted is None else [w for w in wanted if w in z.files]:
                out[key] = z[key]
    except _Missing as e:
        raise ValueError(str(e)) from None
    except ValueError as e:
        if "pickle" in str(e):
            raise ValueError(f"{name}: array {key!r} holds Python objects; only arrays of numbers are read") from None
        raise ValueError(f"{name}: damaged or truncated .npz file ({e})") from None
    except (OSError, EOFError, zipfile.BadZipFile, zlib.error) as e:
        raise ValueError(f"{name}: damaged or truncated .npz file ({e})") from None
    return out


class _Missing(Exception):
    """A required array is missing (told apart from numpy's own ValueErrors)."""


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
        return BodySet(Q.astype(np.float64), source=name, box=None if box is None else box(Q.shape[1] - 1))
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
