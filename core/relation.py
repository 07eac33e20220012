"""The relative position of two ellipses or ellipsoids, as a small integer enum.

Codes are stable (they are the int8 values of batch results): UNDECIDED = -1 is only ever
returned by ``method="float"``; the adaptive and exact paths always decide. INVALID = -2 marks
a pair with an input that is not an ellipse/ellipsoid, only when the caller asked for it
(``classify(..., on_invalid="mark")``); by default such input raises ValueError.
"""

from __future__ import annotations

from enum import IntEnum

__all__ = ["Relation"]


class Relation(IntEnum):
    """Relative position of two closed ellipses/ellipsoids.

    SEPARATE: the closed sets are disjoint. TANGENT: they touch externally (interiors disjoint).
    OVERLAP: the interiors meet (includes internal tangency, nesting and identical shapes).
    UNDECIDED: the float filter could not certify a sign (only from ``method="float"``).
    INVALID: one of the two matrices is not a valid ellipse/ellipsoid (only with
    ``on_invalid="mark"``).
    """

    INVALID = -2
    UNDECIDED = -1
    SEPARATE = 0
    TANGENT = 1
    OVERLAP = 2

    def __str__(self) -> str:
        return self.name.lower()

    @classmethod
    def parse(cls, text: str) -> Relation:
        """Relation from its lower-case name ("separate", "tangent", "overlap", "undecided", "invalid")."""
        try:
            return cls[text.strip().upper()]
        except KeyError:
            raise ValueError(
                f"unknown relation {text!r}; expected one of "
                + ", ".join(str(r) for r in cls)
            ) from None
