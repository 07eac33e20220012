"""Per-pair scalar filter (numba-compiled when numba is installed, plain Python otherwise).

The same certified decisions as the vectorised numpy filter in :mod:`core.filters`, written for
one pair at a time so that numba turns them into a tight loop (tens of millions of pairs per
second) and so that a single pair (a drag in the scene) costs microseconds, not a numpy round trip.
``tests/test_filters.py`` checks that both implementations give identical codes.
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np

from . import _kernels as K
from .errorbound import RADIUS_FACTOR

__all__ = ["HAVE_NUMBA", "classify_pairs", "classify_one", "warm_up"]

try:  # numba is optional: the plain-Python functions below are the reference
    from numba import njit as _njit

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - exercised only where numba is missing
    HAVE_NUMBA = False

    def _njit(*args: Any, **kwargs: Any) -> Any:
        if args and callable(args[0]):
            return args[0]
        return lambda f: f


KERNELS_SHA = "6c2399ba7d5e5373"
"""sha256 prefix of core/_kernels.py, rewritten by ``python -m core.kernelgen``: numba keys the disk
cache of the compiled functions below on this file, and they inline those kernels, so this file
must change whenever the kernels do (a test checks the value)."""

_UNDECIDED, _SEPARATE, _OVERLAP = -1, 0, 2
_RF = RADIUS_FACTOR
_C3, _F3, _H3 = K.PENCIL3_CONSTANTS, K.PENCIL3_FLOOR, K.HAT_S0_3_FLOOR
_C4, _F4, _H4 = K.PENCIL4_CONSTANTS, K.PENCIL4_FLOOR, K.HAT_S0_4_FLOOR
# matrices symmetric only up to rounding: prepared entries are rounded (see prepare_source)
_C3R, _F3R = K.PENCIL3_CONSTANTS_ROUNDED, K.PENCIL3_FLOOR_ROUNDED
_C4R, _F4R = K.PENCIL4_CONSTANTS_ROUNDED, K.PENCIL4_FLOOR_ROUNDED
_prepare3 = _njit(cache=True, inline="always")(K.prepare3)
_prepare4 = _njit(cache=True, inline="always")(K.prepare4)
_pencil3 = _njit(cache=True, inline="always")(K.pencil3)
_pencil4 = _njit(cache=True, inline="always")(K.pencil4)
_hat3 = _njit(cache=True, inline="always")(K.hat_s0_3)
_hat4 = _njit(cache=True, inline="always")(K.hat_s0_4)


@_njit(cache=True, inline="always")
def _certify(r: Any, C: Any, floor: float, n: int) -> int:
    """Validity, signs and Var from pencil outputs r: -1 undecided, else Var(a_n..a_0)."""
    for k in range(2 * (n + 1), len(r), 2):  # leading minors > 0: quadratic blocks definite
        if not r[k] > C[k] * r[k + 1] + floor:
            return -1
    for k in (0, 2 * n):  # a_0 = det B < 0, a_n = det A < 0
        if not r[k] < -(C[k] * r[k + 1] + floor):
            return -1
    var = 0
    last = -1
    for i in range(n - 1, 0, -1):
        v = r[2 * i]
        b = C[2 * i] * r[2 * i + 1] + floor
        if v > b:
            s = 1
        elif v < -b:
            s = -1
        else:
            return -1
        if s != last:
            var += 1
            last = s
    if last != -1:
        var += 1
    return var


@_njit(cache=True, inline="always")
def _coefficients(r: Any, C: Any, floor: float, n: int, c: Any, cr: Any) -> None:
    for i in range(n + 1):
        c[i] = r[2 * i]
        cr[i] = C[2 * i] * r[2 * i + 1] + floor


@_njit(cache=True, inline="always")
def _pair3(A: Any, B: Any, wa: Any, wb: Any, c: Any, cr: Any) -> int:
    sa = _prepare3(A, wa)
    sb = _prepare3(B, wb)
    if sa == 0 or sb == 0:
        return _UNDECIDED
    exact_leaves = sa == 1 and sb == 1
    C = _C3 if exact_leaves else _C3R
    F = _F3 if exact_leaves else _F3R
    r = _pencil3(wa, wb)
    var = _certify(r, C, F, 3)
    if var < 0:
        return _UNDECIDED
    if var != 2:
        return _OVERLAP
    _coefficients(r, C, F, 3, c, cr)
    hv, hr = _hat3(c, cr)
    b = hr * _RF + _H3
    if hv > b:
        return _SEPARATE  # Th. 12 / Cor. 13: s0 > 0
    if hv < -b:
        return _OVERLAP
    return _UNDECIDED


@_njit(cache=True, inline="always")
def _pair4(A: Any, B: Any, wa: Any, wb: Any, c: Any, cr: Any) -> int:
    sa = _prepare4(A, wa)
    sb = _prepare4(B, wb)
    if sa == 0 or sb == 0:
        return _UNDECIDED
    exact_leaves = sa == 1 and sb == 1
    C = _C4 if exact_leaves else _C4R
    F = _F4 if exact_leaves else _F4R
    r = _pencil4(wa, wb)
    var = _certify(r, C, F, 4)
    if var < 0:
        return _UNDECIDED
    if var != 2:
        return _OVERLAP
    _coefficients(r, C, F, 4, c, cr)
    hv, hr = _hat4(c, cr)
    b = hr * _RF + _H4
    if hv < -b:
        return _SEPARATE  # Th. 28.2: s0 < 0
    if hv > b:
        return _OVERLAP
    return _UNDECIDED


@_njit(cache=True)
def _many3(A: Any, B: Any, out: Any) -> None:
    wa = np.empty((3, 3))
    wb = np.empty((3, 3))
    c = np.empty(3 + 1)
    cr = np.empty(3 + 1)
    for i in range(A.shape[0]):
        out[i] = _pair3(A[i], B[i], wa, wb, c, cr)


@_njit(cache=True)
def _many4(A: Any, B: Any, out: Any) -> None:
    wa = np.empty((4, 4))
    wb = np.empty((4, 4))
    c = np.empty(4 + 1)
    cr = np.empty(4 + 1)
    for i in range(A.shape[0]):
        out[i] = _pair4(A[i], B[i], wa, wb, c, cr)


@_njit(cache=True)
def _one3(A: Any, B: Any) -> int:
    wa = np.empty((3, 3))
    wb = np.empty((3, 3))
    c = np.empty(4)
    cr = np.empty(4)
    return _pair3(A, B, wa, wb, c, cr)


@_njit(cache=True)
def _one4(A: Any, B: Any) -> int:
    wa = np.empty((4, 4))
    wb = np.empty((4, 4))
    c = np.empty(5)
    cr = np.empty(5)
    return _pair4(A, B, wa, wb, c, cr)


_ready = threading.Event()
_start_lock = threading.Lock()
_started: list[threading.Thread] = []


def _compile_all() -> None:
    """Compile (or load from numba's disk cache) every entry point once."""
    for n in (3, 4):
        M = np.eye(n)
        M[-1, -1] = -1.0
        N = M.copy()
        N[0, -1] = N[-1, 0] = -3.0
        N[-1, -1] = 8.0
        (_one3 if n == 3 else _one4)(M, N)
        (_many3 if n == 3 else _many4)(M[None], N[None], np.empty(1, np.int8))
    _ready.set()


def warm_up(*, wait: bool = True) -> bool:
    """Compile the numba kernels in a background thread (once); optionally wait for it.

    Returns True when the compiled kernels are ready. Without numba there is nothing to do
    (returns False: the numpy / exact paths are used).
    """
    if not HAVE_NUMBA:
        return False
    with _start_lock:
        if not _started:
            t = threading.Thread(target=_compile_all, name="numba-warm-up", daemon=True)
            _started.append(t)
            t.start()
    if wait:
        _ready.wait()
    return _ready.is_set()


def classify_pairs(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Codes for float64 arrays (N, n, n) with the compiled per-pair kernel."""
    warm_up(wait=True)
    out = np.empty(A.shape[0], dtype=np.int8)
    A = np.ascontiguousarray(A, dtype=np.float64)
    B = np.ascontiguousarray(B, dtype=np.float64)
    (_many3 if A.shape[-1] == 3 else _many4)(A, B, out)
    return out


def classify_one(A: np.ndarray, B: np.ndarray, *, wait: bool = True) -> int:
    """Code for one float64 pair (n, n).

    With ``wait=False`` it never blocks on numba's first compilation (several seconds without
    the disk cache): until the kernels are ready it answers UNDECIDED, so an interactive caller
    falls back to the exact path (~0.1 ms) instead of freezing.
    """
    if not warm_up(wait=wait):
        return _UNDECIDED
    return int((_one3 if A.shape[-1] == 3 else _one4)(A, B))
