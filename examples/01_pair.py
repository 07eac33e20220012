"""A pair: classify two ellipsoids, ask which rule decided, and get a witness.

Run: ``python examples/01_pair.py``. Two shapes given by centre, semi-axes and orientation
(a unit quaternion w, x, y, z); the answer is certified for the exact numbers given.
"""

from __future__ import annotations

from fractions import Fraction

from core import Relation, classify, explain, quadric_from_axes, separating_plane


def main() -> None:
    """Classify an ellipsoid against a sphere at its tip, then a hair further away."""
    A = quadric_from_axes([0, 0, 0], [2, 1, 1], [1, 0, 0, 0])
    B = quadric_from_axes([3, 0, 0], [1, 1, 1], [1, 0, 0, 0])
    relation = classify(A, B)                           # one pair: a Relation (a stack: int8 codes)
    print("sphere at x = 3:", relation, "-", explain(A, B).rule_text)
    assert relation == Relation.TANGENT

    far = quadric_from_axes([Fraction("3.000000001"), 0, 0], [1, 1, 1], [1, 0, 0, 0], exact=True)
    assert classify(A, far) == Relation.SEPARATE
    plane = separating_plane(A, far)
    print("sphere at x = 3.000000001: SEPARATE; a certified separating plane:", plane)


if __name__ == "__main__":
    main()
