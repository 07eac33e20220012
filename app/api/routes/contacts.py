"""POST /api/contacts: certified contacts among many bodies, under the request's limits.

The search runs in a budgeted worker process (:func:`app.jobs.contacts_job`): at most
``max_contacts_bodies`` bodies; the broad phase counts the pairs it would examine before building
any (over ``max_contacts_candidates``: 422 saying how many and the limit); the time budget is
checked between its chunks and the narrow phase's batches (503 with Retry-After); the pairs found
are counted against ``max_contacts_pairs`` before the answer is built (422). A bad body is a 422
that names it ("body 7: ...").
"""

from __future__ import annotations

from fastapi import APIRouter, HTTPException, Request, Response

from ..budget import run_job
from ..contacts_schemas import ContactsIn, ContactsOut
from ..deps import SettingsDep, WorkersDep
from ..jobs import contacts_job
from ..json_body import JsonRoute
from ..schemas import ERROR_RESPONSES, ErrorOut

router = APIRouter(
    prefix="/api",
    tags=["contacts"],
    route_class=JsonRoute,
    responses={**ERROR_RESPONSES, 503: {"model": ErrorOut, "description": "Busy, over the time budget of a request, or stopping (Retry-After)"}},
)


@router.post("/contacts", response_model=ContactsOut)
async def contacts_route(body: ContactsIn, request: Request, settings: SettingsDep, workers: WorkersDep) -> Response:
    """Every pair of bodies that is not separate, with its certified relation.

    422 when there are more bodies than ``max_contacts_bodies``, when the broad phase would examine
    more pairs than ``max_contacts_candidates`` (bodies crowded together), or when the answer
    would list more pairs than ``max_contacts_pairs``; each message gives the number and the limit.
    """
    rows = body.bodies if body.bodies is not None else body.matrices
    if rows is not None and len(rows) > settings.max_contacts_bodies:
        raise HTTPException(422, f"{len(rows)} bodies is over the limit of {settings.max_contacts_bodies} per request")
    data = await run_job(
        request, workers, contacts_job, body, settings.request_budget_s, settings.max_contacts_candidates,
        settings.max_contacts_pairs, seconds=settings.request_budget_s, checks_budget=True,
        hint="send fewer bodies per request", memory_mb=settings.memory_limit_mb,
    )
    return Response(content=data, media_type="application/json")
