"""The contact search on a Dask cluster: spatial partitions with a halo, one task each.

Imported only when Dask is used (``contacts(Q, scheduler=...)`` or a dask array ``Q``;
``pip install -e ".[dask]"``). The data travels once: a numpy ``Q`` is cut into blocks of
:data:`BODY_CHUNK` bodies that are *scattered* to the workers (``Client.scatter``) and stay
there; every later task names blocks by their futures, so the task graphs hold no arrays (no
"Sending large graph" warnings) and the client sends the matrices exactly once. Steps:

1. Bounding spheres, one task per block (:func:`core.bodies.bounds.bounding_spheres`); the
   spheres, (d + 1) floats per body, are gathered to the client, which plans the partitions.
2. The longest axis is cut into slabs holding equal numbers of bodies. Partition p *owns* the
   bodies whose centre lies in its slab and also receives the *halo*: the bodies within
   h = 2 R (1 + 2^-20) + pad of the slab on that axis, R the largest bounding radius (in a
   periodic box, measured across the faces). In a tilted box the slabs cut a fractional
   coordinate f_a (c = f1 a1 + f2 a2 + f3 a3, a the box vector with the largest height h_a)
   and the halo is h / h_a in it (two points within 2 R have f_a within 2 R / h_a), with the
   fractional coordinates' error bound added (:func:`core.bodies.periodic.fractional`).
   Each block sends each partition its members (one small task per block and partition, on
   the worker that holds the block: the plan travels, not the rows).
3. One task per partition runs the broad phase and the narrow phase on its bodies
   (:mod:`core.bodies.broadphase`, :mod:`core.bodies.narrowphase`) and keeps the candidate pairs
   whose smaller body index it owns. A pair that can touch satisfies |x_i - x_j| <= r_i + r_j
   <= 2 R < h, so both bodies are in the partition that owns i, which finds the pair; every
   other partition drops it: each pair is reported exactly once (the duplicates of the halo are
   removed by ownership, not by a global sort).
4. The client concatenates the owned candidates and builds the result exactly as the local
   search does (:func:`core.bodies.search.contacts_of`): the same pairs, relations, certifiers
   and counts as ``contacts(Q)`` on one machine.

A lost worker (a crash, a kill, a restart, or the scheduler's ``distributed.scheduler.worker-ttl``
after it stopped answering): the scheduler runs its tasks again on the workers left (every task is
submitted with ``retries=`` :data:`_TASK_RETRIES`, and one whose worker died is rescheduled), but
the blocks scattered to it are gone, which cancels the futures that needed them, and a message to
it fails: the search warns and starts again from step 1 (:data:`_RETRIES` times), then raises one
RuntimeError saying so. A task that killed its workers again and again (Dask's KilledWorker) is a
RuntimeError at once. The kernels' plugin is registered on the scheduler, which installs it on
every worker that joins; a worker lost while it is installed does not fail the search.

Progress (``progress=True``): Dask's own progress bar (``distributed``'s on a cluster, or
``dask.diagnostics.ProgressBar`` on a local scheduler), drawn on stderr, one bar per step; a
callable ``progress(done, total)`` is called instead as the partition tasks finish.

The compiled kernels are built once per machine and loaded once per worker process: the
:class:`WarmUp` worker plugin does it when a worker starts (registered by :func:`register`).

Pointing it at a real cluster: start ``dask scheduler`` on one machine and ``dask worker
tcp://SCHEDULER:8786`` on each (``--nworkers`` processes, ``--nthreads 1`` each is simplest);
install this package on every worker; then ``contacts(Q, scheduler="tcp://SCHEDULER:8786")``
or ``contacts(Q, scheduler=Client("tcp://SCHEDULER:8786"))``.
"""

from __future__ import annotations

import sys
import time
import warnings
from collections.abc import Sequence
from concurrent.futures import CancelledError
from dataclasses import dataclass
from typing import Any

import dask
import numpy as np
from distributed.comm.core import CommClosedError
from distributed.diagnostics.plugin import WorkerPlugin
from distributed.diagnostics.progressbar import TextProgressBar
from distributed.scheduler import KilledWorker

from ..fixed.lazy import PAIR_CHUNK, is_dask_array
from ..options import check_options
from .bounds import BoundingSpheres, bounding_spheres
from .broadphase import _CELL_SLACK, _PAD, BroadPhase, Candidates, TooManyPairs, candidate_pairs
from .narrowphase import classify_candidates
from .periodic import (
    box_vectors,
    cell_heights,
    check_box,
    fractional,
    is_tilted,
    read_box,
    shift_error,
)
from .result import Contacts
from .search import Progress, contacts_of, read_bodies

__all__ = ["WarmUp", "register", "contacts_distributed", "BODY_CHUNK"]

_RETRIES = 1
"""Times a search starts again after a worker was lost with its data (scattered blocks are not
recomputed: the futures that needed them are cancelled). A worker can be lost by a crash, a
restart, or the scheduler's ``distributed.scheduler.worker-ttl`` when it stops answering."""

_TASK_RETRIES = 2
"""``retries=`` of every task: a task that fails (e.g. its worker shut down under it) runs again elsewhere."""

_LOST = (CancelledError, CommClosedError)
"""What a lost worker makes the client raise: cancelled futures (Dask's FutureCancelledError and
FuturesCancelledError are CancelledErrors), a closed connection to it."""

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
    progress: Progress | bool | None = None,
    max_pairs: int | None = None,
) -> Contacts:
    """:func:`core.contacts` on Dask (same arguments; see the module docstring).

    Args:
        Q: numpy or dask array (N, n, n).
        box: periodic box (sides, or a tilted box's six numbers) or None.
        method: "adaptive", "float" or "exact".
        on_invalid: "raise" or "mark".
        scheduler: a ``distributed.Client``, a scheduler address ("tcp://host:8786"), a
            local scheduler name ("threads", "processes", "synchronous"), or None (Dask's
            current default, e.g. the active Client).
        partitions: number of spatial partitions (default: 2 per worker thread, at least 2).
        chunk: candidate pairs per classify batch inside a task.
        progress: True: Dask's progress bars on stderr; a callable ``progress(done, total)``
            called as partitions finish; None: quiet.
        max_pairs: most pairs the broad phase may examine (counted first, here, on the bounding
            spheres): :class:`~core.bodies.broadphase.TooManyPairs` over it.

    Returns:
        The same :class:`Contacts` as the local search (``seconds`` aside).

    Raises:
        ValueError: bad input (as :func:`core.contacts`).
        RuntimeError: the scheduler at an address cannot be reached, or workers holding the
            search's data were lost twice (the first time the search starts again, warning).
    """
    check_options(method, on_invalid)
    client, own = _client(scheduler)
    try:
        if client is not None:
            try:
                register(client)
            except _LOST:  # stored on the scheduler before it is sent: every worker that joins gets it
                pass
        run = _Runner(client, scheduler if isinstance(scheduler, str) and client is None else None, progress)
        for attempt in range(1 + _RETRIES):
            try:
                return _search(run, Q, box, method, on_invalid, partitions, chunk, max_pairs)
            except KilledWorker as e:
                raise RuntimeError(f"a task of this search killed the Dask workers that ran it, again and again: {_first_line(e)}") from e
            except _LOST as e:
                if client is None or attempt == _RETRIES:
                    raise RuntimeError(
                        f"the Dask cluster lost a worker holding this search's data in each of {attempt + 1} "
                        "attempt(s) (a lost worker: a crash, a restart, or silent past distributed.scheduler.worker-ttl): "
                        f"{type(e).__name__}: {_first_line(e)}"
                    ) from e
                warnings.warn(
                    f"a Dask worker was lost with data of this search; starting it again ({type(e).__name__}: {_first_line(e)})",
                    RuntimeWarning, stacklevel=2,
                )
        raise AssertionError("unreachable")
    finally:
        if own and client is not None:
            client.close()


def _first_line(e: BaseException) -> str:
    """An exception's message as one line (Dask's span several)."""
    text = str(e).strip()
    return text.splitlines()[0] if text else type(e).__name__


def _search(
    run: _Runner, Q: Any, box: Any, method: str, on_invalid: str, partitions: int | None, chunk: int, max_pairs: int | None
) -> Contacts:
    """One whole search (module docstring, steps 1-4): data scattered, bounds, partitions, result."""
    t0 = time.perf_counter()
    client = run.client
    blocks, offsets, N, n = _blocks(Q, client)
    L = read_box(box, n - 1)
    sphere_handles, parts = run.compute([dask.delayed(_block_spheres)(b, o) for b, o in zip(blocks, offsets, strict=True)], "bounds")
    spheres = _merged(parts, n - 1)
    if spheres.invalid and on_invalid == "raise":
        raise ValueError(next(iter(spheres.invalid.values())))
    if L is not None:
        check_box(spheres.centers, spheres.radii, L)
    if max_pairs is not None and (pairs := BroadPhase(spheres.centers, spheres.radii, box=L).pairs) > max_pairs:
        raise TooManyPairs(pairs, max_pairs)
    t1 = time.perf_counter()
    plan = _plan(spheres, L, partitions or _default_partitions(client))
    tasks = []
    for p in range(plan.count):
        pieces = [dask.delayed(_members)(b, s, o, plan, p) for b, s, o in zip(blocks, sphere_handles, offsets, strict=True)]
        tasks.append(dask.delayed(_partition_task)(pieces, L, method, chunk))
    _, results = run.compute(tasks, "contacts", final=True) if tasks else (None, [])
    t2 = time.perf_counter()
    cand, rel, by = _concatenate(results, n - 1, L is not None)
    out = contacts_of(cand, rel, by, N, L, spheres)
    out.seconds = {"bounds": t1 - t0, "partitions": t2 - t1, "total": time.perf_counter() - t0}
    return out


class _StderrProgressBar(TextProgressBar):
    """``distributed``'s text progress bar, drawn on stderr (stdout may carry the program's data)."""

    def __init__(self, keys: Any, label: str, **kwargs: Any) -> None:
        self.label = label
        super().__init__(keys, **kwargs)  # type: ignore[no-untyped-call]  # distributed leaves it unannotated

    def _draw_bar(self, remaining: int, all: int, **kwargs: Any) -> None:
        frac = (1 - remaining / all) if all else 1.0
        bar = "#" * int(self.width * frac)
        sys.stderr.write(f"\r{self.label} [{bar:<{self.width}}] {int(100 * frac):3d}% | {self.elapsed:.1f} s")
        sys.stderr.flush()

    def _draw_stop(self, **kwargs: Any) -> None:
        sys.stderr.write("\n")
        sys.stderr.flush()


class _Runner:
    """Computes lists of delayed tasks on a Client (as futures) or a local scheduler, with progress."""

    def __init__(self, client: Any, local: str | None, progress: Progress | bool | None) -> None:
        self.client = client
        self.local = local
        self.progress = progress

    def compute(self, tasks: Sequence[Any], label: str, *, final: bool = False) -> tuple[list[Any], list[Any]]:
        """(handles usable in later tasks, the results); the callable progress counts the final step."""
        if self.client is not None:
            futures = self.client.compute(list(tasks), retries=_TASK_RETRIES)
            if self.progress is True:
                _StderrProgressBar(futures, label, interval="200ms")
            elif callable(self.progress) and final:
                from distributed import as_completed

                for done, _ in enumerate(as_completed(futures), 1):
                    self.progress(done, len(futures))
            return futures, self.client.gather(futures)
        get = {"scheduler": self.local} if self.local else {}
        if self.progress is True:
            from dask.diagnostics import ProgressBar

            with ProgressBar(out=sys.stderr):
                results = list(dask.compute(*tasks, **get))
        else:
            results = list(dask.compute(*tasks, **get))
            if callable(self.progress) and final:
                self.progress(len(results), len(results))
        return results, results


def connect(address: str) -> Any:
    """A ``distributed.Client`` on the scheduler at ``address``, or RuntimeError("cannot reach ...").

    The address is tried for 10 s unless the Dask config key ``ellipsoids.connect-timeout`` says
    otherwise (e.g. the environment variable ``DASK_ELLIPSOIDS__CONNECT_TIMEOUT=2s``).
    """
    import dask
    from distributed import Client

    try:
        return Client(address, timeout=dask.config.get("ellipsoids.connect-timeout", default="10s"))
    except (OSError, TimeoutError, ValueError) as e:
        first = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise RuntimeError(f"cannot reach the Dask scheduler at {address}: {first}") from None


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
        return connect(scheduler), True
    return scheduler, False


def _default_partitions(client: Any) -> int:
    if client is None:
        return 4
    threads = sum(client.nthreads().values()) or 1
    return max(2, 2 * threads)


def _blocks(Q: Any, client: Any) -> tuple[list[Any], list[int], int, int]:
    """(blocks of whole matrices, their first rows, N, n): scattered once, or the dask array's own blocks."""
    if is_dask_array(Q):
        if Q.ndim != 3 or Q.shape[1] != Q.shape[2] or Q.shape[1] not in (3, 4):
            raise ValueError(f"Q must be an (N, 3, 3) stack of ellipses or (N, 4, 4) of ellipsoids, got shape {Q.shape}")
        q = Q.rechunk({1: -1, 2: -1})  # each task reads its block exactly (read_bodies)
        starts = np.cumsum((0, *q.chunks[0]))[:-1]
        return list(q.to_delayed().ravel()), [int(o) for o in starts], int(q.shape[0]), int(q.shape[1])
    arr = read_bodies(Q)
    N, n = int(arr.shape[0]), int(arr.shape[1])
    offsets = list(range(0, N, BODY_CHUNK))
    pieces: list[Any] = [arr[o : o + BODY_CHUNK] for o in offsets]
    if client is not None and pieces:
        # The matrices travel once; tasks name them by future. hash=False: a content-hashed key is shared
        # with an earlier call on the same data, whose release can race this scatter ("lost dependencies").
        pieces = client.scatter(pieces, hash=False)
    return pieces, offsets, N, n


def _block_spheres(block: np.ndarray, offset: int) -> tuple[np.ndarray, np.ndarray, dict[int, str], int]:
    """Spheres of one block; invalid bodies renamed by their global row."""
    s = bounding_spheres(read_bodies(block))
    invalid = {k + offset: msg.replace(f"body {k}", f"body {k + offset}", 1) for k, msg in s.invalid.items()}
    return s.centers, s.radii, invalid, s.exact


def _merged(parts: list[Any], d: int) -> BoundingSpheres:
    if not parts:
        return BoundingSpheres(np.zeros((0, d)), np.zeros(0), {}, 0)
    invalid: dict[int, str] = {}
    for p in parts:
        invalid.update(p[2])
    return BoundingSpheres(
        np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]), dict(sorted(invalid.items())), sum(p[3] for p in parts)
    )


@dataclass(frozen=True)
class _Plan:
    """The spatial partitions (module docstring, step 2): a few numbers, sent to every task."""

    count: int
    axis: int
    cuts: np.ndarray
    """count - 1 cut positions on the axis; slab p is [cuts[p-1], cuts[p]] (ends: the extreme centres)."""
    lo: float
    hi: float
    halo: float
    side: float | None
    """The box side along the axis (periodic), else None; 1 in a tilted box (fractional coordinates)."""
    tilted: np.ndarray | None = None
    """A tilted box: the slabs cut a fractional coordinate (along a box vector), else None."""

    def coordinate(self, centers: np.ndarray) -> np.ndarray:
        """The coordinate the slabs cut: x[axis], or in a tilted box the fractional f[axis]."""
        if self.tilted is None:
            return centers[:, self.axis]
        return fractional(centers, self.tilted)[0][:, self.axis]

    def slab(self, p: int) -> tuple[float, float]:
        return (self.lo if p == 0 else float(self.cuts[p - 1]), self.hi if p == self.count - 1 else float(self.cuts[p]))


def _plan(spheres: BoundingSpheres, box: np.ndarray | None, count: int) -> _Plan:
    """Slabs of the longest axis holding equal numbers of bodies, and the halo width."""
    valid = np.flatnonzero(spheres.valid)
    if valid.size == 0:
        return _Plan(0, 0, np.zeros(0), 0.0, 0.0, 0.0, None)
    c = spheres.centers[valid]
    d = c.shape[1]
    big = float(np.max(spheres.radii[valid]))
    if is_tilted(box):  # slabs of a fractional coordinate; the halo measured across its faces (the height)
        assert box is not None
        f, eps = fractional(c, box)
        heights = cell_heights(box, d)
        axis = int(np.argmax(heights))
        x = f[:, axis]
        reach = (2 * big + shift_error(box, d)) * _CELL_SLACK + 2 * _PAD * (float(np.max(np.abs(c))) + float(np.abs(box_vectors(box, d)).sum()) + big)
        halo = reach / heights[axis] * _CELL_SLACK + 4 * eps[axis]
        count = max(1, min(count, valid.size // 2))
        cuts = np.quantile(x, np.linspace(0, 1, count + 1)[1:-1]) if count > 1 else np.zeros(0)
        return _Plan(count, axis, cuts, float(x.min()), float(x.max()), float(halo), 1.0, box)
    axis = int(np.argmax(box)) if box is not None else int(np.argmax(np.ptp(c, axis=0)))
    x = c[:, axis]
    span = float(np.max(np.abs(c))) + (float(np.max(box)) if box is not None else 0.0)
    halo = 2 * big * _CELL_SLACK + 2 * _PAD * (span + big) + 4 * np.spacing(span)
    count = max(1, min(count, valid.size // 2))
    cuts = np.quantile(x, np.linspace(0, 1, count + 1)[1:-1]) if count > 1 else np.zeros(0)
    return _Plan(count, axis, cuts, float(x.min()), float(x.max()), float(halo), None if box is None else float(box[axis]))


def _members(block: np.ndarray, spheres: Any, offset: int, plan: _Plan, p: int) -> tuple[np.ndarray, ...]:
    """The bodies of one block that partition p needs: (global rows, owned, matrices, centres, radii)."""
    centers, radii = spheres[0], spheres[1]
    valid = np.isfinite(radii)
    x = plan.coordinate(np.where(valid[:, None], centers, 0.0))
    slab = np.searchsorted(plan.cuts, x, side="right")  # owner of each body
    a, b = plan.slab(p)
    gap = _gap(x, a, b)
    if plan.side is not None:  # across the faces too (the centres span at most one side)
        gap = np.minimum(gap, np.minimum(_gap(x + plan.side, a, b), _gap(x - plan.side, a, b)))
    take = np.flatnonzero(valid & ((gap <= plan.halo) | (slab == p)))
    return take + offset, slab[take] == p, read_bodies(block)[take], centers[take], radii[take]


def _gap(x: np.ndarray, a: float, b: float) -> np.ndarray:
    """Distance from each x to the interval [a, b]."""
    return np.maximum(a - x, 0.0) + np.maximum(x - b, 0.0)


def _partition_task(pieces: list[tuple[np.ndarray, ...]], box: np.ndarray | None, method: str, chunk: int) -> tuple[np.ndarray, ...]:
    """Broad and narrow phase on one partition; the owned candidates with global indices."""
    from ..fixed.compiled import warm_up

    warm_up()
    rows, owned, block, centers, radii = (np.concatenate([piece[k] for piece in pieces]) for k in range(5))
    local = candidate_pairs(centers, radii, box=box)
    mine = np.flatnonzero(owned[local.i])  # i < j locally and globally (rows ascend: blocks in order)
    cand = Candidates(local.i[mine], local.j[mine], None if local.image is None else local.image[mine])
    rel, by = classify_candidates(block, cand, box, method, chunk=chunk)
    image = np.zeros((len(cand), centers.shape[1]), np.int8) if cand.image is None else cand.image
    return rows[cand.i], rows[cand.j], image, rel, by


def _concatenate(results: Any, d: int, periodic: bool) -> tuple[Candidates, np.ndarray, np.ndarray]:
    if not results:
        z = np.zeros(0, np.int64)
        return Candidates(z, z, np.zeros((0, d), np.int8) if periodic else None), np.zeros(0, np.int8), np.zeros(0, np.int8)
    i, j, image, rel, by = (np.concatenate([r[k] for r in results]) for k in range(5))
    return Candidates(i, j, image if periodic else None), rel, by

