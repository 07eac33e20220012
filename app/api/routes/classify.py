"""POST /api/classify and POST /api/explain: the relation of fixed pairs.

No pair is decided on the event loop. Pairs of JSON numbers (binary64 values) are bounded work:
a single pair is classified with the other single pairs waiting at that moment by one thread
(:class:`app.api.batching.PairBatcher`); a batch in a server thread under the request budget
(``ApiSettings.request_budget_s``), checked between pairs, and dropped at the next check when the
client disconnects. Pairs with number strings (exact values up to the server's limits: 400
characters, exponents up to 1000) and every explanation run in the budgeted worker processes
(:func:`app.api.budget.run_job`): queued when busy, killed at the budget, on disconnect or when the
server stops. Every stop is a 503 with Retry-After.
"""

from __future__ import annotations

import threading

from fastapi import APIRouter, HTTPException, Request

from ..budget import Budget, BudgetExceeded, Cancelled, budget_error, run_job, run_off_loop
from ..convert import classify_items, plain_shapes
from ..deps import BatcherDep, SettingsDep, WorkersDep
from ..jobs import classify_job, explain_job
from ..json_body import JsonRoute
from ..schemas import (
    ERROR_RESPONSES,
    BatchIn,
    ClassifyIn,
    ClassifyOut,
    ErrorOut,
    ExplainOut,
    PairItem,
)

router = APIRouter(
    prefix="/api",
    tags=["classify"],
    route_class=JsonRoute,
    responses={**ERROR_RESPONSES, 503: {"model": ErrorOut, "description": "Busy, over the time budget of a request, or stopping (Retry-After)"}},
)


@router.post("/classify", response_model=ClassifyOut | list[ClassifyOut])
async def classify(
    body: ClassifyIn, request: Request, settings: SettingsDep, workers: WorkersDep, batcher: BatcherDep
) -> ClassifyOut | list[ClassifyOut]:
    """Certified relation of one pair ``{"a", "b"}``, or a list for ``{"pairs": [...]}``."""
    batch = isinstance(body, BatchIn)
    pairs = body.pairs if isinstance(body, BatchIn) else [body]
    if len(pairs) > settings.max_batch:
        raise HTTPException(422, f"batch of {len(pairs)} pairs is over the limit of {settings.max_batch}")
    hint = "send fewer pairs per request" if batch else ""
    plain = [plain_shapes(p) for p in pairs]  # the request's one binary64 test, passed down
    if not batch and all(plain[0]):
        try:
            return await batcher.classify(pairs[0], body.method, plain[0])
        except (BudgetExceeded, Cancelled) as e:
            raise budget_error(e) from None
    if all(a and b for a, b in plain):

        def work(cancel: threading.Event) -> list[ClassifyOut]:
            return classify_items(pairs, body.method, Budget(settings.request_budget_s, cancel), batch=batch, plain=plain)

        try:
            out = await run_off_loop(request, work)
        except (BudgetExceeded, Cancelled) as e:
            raise budget_error(e, hint) from None
    else:
        out = await run_job(
            request, workers, classify_job, pairs, body.method, settings.request_budget_s, batch, plain,
            seconds=settings.request_budget_s, checks_budget=True, hint=hint, memory_mb=settings.memory_limit_mb,
        )
    return out if batch else out[0]


@router.post("/explain", response_model=ExplainOut)
async def explain(body: PairItem, request: Request, settings: SettingsDep, workers: WorkersDep) -> ExplainOut:
    """Coefficients of P(T) = det(T A + B), s0, s1, s1,0, their signs, Var and the deciding rule."""
    return await run_job(
        request, workers, explain_job, body, settings.request_budget_s,
        seconds=settings.request_budget_s, checks_budget=True, memory_mb=settings.memory_limit_mb,
    )
