"""``sweep_contacts``: certified first contact times among N moving ellipsoids (ellipses).

Continuous collision detection for one time step: N bodies move over t in [0, 1] (centres on
straight lines, orientations along a rational path: :mod:`core.moving.linear`); for every pair
that is not separate at some t, the first such t* with a certified bracket and its relation.

Pipeline (as :func:`core.contacts` for frozen bodies): read and check the parameters; the swept
broad phase (:mod:`core.bodies.swept`: balls around each body's swept volume on the grid of
:mod:`core.bodies.broadphase`, then a relative-motion test; conservative); the narrow phase
:func:`core.moving.first_contact.first_contacts` (the certified float filter, exact arithmetic
where it abstains); the result :class:`core.bodies.sweep_result.SweepContacts`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, Literal

import numpy as np

from ..fixed.classify import Certifier
from ..moving.first_contact import first_contacts
from ..moving.linear import read_linear_motions
from ..relation import Relation
from .periodic import check_box, is_tilted, read_box
from .sweep_result import SweepContacts
from .swept import swept_pairs, swept_spheres

__all__ = ["sweep_contacts"]

Progress = Callable[[int, int], None]


def sweep_contacts(
    centers0: Any,
    centers1: Any,
    semi_axes: Any,
    orientations0: Any = None,
    orientations1: Any = None,
    *,
    box: Any = None,
    on_invalid: Literal["raise", "mark"] = "raise",
    method: Literal["adaptive", "exact"] = "adaptive",
    progress: Progress | None = None,
) -> SweepContacts:
    """Every pair of moving bodies that touches or overlaps during t in [0, 1], with its first contact.

    Args:
        centers0: (N, 3) centres at t = 0 (2D: (N, 2)); floats, read exactly.
        centers1: (N, d) centres at t = 1: body k's centre is c0 + t (c1 - c0). In a periodic
            box give the unwrapped end (c0 plus the displacement), not a wrapped one.
        semi_axes: (N, d) semi-axes, fixed during the step.
        orientations0: 3D: (N, 4) quaternions wxyz (any non-zero length); 2D: (N,) angles in
            radians or (N, 4) quaternions (w, 0, 0, z); None: axis-aligned.
        orientations1: the same at t = 1; the orientation follows q(t) = (1 - t) q0 + t q1,
            R(q(t) / |q(t)|), a rational motion (2D: the half-angle number (cos(theta / 2),
            sin(theta / 2)) interpolated alike: the body turns from theta0 to theta1).
            None: constant orientation. See :mod:`core.moving.linear`.
        box: periodic box sides (Lx, Ly[, Lz]) or None. Minimum image over the whole step:
            the image of j is chosen once, from the midpoints of the paths, and kept during the
            step. Limits (else a ValueError names the body): the midpoints span at most one box
            side per axis, and the two largest swept radii (largest semi-axis plus half the
            displacement) sum to less than half the smallest side, so that only that image can
            meet body i. Orthorhombic boxes only.
        on_invalid: "raise" a ValueError naming the first bad row (not a number, a semi-axis
            <= 0, a zero quaternion, an orientation path through zero), or "mark": report such
            rows in ``.invalid`` and search the rest.
        method: "adaptive" (the certified float filter, exact arithmetic where it abstains) or
            "exact" (every candidate pair exactly: slow; for checking).
        progress: optional ``progress(done, total)`` over the candidate pairs.

    Returns:
        :class:`core.bodies.sweep_result.SweepContacts`: ``.i``, ``.j`` (int64, i < j, sorted),
        ``.t_lo``, ``.t_hi`` (float64, t_lo <= t* <= t_hi, t_hi - t_lo <= 1e-9), ``.relation``
        (int8 at t*: TANGENT, or OVERLAP when they overlap at t = 0), ``.time(k)`` (t* exactly),
        ``.certified_by``, ``.counts``, ``.invalid``. Pairs that never meet are absent.

    Raises:
        ValueError: arrays of the wrong shape, numbers that are not float64 values, a bad row
            (``on_invalid="raise"``), a bad box or bodies too large for it.

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
    if on_invalid not in ("raise", "mark"):
        raise ValueError(f"unknown on_invalid {on_invalid!r}; valid options: raise, mark")
    t0 = time.perf_counter()
    bodies, bad = read_linear_motions(centers0, centers1, semi_axes, orientations0, orientations1)
    if bad and on_invalid == "raise":
        raise ValueError(next(iter(bad.values())))
    N, d = bodies.centers0.shape
    L = read_box(box, d)
    if is_tilted(L):  # read_box takes tilted boxes for contacts(); the swept search is orthorhombic only
        raise ValueError("box: tilted (triclinic) boxes are not supported for moving bodies yet: give the sides (Lx, Ly[, Lz]) of an orthorhombic box")
    valid = np.ones(N, dtype=bool)
    valid[list(bad)] = False
    spheres = swept_spheres(bodies, valid)
    for k in np.flatnonzero(valid & ~np.isfinite(spheres.radii)).tolist():
        msg = f"row {k}: its swept volume is beyond the float range"
        if on_invalid == "raise":
            raise ValueError(msg)
        bad[k] = msg
    t1 = time.perf_counter()
    if L is not None:
        check_box(spheres.centers, spheres.radii, L)
    cand, broad = swept_pairs(bodies, spheres, L)
    t2 = time.perf_counter()
    shift = None if cand.image is None or L is None else cand.image.astype(np.float64) * L
    fc = first_contacts(bodies, cand.i, cand.j, shift, method=method, progress=progress)
    t3 = time.perf_counter()
    keep = np.flatnonzero(fc.relation != Relation.SEPARATE)
    order = keep[np.lexsort((cand.j[keep], cand.i[keep]))]
    where = np.full(len(cand), -1, dtype=np.int64)  # candidate -> its row in the result
    where[order] = np.arange(order.size)
    counts = {
        "bodies": N,
        "invalid": len(bad),
        "broad": broad,
        "candidates": len(cand),
        "float": int(np.count_nonzero(fc.certified_by == Certifier.FLOAT)),
        "exact": int(np.count_nonzero(fc.certified_by == Certifier.EXACT)),
        "contacts": int(order.size),
        "tangent": int(np.count_nonzero(fc.relation == Relation.TANGENT)),
        "overlap": int(np.count_nonzero(fc.relation == Relation.OVERLAP)),
        "at_start": int(np.count_nonzero(fc.t_hi[keep] == 0.0)),
    }
    out = SweepContacts(
        i=cand.i[order].astype(np.int64),
        j=cand.j[order].astype(np.int64),
        t_lo=fc.t_lo[order],
        t_hi=fc.t_hi[order],
        relation=fc.relation[order].astype(np.int8),
        certified_by=fc.certified_by[order].astype(np.int8),
        n_bodies=N,
        bodies=bodies,
        box=L,
        image=None if cand.image is None else cand.image[order],
        invalid=dict(sorted(bad.items())),
        counts=counts,
        _times={int(where[k]): t for k, t in fc.times.items() if where[k] >= 0},
    )
    out.seconds = {"read": t1 - t0, "broad": t2 - t1, "narrow": t3 - t2, "total": time.perf_counter() - t0}
    return out
