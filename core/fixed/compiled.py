"""The compiled float filter: the extension ``core.fixed._filter``, built when the package is installed.

Why C: the filter's lane functions are straight-line float code generated from one description
(:mod:`core.fixed.driver`, :mod:`core.fixed.kernelgen`), so a C compiler turns them into SIMD
across pairs. ``setup.py`` builds them with the standard setuptools ``Extension`` (``pip install
.`` or ``pip install -e .``): on x86-64 three variants (baseline SSE2, AVX2, AVX-512) in one build,
the best one this CPU runs chosen when the module is imported (:func:`variant`), so a wheel or an
image runs on any CPU of the architecture; elsewhere the portable build. Contraction into fused
multiply-adds is off (``-ffp-contract=off``) and there is no ``-ffast-math``: every operation
rounds once, as the error bounds assume. Nothing is compiled, cached or waited for at run time.

Calls release the GIL, and batches are split over a thread pool: :func:`set_threads` chooses how
many threads (default: every core). If the extension is missing (the package was copied without
being installed, or built without a C compiler) the numpy filter serves, which takes the same
decisions ~100x slower, and a :class:`RuntimeWarning` says so once, naming the cause and the fix.
"""

from __future__ import annotations

import hashlib
import os
import threading
import warnings
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path
from types import ModuleType
from typing import cast

import numpy as np

__all__ = [
    "available", "balance_available", "balance", "spheres_available", "spheres", "query_one_available", "query_one", "query_many", "SPHERE_TIGHT", "SPHERE_LOOSE", "SPHERE_NONE", "SPHERE_OTHER", "pool", "warm_up", "status", "variant", "variants", "select", "rules", "mapped", "rule_one", "set_threads", "get_threads", "threads",
    "header_sha256", "FIX", "HEADER",
]

FIX = 'reinstall the package with a C compiler present: `pip install -e .` (or `pip install .`)'
"""What builds the extension (setup.py, setuptools Extension)."""

_MIN_CHUNK = 16384
"""Pairs per thread below which a batch is not split (thread start-up would dominate)."""

_lock = threading.Lock()
_state: dict[str, object] = {"threads": None, "pool": None, "warned": False}
_CPUS = os.cpu_count() or 1
"""Cores, read once: ``os.cpu_count()`` reads /sys on Linux (~20 us a call, measured), and
:func:`get_threads` runs on every classify call (a one-body index query classifies a few pairs)."""


HEADER = Path(__file__).with_name("_kernels.h")
"""The generated kernels the extension is built from."""


def header_sha256() -> str | None:
    """First 16 hex digits of the SHA-256 of ``_kernels.h`` (None when it is not shipped)."""
    try:
        return hashlib.sha256(HEADER.read_bytes()).hexdigest()[:16]
    except OSError:
        return None


def _load() -> tuple[ModuleType | None, str]:
    try:
        from . import _filter
    except ImportError as e:  # not built: the numpy filter serves (warned once, when used)
        return None, f"the compiled float filter core.fixed._filter is not built ({e})"
    current = header_sha256()
    if current is not None and _filter.kernels_sha256() != current:  # regenerated, not rebuilt
        warnings.warn(
            "core.fixed._filter was built from another core/fixed/_kernels.h than the one beside it "
            "(run `pip install -e .` after `python -m core.fixed.kernelgen`); it still certifies what it "
            "was built to certify, but the numpy filter and the C may now differ.",
            RuntimeWarning,
            stacklevel=2,
        )
    return _filter, f"compiled kernels loaded (core.fixed._filter, {_filter.variant()} variant)"


_EXT, _STATUS = _load()


def available() -> bool:
    """True when the compiled extension serves; False: warn once (cause and fix), numpy serves."""
    if _EXT is not None:
        return True
    if not _state["warned"]:
        _state["warned"] = True
        warnings.warn(
            f"{_STATUS}: classify runs the numpy filter instead (the same certified answers, about "
            f"100x slower). Fix: {FIX}.",
            RuntimeWarning,
            stacklevel=3,
        )
    return False


def warm_up(*, wait: bool = True) -> bool:
    """Start the filter's thread pool now, and say whether the compiled kernels serve.

    The kernels load with the module; what a first large batch would otherwise pay is the
    start of the pool's threads (one per :func:`get_threads`). A server or a Dask worker calls
    this once at start-up. ``wait=False`` starts them without waiting.

    Returns:
        True when the compiled extension serves (False: the numpy filter, ~100x slower).
    """
    if _EXT is not None:
        n = get_threads()
        if n > 1:
            runner = pool(n)
            started = [runner.submit(int) for _ in range(n)]
            if wait:
                for f in started:
                    f.result()
    return _EXT is not None


def status() -> str:
    """Why the compiled kernels are or are not in use."""
    return _STATUS


def variant() -> str | None:
    """The SIMD variant in use ("avx512", "avx2", "baseline"), None without the extension."""
    return None if _EXT is None else str(_EXT.variant())


def variants() -> list[str]:
    """The variants of this build that this CPU runs, slowest first (empty without the extension)."""
    return [] if _EXT is None else list(_EXT.variants())


def select(name: str) -> None:
    """Use this SIMD variant (tests compare them; ``ELLIPSOID_SIMD`` chooses one at import).

    Raises:
        ValueError: unknown, not built, or not supported by this CPU.
        RuntimeError: the extension is not built.
    """
    if _EXT is None:
        raise RuntimeError(f"{_STATUS}; fix: {FIX}")
    _EXT.select(name)


def set_threads(n: int | None) -> None:
    """Threads for batches (None: every core, ``os.cpu_count()``; 1: the calling thread only)."""
    if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 1):
        raise ValueError(f"threads must be a positive integer or None, got {n!r}")
    with _lock:
        _state["threads"] = n


def get_threads() -> int:
    """Threads a batch is split over (:func:`set_threads`, else ``ELLIPSOID_THREADS``, else every core)."""
    n = _state["threads"] or int(os.environ.get("ELLIPSOID_THREADS", "0") or 0) or _CPUS
    return int(cast(int, n))


@contextmanager
def threads(n: int | None) -> Iterator[None]:
    """Within the block, batches use ``n`` threads (as :func:`set_threads`); the setting is restored after.

    Examples:
        >>> with threads(1):
        ...     get_threads()
        1
    """
    with _lock:
        before = _state["threads"]
    set_threads(n)
    try:
        yield
    finally:
        with _lock:
            _state["threads"] = before


def pool(k: int) -> ThreadPoolExecutor:
    """The filter's thread pool, with at least ``k`` threads (one per core by default)."""
    with _lock:
        pool = _state["pool"]
        if pool is None or pool._max_workers < k:  # type: ignore[attr-defined]
            pool = ThreadPoolExecutor(max_workers=max(k, _CPUS), thread_name_prefix="filter")
            _state["pool"] = pool
        return pool  # type: ignore[return-value]


def _forget_pool_in_child() -> None:
    """After ``fork``, in the child: forget the parent's pool and lock.

    None of the parent's threads exist in the child, so its copy of the pool would queue work
    that no thread ever runs (a ``multiprocessing`` child's classify hung forever once the parent
    had classified). The child starts its own pool when it needs one, with a fresh lock (another
    thread of the parent may have held this one at the fork).
    """
    global _lock  # noqa: PLW0603 - the module's one lock, replaced in the child only
    _lock = threading.Lock()
    _state["pool"] = None


if hasattr(os, "register_at_fork"):  # POSIX; Windows has no fork
    os.register_at_fork(after_in_child=_forget_pool_in_child)


def _contiguous(a: np.ndarray) -> np.ndarray:
    """C-contiguous float64 or float32 (float32 stays: half the bytes, widened exactly in C)."""
    dtype = np.float32 if a.dtype == np.float32 else np.float64
    return np.ascontiguousarray(a, dtype=dtype)


def rules(a: np.ndarray, b: np.ndarray, *, threads: int | None = None) -> np.ndarray:
    """Rule ids (int8, -1 undecided) for float64 or float32 stacks (N, n, n), split over threads.

    Raises:
        RuntimeError: the extension is not built (check :func:`available` first).
    """
    return _run(a, b, None, threads)[0]


def mapped(a: np.ndarray, b: np.ndarray, table: np.ndarray, *, threads: int | None = None) -> tuple[np.ndarray, int]:
    """``table[rule id as a byte]`` per pair (int8; ``table`` has 256 entries) and how many pairs are undecided.

    The lookup happens in the kernel as each block is finished (the relation codes of
    :func:`core.fixed.filters.classify_float` without a second pass over the output), and the
    count spares the caller a search for undecided pairs when there are none.

    Raises:
        RuntimeError: the extension is not built (check :func:`available` first).
    """
    return _run(a, b, np.ascontiguousarray(table, dtype=np.int8), threads)


def _run(a: np.ndarray, b: np.ndarray, table: np.ndarray | None, threads: int | None) -> tuple[np.ndarray, int]:
    if _EXT is None:
        raise RuntimeError(f"{_STATUS}; fix: {FIX}")
    n = a.shape[-1]
    a, b = _contiguous(a), _contiguous(b)
    if a.dtype != b.dtype:
        a, b = a.astype(np.float64), b.astype(np.float64)
    N = a.shape[0]
    out = np.empty(N, dtype=np.int8)
    extra = () if table is None else (table,)
    k = min(threads or get_threads(), max(1, N // _MIN_CHUNK))
    if k <= 1:
        return out, int(_EXT.classify(n, a, b, out, *extra))
    # the calling thread takes the first part itself: fewer threads to wake, and none waits idle
    # (the first call of a process was 1.2-2x the second with every part in the pool)
    bounds = np.linspace(0, N, k + 1).astype(np.int64)
    parts = [(int(lo), int(hi)) for lo, hi in zip(bounds[:-1], bounds[1:], strict=True)]
    futures = [pool(k - 1).submit(_EXT.classify, n, a[lo:hi], b[lo:hi], out[lo:hi], *extra) for lo, hi in parts[1:]]
    lo, hi = parts[0]
    undecided = int(_EXT.classify(n, a[lo:hi], b[lo:hi], out[lo:hi], *extra))  # this thread takes a part too
    return out, undecided + sum(int(f.result()) for f in futures)


def balance_available() -> bool:
    """True when the extension has ``balance`` (a build older than it: the numpy twin serves)."""
    return _EXT is not None and hasattr(_EXT, "balance")


def balance(a: np.ndarray, b: np.ndarray, shift_b: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
    """:func:`core.fixed.filters._balanced` in one compiled loop (the extension's ``balance``).

    Returns (a, b, shift_b) with space scaled per pair where exact, and the mask of the pairs
    scaled. ``a``, ``b``: C-contiguous float64 stacks.
    """
    n, N = a.shape[-1], a.shape[0]
    a2, b2, e = np.empty_like(a), np.empty_like(b), np.empty(N, dtype=np.int64)
    if shift_b is None:
        _EXT.balance(n, a, b, a2, b2, e)  # type: ignore[union-attr]
        return a2, b2, None, e != 0
    s = np.ascontiguousarray(shift_b, dtype=np.float64).reshape(N, n - 1)
    s2 = np.empty_like(s)
    _EXT.balance(n, a, b, a2, b2, e, s, s2)  # type: ignore[union-attr]
    return a2, b2, s2, e != 0


SPHERE_TIGHT, SPHERE_LOOSE, SPHERE_NONE, SPHERE_OTHER = 0, 1, 2, 3
"""Status codes of :func:`spheres` (``core/fixed/_spheres.h``): certified; certified but more than
1 % loose; no sphere from this proof (the careful paths of :mod:`core.bodies.bounds` decide); not
exactly symmetric or M_00 = 0 (its general path)."""


def spheres_available() -> bool:
    """True when the extension has ``spheres`` (a build older than it: the numpy proof serves)."""
    return _EXT is not None and hasattr(_EXT, "spheres")


def spheres(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Certified bounding spheres of float64 bodies (N, n, n) in C: (centres, radii, status).

    The float proof of :mod:`core.bodies.bounds` for exactly symmetric matrices
    (``core/fixed/_spheres.h``, the twin of its ``_exact_spheres``): centres (N, n - 1) and radii
    (N,), NaN where there is none; status int8 codes ``SPHERE_*``. One body at a time in C (the
    caller splits a large batch over threads: the GIL is released).
    """
    n, N = M.shape[-1], M.shape[0]
    c, r, st = np.empty((N, n - 1)), np.empty(N), np.empty(N, dtype=np.int8)
    _EXT.spheres(n, np.ascontiguousarray(M, dtype=np.float64), c, r, st)  # type: ignore[union-attr]
    return c, r, st


def query_one_available() -> bool:
    """True when the extension has ``query_one`` (one new body asked of a :class:`core.BodyIndex`)."""
    return _EXT is not None and hasattr(_EXT, "query_one")


QUERY_TOO_FAR, QUERY_GENERAL, QUERY_FAR_BOX, QUERY_SPACE, QUERY_MOVED = -1, -2, -4, -10, -3
"""Outcomes of :func:`query_one` besides a count: an image beyond 127 boxes; the general path
decides (no float sphere, or a body too large for the box); a centre too far from the box;
``QUERY_SPACE - needed``: the outputs must hold ``needed`` bodies. ``QUERY_MOVED``: the code of a
pair with a lattice image (not classified there)."""


def query_one(*args: object) -> tuple[int, int, int]:
    """One new body asked of a :class:`core.BodyIndex` in C (``core/fixed/_near.h``; arguments: ``_filter.pyi``).

    Only :meth:`core.bodies.index.BodyIndex._query_one` calls it, with the buffers it sized.
    """
    out: tuple[int, int, int] = _EXT.query_one(*args)  # type: ignore[union-attr]
    return out


def query_many(*args: object) -> tuple[int, int, int, int, int]:
    """New bodies with their spheres asked of a :class:`core.BodyIndex` in C (``core/fixed/_near.h``; arguments: ``_filter.pyi``).

    Only :meth:`core.bodies.index.BodyIndex._query_many` calls it, with the buffers it sized.
    """
    out: tuple[int, int, int, int, int] = _EXT.query_many(*args)  # type: ignore[union-attr]
    return out


def rule_one(A: np.ndarray, B: np.ndarray) -> int:
    """Rule id of one float64 (n, n) pair (-1 undecided); the extension must be available."""
    out = np.empty(1, dtype=np.int8)
    _EXT.classify(A.shape[0], np.ascontiguousarray(A, dtype=np.float64), np.ascontiguousarray(B, dtype=np.float64), out)  # type: ignore[union-attr]
    return int(out[0])
