"""``sweep_contacts``: certified first contact times among N moving ellipsoids (ellipses).

Continuous collision detection for one time step: N bodies move over t in [0, 1] (centres on
straight lines, orientations along a rational path: :mod:`core.moving.linear`); for every pair
that is not separate at some t, the first such t* with a certified bracket and its relation.

Pipeline (as :func:`core.contacts` for frozen bodies): read and check the parameters; the swept
broad phase (:mod:`core.bodies.swept`: balls around each body's swept volume on the grid of
:mod:`core.bodies.broadphase`, its pairs counted before any is built (``max_pairs``), then built
in chunks, each through a relative-motion test; conservative); the narrow phase
:func:`core.moving.first_contact.first_contacts` on batches of candidates as they come (the
certified float filter, exact arithmetic where it abstains), keeping only the pairs that meet;
the result :class:`core.bodies.sweep_result.SweepContacts`. ``progress`` runs between the chunks
and batches of both phases: the budget hook of a server.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..algebra.algebraic import RealAlgebraic
from ..fixed.classify import Certifier
from ..moving.first_contact import FirstContacts, first_contacts
from ..moving.linear import LinearMotions, read_linear_motions
from ..options import SWEEP_METHODS, OnInvalid, SweepMethod, check_options
from ..relation import Relation
from .bodies import Bodies
from .box import Box
from .broadphase import Candidates
from .periodic import cell_heights, check_box, lattice_shifts, read_box
from .sweep_result import SweepContacts
from .swept import SweptSpheres, approaching, swept_plan, swept_spheres

__all__ = ["sweep_contacts"]

Progress = Callable[[int, int], None]

_BATCH = 1 << 18
"""Candidate pairs gathered from the broad phase before a narrow-phase batch (memory: a few MB)."""


def sweep_contacts(
    centers0: Any,
    centers1: Any,
    semi_axes: Any = None,
    orientations0: Any = None,
    orientations1: Any = None,
    *,
    box: Any = None,
    on_invalid: OnInvalid = "raise",
    method: SweepMethod = "adaptive",
    progress: Progress | None = None,
    max_pairs: int | None = None,
) -> SweepContacts:
    """Every pair of moving bodies that touches or overlaps during t in [0, 1], with its first contact.

    Also ``sweep_contacts(start, end)`` with two :class:`core.Bodies` (two frames): their centres,
    semi-axes (equal in both: the bodies are rigid), orientations, box (``start``'s unless ``box``
    is given) and ids (``end`` is reordered to ``start``'s ids when both have ids; the result
    carries them). In a box the frames may be wrapped: each body moves by its minimum-image
    displacement (``end`` taken at the image nearest ``start``, :meth:`core.Box.unwrap`).

    Args:
        centers0: (N, 3) centres at t = 0 (2D: (N, 2)); floats, read exactly. Or the :class:`core.Bodies` at t = 0.
        centers1: (N, d) centres at t = 1: body k's centre is c0 + t (c1 - c0). In a periodic
            box give the unwrapped end (c0 plus the displacement), not a wrapped one
            (:meth:`core.Box.unwrap` makes it from two wrapped frames).
        semi_axes: (N, d) semi-axes, fixed during the step.
        orientations0: 3D: (N, 4) quaternions wxyz (any non-zero length); 2D: (N,) angles in
            radians or (N, 4) quaternions (w, 0, 0, z); None: axis-aligned.
        orientations1: the same at t = 1; the orientation follows q(t) = (1 - t) q0 + t q1,
            R(q(t) / |q(t)|), a rational motion (2D: the half-angle number (cos(theta / 2),
            sin(theta / 2)) interpolated alike: the body turns from theta0 to theta1).
            None: constant orientation. See :mod:`core.moving.linear`.
        box: periodic box sides (Lx, Ly[, Lz]), a tilted box in HOOMD's convention
            (Lx, Ly, Lz, xy, xz, yz; 2D: Lx, Ly, xy), or None (:func:`core.bodies.periodic.read_box`).
            Minimum image over the whole step: the image k of j is chosen once, from the
            midpoints of the paths, and j's whole path is moved by its lattice vector v(k)
            (:meth:`core.Box.shifts`, as in :func:`core.contacts`). The bodies may stand
            anywhere (a wrapped frame, an unwrapped trajectory): each path is placed by the
            image of its midpoint, and k counts whole boxes (any integers up to 127). Limit
            (else a ValueError names the body): the two largest swept radii (largest semi-axis
            plus half the displacement) sum to less than half the cell's smallest height (the
            smallest side of an orthogonal box), so that only that image can meet body i; a
            body that moves further than that in one step is named (take shorter steps).
        on_invalid: "raise" a ValueError naming the first bad row (not a number, a semi-axis
            <= 0, a zero quaternion, an orientation path through zero), or "mark": report such
            rows in ``.invalid`` and search the rest.
        method: "adaptive" (the certified float filter, exact arithmetic where it abstains) or
            "exact" (every candidate pair exactly: slow; for checking).
        progress: optional ``progress(done, total)``: ``done`` of the ``total`` pairs the broad
            phase examines (counted before any is built), called between its chunks and during
            the narrow phase (between batches of the float filter and between exact pairs); raise
            from it to stop the sweep there (a time budget), as for :func:`core.contacts`.
        max_pairs: most pairs the broad phase may examine (None: no limit). Over it,
            :class:`~core.bodies.broadphase.TooManyPairs` (a ValueError with ``.pairs`` and
            ``.limit``) is raised after counting, before any pair is built: a server's guard
            against crowded input (10,000 bodies at one point are 49,995,000 pairs).

    Returns:
        :class:`core.bodies.sweep_result.SweepContacts`: ``.i``, ``.j`` (int64, i < j, sorted),
        ``.t_lo``, ``.t_hi`` (float64, t_lo <= t* <= t_hi, t_hi - t_lo <= 1e-9), ``.relation``
        (int8 at t*: TANGENT, or OVERLAP when they overlap at t = 0), ``.time(k)`` (t* exactly),
        ``.certified_by``, ``.counts``, ``.invalid``. Pairs that never meet are absent.

    Memory: the answer plus a few chunks of pairs (the broad phase hands its candidates over
    chunk by chunk; each batch goes through the narrow phase and only its contacts are kept).

    Raises:
        ValueError: arrays of the wrong shape, numbers that are not float64 values, a bad row
            (``on_invalid="raise"``), a bad box or bodies too large for it;
            :class:`~core.bodies.broadphase.TooManyPairs` over ``max_pairs``.

    Guarantee:
        Every pair that is not separate at some t in [0, 1] is reported, each bracket holds its
        exact first contact time, for the exact bodies these parameters describe.

    Examples:
        >>> from core import Relation
        >>> res = sweep_contacts([[0, 0], [3, 0], [0, 5]], [[0, 0], [1, 0], [0, 5]], [[1, 1]] * 3)
        >>> res.i.tolist(), res.j.tolist(), [str(Relation(r)) for r in res.relation]   # circle 1 hits circle 0
        ([0], [1], ['tangent'])
        >>> bool(res.t_lo[0] <= 0.5 <= res.t_hi[0] <= res.t_lo[0] + 1e-9), res.time(0).decimal(5)
        (True, '0.5')
    """
    check_options(method, on_invalid, SWEEP_METHODS)
    t0 = time.perf_counter()
    ids = None
    if isinstance(centers0, Bodies) or isinstance(centers1, Bodies):
        centers0, centers1, semi_axes, orientations0, orientations1, box, ids = _frames(
            centers0, centers1, semi_axes, orientations0, orientations1, box
        )
    bodies, bad = read_linear_motions(centers0, centers1, semi_axes, orientations0, orientations1)
    if bad and on_invalid == "raise":
        raise ValueError(next(iter(bad.values())))
    N, d = bodies.centers0.shape
    L = read_box(box, d)
    valid = np.ones(N, dtype=bool)
    valid[list(bad)] = False
    spheres = swept_spheres(bodies, valid)
    for k in np.flatnonzero(valid & ~np.isfinite(spheres.radii)).tolist():
        msg = f"row {k}: its swept volume is beyond the float range"
        if on_invalid == "raise":
            raise ValueError(msg)
        bad[k] = msg
    t1 = time.perf_counter()
    wraps = None
    if L is not None:
        spheres, wraps = _wrapped(spheres, Box.from_any(L, d))
        _check_steps(bodies, spheres, L, d)
        check_box(spheres.centers, spheres.radii, L)
    plan = swept_plan(spheres, L, max_pairs=max_pairs)
    found = _Found(bodies, L, method)
    total = plan.pairs
    if progress is not None:
        progress(0, total)
    waiting: list[Candidates] = []
    held = broad = 0
    chunks = plan.chunks()
    try:
        for local, examined in chunks:
            broad += len(local)
            cand = local if wraps is None else _whole_images(local, wraps)
            near = approaching(bodies, spheres, cand, L)
            if len(near):
                waiting.append(near)
                held += len(near)
            if held >= _BATCH:
                found.add(Candidates.concatenate(waiting, d, L is not None), progress, total)
                waiting, held = [], 0
            if not waiting:  # every pair examined so far is through both phases
                found.done = examined
            if progress is not None:
                progress(found.done, total)
        if waiting:
            found.add(Candidates.concatenate(waiting, d, L is not None), progress, total)
    finally:
        chunks.close()  # an exception above (e.g. from progress) stops the chunks being built
    if progress is not None and total:
        progress(total, total)
    t3 = time.perf_counter()
    cand, fc = found.result(d)
    order = np.lexsort((cand.j, cand.i))
    counts = {
        "bodies": N,
        "invalid": len(bad),
        "broad": broad,
        "candidates": found.candidates,
        "float": found.by_float,
        "exact": found.by_exact,
        "contacts": int(order.size),
        "tangent": int(np.count_nonzero(fc.relation == Relation.TANGENT)),
        "overlap": int(np.count_nonzero(fc.relation == Relation.OVERLAP)),
        "at_start": int(np.count_nonzero(fc.t_hi == 0.0)),
    }
    where = np.empty(order.size, dtype=np.int64)  # kept pair -> its row in the result
    where[order] = np.arange(order.size)
    out = SweepContacts(
        i=cand.i[order].astype(np.int64),
        j=cand.j[order].astype(np.int64),
        t_lo=fc.t_lo[order],
        t_hi=fc.t_hi[order],
        relation=fc.relation[order].astype(np.int8),
        certified_by=fc.certified_by[order].astype(np.int8),
        n_bodies=N,
        bodies=bodies,
        box=Box.from_any(L, d),
        image=None if cand.image is None else cand.image[order],
        invalid=dict(sorted(bad.items())),
        counts=counts,
        _times={int(where[k]): t for k, t in fc.times.items()},
        ids=ids,
    )
    out.seconds = {"read": t1 - t0, "broad": t3 - t1 - found.narrow_s, "narrow": found.narrow_s, "total": time.perf_counter() - t0}
    return out


class _Found:
    """Batches of candidates through the narrow phase; keeps the pairs that meet, counts them all."""

    def __init__(self, bodies: LinearMotions, box: np.ndarray | None, method: SweepMethod) -> None:
        self.bodies = bodies
        self.box = box
        self.method = method
        self.parts: list[tuple[Candidates, FirstContacts]] = []
        self.candidates = self.by_float = self.by_exact = 0
        self.done = 0
        """Broad-phase pairs examined whose candidates are through the narrow phase (the progress
        reported while a batch is in the narrow phase)."""
        self.narrow_s = 0.0

    def add(self, cand: Candidates, progress: Progress | None, total: int) -> None:
        """First contacts of a batch; its pairs that meet are kept (with their exact times)."""
        t = time.perf_counter()
        shift = None if cand.image is None or self.box is None else lattice_shifts(self.box, cand.image)
        fc = first_contacts(
            self.bodies, cand.i, cand.j, shift, method=self.method,
            progress=None if progress is None else (lambda k, m: progress(self.done, total)),
        )
        self.candidates += len(cand)
        self.by_float += int(np.count_nonzero(fc.certified_by == Certifier.FLOAT))
        self.by_exact += int(np.count_nonzero(fc.certified_by == Certifier.EXACT))
        keep = np.flatnonzero(fc.relation != Relation.SEPARATE)
        at = np.full(len(cand), -1, dtype=np.int64)
        at[keep] = np.arange(keep.size)
        self.parts.append((
            Candidates(cand.i[keep], cand.j[keep], None if cand.image is None else cand.image[keep]),
            FirstContacts(fc.relation[keep], fc.t_lo[keep], fc.t_hi[keep], fc.certified_by[keep],
                          {int(at[k]): e for k, e in fc.times.items() if at[k] >= 0}),
        ))
        self.narrow_s += time.perf_counter() - t

    def result(self, d: int) -> tuple[Candidates, FirstContacts]:
        """Every kept pair (in batch order) and its first contact; times by position."""
        cand = Candidates.concatenate([c for c, _ in self.parts], d, self.box is not None)
        times: dict[int, RealAlgebraic] = {}
        offset = 0
        for c, f in self.parts:
            times.update({offset + k: e for k, e in f.times.items()})
            offset += len(c)

        def joined(name: str, dtype: type) -> np.ndarray:
            parts = [getattr(f, name) for _, f in self.parts]
            return np.concatenate(parts).astype(dtype, copy=False) if parts else np.zeros(0, dtype)

        fc = FirstContacts(joined("relation", np.int8), joined("t_lo", np.float64), joined("t_hi", np.float64),
                           joined("certified_by", np.int8), times)
        return cand, fc


def _wrapped(spheres: SweptSpheres, box: Box | None) -> tuple[SweptSpheres, np.ndarray]:
    """The swept balls moved by whole lattice vectors into the cell around the origin, and the images.

    Ball i is moved by -v(m_i), m_i the image of its midpoint (:meth:`core.Box.images`), for the
    broad phase only: a pair found between the moved balls with the local image k is the pair
    (i, j) with j moved by v(k + m_i - m_j) (:func:`_whole_images`). The moved centre is rounded
    once: each radius grows by 2^-50 of the lengths involved (far more than that rounding).
    """
    assert box is not None
    ok = np.isfinite(spheres.radii)
    m = np.zeros(spheres.centers.shape, dtype=np.int64)
    if ok.any():
        with np.errstate(invalid="ignore", over="ignore"):
            f = box.fractional(np.where(ok[:, None], spheres.centers, 0.0))
        far = ok & ~(np.abs(f) < 2.0**40).all(axis=1)
        if far.any():
            k = int(np.flatnonzero(far)[0])
            raise ValueError(f"row {k}: its path lies more than 2^40 boxes from the origin: wrap the positions into the box")
        m[ok] = np.floor(f[ok] + 0.5).astype(np.int64)
    moved = m.any(axis=1)
    if not moved.any():
        return spheres, m
    centers = spheres.centers.copy()
    radii = spheres.radii.copy()
    v = box.shifts(m[moved])
    centers[moved] = spheres.centers[moved] - v
    lengths = np.abs(centers[moved]).sum(axis=1) + np.abs(v).sum(axis=1) + np.abs(spheres.centers[moved]).sum(axis=1)
    radii[moved] = radii[moved] + 2.0**-50 * lengths
    return SweptSpheres(centers, radii, spheres.reach), m


def _whole_images(cand: Candidates, wraps: np.ndarray) -> Candidates:
    """Candidates of the moved balls (:func:`_wrapped`) as pairs of the bodies: k + m_i - m_j.

    (Ball j - v(m_j) moved by v(k) meets ball i - v(m_i): body j moved by v(k + m_i - m_j) meets body i.)
    """
    if cand.image is None or not len(cand):
        return cand
    k = cand.image.astype(np.int64) + wraps[cand.i] - wraps[cand.j]
    if np.abs(k).max(initial=0) > 127:
        row = int(np.flatnonzero((np.abs(k) > 127).any(axis=1))[0])
        raise ValueError(
            f"rows {int(cand.i[row])} and {int(cand.j[row])} meet across more than 127 boxes of an unwrapped "
            "trajectory: wrap the positions into the box"
        )
    return Candidates(cand.i, cand.j, k.astype(np.int8))


def _check_steps(bodies: LinearMotions, spheres: SweptSpheres, L: np.ndarray, d: int) -> None:
    """Name a body that moves too far in one step for the minimum image (before the size rule's message)."""
    h = float(np.min(cell_heights(L, d)))
    with np.errstate(all="ignore"):
        step = np.sqrt(((bodies.centers1 - bodies.centers0) ** 2).sum(axis=1))
    ok = np.isfinite(spheres.radii)
    far = np.flatnonzero(ok & ~(step < h / 2))
    if far.size:
        k = int(far[np.argmax(step[far])])
        raise ValueError(
            f"row {k} moves {step[k]:.6g} in one step, more than half the smallest height of the periodic cell "
            f"({h:.6g} / 2): which image it meets is not defined; take shorter steps (more frames), or give the "
            "unwrapped end if the frames are not wrapped"
        )


def _frames(start: Any, end: Any, semi_axes: Any, o0: Any, o1: Any, box: Any) -> tuple[Any, ...]:
    """The arrays of ``sweep_contacts(start, end)`` with two :class:`core.Bodies`, and their ids."""
    if not (isinstance(start, Bodies) and isinstance(end, Bodies)):
        raise ValueError("sweep_contacts: give two Bodies (start, end), or the arrays centers0, centers1, semi_axes, ...")
    if semi_axes is not None or o0 is not None or o1 is not None:
        raise ValueError("sweep_contacts(start, end): the Bodies carry the semi-axes and orientations; give no arrays")
    if not (start.has_parameters and end.has_parameters):
        raise ValueError("sweep_contacts: the Bodies need centres and semi-axes (not matrices alone)")
    end = end.ordered_like(start)
    if start.dimensions != end.dimensions:
        raise ValueError(f"sweep_contacts: {start.dimensions}D bodies at the start and {end.dimensions}D at the end")
    if box is None:
        box = start.box if start.box is not None else end.box
    centers1 = end.centers
    if box is not None:  # frames of a trajectory are wrapped: each body moves by its minimum image
        b = Box.from_any(box, start.dimensions)
        assert b is not None
        ok = np.isfinite(start.centers).all(axis=1) & np.isfinite(end.centers).all(axis=1)
        centers1 = np.array(end.centers, dtype=np.float64, copy=True)
        if ok.any():
            centers1[ok] = b.unwrap(start.centers[ok], end.centers[ok])[0]
    differ = np.flatnonzero((start.semi_axes != end.semi_axes).any(axis=1))
    if differ.size:
        k = int(differ[0])
        raise ValueError(
            f"sweep_contacts: {start.name(k)} has semi-axes {start.semi_axes[k].tolist()} at the start and "
            f"{end.semi_axes[k].tolist()} at the end: the bodies must keep their shape during the step"
        )
    return start.centers, centers1, start.semi_axes, start.orientations, end.orientations, box, start.ids
