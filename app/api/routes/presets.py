"""GET /api/presets and GET /api/presets/{name}: built-in moving pairs, ready to post to /api/analyse."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException

from ..motion_schemas import PresetOut
from ..presets_source import api_preset, api_presets
from ..schemas import ErrorOut

router = APIRouter(prefix="/api/presets", tags=["presets"])


@router.get("", response_model=list[PresetOut], response_model_exclude_none=True)
def list_presets() -> list[PresetOut]:
    """The paper's Examples 29-33 and the 2D presets, each in the input format of /api/analyse."""
    return [PresetOut(**p) for p in api_presets()]


@router.get("/{name}", response_model=PresetOut, response_model_exclude_none=True, responses={404: {"model": ErrorOut, "description": "Unknown preset"}})
def get_preset(name: str) -> PresetOut:
    """One preset by name (404 lists the available names)."""
    try:
        return PresetOut(**api_preset(name))
    except KeyError as e:
        raise HTTPException(404, e.args[0]) from None
