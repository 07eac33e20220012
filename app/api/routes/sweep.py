"""POST /api/sweep: certified first contact times among moving bodies, under the request's limits.

As ``/api/contacts`` (:mod:`app.api.routes.contacts`): the sweep runs in a budgeted worker
process (:func:`app.jobs.sweep_job`): at most ``max_contacts_bodies`` bodies; the swept broad
phase counts the pairs it would examine before building any (over ``max_contacts_candidates``:
422 saying how many and the limit); the time budget is checked between its chunks and the
narrow phase's batches (503 with Retry-After); the pairs found are counted against
``max_contacts_pairs`` before the answer is built (422), and with ``exact_times`` against
``max_sweep_exact_times`` before any exact time is computed (422). A disconnected client's
worker is killed. A bad row is a 422 that names it ("end row 3: ...").
"""

from __future__ import annotations

from fastapi import APIRouter, HTTPException, Request, Response

from ..budget import run_job
from ..deps import SettingsDep, WorkersDep
from ..jobs import sweep_job
from ..json_body import JsonRoute
from ..schemas import ERROR_RESPONSES, ErrorOut
from ..sweep_schemas import SweepIn, SweepOut

router = APIRouter(
    prefix="/api",
    tags=["sweep"],
    route_class=JsonRoute,
    responses={**ERROR_RESPONSES, 503: {"model": ErrorOut, "description": "Busy, over the time budget of a request, or stopping (Retry-After)"}},
)


@router.post("/sweep", response_model=SweepOut)
async def sweep_route(body: SweepIn, request: Request, settings: SettingsDep, workers: WorkersDep) -> Response:
    """Every pair of moving bodies that touches or overlaps during t in [0, 1], with its first contact t*.

    Body k moves from ``start[k]`` (t = 0) to ``end[k]`` (t = 1): its centre on the straight line,
    its orientation along q(t) = (1 - t) q0 + t q1 (:func:`core.sweep_contacts`). Each pair gets
    a certified bracket t_lo <= t* <= t_hi (width <= 1e-9) and the relation at t*; with
    ``exact_times``, t* exactly (``time``).

    422 when there are more bodies than ``max_contacts_bodies``, when the swept broad phase would
    examine more pairs than ``max_contacts_candidates`` (bodies crowded together), when the
    answer would list more pairs than ``max_contacts_pairs``, or ``exact_times`` more than
    ``max_sweep_exact_times``; each message gives the number and the limit.
    """
    n = max(len(body.start), len(body.end))
    if n > settings.max_contacts_bodies:
        raise HTTPException(422, f"{n} bodies is over the limit of {settings.max_contacts_bodies} per request")
    if body.digits > settings.max_digits:
        raise HTTPException(422, f"digits = {body.digits} is over the limit of {settings.max_digits}")
    data = await run_job(
        request, workers, sweep_job, body, settings.request_budget_s, settings.max_contacts_candidates,
        settings.max_contacts_pairs, settings.max_sweep_exact_times, seconds=settings.request_budget_s,
        checks_budget=True, hint="send fewer bodies per request", memory_mb=settings.memory_limit_mb,
    )
    return Response(content=data, media_type="application/json")
