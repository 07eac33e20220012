"""The choices of the CLI and the API derive from core.options (one list per option, issue 53)."""

from __future__ import annotations

import argparse
from typing import get_args

from app.api.schemas import PairIn
from app.api.sweep_schemas import SweepIn
from app.cli import build_parser
from core.options import METHODS, ON_INVALID, SWEEP_METHODS, Method, OnInvalid, SweepMethod


def _choices(command: str, option: str) -> tuple[str, ...]:
    """The choices of ``python -m app COMMAND OPTION`` as the parser has them."""
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    action = next(a for a in sub.choices[command]._actions if option in a.option_strings)
    return tuple(action.choices)


def test_the_tuples_match_their_literals():
    assert METHODS == get_args(Method) and ON_INVALID == get_args(OnInvalid) and SWEEP_METHODS == get_args(SweepMethod)
    assert set(SWEEP_METHODS) < set(METHODS)  # a sweep has no float-only answer


def test_the_sweep_choices_derive_from_core_options():
    assert _choices("sweep", "--method") == SWEEP_METHODS
    assert _choices("sweep", "--on-invalid") == ON_INVALID
    assert tuple(SweepIn.model_json_schema()["properties"]["method"]["enum"]) == SWEEP_METHODS


def test_the_pair_and_contacts_choices_derive_from_core_options():
    assert _choices("contacts", "--method") == METHODS
    assert tuple(PairIn.model_json_schema()["properties"]["method"]["enum"]) == METHODS
