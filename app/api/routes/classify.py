"""POST /api/classify and POST /api/explain: the relation of fixed pairs.

The work runs off the event loop under the request budget (``ApiSettings.request_budget_s``):
a batch that runs over it is stopped between pairs and answered with 503, and work whose client
has disconnected is dropped at the next check.
"""

from __future__ import annotations

import threading

from fastapi import APIRouter, HTTPException, Request

from core import explain as core_explain

from ..budget import Budget, BudgetExceeded, Cancelled, budget_error, run_off_loop
from ..convert import bad_input, checked_pair, classify_items, is_plain_pair
from ..deps import SettingsDep
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
    responses={**ERROR_RESPONSES, 503: {"model": ErrorOut, "description": "Over the time budget of a request"}},
)


@router.post("/classify", response_model=ClassifyOut | list[ClassifyOut])
async def classify(body: ClassifyIn, request: Request, settings: SettingsDep) -> ClassifyOut | list[ClassifyOut]:
    """Certified relation of one pair ``{"a", "b"}``, or a list for ``{"pairs": [...]}``."""
    batch = isinstance(body, BatchIn)
    pairs = body.pairs if isinstance(body, BatchIn) else [body]
    if len(pairs) > settings.max_batch:
        raise HTTPException(422, f"batch of {len(pairs)} pairs is over the limit of {settings.max_batch}")

    def work(cancel: threading.Event) -> list[ClassifyOut]:
        return classify_items(pairs, body.method, Budget(settings.request_budget_s, cancel), batch=batch)

    try:
        if not batch and is_plain_pair(pairs[0]):  # bounded (< 1 ms): no thread hop
            out = work(threading.Event())
        else:
            out = await run_off_loop(request, work)
    except (BudgetExceeded, Cancelled) as e:
        raise budget_error(e, "send fewer pairs per request" if batch else "") from None
    return out if batch else out[0]


@router.post("/explain", response_model=ExplainOut)
async def explain(body: PairItem, request: Request, settings: SettingsDep) -> ExplainOut:
    """Coefficients of P(T) = det(T A + B), s0, s1, s1,0, their signs, Var and the deciding rule."""

    def work(cancel: threading.Event) -> ExplainOut:
        budget = Budget(settings.request_budget_s, cancel)
        a, b = checked_pair(body)
        budget.check("after reading the pair")
        with bad_input():
            return ExplainOut(**core_explain(a, b).to_dict())

    try:
        return await run_off_loop(request, work)
    except (BudgetExceeded, Cancelled) as e:
        raise budget_error(e) from None
