"""What the 3D view shows at one instant: the shapes, their certified relation and its witnesses.

A :class:`Picture` is derived from the tab's state in one place, so the shapes drawn are always
the shapes whose relation is shown: :func:`static_picture` classifies the fixed shapes
(``core.classify`` while dragging, ``core.explain`` and the certified witnesses otherwise);
:func:`motion_picture` places the moving shapes at the float t and takes the relation from the
analysis at the exact t (or the exact event). Floats are for drawing only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from core import Relation, classify, explain

from ..common.shapes import Pose
from ..common.state import ShapeState
from .analysis import AnalysisView
from .contact import WitnessView, contact_point, witness_view
from .motion import MotionModel

__all__ = ["Picture", "static_picture", "motion_picture"]


@dataclass
class Picture:
    """One frame of the 3D view and the data of its readout."""

    poses: dict[str, Pose] | None
    """(position, wxyz, scale) per shape; None: keep the last poses (not drawable at this t)."""
    shapes: dict[str, ShapeState] | None
    """The shapes drawn (exact when typed; floats from a motion or a drag)."""
    relation: str | None
    """Certified relation drawn (None: unknown, e.g. invalid shapes or analysis running)."""
    explanation: dict[str, Any] | None = None
    """``core.explain`` dict (static shapes; a motion's readout is built with the panels)."""
    witness: WitnessView | None = None
    """Certified witness of static shapes (margin, sentence, plane, point)."""
    point: tuple[float, ...] | None = None
    point_label: str = "contact"
    normal: tuple[float, ...] | None = None
    plane: tuple[np.ndarray, float] | None = None
    matrices: tuple[Any, Any] | None = None
    """Matrices of A and B (for placing the plane)."""
    error: str | None = None
    """Why no relation is shown (invalid shapes)."""
    quick: bool = False
    """Only the relation (a drag): the readout and witnesses follow with the panels."""


def static_picture(shapes: dict[str, ShapeState], *, quick: bool, plane: bool) -> Picture:
    """The fixed shapes with their certified relation.

    Args:
        shapes: "A" and "B".
        quick: classify only (microseconds; a drag): explanation and witnesses follow later.
        plane: the separating plane is wanted (when separate).
    """
    poses = {name: sh.float_pose() for name, sh in shapes.items()}
    try:
        A, B = shapes["A"].quadric(), shapes["B"].quadric()
        if quick:
            return Picture(poses, dict(shapes), str(classify(A, B)), quick=True)
        expl = explain(A, B).to_dict()
    except ValueError as e:
        return Picture(poses, dict(shapes), None, error=str(e))
    rel = expl["relation"]
    view = witness_view(A, B, rel)  # margin, sentence, certified plane / point
    pic = Picture(poses, dict(shapes), rel, explanation=expl, witness=view, matrices=(A, B))
    if view is not None:
        pic.point, pic.point_label, pic.normal = view.point, view.point_label, view.normal
        if plane and rel == str(Relation.SEPARATE):
            pic.plane = view.plane
    elif rel == str(Relation.TANGENT):
        pic.point = _tuple(contact_point(A, B, [q["approx"] for q in expl["coefficients"]]))
    return pic


def motion_picture(model: MotionModel, analysis: AnalysisView | None, t: float, exact: Any, event: int | None, *, plane: bool) -> Picture:
    """The moving shapes at t with the relation certified by the analysis.

    Args:
        model: the loaded motion (float matrices for drawing).
        analysis: its analysis (None while it runs: no relation is shown).
        t: the float time drawn.
        exact: the exact time the relation is certified at (a rational or algebraic number typed
            in the t box), or None for the float t itself.
        event: 1-based index of the event shown exactly (its relation), or None.
        plane: the separating plane is wanted (when separate).
    """
    try:
        a, b = model.shapes_at(t)
        shapes: dict[str, ShapeState] | None = {"A": a, "B": b}
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        shapes = None  # not drawable in floats at this t (extreme coefficients): keep the last pose
    poses = None if shapes is None else {name: sh.float_pose() for name, sh in shapes.items()}
    if analysis is None:
        return Picture(poses, shapes, None)
    if event is not None:
        relation = analysis.events[event - 1].relation
    else:
        relation = analysis.relation_at(analysis.inside(t) if exact is None else exact)
    pic = Picture(poses, shapes, relation)
    if shapes is None:
        return pic
    A, B = model.float_matrices(t)
    pic.matrices = (A, B)
    if relation == str(Relation.TANGENT):
        from core.formulae.pencil import pencil_coefficients

        pic.point = _tuple(contact_point(A, B, [float(v) for v in pencil_coefficients(A, B)]))
    if plane and relation == str(Relation.SEPARATE):
        from core.witness import SeparatingPlane, separating_plane

        try:  # the float matrices at t, certified by floats (display of a certified plane)
            p = separating_plane(np.asarray(A, dtype=float), np.asarray(B, dtype=float), method="float", on_invalid="mark")
            if isinstance(p, SeparatingPlane):
                pic.plane = p.unit()
        except (ValueError, ArithmeticError):
            pass
    return pic


def _tuple(p: Any) -> tuple[float, ...] | None:
    return None if p is None else tuple(float(v) for v in p)
