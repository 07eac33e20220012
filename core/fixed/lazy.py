"""``classify`` on dask arrays: a lazy dask array of codes, computed chunk by chunk on the workers.

:func:`core.classify` hands dask input here (recognised without importing dask, so ``core``
does not need it); this module imports dask only when it is called (``pip install -e ".[dask]"``).
Each chunk of pairs is one call of the certified classifier (``map_blocks``), so the graph runs
unchanged on a threaded scheduler, a ``LocalCluster`` or a distributed cluster. The compiled
kernels are part of the installed package (the extension built by ``pip install``): a worker
imports them with ``core``, nothing is compiled or waited for;
:class:`core.bodies.distributed.WarmUp` is a worker plugin that imports them when a worker
starts.

Chunk size: about 1 M pairs (:data:`PAIR_CHUNK`). One chunk of ellipsoid pairs is then
2 x 128 MiB of matrices (dask's default chunk size per array) and about 50 ms of work per
core, far above a distributed task's ~1 ms of scheduling overhead; smaller chunks spend more
time in the scheduler, larger ones hold more memory per worker thread.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

__all__ = ["is_dask_array", "classify_lazy", "as_pairs", "PAIR_CHUNK"]

PAIR_CHUNK = 1 << 20
"""Pairs per chunk when a numpy operand is turned into a dask array (see the module docstring)."""


class LazyArray(Protocol):
    """What :func:`core.classify` returns for dask input: a ``dask.array.Array`` of int8 codes."""

    @property
    def shape(self) -> tuple[int, ...]:
        """The broadcast batch shape."""

    def compute(self, **kwargs: Any) -> np.ndarray:
        """The codes, computed on the workers."""


def is_dask_array(x: Any) -> bool:
    """True for a ``dask.array.Array`` (checked by type, without importing dask)."""
    return type(x).__name__ == "Array" and type(x).__module__.startswith("dask.array")


def as_pairs(A: Any, B: Any) -> tuple[Any, Any]:
    """Both operands as dask arrays with a common batch shape and whole (n, n) matrices per chunk.

    A numpy operand becomes a dask array chunked like the other (or :data:`PAIR_CHUNK` pairs
    along the first batch axis); batch shapes broadcast as for :func:`core.classify`.

    Raises:
        ValueError: trailing shapes that are not (3, 3) or (4, 4), or that differ; batch shapes
            that do not broadcast.
    """
    import dask.array as da

    a = A if is_dask_array(A) else np.asarray(A)
    b = B if is_dask_array(B) else np.asarray(B)
    for name, x in (("A", a), ("B", b)):
        if x.ndim < 2 or x.shape[-1] != x.shape[-2] or x.shape[-1] not in (3, 4):
            raise ValueError(f"{name} must be a stack (..., n, n) of 3x3 (ellipse) or 4x4 (ellipsoid) matrices, got shape {x.shape}")
    if a.shape[-1] != b.shape[-1]:
        raise ValueError(f"A is {a.shape[-1]}x{a.shape[-1]} but B is {b.shape[-1]}x{b.shape[-1]}: both must be ellipses or both ellipsoids")
    n = a.shape[-1]
    try:
        batch = np.broadcast_shapes(a.shape[:-2], b.shape[:-2])
    except ValueError:
        raise ValueError(f"batch shapes {a.shape[:-2]} and {b.shape[:-2]} do not broadcast") from None
    out = []
    for x in (a, b):
        y = x
        if not is_dask_array(y):  # PAIR_CHUNK pairs along the first batch axis, the rest whole
            y = da.from_array(y, chunks=tuple(min(PAIR_CHUNK, s) if k == 0 and y.ndim > 2 else s for k, s in enumerate(y.shape)))
        y = da.broadcast_to(y, (*batch, n, n))
        out.append(y.rechunk({y.ndim - 2: -1, y.ndim - 1: -1}))
    a, b = out
    if is_dask_array(A) or not is_dask_array(B):
        return a, b.rechunk(a.chunks)  # the same chunks of pairs: one block of A meets one of B
    return a.rechunk(b.chunks), b


def classify_lazy(block: Callable[..., np.ndarray], A: Any, B: Any, **options: Any) -> LazyArray:
    """A lazy dask array of int8 codes: ``block(a, b, **options)`` on each chunk of pairs.

    Args:
        block: the classifier of one chunk (numpy stacks -> int8 codes of the batch shape);
            passed in by :func:`core.fixed.classify.classify` (this module does not import it).
        A: dask array (or numpy) stack (..., n, n).
        B: the same; batch shapes broadcast.
        **options: keyword arguments of ``block`` (method, on_invalid).

    Returns:
        ``dask.array.Array`` of int8 with the broadcast batch shape; nothing is computed yet.
    """
    import dask.array as da

    a, b = as_pairs(A, B)
    lazy: LazyArray = da.map_blocks(
        _run_block, a, b, dtype=np.int8, drop_axis=[a.ndim - 2, a.ndim - 1], block=block, options=options
    )
    return lazy


def _run_block(a: np.ndarray, b: np.ndarray, *, block: Callable[..., np.ndarray], options: dict[str, Any], block_info: Any = None) -> np.ndarray:
    """One chunk on a worker: classify, name the pair."""
    try:
        return np.asarray(block(a, b, **options), dtype=np.int8).reshape(a.shape[:-2])
    except ValueError as e:
        match = re.match(r"pair (\d+): ", str(e))
        if not (match and block_info and 0 in block_info):
            raise
        # name the pair by its index in the whole batch, not in this chunk
        start = [lo for lo, _ in block_info[0]["array-location"][:-2]]
        local = np.unravel_index(int(match.group(1)), a.shape[:-2])
        index = [int(s + k) for s, k in zip(start, local, strict=True)]
        where = str(index[0]) if len(index) == 1 else str(tuple(index))
        raise ValueError(f"pair {where}: {str(e)[match.end():]}") from None
