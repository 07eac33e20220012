"""Speed baselines built at benchmark time: the paper's tree in plain uncertified C, and the memory read.

``bench/baseline_tree.c`` is compiled with ``gcc -O3 -march=native`` (one thread) into a temporary
directory and called through ctypes on the same float64 arrays the certified filter gets, so the
two run on identical data in one process. Returns None when no C compiler is available.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "baseline_tree.c"
FLAGS = ["-O3", "-march=native", "-std=c99", "-fPIC", "-shared"]

_lib: list[ctypes.CDLL] = []


def build() -> ctypes.CDLL | None:
    """Compile and load the baseline (once per process)."""
    if _lib:
        return _lib[0]
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        return None
    out = Path(tempfile.mkdtemp(prefix="baseline-")) / "baseline.so"
    subprocess.run([cc, *FLAGS, "-o", str(out), str(SOURCE)], check=True, capture_output=True)
    lib = ctypes.CDLL(str(out))
    for n in (3, 4):
        fn = getattr(lib, f"baseline{n}")
        fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int64]
        fn.restype = None
    lib.read_all.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int64]
    lib.read_all.restype = ctypes.c_double
    _lib.append(lib)
    return lib


def baseline_codes(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Relation codes from the uncertified tree (may be wrong near tangency)."""
    lib = build()
    if lib is None:
        raise RuntimeError("no C compiler: the uncertified baseline cannot be built")
    A = np.ascontiguousarray(A, dtype=np.float64)
    B = np.ascontiguousarray(B, dtype=np.float64)
    out = np.empty(A.shape[0], dtype=np.int8)
    getattr(lib, f"baseline{A.shape[-1]}")(A.ctypes.data, B.ctypes.data, out.ctypes.data, A.shape[0])
    return out


def best_rate(fn, count: int, repeats: int = 5) -> float:
    """Best of ``repeats`` runs of ``fn()``, as items per second."""
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return count / best


def read_all(A: np.ndarray, B: np.ndarray) -> float:
    """Sum every entry of both arrays once in C (one thread): the memory-read limit."""
    lib = build()
    if lib is None:
        raise RuntimeError("no C compiler")
    flatA, flatB = A.reshape(-1), B.reshape(-1)
    return float(lib.read_all(flatA.ctypes.data, flatB.ctypes.data, flatA.size))


def read_rate(A: np.ndarray, B: np.ndarray, repeats: int = 5) -> float:
    """Pairs per second at which one thread can merely read both input arrays once."""
    lib = build()
    if lib is None:
        raise RuntimeError("no C compiler")
    flatA, flatB = A.reshape(-1), B.reshape(-1)
    return best_rate(lambda: lib.read_all(flatA.ctypes.data, flatB.ctypes.data, flatA.size), A.shape[0], repeats)
