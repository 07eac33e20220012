"""The witness behind each answer, in one call, with the sentence that explains it.

* separate: a plane that separates them (exact rationals, verified; :mod:`core.witness.plane`),
* tangent: the point where they touch and the common normal (exact; :mod:`core.witness.point`),
* overlap: a rational point inside both (verified; :mod:`core.witness.point`),

and, for every relation, the certified contact scale mu* (:mod:`core.witness.scale`): how far
from touching, as a margin a class can read ("1.8 % apart", "overlapping by 3 %").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..fixed.classify import Certifier
from ..relation import Relation
from .filtered import NoWitness
from .numbers import to_float
from .plane import SeparatingPlane
from .point import ContactPoint
from .scale import ContactScale

__all__ = ["Witness", "compose", "margin_text", "SENTENCES"]

SENTENCES = {
    Relation.SEPARATE: "separate: this plane separates them",
    Relation.TANGENT: "tangent: they touch here",
    Relation.OVERLAP: "overlap: this point is inside both",
}
"""What each witness shows, as one sentence."""


def margin_text(lo: float, hi: float, relation: Relation | int | str) -> str:
    """The contact scale as a margin: "1.8 % apart", "touching", "overlapping by 3 %".

    The percentage is (mu* - 1) or (1 - mu*) at the middle of the certified bracket [lo, hi]
    with two significant digits (whole percents from 10 %): both shapes must grow (apart) or shrink (overlapping) by
    that much about their own centres to touch.

    Examples:
        >>> margin_text(1.018, 1.018, "separate"), margin_text(0.97, 0.97, "overlap")
        ('1.8 % apart', 'overlapping by 3 %')
        >>> margin_text(1.0, 1.0, "tangent"), margin_text(2.0, 2.0, "separate")
        ('touching', '100 % apart')
        >>> margin_text(1 + 3e-9, 1 + 3e-9, "separate")
        '3e-07 % apart'
    """
    rel = Relation.parse(relation) if isinstance(relation, str) else Relation(relation)
    if rel == Relation.TANGENT:
        return "touching"
    mid = 0.5 * (float(lo) + float(hi))
    pct = abs(mid - 1.0) * 100.0
    text = f"{pct:.0f}" if pct >= 10 else f"{pct:.2g}"
    if rel == Relation.SEPARATE:
        return f"{text} % apart"
    if rel == Relation.OVERLAP:
        return f"overlapping by {text} %"
    return "unknown"


@dataclass
class Witness:
    """The certified relation, the sentence that explains it and the object that proves it."""

    relation: Relation
    sentence: str
    scale: ContactScale
    plane: SeparatingPlane | None = None
    """Separate pairs: the verified separating plane."""
    point: ContactPoint | None = None
    """Tangent pairs: the exact contact point and normal; overlap: a rational point in both."""
    certified_by: Certifier = Certifier.EXACT
    """FLOAT when floats with directed rounding certified every part, else EXACT."""

    @property
    def margin(self) -> str:
        """The contact scale as a margin ("1.8 % apart", "touching", "overlapping by 3 %")."""
        return margin_text(to_float(self.scale.lo), to_float(self.scale.hi), self.relation)

    def to_dict(self, digits: int = 20) -> dict[str, Any]:
        """JSON form (exact values as strings)."""
        return {
            "relation": str(self.relation),
            "sentence": self.sentence,
            "margin": self.margin,
            "contact_scale": self.scale.to_dict(digits),
            "plane": None if self.plane is None else self.plane.to_dict(),
            "point": None if self.point is None else self.point.to_dict(digits),
            "certified_by": str(self.certified_by),
        }


def compose(scale: ContactScale | NoWitness, part: SeparatingPlane | ContactPoint | NoWitness) -> Witness | NoWitness:
    """The witness of one pair from its contact scale and its plane (separate) or point (otherwise)."""
    if isinstance(scale, NoWitness):
        return scale
    if isinstance(part, NoWitness):
        return NoWitness(scale.relation, part.kind, part.reason)
    rel = scale.relation
    by = Certifier.FLOAT if scale.certified_by == part.certified_by == Certifier.FLOAT else Certifier.EXACT
    if isinstance(part, SeparatingPlane):
        return Witness(rel, SENTENCES[rel], scale, plane=part, certified_by=by)
    return Witness(rel, SENTENCES[rel], scale, point=part, certified_by=by)
