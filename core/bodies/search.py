"""The contact search on one machine: bounds, broad phase, narrow phase, result."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..fixed.classify import METHODS, ON_INVALID, Certifier
from ..fixed.compiled import warm_up
from ..relation import Relation
from .bounds import BoundingSpheres, bounding_spheres
from .broadphase import Candidates, candidate_pairs
from .narrowphase import CHUNK_PAIRS, classify_candidates
from .periodic import check_box, read_box
from .result import Contacts

__all__ = ["search", "read_bodies", "contacts_of"]

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
    kind = arr.dtype.kind
    if kind == "f":
        wide = arr.astype(np.float64)
        if arr.dtype.itemsize > 8 and not ((wide.astype(arr.dtype) == arr) | np.isnan(arr)).all():
            raise ValueError("Q holds long doubles that are not float64 values: contacts reads float64 matrices")
        return wide
    if kind in "iu":
        if arr.size and np.abs(arr.astype(object)).max() >= 2**53:
            raise ValueError("Q holds integers beyond 2^53: contacts reads float64 matrices")
        return arr.astype(np.float64)
    raise ValueError(f"Q must hold float numbers, got dtype {arr.dtype}: contacts reads float64 matrices")


def search(
    Q: Any,
    *,
    box: Any = None,
    method: str = "adaptive",
    on_invalid: str = "raise",
    chunk: int = CHUNK_PAIRS,
    progress: Progress | None = None,
) -> Contacts:
    """Every non-separate pair among the bodies ``Q``, certified (see :func:`core.contacts`)."""
    _check(method, METHODS, "method")
    _check(on_invalid, ON_INVALID, "on_invalid")
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
    cand = candidate_pairs(spheres.centers, spheres.radii, box=L)
    if len(cand) > 10_000:
        warm_up()  # a large batch waits for the compiled filter (loaded once per process)
    t2 = time.perf_counter()
    rel, by = classify_candidates(Q, cand, L, method, chunk=chunk, progress=progress)
    t3 = time.perf_counter()
    out = contacts_of(cand, rel, by, Q.shape[0], L, spheres)
    out.seconds = {"bounds": t1 - t0, "broad": t2 - t1, "narrow": t3 - t2, "total": time.perf_counter() - t0}
    return out


def contacts_of(
    cand: Candidates, rel: np.ndarray, by: np.ndarray, n_bodies: int, box: np.ndarray | None, spheres: BoundingSpheres
) -> Contacts:
    """The :class:`Contacts` of classified candidates (non-separate pairs, sorted by (i, j))."""
    keep = np.flatnonzero(rel != Relation.SEPARATE)
    order = keep[np.lexsort((cand.j[keep], cand.i[keep]))]
    counts = {
        "bodies": n_bodies,
        "invalid": len(spheres.invalid),
        "exact_bounds": spheres.exact,
        "candidates": len(cand),
        "float": int(np.count_nonzero(by == Certifier.FLOAT)),
        "exact": int(np.count_nonzero(by == Certifier.EXACT)),
        "undecided": int(np.count_nonzero(rel == Relation.UNDECIDED)),
    }
    for r in (Relation.SEPARATE, Relation.TANGENT, Relation.OVERLAP):
        counts[str(r)] = int(np.count_nonzero(rel == r))
    return Contacts(
        i=cand.i[order].astype(np.int64),
        j=cand.j[order].astype(np.int64),
        relation=rel[order].astype(np.int8),
        certified_by=by[order].astype(np.int8),
        n_bodies=n_bodies,
        box=box,
        image=None if cand.image is None else cand.image[order],
        invalid=dict(sorted(spheres.invalid.items())),
        counts=counts,
    )


def _check(value: str, options: tuple[str, ...], what: str) -> None:
    if value not in options:
        raise ValueError(f"unknown {what} {value!r}; valid options: {', '.join(options)}")
