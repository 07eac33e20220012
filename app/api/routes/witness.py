"""POST /api/contact-scale, /api/separating-plane, /api/contact-point, /api/witness.

The witnesses behind an answer (core.witness): how far from touching (certified contact scale),
which plane separates a separate pair, where a tangent pair touches, a point inside both shapes
of an overlapping pair. Exact values travel as strings. A plane asked of a pair that is not
separate, or a point of a separate pair, is a 422 that says why.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any, TypeVar, cast

from fastapi import APIRouter, HTTPException, Request

from core import Certifier, Relation
from core.witness import (
    SENTENCES,
    ContactPoint,
    ContactScale,
    SeparatingPlane,
    contact_point,
    contact_scale,
    margin_text,
)
from core.witness import separating_plane as core_separating_plane
from core.witness.numbers import algebraic_dict

from ..budget import Budget, BudgetExceeded, Cancelled, budget_error, run_off_loop
from ..convert import bad_input, checked_pair
from ..deps import SettingsDep
from ..json_body import JsonRoute
from ..schemas import ERROR_RESPONSES, ErrorOut
from ..witness_schemas import (
    AlgebraicOut,
    CertifiedBy,
    ContactPointOut,
    ContactScaleIn,
    ContactScaleOut,
    Decided,
    Kind,
    PlaneOut,
    WitnessIn,
    WitnessOut,
)

router = APIRouter(
    prefix="/api",
    tags=["witness"],
    route_class=JsonRoute,
    responses={**ERROR_RESPONSES, 503: {"model": ErrorOut, "description": "Over the time budget of a request"}},
)

T = TypeVar("T")


async def _off_loop(request: Request, settings: Any, fn: Callable[[], T]) -> T:
    """Run ``fn`` in a worker thread under the request budget, as /api/classify does.

    The event loop stays free, and the answer of a client that went away is dropped.
    """

    def work(cancel: threading.Event) -> T:
        budget = Budget(settings.request_budget_s, cancel)
        budget.check("before the witness")
        out = fn()
        budget.check("after the witness")
        return out

    try:
        return await run_off_loop(request, work)
    except (BudgetExceeded, Cancelled) as e:
        raise budget_error(e) from None


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def _algebraic(d: dict[str, Any]) -> AlgebraicOut:
    return AlgebraicOut(**{**d, "approx": _finite(d["approx"])})


def _check_digits(digits: int, settings: Any) -> None:
    if digits > settings.max_digits:
        raise HTTPException(422, f"digits = {digits} is over the limit of {settings.max_digits}")


def _decided(relation: Relation) -> Decided:
    """The API name of a witnessed relation (core's witnesses are of decided pairs only)."""
    return cast(Decided, str(relation))


def _scale_out(cs: ContactScale, kind: Kind, digits: int | None) -> ContactScaleOut:
    return ContactScaleOut(
        relation=_decided(cs.relation),
        kind=kind,
        lo=str(cs.lo),
        hi=str(cs.hi),
        approx=_finite(cs.approx),
        margin=_finite(cs.margin),
        margin_text=margin_text(float(cs.lo), float(cs.hi), cs.relation),
        exact=None if digits is None else _algebraic(algebraic_dict(cs.algebraic(), digits)),
        certified_by=_by(cs.certified_by),
    )


def _point_out(cp: ContactPoint, digits: int) -> ContactPointOut:
    d = cp.to_dict(digits)
    return ContactPointOut(
        relation=d["relation"],
        sentence=SENTENCES[cp.relation],
        point=[_algebraic(c) for c in d["point"]],
        normal=None if d["normal"] is None else [_algebraic(c) for c in d["normal"]],
        pencil_root=None if d["pencil_root"] is None else _algebraic(d["pencil_root"]),
        certified_by=_by(cp.certified_by),
    )


def _plane_out(plane: SeparatingPlane) -> PlaneOut:
    d = plane.to_dict()
    d["offset_approx"] = _finite(d["offset_approx"])
    d["gap_lower_bound"] = _finite(d["gap_lower_bound"])
    d["certified_by"] = _by(plane.certified_by)
    return PlaneOut(relation="separate", sentence=SENTENCES[Relation.SEPARATE], **d)


def _by(c: Certifier) -> CertifiedBy:
    """The API name of the arithmetic that certified a witness."""
    return "float" if c == Certifier.FLOAT else "exact"


def _kind(a: Any) -> Kind:
    return "ellipse" if len(a) == 3 else "ellipsoid"


@router.post("/contact-scale", response_model=ContactScaleOut)
async def contact_scale_route(body: ContactScaleIn, request: Request, settings: SettingsDep) -> ContactScaleOut:
    """Certified bracket of the contact scale mu* (mu* > 1 separate, = 1 tangent, < 1 overlap).

    With ``exact``, mu* as an algebraic number too (polynomial, isolating interval, decimals).
    """
    _check_digits(body.digits, settings)

    def fn() -> ContactScaleOut:
        a, b = checked_pair(body)
        with bad_input():
            cs = contact_scale(a, b, rtol=body.rtol)
            return _scale_out(cs, _kind(a), body.digits if body.exact else None)

    return await _off_loop(request, settings, fn)


@router.post("/separating-plane", response_model=PlaneOut)
async def separating_plane_route(body: WitnessIn, request: Request, settings: SettingsDep) -> PlaneOut:
    """A separating plane n.x = d with exact rationals, verified exactly.

    a lies strictly on the side n.x < d and b strictly on n.x > d; 422 when the pair is tangent
    or overlapping.
    """

    def fn() -> PlaneOut:
        a, b = checked_pair(body)
        with bad_input():
            return _plane_out(core_separating_plane(a, b))

    return await _off_loop(request, settings, fn)


@router.post("/contact-point", response_model=ContactPointOut)
async def contact_point_route(body: WitnessIn, request: Request, settings: SettingsDep) -> ContactPointOut:
    """Where the pair meets.

    Tangent pair: the exact contact point and common normal. Overlapping pair: a rational point
    strictly inside both. 422 when the pair is separate.
    """
    _check_digits(body.digits, settings)

    def fn() -> ContactPointOut:
        a, b = checked_pair(body)
        with bad_input():
            return _point_out(contact_point(a, b), body.digits)

    return await _off_loop(request, settings, fn)


@router.post("/witness", response_model=WitnessOut)
async def witness_route(body: WitnessIn, request: Request, settings: SettingsDep) -> WitnessOut:
    """All of it at once.

    The relation, the sentence that explains it, the contact scale, and the separating plane
    (separate) or the point (tangent, overlap).
    """
    from core.witness import witness

    _check_digits(body.digits, settings)

    def fn() -> WitnessOut:
        a, b = checked_pair(body)
        with bad_input():
            w = witness(a, b)
            return WitnessOut(
                relation=_decided(w.relation),
                sentence=w.sentence,
                margin_text=w.margin,
                contact_scale=_scale_out(w.scale, _kind(a), None),
                plane=None if w.plane is None else _plane_out(w.plane),
                point=None if w.point is None else _point_out(w.point, body.digits),
            )

    return await _off_loop(request, settings, fn)
