"""POST /api/contact-scale, /api/separating-plane, /api/contact-point, /api/witness.

The witnesses behind an answer (core.witness): how far from touching (certified contact scale),
which plane separates a separate pair, where a tangent pair touches, a point inside both shapes
of an overlapping pair. Exact values travel as strings. A plane asked of a pair that is not
separate, or a point of a separate pair, is a 422 that says why. Each runs in a budgeted worker
process (its work grows with the size of the numbers: ``exact`` on ``1e999``...), queued when
the workers are busy, killed at the request budget, on disconnect or when the server stops
(503 with Retry-After).
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException, Request

from ..budget import run_job
from ..deps import SettingsDep, WorkersDep
from ..jobs import contact_point_job, contact_scale_job, separating_plane_job, witness_job
from ..json_body import JsonRoute
from ..schemas import ERROR_RESPONSES, ErrorOut
from ..witness_schemas import (
    ContactPointOut,
    ContactScaleIn,
    ContactScaleOut,
    PlaneOut,
    WitnessIn,
    WitnessOut,
)

router = APIRouter(
    prefix="/api",
    tags=["witness"],
    route_class=JsonRoute,
    responses={**ERROR_RESPONSES, 503: {"model": ErrorOut, "description": "Busy, over the time budget of a request, or stopping (Retry-After)"}},
)


def _check_digits(digits: int, settings: Any) -> None:
    if digits > settings.max_digits:
        raise HTTPException(422, f"digits = {digits} is over the limit of {settings.max_digits}")


@router.post("/contact-scale", response_model=ContactScaleOut)
async def contact_scale_route(body: ContactScaleIn, request: Request, settings: SettingsDep, workers: WorkersDep) -> ContactScaleOut:
    """Certified bracket of the contact scale mu* (mu* > 1 separate, = 1 tangent, < 1 overlap).

    With ``exact``, mu* as an algebraic number too (polynomial, isolating interval, decimals).
    """
    _check_digits(body.digits, settings)
    return await run_job(request, workers, contact_scale_job, body, seconds=settings.request_budget_s,
                         memory_mb=settings.memory_limit_mb)


@router.post("/separating-plane", response_model=PlaneOut)
async def separating_plane_route(body: WitnessIn, request: Request, settings: SettingsDep, workers: WorkersDep) -> PlaneOut:
    """A separating plane n.x = d with exact rationals, verified exactly.

    a lies strictly on the side n.x < d and b strictly on n.x > d; 422 when the pair is tangent
    or overlapping.
    """
    return await run_job(request, workers, separating_plane_job, body, seconds=settings.request_budget_s,
                         memory_mb=settings.memory_limit_mb)


@router.post("/contact-point", response_model=ContactPointOut)
async def contact_point_route(body: WitnessIn, request: Request, settings: SettingsDep, workers: WorkersDep) -> ContactPointOut:
    """Where the pair meets.

    Tangent pair: the exact contact point and common normal. Overlapping pair: a rational point
    strictly inside both. 422 when the pair is separate.
    """
    _check_digits(body.digits, settings)
    return await run_job(request, workers, contact_point_job, body, seconds=settings.request_budget_s,
                         memory_mb=settings.memory_limit_mb)


@router.post("/witness", response_model=WitnessOut)
async def witness_route(body: WitnessIn, request: Request, settings: SettingsDep, workers: WorkersDep) -> WitnessOut:
    """All of it at once.

    The relation, the sentence that explains it, the contact scale, and the separating plane
    (separate) or the point (tangent, overlap).
    """
    _check_digits(body.digits, settings)
    return await run_job(request, workers, witness_job, body, seconds=settings.request_budget_s,
                         memory_mb=settings.memory_limit_mb)
