"""Level of detail for many bodies: which bodies are drawn as solids, and how finely, for a camera.

In software WebGL (headless Chromium, SwiftShader) a frame costs about 2.5 us per triangle on
this 2-core machine, instanced or not (bench/bodies_browser.py), so 20,000 icospheres of 80
triangles took ~15 s a frame. viser 1.1.1's own ``lod`` option of ``add_batched_meshes_simple``
cannot help: ``"auto"`` leaves meshes under 256 vertices alone, and explicit ``(distance,
ratio)`` levels are simplified by meshoptimizer with a 2 % error cap that an icosphere never
gets under (measured: 6.4 M triangles drawn for 20,000 spheres of 320 with levels at 25 % and
6 %); its levels also go by distance, not by size on screen.

So every body is drawn as a point (one vertex; :mod:`app.scene.bodies.bodies_layers`), and the bodies
largest on screen are drawn as solids on top, within a triangle budget: the finest mesh for
those a few dozen pixels across, a coarse one for those a few pixels across, nothing for the
rest. :func:`choose_detail` picks them for a camera pose (:class:`ViewPose`); the view calls it
again when the camera stops moving.

Examples:
    >>> pose = ViewPose.looking_at((0, 0, 10), (0, 0, 0), (0, 1, 0), fov=1.0, aspect=1.5, height_px=800)
    >>> pos = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -500.0], [0.0, 0.0, 20.0]])
    >>> fine, coarse = choose_detail(pose, pos, np.ones(3), budget=1000, costs=(320, 80))
    >>> fine.tolist(), coarse.tolist()   # near: fine; far: a point; behind the camera: nothing
    ([0], [])
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.shapes.quadrics import rotation_from_quaternion

__all__ = ["ViewPose", "choose_detail", "FINE_PX", "COARSE_PX", "TRIANGLE_BUDGET"]

FINE_PX = 24.0
"""Radius on screen (pixels) from which a body gets the finest mesh."""
COARSE_PX = 3.0
"""Radius on screen from which a body gets a solid at all (below: its point only)."""
TRIANGLE_BUDGET = 48_000
"""Triangles of solids per frame: ~0.1 s of software WebGL on this machine (bench/bodies_browser.py)."""


@dataclass(frozen=True)
class ViewPose:
    """A perspective camera: where it is, how it is turned, its field of view and image height.

    ``rotation`` maps camera to world coordinates in the OpenCV convention of viser's
    ``CameraHandle.wxyz``: the columns are the image's right, its down and the viewing direction.
    """

    position: np.ndarray
    rotation: np.ndarray
    fov: float
    """Vertical field of view, radians."""
    aspect: float
    """Width over height."""
    height_px: int

    @classmethod
    def looking_at(cls, position: Any, look_at: Any, up: Any, *, fov: float, aspect: float, height_px: int) -> ViewPose:
        """The pose of a camera at ``position`` looking at ``look_at`` with ``up`` up."""
        p = np.asarray(position, dtype=float)
        f = np.asarray(look_at, dtype=float) - p
        f /= np.linalg.norm(f)
        right = np.cross(f, np.asarray(up, dtype=float))
        if np.linalg.norm(right) < 1e-12:  # looking along up: any right will do
            right = np.cross(f, [1.0, 0.0, 0.0] if abs(f[0]) < 0.9 else [0.0, 1.0, 0.0])
        right /= np.linalg.norm(right)
        down = np.cross(f, right)
        return cls(p, np.stack([right, down, f], axis=1), float(fov), float(aspect), int(height_px))

    @classmethod
    def of_camera(cls, cam: Any) -> ViewPose | None:
        """The pose a browser tab reported (``viser.CameraHandle``), or None if it has not yet."""
        try:
            wxyz = np.asarray(cam.wxyz, dtype=float)
            position = np.asarray(cam.position, dtype=float)
            fov, aspect, height = float(cam.fov), float(cam.aspect), int(cam.image_height)
        except Exception:  # noqa: BLE001 - no camera message from the tab yet
            return None
        if not (fov > 0 and aspect > 0 and height > 0 and np.isfinite(wxyz).all() and np.isfinite(position).all()):
            return None
        R = rotation_from_quaternion(wxyz) if wxyz.any() else np.eye(3)
        return cls(position, R, fov, aspect, height)

    @property
    def focal_px(self) -> float:
        """Pixels per unit of (lateral size / depth)."""
        return self.height_px / 2 / math.tan(self.fov / 2)

    def screen_radius(self, positions: np.ndarray, reach: np.ndarray) -> np.ndarray:
        """Radius on screen (pixels) of spheres of radius ``reach`` at ``positions``.

        0 when a sphere is outside the view, inf when the camera is inside it.
        """
        cam = (np.asarray(positions, dtype=float) - self.position) @ self.rotation  # camera frame
        depth = cam[:, 2]
        t = math.tan(self.fov / 2)
        inside = np.einsum("ij,ij->i", cam, cam) <= reach * reach
        in_view = (depth > -reach) & (np.abs(cam[:, 0]) <= np.maximum(depth, 0) * t * self.aspect + 1.5 * reach) & (
            np.abs(cam[:, 1]) <= np.maximum(depth, 0) * t + 1.5 * reach
        )
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(depth > 0, reach * self.focal_px / depth, np.inf)
        r = np.where(in_view, r, 0.0)
        return np.where(inside, np.inf, r)


def choose_detail(
    pose: ViewPose,
    positions: np.ndarray,
    reach: np.ndarray,
    *,
    budget: int = TRIANGLE_BUDGET,
    costs: tuple[int, int],
    eligible: np.ndarray | None = None,
    fine_px: float = FINE_PX,
    coarse_px: float = COARSE_PX,
) -> tuple[np.ndarray, np.ndarray]:
    """The bodies to draw as fine and as coarse solids for this camera (largest on screen first).

    Args:
        pose: the camera.
        positions: (N, 3) centres.
        reach: (N,) radius of each body (its largest semi-axis).
        budget: triangles all solids together may have.
        costs: triangles of one fine and of one coarse solid.
        eligible: (N,) bool, bodies that may be solids (e.g. not hidden); default all.
        fine_px: screen radius from which a body is fine.
        coarse_px: screen radius from which a body is a solid at all.

    Returns:
        Two ascending index arrays (fine, coarse), disjoint, within the budget.
    """
    r = pose.screen_radius(positions, reach)
    ok = r >= coarse_px
    if eligible is not None:
        ok &= eligible
    cand = np.flatnonzero(ok)
    cand = cand[np.argsort(-r[cand], kind="stable")]
    fine = r[cand] >= fine_px
    cost = np.where(fine, costs[0], costs[1])
    take = np.cumsum(cost) <= budget
    return np.sort(cand[take & fine]), np.sort(cand[take & ~fine])
