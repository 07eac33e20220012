"""POST /api/analyse: exact events and intervals of two moving shapes, in a worker process."""

from __future__ import annotations

import threading
from typing import Any

from fastapi import APIRouter, HTTPException, Request

from core.moving.result import MotionAnalysis

from ...jobs import analyse_job
from ..budget import run_job, run_off_loop
from ..deps import SettingsDep, WorkersDep
from ..json_body import JsonRoute
from ..motion_input import motion_payload
from ..motion_schemas import AnalyseIn, AnalyseOut
from ..schemas import ERROR_RESPONSES, ErrorOut

router = APIRouter(
    prefix="/api",
    tags=["motion"],
    route_class=JsonRoute,
    responses={**ERROR_RESPONSES, 503: {"model": ErrorOut, "description": "Busy, over the time/memory budget, or stopping (Retry-After)"}},
)


@router.post("/analyse", response_model=AnalyseOut)
async def analyse(body: AnalyseIn, request: Request, settings: SettingsDep, workers: WorkersDep) -> AnalyseOut:
    """Tangency events (exact isolating intervals, decimals), intervals of constant relation, sign table.

    The motion text is parsed and analysed in a separate process under the server's time and
    memory budget (a busy server queues the request, or answers 503 before reading it when the
    queue is full); the event loop and the scene stay responsive meanwhile, and the worker is
    stopped if the client disconnects.
    """
    if body.digits > settings.max_digits:
        raise HTTPException(422, f"digits = {body.digits} is over the limit of {settings.max_digits}")
    a, b = motion_payload(body.a), motion_payload(body.b)
    result = await run_job(
        request, workers, analyse_job, a, b, body.interval, body.digits, settings.text_limits(), ("a", "b"),
        seconds=settings.time_budget_s, stopped="analysis stopped: ", hint="narrow the interval or simplify the motion",
        memory_mb=settings.memory_limit_mb,
    )

    def write(cancel: threading.Event) -> AnalyseOut:  # exact numbers to text: bounded, but not for the event loop
        return AnalyseOut(**_json(result, body.polynomials))

    return await run_off_loop(request, write)


def _json(result: MotionAnalysis, polynomials: bool) -> dict[str, Any]:
    """The analysis as the API's JSON (core's ``to_dict``, with the motions named "a" and "b")."""
    out = result.to_dict(polynomials=polynomials)
    out["a"] = out.pop("A")
    out["b"] = out.pop("B")
    return out
