"""POST /api/analyse: exact events and intervals of two moving shapes, in a worker process."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException

from ..convert import bad_input
from ..deps import SettingsDep, WorkersDep
from ..jobs import analyse_job
from ..motion_input import check_motion, motion_payload
from ..motion_schemas import AnalyseIn, AnalyseOut
from ..schemas import ERROR_RESPONSES, ErrorOut
from ..workers import WorkerBusy, WorkerDied, WorkerFailed, WorkerTimeout

router = APIRouter(
    prefix="/api",
    tags=["motion"],
    responses={**ERROR_RESPONSES, 503: {"model": ErrorOut, "description": "Busy, or over the time/memory budget"}},
)


@router.post("/analyse", response_model=AnalyseOut)
def analyse(body: AnalyseIn, settings: SettingsDep, workers: WorkersDep) -> AnalyseOut:
    """Tangency events (exact isolating intervals, decimals), intervals of constant relation, sign table.

    Runs in a separate process under the server's time budget; the event loop and the scene
    stay responsive meanwhile.
    """
    if body.digits > settings.max_digits:
        raise HTTPException(422, f"digits = {body.digits} is over the limit of {settings.max_digits}")
    a, b = motion_payload(body.a), motion_payload(body.b)
    with bad_input():
        check_motion(a, "a", settings)
        check_motion(b, "b", settings)
    try:
        with bad_input():
            out = workers.run(analyse_job, a, b, body.interval, body.digits, body.polynomials, timeout=settings.time_budget_s)
    except WorkerBusy as e:
        raise HTTPException(503, f"{e}; retry in a moment", headers={"Retry-After": "2"}) from None
    except WorkerTimeout as e:
        raise HTTPException(503, f"analysis stopped: {e}; narrow the interval or simplify the motion") from None
    except WorkerDied as e:
        raise HTTPException(503, f"analysis stopped: {e} (memory limit {settings.memory_limit_mb} MB)") from None
    except WorkerFailed as e:
        raise HTTPException(500, f"internal error in the analysis: {e}") from None
    return AnalyseOut(**out)
