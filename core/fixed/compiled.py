"""The compiled float filter: ``core/fixed/_kernels.c`` built once per machine and source, called by ctypes.

Why C: the filter's kernels are straight-line float code generated from the same trace as the
numpy ones (:mod:`core.fixed.kernelgen`), so a C compiler turns them into the fastest code this
machine can run (``-O3 -march=native``), in about half a second (numba needed 20 s), with
no runtime dependency beyond a C compiler. Contraction into fused multiply-adds is off
(``-ffp-contract=off``) and there is no ``-ffast-math``: every operation rounds once, as the
error bounds assume.

The shared library is cached under ``$ELLIPSOID_KERNEL_CACHE`` (else ``$XDG_CACHE_HOME`` or
``~/.cache``, then the temp directory) in a file named by the hash of the source, the flags, the
compiler and the CPU, written atomically, so every process of the machine (scene, API workers,
Dask workers) loads it without compiling again. Calls release the GIL (ctypes), and batches are
split over a thread pool: :func:`set_threads` chooses how many threads (default: every core).
Without a C compiler :func:`library` returns None and the numpy filter serves.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import platform
import shutil
import subprocess
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

__all__ = ["library", "load_source", "warm_up", "status", "rules", "rule_one", "set_threads", "get_threads", "SOURCE", "FLAGS"]

SOURCE = Path(__file__).with_name("_kernels.c")
FLAGS: tuple[str, ...] = (
    "-O3",
    "-march=native",
    "-mprefer-vector-width=512",
    "-std=c99",
    "-ffp-contract=off",
    "-fno-fast-math",
    "-fno-math-errno",
    "-fno-trapping-math",
    "-fPIC",
    "-shared",
)
"""Compiler flags: optimise for this CPU, but never fuse or reassociate floating-point operations.

``-fno-math-errno`` and ``-fno-trapping-math`` only let the compiler assume that sqrt need not
set errno and that floating-point exceptions are not trapped (so it may evaluate both sides of a
select and vectorise the branch-free loops); the value of every operation is unchanged, which is
all the error bounds rely on. Value-changing options (-ffast-math, -fassociative-math,
-ffinite-math-only, contraction into FMA) stay off."""

PORTABLE_FLAGS: tuple[str, ...] = ("-O2", "-std=c99", "-ffp-contract=off", "-fno-fast-math", "-fPIC", "-shared")
"""Fallback for compilers that do not know a flag of FLAGS (same guarantees, less speed)."""

_MIN_CHUNK = 16384
"""Pairs per thread below which a batch is not split (thread start-up would dominate)."""

_lock = threading.Lock()
_ready = threading.Event()
_state: dict[str, object] = {"lib": None, "status": "not built yet", "thread": None, "threads": None, "pool": None}


def _compiler() -> str | None:
    cc = os.environ.get("CC")
    if cc:
        return cc
    for name in ("cc", "gcc", "clang"):
        if shutil.which(name):
            return name
    return None


def _cpu_tag() -> str:
    """What -march=native depends on: the CPU's flags (a shared cache serves mixed machines)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith(("flags", "Features")):
                return line
    except OSError:
        pass
    return platform.processor() or platform.machine()


def cache_dir() -> Path:
    """Where compiled libraries are kept (created on demand)."""
    env = os.environ.get("ELLIPSOID_KERNEL_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "ellipsoid-interference"


def _library_path(cc: str, source: Path = SOURCE) -> Path:
    try:
        version = subprocess.run([cc, "--version"], capture_output=True, text=True, timeout=30, check=False).stdout
    except (OSError, subprocess.SubprocessError):
        version = cc
    h = hashlib.sha256()
    for part in (source.read_bytes(), " ".join(FLAGS).encode(), version.encode(), _cpu_tag().encode(), platform.machine().encode()):
        h.update(part)
        h.update(b"\0")
    stem = "kernels" if source == SOURCE else source.stem.lstrip("_")
    return Path(f"{stem}-{h.hexdigest()[:20]}.so")


def load_source(source: Path) -> tuple[ctypes.CDLL | None, str]:
    """Compile a C source with :data:`FLAGS` (or find it in the cache) and load it.

    The same cache, naming by hash (source, flags, compiler, CPU) and atomic write as the
    filter's own kernels, so any C file of the project is built once per machine.

    Returns:
        (the library, or None; a sentence saying where it was loaded from or why not).
    """
    cc = _compiler()
    if cc is None:
        return None, "no C compiler found (set CC)"
    name = _library_path(cc, source)
    status = "not built"
    for folder in (cache_dir(), Path(tempfile.gettempdir()) / "ellipsoid-interference"):
        target = folder / name
        try:
            if not target.exists():
                folder.mkdir(parents=True, exist_ok=True)
                fd, tmp = tempfile.mkstemp(suffix=".so", dir=folder)
                os.close(fd)
                for flags in (FLAGS, PORTABLE_FLAGS):  # a compiler that lacks a flag: portable build
                    cmd = [cc, *flags, "-o", tmp, str(source), "-lm"]
                    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300, check=False)
                    if res.returncode == 0:
                        break
                else:
                    os.unlink(tmp)
                    return None, f"C compilation failed: {res.stderr.strip()[:500]}"
                os.replace(tmp, target)  # atomic: concurrent builders agree on the result
            return ctypes.CDLL(str(target)), f"compiled kernels loaded from {target}"
        except OSError as e:  # unwritable cache: try the next folder
            status = f"cannot use {folder}: {e}"
    return None, status


def _build() -> None:
    """Compile (or find in the cache) and load the library; record why not otherwise."""
    try:
        lib, status = load_source(SOURCE)
        if lib is None:
            _state["status"] = status + ("" if "compiler" not in status else ": the numpy filter serves")
            return
        for n in (3, 4):
            fn = getattr(lib, f"classify{n}")
            fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int64]
            fn.restype = None
        _state["lib"] = lib
        _state["status"] = status
    except Exception as e:  # noqa: BLE001 - never break classification: numpy serves
        _state["status"] = f"could not build the compiled kernels: {type(e).__name__}: {e}"
    finally:
        _ready.set()


def warm_up(*, wait: bool = True) -> bool:
    """Build or load the compiled kernels in a background thread (once); optionally wait.

    Returns True when they are ready (False without a C compiler: the numpy filter serves).
    """
    with _lock:
        if _state["thread"] is None:
            t = threading.Thread(target=_build, name="kernel-build", daemon=True)
            _state["thread"] = t
            t.start()
    if wait:
        _ready.wait()
    return _state["lib"] is not None


def library(*, wait: bool = True) -> ctypes.CDLL | None:
    """The loaded library, or None (not ready with ``wait=False``, or no compiler)."""
    warm_up(wait=wait)
    return _state["lib"]  # type: ignore[return-value]


def status() -> str:
    """Why the compiled kernels are or are not in use."""
    return str(_state["status"])


def set_threads(n: int | None) -> None:
    """Threads for batches (None: every core, ``os.cpu_count()``; 1: the calling thread only)."""
    if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 1):
        raise ValueError(f"threads must be a positive integer or None, got {n!r}")
    with _lock:
        _state["threads"] = n


def get_threads() -> int:
    """Threads a batch is split over."""
    n = _state["threads"] or int(os.environ.get("ELLIPSOID_THREADS", "0") or 0) or os.cpu_count() or 1
    return int(n)  # type: ignore[call-overload]


def _pool(k: int) -> ThreadPoolExecutor:
    with _lock:
        pool = _state["pool"]
        if pool is None or pool._max_workers < k:  # type: ignore[attr-defined]
            pool = ThreadPoolExecutor(max_workers=max(k, os.cpu_count() or 1), thread_name_prefix="filter")
            _state["pool"] = pool
        return pool  # type: ignore[return-value]


def rules(a: np.ndarray, b: np.ndarray, *, threads: int | None = None) -> np.ndarray:
    """Rule ids (int8, -1 undecided) for float64 stacks (N, n, n), split over threads.

    Raises:
        RuntimeError: the library is not available (check :func:`warm_up` first).
    """
    lib = library(wait=True)
    if lib is None:
        raise RuntimeError(f"compiled kernels unavailable: {status()}")
    n = a.shape[-1]
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    N = a.shape[0]
    out = np.empty(N, dtype=np.int8)
    fn = getattr(lib, f"classify{n}")
    k = min(threads or get_threads(), max(1, N // _MIN_CHUNK))
    if k <= 1:
        fn(a.ctypes.data, b.ctypes.data, out.ctypes.data, N)
        return out
    bounds = np.linspace(0, N, k + 1).astype(np.int64)
    stride = 8 * n * n

    def run(lo: int, hi: int) -> None:
        fn(a.ctypes.data + stride * lo, b.ctypes.data + stride * lo, out.ctypes.data + lo, hi - lo)

    futures = [_pool(k).submit(run, int(lo), int(hi)) for lo, hi in zip(bounds[:-1], bounds[1:], strict=True)]
    for f in futures:
        f.result()
    return out


def rule_one(A: np.ndarray, B: np.ndarray) -> int:
    """Rule id of one contiguous float64 (n, n) pair (-1 undecided); the library must be ready."""
    lib = _state["lib"]
    out = np.empty(1, dtype=np.int8)
    getattr(lib, f"classify{A.shape[0]}")(A.ctypes.data, B.ctypes.data, out.ctypes.data, 1)
    return int(out[0])
