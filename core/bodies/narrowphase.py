"""Narrow phase: the certified classifier on the candidate pairs, in chunks.

Pairs in open space (or with the image k = 0 in a box) go to :func:`core.classify_detailed` in
batches of ``chunk`` pairs: the matrices of both bodies are gathered chunk by chunk (1 M pairs
of ellipsoids are 256 MB), and each batch is one call of the compiled filter, which spreads it
over every core. Pairs with a lattice image go to :func:`core.bodies.periodic.classify_images`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..fixed.classify import classify_detailed
from ..fixed.lazy import PAIR_CHUNK
from ..relation import Relation
from .broadphase import Candidates
from .periodic import classify_images, lattice_shifts

__all__ = ["classify_candidates", "CHUNK_PAIRS"]

CHUNK_PAIRS = PAIR_CHUNK
"""Pairs per classify call (the same as a Dask chunk of pairs, :data:`core.fixed.lazy.PAIR_CHUNK`):
large enough that the threads of the C filter stay busy (a call costs ~0.05 ms of set-up against
~50 ms of work), small enough for the gathered matrices (2 x 128 MB for ellipsoids)."""


def classify_candidates(
    Q: np.ndarray,
    cand: Candidates,
    box: np.ndarray | None,
    method: str,
    *,
    chunk: int = CHUNK_PAIRS,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Certified relations of the candidate pairs, and which arithmetic certified each.

    Args:
        Q: (N, n, n) float64 matrices of valid bodies (validated by :mod:`core.bodies.bounds`).
        cand: the pairs (and, in a box, the image of j).
        box: the box (:func:`core.bodies.periodic.read_box`), or None.
        method: "adaptive", "float" or "exact" (as for :func:`core.classify`).
        chunk: pairs per batch.
        progress: optional callable ``progress(done, total)`` after each batch, and (with the
            done so far) before each pair that needs exact arithmetic: raise from it to stop.

    Returns:
        (int8 Relation codes, int8 Certifier codes), one per candidate pair.
    """
    M = len(cand)
    codes = np.full(M, Relation.UNDECIDED, dtype=np.int8)
    by = np.zeros(M, dtype=np.int8)
    shifted = np.zeros(M, dtype=bool) if cand.image is None else cand.image.any(axis=1)
    plain = np.flatnonzero(~shifted)
    done = 0
    for s in range(0, plain.size, chunk):
        rows = plain[s : s + chunk]
        check = None if progress is None else (lambda k, m, done=done: progress(done, M))
        res = classify_detailed(Q[cand.i[rows]], Q[cand.j[rows]], method=method, progress=check)  # type: ignore[arg-type]
        codes[rows], by[rows] = res.relation, res.certified_by
        done += rows.size
        if progress is not None:
            progress(done, M)
    images = np.flatnonzero(shifted)
    for s in range(0, images.size, chunk):
        rows = images[s : s + chunk]
        assert cand.image is not None and box is not None
        shift = lattice_shifts(box, cand.image[rows])  # the float vectors v(k) of the images
        codes[rows], by[rows] = classify_images(Q[cand.i[rows]], Q[cand.j[rows]], shift, method)
        done += rows.size
        if progress is not None:
            progress(done, M)
    return codes, by
