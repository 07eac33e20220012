"""POST /api/analyse: exact events and intervals of two moving shapes, in a worker process."""

from __future__ import annotations

import threading
from typing import Any

from fastapi import APIRouter, HTTPException, Request

from ...workers import WorkerBusy, WorkerCancelled, WorkerDied, WorkerFailed, WorkerTimeout
from ..budget import run_off_loop
from ..convert import bad_input
from ..deps import SettingsDep, WorkersDep
from ..jobs import analyse_job
from ..json_body import JsonRoute
from ..motion_input import motion_payload
from ..motion_schemas import AnalyseIn, AnalyseOut
from ..schemas import ERROR_RESPONSES, ErrorOut

router = APIRouter(
    prefix="/api",
    tags=["motion"],
    route_class=JsonRoute,
    responses={**ERROR_RESPONSES, 503: {"model": ErrorOut, "description": "Busy, or over the time/memory budget"}},
)


@router.post("/analyse", response_model=AnalyseOut)
async def analyse(body: AnalyseIn, request: Request, settings: SettingsDep, workers: WorkersDep) -> AnalyseOut:
    """Tangency events (exact isolating intervals, decimals), intervals of constant relation, sign table.

    The motion text is parsed and analysed in a separate process under the server's time and
    memory budget (a busy server answers 503 before reading it); the event loop and the scene
    stay responsive meanwhile, and the worker is stopped if the client disconnects.
    """
    if body.digits > settings.max_digits:
        raise HTTPException(422, f"digits = {body.digits} is over the limit of {settings.max_digits}")
    a, b = motion_payload(body.a), motion_payload(body.b)
    args = (a, b, body.interval, body.digits, body.polynomials, settings.text_limits())

    def work(cancel: threading.Event) -> dict[str, Any]:
        return workers.run(analyse_job, *args, timeout=settings.time_budget_s, cancel=cancel)

    try:
        with bad_input():
            out = await run_off_loop(request, work)
    except WorkerBusy as e:
        raise HTTPException(503, f"{e}; retry in a moment", headers={"Retry-After": "2"}) from None
    except WorkerTimeout as e:
        raise HTTPException(503, f"analysis stopped: {e}; narrow the interval or simplify the motion") from None
    except WorkerCancelled as e:
        raise HTTPException(503, f"analysis stopped: {e}") from None
    except WorkerDied as e:
        raise HTTPException(503, f"analysis stopped: {e} (memory limit {settings.memory_limit_mb} MB)") from None
    except WorkerFailed as e:
        raise HTTPException(500, f"internal error in the analysis: {e}") from None
    return AnalyseOut(**out)
