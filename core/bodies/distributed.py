"""The contact search on a Dask cluster: spatial partitions with a halo, one task each.

Imported only when Dask is used (``contacts(Q, scheduler=...)`` or a dask array ``Q``;
``pip install -e ".[dask]"``). Steps:

1. Bounding spheres, one task per chunk of bodies (:func:`core.bodies.bounds.bounding_spheres`),
   gathered to the client: (d + 1) floats per body.
2. The longest axis is cut into slabs holding equal numbers of bodies. Partition p *owns* the
   bodies whose centre lies in its slab and also receives the *halo*: the bodies within
   h = 2 R (1 + 2^-20) + pad of the slab on that axis, R the largest bounding radius (in a
   periodic box, measured across the faces).
3. One task per partition runs the broad phase and the narrow phase on its bodies
   (:mod:`core.bodies.broadphase`, :mod:`core.bodies.narrowphase`) and keeps the candidate pairs
   whose smaller body index it owns. A pair that can touch satisfies |x_i - x_j| <= r_i + r_j
   <= 2 R < h, so both bodies are in the partition that owns i, which finds the pair; every
   other partition drops it: each pair is reported exactly once (the duplicates of the halo are
   removed by ownership, not by a global sort).
4. The client concatenates the owned candidates and builds the result exactly as the local
   search does (:func:`core.bodies.search.contacts_of`): the same pairs, relations, certifiers
   and counts as ``contacts(Q)`` on one machine.

The compiled kernels are built once per machine and loaded once per worker process: the
:class:`WarmUp` worker plugin does it when a worker starts (registered by :func:`register`).

Pointing it at a real cluster: start ``dask scheduler`` on one machine and ``dask worker
tcp://SCHEDULER:8786`` on each (``--nworkers`` processes, ``--nthreads 1`` each is simplest);
install this package on every worker; then ``contacts(Q, scheduler="tcp://SCHEDULER:8786")``
or ``contacts(Q, scheduler=Client("tcp://SCHEDULER:8786"))``.
"""

from __future__ import annotations

from typing import Any

import dask
import dask.array as da
import numpy as np
from distributed.diagnostics.plugin import WorkerPlugin

from ..fixed.lazy import PAIR_CHUNK, is_dask_array
from .bounds import BoundingSpheres, bounding_spheres
from .broadphase import _CELL_SLACK, _PAD, BroadPhase, Candidates, TooManyPairs, candidate_pairs
from .narrowphase import classify_candidates
from .periodic import check_box, read_box
from .result import Contacts
from .search import _check, contacts_of, read_bodies

__all__ = ["WarmUp", "register", "contacts_distributed", "BODY_CHUNK"]

BODY_CHUNK = 1 << 18
"""Bodies per chunk when numpy input is handed to Dask (32 MiB of ellipsoid matrices)."""


class WarmUp(WorkerPlugin):
    """Worker plugin: build or load the compiled kernels when a worker starts (once per process).

    Args:
        threads: threads of the C filter in each worker process (None: every core; 1 when a
            machine runs one single-threaded worker process per core, so they do not
            oversubscribe it).
    """

    name = "ellipsoid-interference-kernels"
    idempotent = True

    def __init__(self, threads: int | None = None) -> None:
        self.threads = threads

    def setup(self, worker: Any) -> None:
        """Called once in each worker process (and in every worker that joins later)."""
        from ..fixed.compiled import set_threads, warm_up

        if self.threads is not None:
            set_threads(self.threads)
        warm_up()


def register(client: Any, *, threads: int | None = None) -> None:
    """Register :class:`WarmUp` on a ``distributed.Client`` (idempotent)."""
    client.register_plugin(WarmUp(threads))


def contacts_distributed(
    Q: Any,
    *,
    box: Any = None,
    method: str = "adaptive",
    on_invalid: str = "raise",
    scheduler: Any = None,
    partitions: int | None = None,
    chunk: int = PAIR_CHUNK,
    max_pairs: int | None = None,
) -> Contacts:
    """:func:`core.contacts` on Dask (same arguments; see the module docstring).

    Args:
        Q: numpy or dask array (N, n, n).
        box: periodic box sides or None.
        method: "adaptive", "float" or "exact".
        on_invalid: "raise" or "mark".
        scheduler: a ``distributed.Client``, a scheduler address ("tcp://host:8786"), a
            local scheduler name ("threads", "processes", "synchronous"), or None (Dask's
            current default, e.g. the active Client).
        partitions: number of spatial partitions (default: 2 per worker thread, at least 2).
        chunk: candidate pairs per classify batch inside a task.
        max_pairs: most pairs the broad phase may examine (counted first, here, on the bounding
            spheres): :class:`~core.bodies.broadphase.TooManyPairs` over it.

    Returns:
        The same :class:`Contacts` as the local search (``seconds`` aside).
    """
    import time

    _check(method, ("adaptive", "float", "exact"), "method")
    _check(on_invalid, ("raise", "mark"), "on_invalid")
    t0 = time.perf_counter()
    client, own = _client(scheduler)
    try:
        if client is not None:
            register(client)
        get = {"scheduler": client} if client is not None else ({"scheduler": scheduler} if isinstance(scheduler, str) else {})
        q = _as_dask(Q)
        n = q.shape[-1]
        L = read_box(box, n - 1)
        spheres = _spheres(q, get)
        if spheres.invalid and on_invalid == "raise":
            raise ValueError(next(iter(spheres.invalid.values())))
        if L is not None:
            check_box(spheres.centers, spheres.radii, L)
        if max_pairs is not None and (pairs := BroadPhase(spheres.centers, spheres.radii, box=L).pairs) > max_pairs:
            raise TooManyPairs(pairs, max_pairs)
        t1 = time.perf_counter()
        parts = _partitions(spheres, L, partitions or _default_partitions(client))
        tasks = []
        for members, owned in parts:
            rows = np.sort(members)
            tasks.append(
                dask.delayed(_partition_task)(
                    q[rows], rows, owned, spheres.centers[rows], spheres.radii[rows], L, method, chunk
                )
            )
        results = dask.compute(*tasks, **get) if tasks else []
        t2 = time.perf_counter()
        cand, rel, by = _concatenate(results, n - 1, L is not None)
        out = contacts_of(cand, rel, by, q.shape[0], L, spheres)
        out.seconds = {"bounds": t1 - t0, "partitions": t2 - t1, "total": time.perf_counter() - t0}
        return out
    finally:
        if own and client is not None:
            client.close()


def _client(scheduler: Any) -> tuple[Any, bool]:
    """(Client or None, whether we created it)."""
    if scheduler is None or scheduler in ("threads", "threading", "processes", "synchronous", "sync", "single-threaded"):
        if scheduler is None:
            try:
                from distributed import default_client

                return default_client(), False
            except ValueError:
                return None, False
        return None, False
    if isinstance(scheduler, str):
        from distributed import Client

        return Client(scheduler), True
    return scheduler, False


def _default_partitions(client: Any) -> int:
    if client is None:
        return 4
    threads = sum(client.nthreads().values()) or 1
    return max(2, 2 * threads)


def _as_dask(Q: Any) -> Any:
    """Q as a dask array (N, n, n) whose chunks hold whole matrices (numpy input is read first)."""
    if is_dask_array(Q):
        if Q.ndim != 3 or Q.shape[1] != Q.shape[2] or Q.shape[1] not in (3, 4):
            raise ValueError(f"Q must be an (N, 3, 3) stack of ellipses or (N, 4, 4) of ellipsoids, got shape {Q.shape}")
        return Q.rechunk({1: -1, 2: -1})  # each task reads its block exactly (read_bodies)
    arr = read_bodies(Q)
    return da.from_array(arr, chunks=(min(BODY_CHUNK, max(1, arr.shape[0])), arr.shape[1], arr.shape[2]))


def _spheres(q: Any, get: dict[str, Any]) -> BoundingSpheres:
    """Bounding spheres of every body, one task per chunk, gathered (invalid rows named globally)."""
    blocks = q.to_delayed().ravel()
    offsets = np.cumsum((0, *q.chunks[0]))[:-1]
    parts = dask.compute(*(dask.delayed(_block_spheres)(b, int(o)) for b, o in zip(blocks, offsets, strict=True)), **get)
    d = q.shape[-1] - 1
    if not parts:
        return BoundingSpheres(np.zeros((0, d)), np.zeros(0), {}, 0)
    invalid: dict[int, str] = {}
    for p in parts:
        invalid.update(p[2])
    return BoundingSpheres(
        np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]), dict(sorted(invalid.items())), sum(p[3] for p in parts)
    )


def _block_spheres(block: np.ndarray, offset: int) -> tuple[np.ndarray, np.ndarray, dict[int, str], int]:
    """Spheres of one chunk; invalid bodies renamed by their global row."""
    s = bounding_spheres(read_bodies(block))
    invalid = {k + offset: msg.replace(f"body {k}", f"body {k + offset}", 1) for k, msg in s.invalid.items()}
    return s.centers, s.radii, invalid, s.exact


def _partitions(spheres: BoundingSpheres, box: np.ndarray | None, count: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """(members, owned mask over members) per slab of the longest axis (module docstring, step 2)."""
    valid = np.flatnonzero(spheres.valid)
    if valid.size < 2:
        return [(valid, np.ones(valid.size, dtype=bool))] if valid.size else []
    c = spheres.centers[valid]
    axis = int(np.argmax(box)) if box is not None else int(np.argmax(np.ptp(c, axis=0)))
    x = c[:, axis]
    big = float(np.max(spheres.radii[valid]))
    span = float(np.max(np.abs(c))) + (float(np.max(box)) if box is not None else 0.0)
    halo = 2 * big * _CELL_SLACK + 2 * _PAD * (span + big) + 4 * np.spacing(span)
    count = max(1, min(count, valid.size // 2))
    cuts = np.quantile(x, np.linspace(0, 1, count + 1)[1:-1]) if count > 1 else np.zeros(0)
    slab = np.searchsorted(cuts, x, side="right")  # owner of each body
    out = []
    for p in range(count):
        a = x.min() if p == 0 else cuts[p - 1]  # the slab [a, b] holds every owned centre
        b = x.max() if p == count - 1 else cuts[p]
        gap = _gap(x, a, b)
        if box is not None:  # across the faces too (the centres span at most one side)
            gap = np.minimum(gap, np.minimum(_gap(x + box[axis], a, b), _gap(x - box[axis], a, b)))
        take = (gap <= halo) | (slab == p)
        out.append((valid[take], slab[take] == p))
    return out


def _gap(x: np.ndarray, a: float, b: float) -> np.ndarray:
    """Distance from each x to the interval [a, b]."""
    return np.maximum(a - x, 0.0) + np.maximum(x - b, 0.0)


def _partition_task(
    block: np.ndarray,
    rows: np.ndarray,
    owned: np.ndarray,
    centers: np.ndarray,
    radii: np.ndarray,
    box: np.ndarray | None,
    method: str,
    chunk: int,
) -> tuple[np.ndarray, ...]:
    """Broad and narrow phase on one partition; the owned candidates with global indices."""
    from ..fixed.compiled import warm_up

    warm_up()
    local = candidate_pairs(centers, radii, box=box)
    mine = np.flatnonzero(owned[local.i])  # i < j locally and globally (rows are sorted)
    cand = Candidates(local.i[mine], local.j[mine], None if local.image is None else local.image[mine])
    rel, by = classify_candidates(read_bodies(block), cand, box, method, chunk=chunk)
    image = np.zeros((len(cand), centers.shape[1]), np.int8) if cand.image is None else cand.image
    return rows[cand.i], rows[cand.j], image, rel, by


def _concatenate(results: Any, d: int, periodic: bool) -> tuple[Candidates, np.ndarray, np.ndarray]:
    if not results:
        z = np.zeros(0, np.int64)
        return Candidates(z, z, np.zeros((0, d), np.int8) if periodic else None), np.zeros(0, np.int8), np.zeros(0, np.int8)
    i, j, image, rel, by = (np.concatenate([r[k] for r in results]) for k in range(5))
    return Candidates(i, j, image if periodic else None), rel, by
