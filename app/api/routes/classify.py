"""POST /api/classify and POST /api/explain: the relation of fixed pairs."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException

from core import explain as core_explain

from ..convert import bad_input, checked_pair, classify_pair
from ..deps import SettingsDep
from ..schemas import ERROR_RESPONSES, BatchIn, ClassifyIn, ClassifyOut, ExplainOut, PairItem

router = APIRouter(prefix="/api", tags=["classify"], responses=ERROR_RESPONSES)


@router.post("/classify", response_model=ClassifyOut | list[ClassifyOut])
def classify(body: ClassifyIn, settings: SettingsDep) -> ClassifyOut | list[ClassifyOut]:
    """Certified relation of one pair ``{"a", "b"}``, or a list for ``{"pairs": [...]}``."""
    if isinstance(body, BatchIn):
        if len(body.pairs) > settings.max_batch:
            raise HTTPException(422, f"batch of {len(body.pairs)} pairs is over the limit of {settings.max_batch}")
        return [classify_pair(p, body.method, f"pairs[{i}]: ") for i, p in enumerate(body.pairs)]
    return classify_pair(body, body.method)


@router.post("/explain", response_model=ExplainOut)
def explain(body: PairItem) -> ExplainOut:
    """Coefficients of P(T) = det(T A + B), s0, s1, s1,0, their signs, Var and the deciding rule."""
    a, b = checked_pair(body)
    with bad_input():
        return ExplainOut(**core_explain(a, b).to_dict())
