"""Framing: point a tab's camera at the shapes (2D: from above) and lay a grid under them.

The GUI panel covers about the right third of the page, so the shapes are fitted in the left
part and the camera aims right of them by the matching offset. In presenter mode every tab's
camera is framed (each tab has its own camera even though the scene is shared).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Protocol

import numpy as np
import viser

from .markers import vec3

__all__ = ["Framing", "Camera", "frame_cameras", "extent_of"]

FREE = 0.62
"""Share of the page width left of the GUI panel."""


class Camera(Protocol):
    """What :meth:`Framing.aim` reads and sets of a camera.

    A tab's :class:`viser.CameraHandle`, or an adapter with the same attributes.
    """

    @property
    def fov(self) -> float:
        """Vertical field of view, radians."""
        ...

    @property
    def aspect(self) -> float:
        """Width over height of the view."""
        ...

    position: tuple[float, float, float] | np.ndarray
    look_at: tuple[float, float, float] | np.ndarray
    up_direction: tuple[float, float, float] | np.ndarray


class Framing:
    """Where the shapes are: an axis-aligned box (lo, hi corners in 3D) and the dimension."""

    def __init__(self, points: np.ndarray, dim: int) -> None:
        pts = np.asarray(points, dtype=float).reshape(-1, 3)
        self.lo, self.hi = np.min(pts, axis=0), np.max(pts, axis=0)
        self.dim = dim

    @property
    def centre(self) -> np.ndarray:
        """Centre of the box."""
        centre: np.ndarray = (self.lo + self.hi) / 2
        return centre

    @property
    def radius(self) -> float:
        """Half the diagonal of the box (at least 1)."""
        return max(float(np.linalg.norm(self.hi - self.lo)) / 2, 1.0)

    def grid_key(self) -> tuple[float, float, float, float]:
        """Side, centre (x, y) and height of the grid: equal keys, equal grids."""
        size = float(2 ** math.ceil(math.log2(4 * self.radius)))
        c = self.centre
        return size, float(c[0]), float(c[1]), -0.02 if self.dim == 2 else float(self.lo[2])

    def grid(self, scene: viser.SceneApi, into: viser.GridHandle | None = None) -> viser.GridHandle:
        """Lay the grid under the shapes (z = 0 plane in 2D, the bottom of the box in 3D).

        ``into``: a grid already in the scene, changed in place (a grid added anew is a new
        node and material for the browser to build, where a few numbers change).
        """
        size, cx, cy, floor = self.grid_key()
        if into is None:
            return scene.add_grid(
                "/grid",
                width=size,
                height=size,
                plane="xy",
                cell_size=size / 16,
                section_size=size / 4,
                position=(cx, cy, floor),
            )
        into.width = into.height = size
        into.cell_size, into.section_size = size / 16, size / 4
        into.position = (cx, cy, floor)
        return into

    def aim(
        self,
        cam: Camera,
        *,
        free: float = FREE,
        fill: float = 0.9,
        view: tuple[float, float, float] = (0.3, -1.05, 0.6),
        whole: bool = True,
    ) -> None:
        """Point one camera at the box (the one framing arithmetic of the scene and the bodies view).

        Args:
            cam: the camera (a tab's, or anything with the same attributes).
            free: share of the width not covered by a panel (1: the whole view).
            fill: distance factor (larger: the box looks smaller).
            view: 3D direction from the box's centre to the camera.
            whole: the box fits whole (two shapes; a margin of ``fill`` / 0.8): in 2D its width in
                the free part of the view and its height, in 3D its bounding sphere. False: the
                tangent rule on the box's radius with the caller's ``fill`` (the many-bodies overview).
        """
        try:
            fov, aspect = float(cam.fov), float(cam.aspect)
        except Exception:  # noqa: BLE001 - camera state not known yet: typical values
            fov, aspect = 1.3, 1.5
        half_h = math.tan(fov / 2)
        seen = half_h * min(1.0, free * aspect)  # tan of the half-angle the box must fit in
        if not whole:
            dist = fill * self.radius / seen
        elif self.dim == 2:  # the box itself, in the plane facing the camera: its width within the free part
            hx, hy = (float(v) / 2 for v in (self.hi - self.lo)[:2])
            dist = max(hy, hx / (free * aspect), 1.0) / half_h * fill / 0.8
        else:  # the box's bounding sphere: its apparent half-angle asin(r / d) fits (the tangent cut solids off)
            dist = fill * self.radius / math.sin(math.atan(seen))
        shift = (0.5 - free / 2) * 2 * dist * half_h * aspect
        c = self.centre
        if self.dim == 2:
            cam.up_direction = (0.0, 1.0, 0.0)
            x = float(c[0]) + shift
            cam.position = (x, float(c[1]) - 1e-3, dist)
            cam.look_at = (x, float(c[1]), 0.0)
        else:
            cam.up_direction = (0.0, 0.0, 1.0)
            v = np.asarray(view, dtype=float)
            v /= np.linalg.norm(v)
            right = np.cross(-v, np.array([0.0, 0.0, 1.0]))
            right /= np.linalg.norm(right)
            # viser keeps the orientation when the position is set: position first, then look_at
            cam.position = vec3(c + dist * v + shift * right)
            cam.look_at = vec3(c + shift * right)


def extent_of(poses: Iterable[tuple[tuple[float, float, float], object, tuple[float, float, float]]], dim: int) -> np.ndarray:
    """Corner points of the boxes around shapes given as (position, wxyz, scale) poses."""
    pts = []
    for pos, _, scale in poses:
        r = max(scale[:2] if dim == 2 else scale)
        pts += [np.array(pos) + r, np.array(pos) - r]
    return np.array(pts)


def frame_cameras(
    scene: viser.SceneApi,
    cameras: Iterable[viser.CameraHandle],
    framing: Framing,
    laid: tuple[viser.GridHandle, tuple[float, float, float, float]] | None = None,
) -> tuple[viser.GridHandle, tuple[float, float, float, float]]:
    """Aim every camera at the shapes and lay the grid under them; return the grid and its key.

    ``laid``: the grid already in the scene and its key. An equal grid is not sent again (a
    preset pick frames twice: loaded, then analysed); another one is changed in place.
    """
    key = framing.grid_key()
    if laid is not None and laid[1] == key:
        grid = laid[0]
    else:
        grid = framing.grid(scene, None if laid is None else laid[0])
    for cam in cameras:
        framing.aim(cam)
    return grid, key
