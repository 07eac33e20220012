"""Core witnesses -> the response models of the witness routes (no mathematics here).

Floats that cannot be shown (beyond the float range) become ``None``; exact values are strings
and algebraic numbers (:func:`core.witness.numbers.algebraic_dict`).
"""

from __future__ import annotations

import math
from typing import Any, cast

from core import Certifier, Relation
from core.witness import SENTENCES, ContactPoint, ContactScale, SeparatingPlane, margin_text
from core.witness.numbers import algebraic_dict

from .schemas import AlgebraicOut
from .witness_schemas import CertifiedBy, ContactPointOut, ContactScaleOut, Decided, Kind, PlaneOut

__all__ = ["scale_out", "point_out", "plane_out", "kind_of", "decided", "certified_by"]


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def _algebraic(d: dict[str, Any]) -> AlgebraicOut:
    return AlgebraicOut(**{**d, "approx": _finite(d["approx"])})


def decided(relation: Relation) -> Decided:
    """The API name of a witnessed relation (core's witnesses are of decided pairs only)."""
    return cast(Decided, str(relation))


def certified_by(c: Certifier) -> CertifiedBy:
    """The API name of the arithmetic that certified a witness."""
    return "float" if c == Certifier.FLOAT else "exact"


def kind_of(a: Any) -> Kind:
    """"ellipse" for a 3x3 matrix, "ellipsoid" for a 4x4 one."""
    return "ellipse" if len(a) == 3 else "ellipsoid"


def scale_out(cs: ContactScale, kind: Kind, digits: int | None) -> ContactScaleOut:
    """The contact scale bracket (and, with ``digits``, mu* as an algebraic number)."""
    return ContactScaleOut(
        relation=decided(cs.relation),
        kind=kind,
        lo=str(cs.lo),
        hi=str(cs.hi),
        approx=_finite(cs.approx),
        margin=_finite(cs.margin),
        margin_text=margin_text(float(cs.lo), float(cs.hi), cs.relation),
        exact=None if digits is None else _algebraic(algebraic_dict(cs.algebraic(), digits)),
        certified_by=certified_by(cs.certified_by),
    )


def point_out(cp: ContactPoint, digits: int) -> ContactPointOut:
    """The contact point (and normal, pencil root) of a tangent pair, or a point inside both."""
    d = cp.to_dict(digits)
    return ContactPointOut(
        relation=d["relation"],
        sentence=SENTENCES[cp.relation],
        point=[_algebraic(c) for c in d["point"]],
        normal=None if d["normal"] is None else [_algebraic(c) for c in d["normal"]],
        pencil_root=None if d["pencil_root"] is None else _algebraic(d["pencil_root"]),
        certified_by=certified_by(cp.certified_by),
    )


def plane_out(plane: SeparatingPlane) -> PlaneOut:
    """A certified separating plane."""
    d = plane.to_dict()
    d["offset_approx"] = _finite(d["offset_approx"])
    d["gap_lower_bound"] = _finite(d["gap_lower_bound"])
    d["certified_by"] = certified_by(plane.certified_by)
    return PlaneOut(relation="separate", sentence=SENTENCES[Relation.SEPARATE], **d)
