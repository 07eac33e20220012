"""``contacts(Q)``: certified contacts among N ellipses/ellipsoids, on one machine or a Dask cluster."""

from __future__ import annotations

from typing import Any

from ..fixed.lazy import is_dask_array
from ..options import Method, OnInvalid
from .bodies import unpack
from .narrowphase import CHUNK_PAIRS
from .result import Contacts
from .search import Progress, search

__all__ = ["contacts"]


def contacts(
    Q: Any,
    *,
    box: Any = None,
    method: Method = "adaptive",
    on_invalid: OnInvalid = "raise",
    scheduler: Any = None,
    partitions: int | None = None,
    chunk: int = CHUNK_PAIRS,
    progress: Progress | bool | None = None,
    max_pairs: int | None = None,
) -> Contacts:
    """Every pair of bodies that is not separate, with its certified relation.

    Broad phase: certified bounding spheres on a uniform grid per size class (never drops a pair
    that touches: :mod:`core.bodies.broadphase`); narrow phase: the certified :func:`core.classify`
    on the candidate pairs, in batches.

    Args:
        Q: (N, 4, 4) ellipsoids or (N, 3, 3) ellipses (float arrays; e.g. from
            :func:`core.bodies_from_axes`), a ``dask.array`` of them (then the search runs on
            the Dask cluster, see ``scheduler``), or :class:`core.Bodies` (their matrices, their
            box unless ``box`` is given, and their ids: the result carries them).
        box: a :class:`core.Box`, periodic box sides (Lx, Ly[, Lz]), a tilted box in HOOMD's convention
            (Lx, Ly, Lz, xy, xz, yz) (2D: (Lx, Ly, xy)), or None for open space. Minimum image
            convention: pairs across faces count (body i with the nearest image of body j, its
            exact translate by the float lattice vector v(k): :mod:`core.bodies.periodic`). The
            centres must lie in one box (a span of at most one box length along each box
            vector) and every body must be small enough (the two largest bounding radii sum to
            less than half the cell's smallest height: the smallest side of an orthogonal box):
            else a ValueError.
        method: "adaptive" (default), "float" (may report UNDECIDED pairs) or "exact".
        on_invalid: "raise" a ValueError naming the first body that is not an ellipse/ellipsoid
            (NaN, indefinite, empty...), or "mark": report such bodies in ``.invalid``.
        scheduler: run on Dask: a ``distributed.Client``, a scheduler address
            ("tcp://host:8786") or "local"/"threads"/"processes"; None runs here (unless ``Q``
            is a dask array). Spatial partitions with a halo: :mod:`core.bodies.distributed`.
        partitions: number of spatial partitions for Dask (default: 2 per worker).
        chunk: candidate pairs per classify batch (memory: 256 bytes per ellipsoid pair).
        progress: optional ``progress(done, total)``: ``done`` of the ``total`` pairs the broad
            phase examines (counted before any is built), called between chunks of the broad
            and the narrow phase (a progress bar); raise from it to stop the search there (a
            time budget). On Dask it is called as the partition tasks finish, and True draws
            Dask's own progress bars on stderr.
        max_pairs: most pairs the broad phase may examine (None: no limit). Over it,
            :class:`~core.bodies.broadphase.TooManyPairs` (a ValueError with ``.pairs`` and
            ``.limit``) is raised after counting, before any pair is built: a server's guard
            against crowded input (10,000 bodies at one point are 49,995,000 pairs).

    Memory: the answer plus a few chunks of pairs (candidates are built, classified and
    dropped or kept chunk by chunk), however crowded the bodies are.

    Returns:
        :class:`Contacts` with ``.i``, ``.j`` (int64, i < j, sorted by (i, j)), ``.relation``
        (int8 Relation codes), ``.certified_by``, ``.counts``, ``.invalid``.

    Raises:
        ValueError: bad shapes or options, an invalid body (``on_invalid="raise"``), a bad box;
            :class:`~core.bodies.broadphase.TooManyPairs` over ``max_pairs``.

    Guarantee:
        Every pair that touches or overlaps is reported, with its true relation for the input
        (the float matrices as given, and their exact lattice translates in a box).

    Examples:
        >>> from core import Relation, bodies_from_axes
        >>> Q = bodies_from_axes([[0, 0], [1, 0], [2.5, 0]], [[0.5, 0.5]] * 3, [0.0] * 3)
        >>> c = contacts(Q)
        >>> list(zip(c.i.tolist(), c.j.tolist(), [str(Relation(r)) for r in c.relation]))
        [(0, 1, 'tangent')]
        >>> c = contacts(Q, box=(3, 3))   # body 2 touches the image of body 0 at x = 3
        >>> list(zip(c.i.tolist(), c.j.tolist(), [str(Relation(r)) for r in c.relation]))
        [(0, 1, 'tangent'), (0, 2, 'overlap')]
        >>> contacts(Q, box=(1.2, 1.2))
        Traceback (most recent call last):
        ...
        ValueError: body 2: centre x = 2.5 is more than one box side (Lx = 1.2) from body 0's (x = 0): the centres must lie in one box (wrap them into it first, e.g. x mod Lx)
    """
    Q, box, ids = unpack(Q, box)
    if scheduler is not None or is_dask_array(Q):
        from .distributed import contacts_distributed

        out = contacts_distributed(
            Q, box=box, method=method, on_invalid=on_invalid, scheduler=scheduler, partitions=partitions, chunk=chunk,
            progress=progress, max_pairs=max_pairs,
        )
    else:
        out = search(
            Q, box=box, method=method, on_invalid=on_invalid, chunk=chunk,
            progress=None if progress is True else progress or None, max_pairs=max_pairs,
        )
    out.ids = ids
    return out

