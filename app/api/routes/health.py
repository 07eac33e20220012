"""GET /healthz (and HEAD, for load balancers): liveness, the load of the worker processes and of the line."""

from __future__ import annotations

from fastapi import APIRouter

from ..deps import LineDep, SettingsDep, WorkersDep
from ..schemas import HealthOut

router = APIRouter(tags=["health"])


@router.head("/healthz", response_model=HealthOut, name="healthz_head")  # its own operation id
@router.get("/healthz", response_model=HealthOut)
async def healthz(settings: SettingsDep, workers: WorkersDep, line: LineDep) -> HealthOut:
    """Answers at once (runs on the event loop, never waits on a worker); HEAD: the status alone."""
    return HealthOut(
        status="ok",
        analyses_running=workers.running,
        max_concurrent_analyses=settings.max_concurrent_analyses,
        analyses_waiting=workers.waiting,
        max_queued_analyses=settings.max_queued_analyses,
        large_bodies=line.taken,
        max_large_bodies=settings.max_large_bodies,
    )
