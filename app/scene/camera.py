"""Aiming a tab's camera at a box of the scene, leaving room for the GUI panel."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["aim_at_box", "PANEL_FREE"]

PANEL_FREE = 0.62
"""Fraction of the page width left of the GUI panel (which covers about the right third)."""


def aim_at_box(cam: Any, lo: np.ndarray, hi: np.ndarray, dim: int, *, fill: float = 0.9, view: Any = (0.3, -1.05, 0.6)) -> None:
    """Point ``cam`` (a viser camera handle) at the box [lo, hi] so that it fills the free page.

    Args:
        cam: ``client.camera``.
        lo: lower corner (3,).
        hi: upper corner (3,).
        dim: 2 (look down the z axis, y up) or 3 (``view`` direction, z up).
        fill: distance factor (larger: the box looks smaller).
        view: 3D direction from the box's centre to the camera.
    """
    centre = (np.asarray(lo, dtype=float) + np.asarray(hi, dtype=float)) / 2
    radius = max(float(np.linalg.norm(np.asarray(hi, dtype=float) - np.asarray(lo, dtype=float))) / 2, 1e-3)
    try:
        fov, aspect = float(cam.fov), float(cam.aspect)
    except Exception:  # noqa: BLE001 - camera state not known yet: typical values
        fov, aspect = 1.3, 1.5
    half_h = math.tan(fov / 2)
    dist = fill * radius / (half_h * min(1.0, PANEL_FREE * aspect))
    shift = (0.5 - PANEL_FREE / 2) * 2 * dist * half_h * aspect  # aim right of the box: it sits left
    if dim == 2:
        cam.up_direction = (0.0, 1.0, 0.0)
        x = float(centre[0]) + shift
        cam.position = (x, float(centre[1]) - 1e-3, dist)
        cam.look_at = (x, float(centre[1]), 0.0)
        return
    cam.up_direction = (0.0, 0.0, 1.0)
    v = np.asarray(view, dtype=float)
    v /= np.linalg.norm(v)
    right = np.cross(-v, np.array([0.0, 0.0, 1.0]))
    right /= np.linalg.norm(right)
    # viser keeps the orientation when the position is set: position first, then look_at
    cam.position = tuple(float(x) for x in centre + dist * v + shift * right)
    cam.look_at = tuple(float(x) for x in centre + shift * right)
