"""The witnesses in the 3D view: contact point and common normal, point inside both, separating plane.

:class:`WitnessMarkers` draws what :mod:`app.scene.pair.contact` computed (certified witnesses for
fixed shapes; at a timeline tangency a float estimate of where they touch) and hides what does
not apply. Handles are created once per scene (the normal on first use) and updated by
assignment; every setter sends only changes.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
import viser

__all__ = ["WitnessMarkers", "rotation_to", "vec3"]


def vec3(values: Iterable[float]) -> tuple[float, float, float]:
    """The three values as floats: a position or scale for viser (exactly three, else ValueError).

    Examples:
        >>> vec3(np.array([1, 2, 3]))
        (1.0, 2.0, 3.0)
    """
    x, y, z = (float(v) for v in values)
    return (x, y, z)


def rotation_to(n: Sequence[float] | np.ndarray) -> tuple[float, float, float, float]:
    """Unit quaternion wxyz turning +z into the unit vector n (3D).

    Examples:
        >>> [round(v, 6) for v in rotation_to((1.0, 0.0, 0.0))]
        [0.707107, 0.0, 0.707107, 0.0]
        >>> rotation_to((0.0, 0.0, -1.0))
        (0.0, 1.0, 0.0, 0.0)
    """
    v = np.asarray(n, dtype=float)
    axis = np.cross([0.0, 0.0, 1.0], v)
    w = 1.0 + float(v[2])
    q = np.array([w, *axis]) if w > 1e-9 else np.array([0.0, 1.0, 0.0, 0.0])
    q /= np.linalg.norm(q)
    return (float(q[0]), float(q[1]), float(q[2]), float(q[3]))


def _centre(M: np.ndarray) -> np.ndarray:
    d = M.shape[0] - 1
    return -np.linalg.solve(M[:d, :d], M[:d, d])


class WitnessMarkers:
    """Contact point (with its label and the common normal) and the separating plane of one scene."""

    def __init__(self, scene: viser.SceneApi) -> None:
        self._scene = scene
        self.point: viser.IcosphereHandle = scene.add_icosphere("/contact/point", radius=0.06, color=(20, 20, 20), visible=False)
        self.label: viser.LabelHandle = scene.add_label("/contact/point/label", "contact", visible=False)
        self.normal: viser.LineSegmentsHandle | None = None
        square = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float32)
        self.plane: viser.MeshHandle = scene.add_mesh_simple(
            "/separating_plane",
            square,
            np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32),
            color=(60, 110, 200),
            opacity=0.35,
            side="double",
            cast_shadow=False,
            receive_shadow=False,
            visible=False,
        )
        self._point_on = False
        self._plane_on = False

    @property
    def plane_shown(self) -> bool:
        """True while the plane is drawn."""
        return self._plane_on

    def show_point(self, point: Sequence[float] | None, label: str = "contact", normal: Sequence[float] | None = None) -> None:
        """Draw the point (2D points in z = 0) with its label and normal, or hide them (None)."""
        if point is None:
            if self._point_on:
                self.point.visible = False
                self.label.visible = False
                self._point_on = False
            self._show_normal(None)
            return
        self.point.position = vec3((*point, 0.0) if len(point) == 2 else point)
        if self.label.text != label:
            self.label.text = label
        if not self._point_on:
            self.point.visible = True
            self.label.visible = True
            self._point_on = True
        self._show_normal(normal)

    def _show_normal(self, normal: Sequence[float] | None) -> None:
        """The common normal at the contact point: a short segment (created on first use)."""
        if normal is None:
            if self.normal is not None and self.normal.visible:
                self.normal.visible = False
            return
        if self.normal is None:
            segment = np.array([[[0.0, 0.0, 0.0], [0.0, 0.0, 0.6]]], dtype=np.float32)
            self.normal = self._scene.add_line_segments("/contact/point/normal", segment, (20, 20, 20), thickness=0.015)
        n = [float(v) for v in normal] + ([0.0] if len(normal) == 2 else [])
        self.normal.wxyz = rotation_to(n)
        if not self.normal.visible:
            self.normal.visible = True

    def show_plane(self, plane: tuple[np.ndarray, float] | None, A: np.ndarray | None = None, B: np.ndarray | None = None) -> None:
        """Draw the plane n.x = d (unit n) between the centres of A and B (float matrices), or hide it."""
        if plane is None or A is None or B is None:
            if self._plane_on:
                self.plane.visible = False
                self._plane_on = False
            return
        n, h = np.asarray(plane[0], dtype=float), float(plane[1])
        Af, Bf = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
        d = Af.shape[0] - 1
        cA, cB = _centre(Af), _centre(Bf)
        mid = (cA + cB) / 2
        p = mid + (h - n @ mid) * n
        n3 = np.append(n, 0.0) if d == 2 else n
        p3 = np.append(p, 0.0) if d == 2 else p
        size = 0.75 * float(np.linalg.norm(cB - cA)) + 1.0
        self.plane.position = vec3(p3)
        self.plane.wxyz = rotation_to(n3)
        self.plane.scale = (size, size, 1.0)
        if not self._plane_on:
            self.plane.visible = True
            self._plane_on = True
