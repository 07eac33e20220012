"""The contact search on one machine: bounds, broad phase, narrow phase, result."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..fixed.classify import Certifier
from ..fixed.compiled import warm_up
from ..options import check_options
from ..relation import Relation
from ..shapes.numbers import binary64_array
from .bounds import BoundingSpheres, bounding_spheres
from .box import Box
from .broadphase import BroadPhase, Candidates, TooManyPairs
from .narrowphase import CHUNK_PAIRS, classify_candidates
from .periodic import check_box, read_box
from .result import Contacts

__all__ = ["search", "read_bodies", "contacts_of", "ContactsBuilder"]

Progress = Callable[[int, int], None]


def read_bodies(Q: Any) -> np.ndarray:
    """The bodies as a float64 array (N, n, n), n = 3 or 4 (values never rounded).

    Raises:
        ValueError: wrong shape, or entries that are not float64 values (complex, objects,
            integers beyond 2^53, long doubles that a float64 cannot hold).

    Examples:
        >>> read_bodies(np.zeros((2, 3, 3), dtype=np.float32)).dtype
        dtype('float64')
        >>> read_bodies(np.zeros((2, 5, 5)))
        Traceback (most recent call last):
        ...
        ValueError: Q must be an (N, 3, 3) stack of ellipses or (N, 4, 4) of ellipsoids, got shape (2, 5, 5)
    """
    arr = np.asarray(Q)
    if arr.ndim != 3 or arr.shape[1] != arr.shape[2] or arr.shape[1] not in (3, 4):
        raise ValueError(f"Q must be an (N, 3, 3) stack of ellipses or (N, 4, 4) of ellipsoids, got shape {arr.shape}")
    if arr.dtype == np.float64:
        return arr  # read in place (never written)
    out = binary64_array(arr)
    if out is None:
        raise ValueError(f"Q holds numbers that are not float64 values (dtype {arr.dtype}): contacts reads float64 matrices")
    return out


def search(
    Q: Any,
    *,
    box: Any = None,
    method: str = "adaptive",
    on_invalid: str = "raise",
    chunk: int = CHUNK_PAIRS,
    progress: Progress | None = None,
    max_pairs: int | None = None,
) -> Contacts:
    """Every non-separate pair among the bodies ``Q``, certified (see :func:`core.contacts`).

    The broad phase counts the pairs to examine first (``max_pairs``: :class:`TooManyPairs`
    before any is built), then hands over candidates chunk by chunk; each batch of ``chunk``
    candidates is classified and only its non-separate pairs are kept. So the memory is the
    answer plus a few chunks, however crowded the bodies are, and ``progress(done, total)``
    (done of the total pairs to examine) runs between chunks of both phases: raising from it
    stops the search there.
    """
    check_options(method, on_invalid)
    if max_pairs is not None and (isinstance(max_pairs, bool) or not isinstance(max_pairs, int) or max_pairs < 0):
        raise ValueError(f"max_pairs must be a non-negative integer or None, got {max_pairs!r}")
    t0 = time.perf_counter()
    warm_up(wait=False)  # the compiled filter loads while the spheres and the grid are built
    Q = read_bodies(Q)
    L = read_box(box, Q.shape[-1] - 1)
    spheres = bounding_spheres(Q)
    if spheres.invalid and on_invalid == "raise":
        raise ValueError(next(iter(spheres.invalid.values())))
    t1 = time.perf_counter()
    if L is not None:
        check_box(spheres.centers, spheres.radii, L)
    plan = BroadPhase(spheres.centers, spheres.radii, box=L)
    planning = time.perf_counter() - t1
    if max_pairs is not None and plan.pairs > max_pairs:
        raise TooManyPairs(plan.pairs, max_pairs)
    total = plan.pairs
    if progress is not None:
        progress(0, total)
    if total > 10_000:
        warm_up()  # a large batch waits for the compiled filter (loaded once per process)
    found = ContactsBuilder(plan.d, L is not None, Q.shape[0])
    waiting: list[Candidates] = []
    held = 0
    broad, narrow = planning, 0.0
    done = 0

    def classify_waiting(examined: int) -> None:
        nonlocal waiting, held, narrow, done
        batch = Candidates.concatenate(waiting, plan.d, L is not None)
        waiting, held = [], 0
        t = time.perf_counter()
        rel, by = classify_candidates(
            Q, batch, L, method, chunk=chunk,
            progress=None if progress is None else (lambda k, m: progress(done, total)),
        )
        found.add(batch, rel, by)
        narrow += time.perf_counter() - t
        done = examined

    t = time.perf_counter()
    chunks = plan.chunks()
    try:
        examined = 0
        for cand, examined in chunks:
            broad += time.perf_counter() - t
            if len(cand):
                waiting.append(cand)
                held += len(cand)
            if held >= chunk:
                classify_waiting(examined)
            if progress is not None:
                progress(done, total)
            t = time.perf_counter()
        if waiting:
            classify_waiting(examined)
    finally:
        chunks.close()  # an exception above (e.g. from progress) stops the chunks being built
    done = total
    if progress is not None and total:
        progress(total, total)
    out = found.result(Q.shape[0], L, spheres)
    out.seconds = {"bounds": t1 - t0, "broad": broad, "narrow": narrow, "total": time.perf_counter() - t0}
    return out


class ContactsBuilder:
    """Classified candidates in, :class:`Contacts` out: keeps the non-separate pairs, counts all.

    Each kept pair is packed into one 64-bit key, (i, j) in the high bits and the relation, the
    certifier and the image below, so the pairs held cost 8 bytes each and are sorted by (i, j)
    in place at the end: the peak memory is about 1.5 x the answer (N > ~6e7 bodies fall back to
    separate arrays and a lexsort).

    Args:
        d: dimension (2 or 3).
        periodic: pairs carry a lattice image.
        n_bodies: number of bodies (the radix of i and j).
    """

    def __init__(self, d: int, periodic: bool, n_bodies: int) -> None:
        self.d = d
        self.periodic = periodic
        self.n = max(int(n_bodies), 2)
        self.low = 5 + (2 * d if periodic else 0)  # certifier 2 bits, relation 3 bits, image 2 bits per axis
        self.packed = 2 * (self.n - 1).bit_length() + self.low <= 63
        self.keys: list[np.ndarray] = []
        self.parts: list[tuple[Candidates, np.ndarray, np.ndarray]] = []
        self.candidates = 0
        self.by = np.zeros(3, np.int64)
        self.rel = np.zeros(5, np.int64)

    def add(self, cand: Candidates, rel: np.ndarray, by: np.ndarray) -> None:
        """Count a batch of classified candidates and keep its non-separate pairs."""
        self.candidates += len(cand)
        self.by += np.bincount(by.astype(np.int64), minlength=3)[:3]
        self.rel += np.bincount(rel.astype(np.int64) + 2, minlength=5)[:5]
        keep = np.flatnonzero(rel != Relation.SEPARATE)
        image = None if cand.image is None else cand.image[keep]
        if not self.packed:
            self.parts.append((Candidates(cand.i[keep], cand.j[keep], image), rel[keep], by[keep]))
            return
        key = cand.i[keep].astype(np.int64) * self.n + cand.j[keep]
        key <<= self.low
        key |= by[keep].astype(np.int64) | (rel[keep].astype(np.int64) + 2) << 2
        if image is not None:
            for a in range(self.d):
                key |= (image[:, a].astype(np.int64) + 1) << (5 + 2 * a)
        self.keys.append(key)

    def _unpacked(self) -> tuple[Candidates, np.ndarray, np.ndarray]:
        """The kept pairs sorted by (i, j): from the keys (sorted in place) or by a lexsort."""
        if not self.packed:
            cand = Candidates.concatenate([p[0] for p in self.parts], self.d, self.periodic)
            rel = np.concatenate([p[1] for p in self.parts]) if self.parts else np.zeros(0, np.int8)
            by = np.concatenate([p[2] for p in self.parts]) if self.parts else np.zeros(0, np.int8)
            self.parts = []
            order = np.lexsort((cand.j, cand.i))
            image = None if cand.image is None else cand.image[order]
            return Candidates(cand.i[order], cand.j[order], image), rel[order], by[order]
        key = np.empty(sum(k.size for k in self.keys), np.int64)
        at = 0
        while self.keys:  # each part is freed as soon as it is copied
            part = self.keys.pop(0)
            key[at : at + part.size] = part
            at += part.size
            del part
        key.sort()
        by = (key & 3).astype(np.int8)
        rel = ((key >> 2) & 7).astype(np.int8) - 2
        image = None
        if self.periodic:
            image = np.empty((key.size, self.d), np.int8)
            for a in range(self.d):
                image[:, a] = ((key >> (5 + 2 * a)) & 3).astype(np.int8) - 1
        key >>= self.low
        j = key % self.n
        key //= self.n
        return Candidates(key, j, image), rel, by

    def result(self, n_bodies: int, box: np.ndarray | None, spheres: BoundingSpheres) -> Contacts:
        """The :class:`Contacts`: pairs sorted by (i, j), with the counts."""
        cand, rel, by = self._unpacked()
        counts = {
            "bodies": n_bodies,
            "invalid": len(spheres.invalid),
            "exact_bounds": spheres.exact,
            "candidates": self.candidates,
            "float": int(self.by[Certifier.FLOAT]),
            "exact": int(self.by[Certifier.EXACT]),
            "undecided": int(self.rel[Relation.UNDECIDED + 2]),
        }
        for r in (Relation.SEPARATE, Relation.TANGENT, Relation.OVERLAP):
            counts[str(r)] = int(self.rel[r + 2])
        return Contacts(
            i=cand.i.astype(np.int64, copy=False),
            j=cand.j.astype(np.int64, copy=False),
            relation=rel.astype(np.int8, copy=False),
            certified_by=by.astype(np.int8, copy=False),
            n_bodies=n_bodies,
            box=Box.from_any(box, self.d),
            image=cand.image,
            invalid=dict(sorted(spheres.invalid.items())),
            counts=counts,
        )


def contacts_of(
    cand: Candidates, rel: np.ndarray, by: np.ndarray, n_bodies: int, box: np.ndarray | None, spheres: BoundingSpheres
) -> Contacts:
    """The :class:`Contacts` of classified candidates (non-separate pairs, sorted by (i, j))."""
    found = ContactsBuilder(spheres.centers.shape[1], cand.image is not None, n_bodies)
    found.add(cand, rel, by)
    return found.result(n_bodies, box, spheres)


