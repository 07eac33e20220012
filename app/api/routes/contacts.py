"""POST /api/contacts: certified contacts among many bodies (at most ``max_contacts_bodies``).

The search (:func:`core.contacts`) runs off the event loop under the request budget; it is
checked after each batch of pairs, so an over-budget search answers 503. A bad body is a 422
that names it ("body 7: ...").
"""

from __future__ import annotations

import threading
from typing import cast

import numpy as np
from fastapi import APIRouter, HTTPException, Request

from core import Certifier, Relation, bodies_from_axes, contacts

from ..budget import Budget, BudgetExceeded, Cancelled, budget_error, run_off_loop
from ..contacts_schemas import ContactsIn, ContactsOut, PairOut, PairRelation
from ..convert import bad_input
from ..deps import SettingsDep
from ..json_body import JsonRoute
from ..schemas import ERROR_RESPONSES, CertifiedBy, ErrorOut

router = APIRouter(
    prefix="/api",
    tags=["contacts"],
    route_class=JsonRoute,
    responses={**ERROR_RESPONSES, 503: {"model": ErrorOut, "description": "Over the time budget of a request"}},
)


@router.post("/contacts", response_model=ContactsOut)
async def contacts_route(body: ContactsIn, request: Request, settings: SettingsDep) -> ContactsOut:
    """Every pair of bodies that is not separate, with its certified relation."""
    Q = _matrices(body, settings.max_contacts_bodies)

    def work(cancel: threading.Event) -> ContactsOut:
        budget = Budget(settings.request_budget_s, cancel)

        def progress(done: int, total: int) -> None:
            budget.check(f"after {done} of {total} candidate pairs")

        with bad_input():
            res = contacts(Q, box=body.box, method=body.method, on_invalid=body.on_invalid, progress=progress)
        names = {int(r): str(r) for r in Relation}  # core lists the non-separate pairs of valid bodies
        by_name: dict[int, CertifiedBy] = {int(Certifier.FLOAT): "float", int(Certifier.EXACT): "exact"}
        images = res.image.tolist() if res.image is not None else None
        pairs = [
            PairOut(i=a, j=b, relation=cast(PairRelation, names[r]), certified_by=by_name.get(c), image=None if images is None else images[k],
                    **({} if images is None else dict(zip(("image_x", "image_y", "image_z"), images[k], strict=False))))
            for k, (a, b, r, c) in enumerate(zip(res.i.tolist(), res.j.tolist(), res.relation.tolist(), res.certified_by.tolist(), strict=True))
        ]
        return ContactsOut(bodies=res.n_bodies, pairs=pairs, counts=res.counts, invalid=res.invalid, summary=res.summary())

    try:
        return await run_off_loop(request, work)
    except (BudgetExceeded, Cancelled) as e:
        raise budget_error(e, "send fewer bodies per request") from None


def _matrices(body: ContactsIn, limit: int) -> np.ndarray:
    """The bodies as float matrices (422 for a wrong count, mixed forms or bad rows)."""
    if (body.bodies is None) == (body.matrices is None):
        raise HTTPException(422, "send either 'bodies' (rows of parameters) or 'matrices', not both or neither")
    rows = body.bodies if body.bodies is not None else body.matrices
    assert rows is not None
    if len(rows) > limit:
        raise HTTPException(422, f"{len(rows)} bodies is over the limit of {limit} per request")
    if body.matrices is not None:
        sizes = {len(m) for m in body.matrices} | {len(r) for m in body.matrices for r in m}
        if len(sizes) > 1:
            raise HTTPException(422, "matrices: every matrix must be 3x3 (ellipses) or every one 4x4 (ellipsoids)")
        return np.array(body.matrices, dtype=np.float64).reshape(len(body.matrices), *(2 * (sizes.pop() if sizes else 4,)))
    widths = {len(r) for r in body.bodies or []}
    if not widths:
        return np.zeros((0, 4, 4))
    if widths not in ({10}, {5}):
        raise HTTPException(422, "bodies: every row must be [x, y, z, a, b, c, qw, qx, qy, qz] (3D) or every row [x, y, a, b, angle] (2D)")
    if body.box is not None and len(body.box) not in ((3, 6) if 10 in widths else (2, 3, 6)):
        raise HTTPException(422, f"box: {len(body.box)} numbers for {'3D' if 10 in widths else '2D'} bodies")
    t = np.array(body.bodies, dtype=np.float64)
    d = 3 if t.shape[1] == 10 else 2
    with bad_input("bodies: "):
        if body.on_invalid == "mark":
            return bodies_from_axes(t[:, :d], t[:, d : 2 * d], t[:, 2 * d :] if d == 3 else t[:, 4], on_invalid="mark")
        return bodies_from_axes(t[:, :d], t[:, d : 2 * d], t[:, 2 * d :] if d == 3 else t[:, 4])
