"""Golden catalogue of hand-checkable exact pairs (shapely tests/common.py style).

Each case: name, A, B, expected relation, and why (checkable by hand). Matrices use exact
rationals (ints / "p/q" strings) in the project convention (interior X^T M X < 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction as F
from typing import Any


def circle(cx: Any, cy: Any, r: Any) -> list[list[Any]]:
    cx, cy, r = F(cx), F(cy), F(r)
    return [[1, 0, -cx], [0, 1, -cy], [-cx, -cy, cx * cx + cy * cy - r * r]]


def sphere(cx: Any, cy: Any, cz: Any, r: Any) -> list[list[Any]]:
    c = [F(cx), F(cy), F(cz)]
    M = [[F(int(i == j)) for j in range(3)] + [-c[i]] for i in range(3)]
    M.append([-v for v in c] + [sum(v * v for v in c) - F(r) ** 2])
    return M


def axis_ellipsoid(center: list[Any], axes: list[Any]) -> list[list[Any]]:
    """(x - c)^T diag(1/r^2) (x - c) - 1, exact."""
    d = len(center)
    c = [F(v) for v in center]
    q = [1 / F(r) ** 2 for r in axes]
    M = [[q[i] if i == j else F(0) for j in range(d)] + [-q[i] * c[i]] for i in range(d)]
    M.append([-q[i] * c[i] for i in range(d)] + [sum(q[i] * c[i] ** 2 for i in range(d)) - 1])
    return M


@dataclass(frozen=True)
class Case:
    name: str
    A: Any
    B: Any
    relation: str
    why: str
    rule: str | None = None


GAP = F(1, 10**9)

CASES: list[Case] = [
    Case("concentric circles", circle(0, 0, 1), circle(0, 0, 2), "overlap", "one inside the other"),
    Case("identical circles", circle(1, 2, 3), circle(1, 2, 3), "overlap", "same interior"),
    Case("unit circles at 2", circle(0, 0, 1), circle(2, 0, 1), "tangent", "touch at (1, 0)", "2d-s0=0"),
    Case("unit circles at 2+1e-9", circle(0, 0, 1), circle(2 + GAP, 0, 1), "separate", "gap 1e-9", "2d-s0>0"),
    Case("unit circles at 2-1e-9", circle(0, 0, 1), circle(2 - GAP, 0, 1), "overlap", "overlap 1e-9"),
    Case("circles 3-4-5", circle(0, 0, 2), circle(3, 4, 3), "tangent", "distance 5 = 2 + 3"),
    Case(
        "ellipse and circle at (2, 0)",
        axis_ellipsoid([0, 0], [2, 1]),
        circle(3, 0, 1),
        "tangent",
        "ellipse x<=2, circle x>=2, both contain (2, 0)",
    ),
    Case("concentric spheres", sphere(0, 0, 0, 1), sphere(0, 0, 0, 2), "overlap", "nested", "var"),
    Case("identical spheres", sphere(1, 1, 1, 1), sphere(1, 1, 1, 1), "overlap", "same interior"),
    Case(
        "unit spheres at 2",
        sphere(0, 0, 0, 1),
        sphere(2, 0, 0, 1),
        "tangent",
        "P = -(T+1)^2 (T-1)^2: double positive and double negative root, Theorem 24(1)",
        "3d-s1=0",
    ),
    Case("unit spheres at 2+1e-9", sphere(0, 0, 0, 1), sphere(2 + GAP, 0, 0, 1), "separate", "gap 1e-9", "3d-s10<0"),
    Case("unit spheres at 2-1e-9", sphere(0, 0, 0, 1), sphere(2 - GAP, 0, 0, 1), "overlap", "overlap 1e-9"),
    Case("unit spheres at 3", sphere(0, 0, 0, 1), sphere(3, 0, 0, 1), "separate",
         "P = (T+1)^2 q(T): double negative root, two positive, Theorem 28(1)", "3d-s10<0"),
    Case("spheres 2-3-6-7", sphere(0, 0, 0, 3), sphere(2, 3, 6, 4), "tangent", "distance 7 = 3 + 4"),
    Case(
        "ellipsoid and sphere at (2, 0, 0)",
        axis_ellipsoid([0, 0, 0], [2, 1, 1]),
        sphere(3, 0, 0, 1),
        "tangent",
        "ellipsoid x<=2, sphere x>=2, both contain (2, 0, 0)",
    ),
    Case(
        "ellipsoids tangent at (0, 3, 0)",
        axis_ellipsoid([0, 0, 0], [1, 3, 2]),
        axis_ellipsoid([0, 5, 0], [4, 2, 5]),
        "tangent",
        "first has y<=3, second y>=3, both contain (0, 3, 0)",
    ),
    Case(
        "ellipsoids apart by 1/10^9",
        axis_ellipsoid([0, 0, 0], [1, 3, 2]),
        axis_ellipsoid([0, 5 + GAP, 0], [4, 2, 5]),
        "separate",
        "the plane y = 3 + gap/2 separates them",
    ),
]
