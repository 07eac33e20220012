"""Drawing one ellipse/ellipsoid in a viser scene, updated by assignment (never rebuilt per frame).

An ellipsoid is a unit icosphere (``trimesh.creation.icosphere``) scaled by its semi-axes; an
ellipse is a unit disc in the z = 0 plane scaled by (a, b, 1). The mesh hangs under a transform
gizmo node ``/shapes/<name>`` so that dragging moves it in the browser at once; Python only
recolours. Every setter compares with the last value sent, so unchanged nodes are not re-sent;
a view that is (re)built sends its whole state once, explicitly (the browser may remember the
pose of an earlier node with the same name). The relation shows three ways: the colour, the
label ("B · tangent") and, for a tangency, a brighter, opaque surface.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, Literal

import numpy as np
import viser

from . import wire
from .markers import vec3
from .mesh_detail import SPHERE_SUBDIVISIONS, check_sphere_subdivisions
from .state import PALETTES, RELATION_HEX

__all__ = [
    "RELATION_COLORS",
    "RELATION_HEX",
    "PALETTES",
    "NEUTRAL",
    "EllipsoidView",
    "unit_sphere",
    "unit_disc",
    "MESH_GAP",
    "SPHERE_SUBDIVISIONS",
    "DISC_SEGMENTS",
    "rgb",
]


def rgb(hex_colour: str) -> tuple[int, int, int]:
    """"#rrggbb" -> (r, g, b) in 0..255.

    Examples:
        >>> rgb("#ffbf00")
        (255, 191, 0)
    """
    return int(hex_colour[1:3], 16), int(hex_colour[3:5], 16), int(hex_colour[5:7], 16)


RELATION_COLORS: dict[str, tuple[int, int, int]] = {k: rgb(v) for k, v in RELATION_HEX.items()}
"""Relation -> RGB 0..255 (default palette)."""

NEUTRAL = (150, 150, 150)
"""Colour while no certified relation is known (e.g. an invalid typed shape, an analysis running)."""

Pose = tuple[tuple[float, float, float], tuple[float, float, float, float], tuple[float, float, float]]
"""(position, wxyz, scale) of a shape, in 3D (2D shapes live in z = 0)."""


DISC_SEGMENTS = 256
"""Sides of the polygon drawn for an ellipse (its sides lie within 1 - cos(π/256) = 7.5e-5)."""

MESH_GAP = 3e-4
"""How far inside the true surface a shape's drawing may lie, relative to its largest semi-axis.

The mesh is *inscribed*: its vertices lie on the unit sphere (circle), so its convex hull lies
inside the ball and contains the ball of radius 1 - MESH_GAP. A shape's drawing is the linear
image of that mesh, so it lies inside the true ellipsoid and contains the ellipsoid shrunk by
(1 - MESH_GAP) about its centre. Hence two tangent shapes are never drawn interpenetrating
(their interiors are disjoint and each drawing is inside its shape), and the gap drawn at the
contact is at most MESH_GAP times the larger semi-axis: under a pixel for a shape up to 3,000
pixels across. Drawn opaque at a tangency, they look touching."""


@lru_cache(maxsize=4)
def unit_sphere(subdivisions: int = SPHERE_SUBDIVISIONS) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) float32 and faces (F, 3) uint32 of a unit icosphere (built once).

    The vertices lie on the unit sphere (to float32 rounding): the mesh is inscribed.
    """
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.uint32)


@lru_cache(maxsize=4)
def unit_disc(segments: int = 96) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of a unit disc in the z = 0 plane (both sides drawn by the material).

    Examples:
        >>> v, f = unit_disc(8)
        >>> v.shape, f.shape, round(float(np.linalg.norm(v[1:], axis=1).min()), 6)
        ((9, 3), (8, 3), 1.0)
    """
    ang = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    v = np.zeros((segments + 1, 3), np.float32)
    v[1:, 0], v[1:, 1] = np.cos(ang), np.sin(ang)
    i = np.arange(segments)
    f = np.stack([np.zeros(segments, int), 1 + i, 1 + (i + 1) % segments], axis=1).astype(np.uint32)
    return v, f


_GIZMO_LIMITS: dict[int, dict[str, Any]] = {
    2: {
        "active_axes": (True, True, False),
        "translation_limits": ((-1000.0, 1000.0), (-1000.0, 1000.0), (0.0, 0.0)),
        "rotation_limits": ((0.0, 0.0), (0.0, 0.0), (-1000.0, 1000.0)),
    },
    3: {
        "active_axes": (True, True, True),
        "translation_limits": ((-1000.0, 1000.0),) * 3,
        "rotation_limits": ((-1000.0, 1000.0),) * 3,
    },
}
"""Gizmo axes and limits by dimension: a 2D shape moves in its plane and turns about z."""

_SIDE: dict[int, Literal["front", "double"]] = {2: "double", 3: "front"}
"""Faces drawn by dimension: a disc from both sides, a closed solid from outside."""


def _geometry(dim: int, subdivisions: int = SPHERE_SUBDIVISIONS) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of a shape's unit mesh: a disc (2D) or an icosphere (3D)."""
    return unit_disc(DISC_SEGMENTS) if dim == 2 else unit_sphere(subdivisions)


_POINT = (np.zeros((3, 3), np.float32), np.array([[0, 1, 2]], np.uint32))
"""A triangle of zero area: drawn (so its material stays compiled), covers no pixel."""


def _shape_mesh(
    scene: viser.SceneApi,
    name: str,
    vertices: np.ndarray,
    faces: np.ndarray,
    color: tuple[int, int, int],
    opacity: float | None,
    side: Literal["front", "double"],
) -> viser.MeshHandle:
    """A mesh with the shapes' material (the one place its flags are chosen)."""
    return scene.add_mesh_simple(
        name, vertices, faces, color=color, opacity=opacity, side=side, cast_shadow=False, receive_shadow=False
    )


class EllipsoidView:
    """One shape in the scene: gizmo node, mesh (scaled unit sphere or disc) and its label.

    Args:
        scene: a viser ``SceneApi`` (``client.scene`` for one tab, ``server.scene`` for all).
        name: "A" or "B" (node ``/shapes/<name>``, label text).
        dim: 2 (flat disc in z = 0, gizmo limited to the plane) or 3.
        opacity: mesh opacity (semi-transparent so the other shape shows through).
        gizmo: show the transform gizmo.
        subdivisions: of the icosphere a solid is drawn with (:data:`app.scene.common.mesh_detail.SPHERE_SUBDIVISIONS_RANGE`).
    """

    OPACITY = 0.6
    """Mesh opacity when separate or overlapping (the other shape shows through)."""
    TANGENT_OPACITY = 1.0
    """Mesh opacity at a tangency: opaque, so neither shape shows through the other (two
    see-through shapes that touch look interpenetrating) and the relation shows by more than
    its colour."""

    def __init__(
        self, scene: viser.SceneApi, name: str, dim: int, *, gizmo: bool = True, subdivisions: int = SPHERE_SUBDIVISIONS
    ) -> None:
        self.name = name
        self.dim = dim
        self.subdivisions = check_sphere_subdivisions(subdivisions)
        root = f"/shapes/{name}"
        self.control: viser.TransformControlsHandle = scene.add_transform_controls(
            root, scale=1.2, depth_test=False, **_GIZMO_LIMITS[dim]
        )
        self.mesh: viser.MeshHandle = _shape_mesh(
            scene, f"{root}/mesh", *_geometry(dim, subdivisions), NEUTRAL, self.OPACITY, _SIDE[dim]
        )
        # a point-sized double-sided twin: keeps both shader variants (disc: back and front
        # pass; solid: front) compiled in the browser, so a 2D <-> 3D switch compiles nothing
        # (SwiftShader took ~100 ms per switch to compile them again)
        _shape_mesh(scene, f"{root}/shaders", *_POINT, NEUTRAL, self.OPACITY, "double")
        self.label: viser.LabelHandle = scene.add_label(f"{root}/label", name, position=(0.0, 0.0, 0.0), anchor="bottom-center")
        self._pose: tuple[tuple[float, ...], tuple[float, ...]] | None = None
        self._scale: tuple[float, ...] | None = None
        self._color: tuple[int, int, int] = NEUTRAL
        self._relation: str | None = None
        self._fresh = True  # nothing of this node's pose reached the browser yet: send it all
        self.sent = 0
        """Number of property assignments sent (for the cost measurement)."""
        self._gizmo = True
        self.set_gizmo(gizmo)

    @property
    def drawn(self) -> bool:
        """True once the view's pose has been sent (the browser shows this node)."""
        return not self._fresh

    def remove(self) -> None:
        """Remove the node (gizmo, mesh and label) from the scene."""
        self.control.remove()

    def set_dim(self, dim: int) -> None:
        """Turn the shape into a disc (2) or a solid (3) in place.

        The gizmo node, its mesh and label stay (building a gizmo anew costs the browser about
        half a second); the gizmo's axes and limits and the mesh's geometry and sides change,
        and the whole pose is sent again with the next :meth:`set_pose`.
        """
        if dim == self.dim:
            return
        self.dim = dim
        c = self.control
        limits = _GIZMO_LIMITS[dim]
        c.active_axes = limits["active_axes"]
        c.translation_limits = limits["translation_limits"]
        c.rotation_limits = limits["rotation_limits"]
        self.mesh.vertices, self.mesh.faces = _geometry(dim, self.subdivisions)
        self.mesh.side = _SIDE[dim]
        self._fresh = True
        self._scale = None
        self.sent += 6

    def set_pose(
        self,
        position: tuple[float, float, float],
        wxyz: tuple[float, float, float, float],
        scale: tuple[float, float, float],
        *,
        from_drag: bool = False,
    ) -> None:
        """Move/resize the shape; after a drag the browser already shows the pose (not re-sent)."""
        if self.dim == 2 and self.name == "B":
            # two discs in one plane z-fight where they overlap: lift B a hair (display)
            position = (position[0], position[1], position[2] + 0.01)
        if self._fresh:
            wire.force_pose(self.control, position, wxyz)
            self._pose = (position, wxyz)
            self._fresh = False
            self.sent += 2
        elif (position, wxyz) != self._pose:
            self._pose = (position, wxyz)
            if not from_drag:
                wire.set_position(self.control, position)
                wire.set_wxyz(self.control, wxyz)
                self.sent += 2
        # semi-axes from a float eigen-decomposition jitter in the last bits under a rigid
        # motion: compare at display precision so an unchanged size sends nothing
        scale = vec3(float(f"{v:.9g}") for v in scale)
        if scale != self._scale:
            self._scale = scale
            self.mesh.scale = scale
            # label above the top of the shape, in the body frame of the gizmo node
            self.label.position = (0.0, 0.0, scale[2] if self.dim == 3 else 0.0)
            self.sent += 2

    def resend_pose(self) -> None:
        """Send the pose last set again, explicitly.

        After a drag the browser's gizmo holds the pointer's float pose; the certified shape is
        the rounded one (:meth:`app.scene.common.state.ShapeState.rationalised`), drawn from here on.
        """
        if self._pose is not None:
            wire.force_pose(self.control, *self._pose)
            self.sent += 2

    def set_relation(self, relation: str | None, palette: dict[str, str] = RELATION_HEX) -> None:
        """Colour, label text and opacity of the relation (grey when unknown); sent on change."""
        color = rgb(palette[relation]) if relation in palette else NEUTRAL
        if color != self._color:
            self._color = color
            self.mesh.color = color
            self.sent += 1
        if relation != self._relation:
            self._relation = relation
            self.label.text = self.name if relation is None else f"{self.name} · {relation}"
            self.mesh.opacity = self.TANGENT_OPACITY if relation == "tangent" else self.OPACITY
            self.sent += 2

    def set_gizmo(self, visible: bool) -> None:
        """Show or hide the transform gizmo (hidden while a motion drives the shape).

        The gizmo node stays visible (it carries the mesh and label as children): hiding means
        fully transparent and inert.
        """
        if self._gizmo != visible:
            self._gizmo = visible
            c = self.control
            c.opacity = 1.0 if visible else 0.0
            c.disable_axes = not visible
            c.disable_sliders = not visible
            c.disable_rotations = not visible
            self.sent += 4
