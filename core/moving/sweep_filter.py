"""Certified float filter for the first contact of bodies in linear motion (the C kernel's driver).

For each pair (i, j) of :class:`core.moving.linear.LinearMotions` (j optionally moved by a
lattice vector) the kernel ``core/moving/_sweep_filter.c`` returns one of

* ``NEVER``: separate at every t in [0, 1], certified;
* ``OVERLAP_AT_START``: a point inside both at t = 0, certified (t* = 0, relation OVERLAP);
* ``CONTACT``: separate on [0, t_lo] and a point inside both at t_hi, certified, with
  t_hi - t_lo <= 1e-9 (t_lo, t_hi floats): the first contact t* is in (t_lo, t_hi], and the
  shapes are tangent there (they were separate just before: the first time two moving closed
  shapes meet they only touch, since a common interior point would be one a little earlier);
* ``UNDECIDED``: no certificate (touching without crossing, tangency at t = 0, gaps below the
  float resolution, degenerate or extreme input): exact arithmetic decides
  (:func:`core.moving.first_contact.first_contact`).

The certificates are the paper's: two shapes are separate exactly when P(T) = det(T A + B) has
two distinct positive roots, so P(t, T) > 0 for one T > 0 and every t of an interval proves
separation there; it is proven by the Bernstein coefficients of P(., T) on that interval, each
larger than its certified error radius. The proofs of the radii are in the C source's header;
every constant a radius adds is a named allowance there, checked against a trace of the
operations it covers by :mod:`core.moving.sweepbounds`.
The search is a Newton-like advance: T maximises P(t_a, .) at the current t_a, the next float
root of P(., T) is the target, and the advance converges quadratically to a transversal contact.

The kernel is the extension ``core.moving._sweep_filter`` (``_sweep_filter.pyi``), built when
the package is installed (``setup.py``; nothing is compiled at run time): its ``sweep_pairs``
takes the arrays through the buffer protocol, checks them, and releases the GIL while it runs, so
a large batch is split over threads. Without it every pair is UNDECIDED (the exact path answers
all of them, slowly) and a :class:`RuntimeWarning` says so once, naming the cause and the fix.
"""

from __future__ import annotations

import importlib
import threading
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from ..fixed.compiled import FIX, get_threads
from .linear import LinearMotions

__all__ = ["NEVER", "CONTACT", "OVERLAP_AT_START", "UNDECIDED", "FilterResult", "first_contacts_float", "filter_status", "available"]

NEVER, CONTACT, OVERLAP_AT_START, UNDECIDED = 0, 1, 2, -1
"""Status codes of :class:`FilterResult` (the kernel's: its module constants of the same names)."""

_MIN_CHUNK = 256
"""Pairs per thread below which a batch is not split."""

_lock = threading.Lock()
_state: dict[str, object] = {"lib": None, "status": "not built yet", "tried": False}


@dataclass
class FilterResult:
    """What the float filter certified for each pair."""

    status: np.ndarray
    """int8 NEVER, CONTACT, OVERLAP_AT_START or UNDECIDED."""
    t_lo: np.ndarray
    """float64: CONTACT: separate on [0, t_lo]; OVERLAP_AT_START: 0; else NaN."""
    t_hi: np.ndarray
    """float64: CONTACT: not separate at t_hi (t_hi - t_lo <= 1e-9); OVERLAP_AT_START: 0; else NaN."""
    iterations: np.ndarray
    """int32 advancement steps (diagnostics)."""


def _library() -> ModuleType | None:
    """The compiled kernel's module (imported once), or None with a one-time warning saying why."""
    with _lock:
        if not _state["tried"]:
            _state["tried"] = True
            lib: ModuleType | None = None
            try:
                lib = importlib.import_module("core.moving._sweep_filter")
                if not callable(getattr(lib, "sweep_pairs", None)):  # built from an older source
                    where = getattr(lib, "__file__", lib.__name__)
                    raise ImportError(f"{where} has no sweep_pairs: it was built from an older core/moving/_sweep_module.c")
                status = f"compiled sweep kernel loaded from {lib.__file__}"
            except ImportError as e:
                lib = None
                status = f"the compiled sweep kernel is missing ({type(e).__name__}: {e}): exact arithmetic answers every pair"
                warnings.warn(f"{status}; to fix it, {FIX}", RuntimeWarning, stacklevel=3)
            _state["lib"] = lib
            _state["status"] = status
    return _state["lib"]  # type: ignore[return-value]


def available() -> bool:
    """True when the compiled sweep filter serves (else a one-time warning; exact arithmetic answers)."""
    return _library() is not None


def filter_status() -> str:
    """Why the compiled sweep filter is or is not in use."""
    _library()
    return str(_state["status"])


def first_contacts_float(
    bodies: LinearMotions,
    i: np.ndarray,
    j: np.ndarray,
    shift: np.ndarray | None = None,
    *,
    threads: int | None = None,
) -> FilterResult:
    """Run the certified float filter on the pairs (i[k], j[k]) (j moved by shift[k]).

    Args:
        bodies: the bodies (their rows are read by index).
        i: int64 (M,) first body of each pair.
        j: int64 (M,) second body.
        shift: (M, d) float lattice vectors added to body j's centre (exact floats), or None.
        threads: threads to split the batch over (None: :func:`core.fixed.compiled.get_threads`).

    Returns:
        :class:`FilterResult` (every pair UNDECIDED when the kernel is unavailable).

    Raises:
        ValueError: i and j of different sizes, an index that is not a body, a shift of another shape.
    """
    M = int(np.asarray(i).size)
    if int(np.asarray(j).size) != M:
        raise ValueError(f"i and j must hold one body per pair each, got {M} and {np.asarray(j).size}")
    out = FilterResult(np.full(M, UNDECIDED, np.int8), np.full(M, np.nan), np.full(M, np.nan), np.zeros(M, np.int32))
    lib = _library()
    if lib is None or M == 0:
        return out
    rows = bodies.packed()
    d = bodies.dim
    pi = np.ascontiguousarray(i, dtype=np.int64).reshape(M)
    pj = np.ascontiguousarray(j, dtype=np.int64).reshape(M)
    sh = None if shift is None else np.ascontiguousarray(shift, dtype=np.float64).reshape(M, d)
    fn = lib.sweep_pairs

    def run(lo: int, hi: int) -> None:
        # the C checks the arrays (types, shapes, indices) and releases the GIL while it runs
        s = slice(lo, hi)
        fn(d, rows, pi[s], pj[s], None if sh is None else sh[s], out.status[s], out.t_lo[s], out.t_hi[s], out.iterations[s])

    k = min(threads or get_threads(), max(1, M // _MIN_CHUNK))
    if k <= 1:
        run(0, M)
        return out
    # interleaved blocks: hard pairs (clustered in space, hence in index order) spread evenly
    bounds = np.linspace(0, M, 8 * k + 1).astype(np.int64)
    with ThreadPoolExecutor(k, thread_name_prefix="sweep") as pool:
        for f in [pool.submit(run, int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]:
            f.result()
    return out
