"""The scene nodes that draw many bodies: points for all, solids for the largest on screen.

Under one frame ``/bodies`` (placed at the centre of the set, so that float32 coordinates keep
their precision far from the origin):

* ``/bodies/points/<group>/<size>``: every body as a point (one vertex, a shaded disc on
  screen), one point cloud per group ("separate" and "contact": separate bodies can be hidden
  without resending anything) and per size class (mean radius, the geometric mean of the
  semi-axes, in classes a factor 2 apart; a point's radius is the middle of its class, within a
  factor 1.42 of the body's mean radius);
* ``/bodies/solids/fine`` and ``/bodies/solids/coarse``: batched meshes (one instance per body)
  of the bodies largest on screen for the tab's camera (:func:`app.scene.bodies.bodies_lod.choose_detail`),
  replaced when the camera stops;
* ``/bodies/network``: optionally, one line segment per contact pair (one batched node);
* ``/bodies/box``: the periodic box, if any.

Every body is in the colour of its worst certified relation. "faded" separate bodies are drawn
in a pale green (opaque: a transparent instanced mesh sorts every instance every frame).

For a later moving-bodies timeline, :meth:`BodyLayers.set_bodies` takes new per-body poses and
colours: it resends the points and re-picks the solids, nothing else.
"""

from __future__ import annotations

import threading
from functools import lru_cache
from typing import Any

import numpy as np

from core import Box, Relation

from ..common.shapes import RELATION_COLORS, unit_disc
from .bodies_lod import TRIANGLE_BUDGET, ViewPose, choose_detail

__all__ = ["BodyLayers", "SEPARATE_MODES", "ROOT", "FINE_NODE", "COARSE_NODE", "NETWORK_NODE", "points_node"]

ROOT = "/bodies"
FINE_NODE = f"{ROOT}/solids/fine"
COARSE_NODE = f"{ROOT}/solids/coarse"
NETWORK_NODE = f"{ROOT}/network"
SEPARATE_MODES = ("shown", "faded", "hidden")
"""How separate bodies are drawn."""
FADE = 0.5
"""How far a faded body's colour goes towards white."""


def points_node(group: str, size_class: int) -> str:
    """Scene name of the point cloud of one group ("separate" / "contact") and size class."""
    return f"{ROOT}/points/{group}/{size_class}"


@lru_cache(maxsize=8)
def _geometry(dim: int, fine: bool) -> tuple[np.ndarray, np.ndarray]:
    """Unit sphere (3D: icosphere of 320 / 80 triangles) or unit disc (2D: 48 / 12 triangles)."""
    if dim == 2:
        return unit_disc(48 if fine else 12)
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=2 if fine else 1)
    return np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.uint32)


def _f32(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float32)


class BodyLayers:
    """The nodes of the bodies of one tab's scene.

    Args:
        scene: the tab's ``viser.SceneApi``.
        dim: 2 or 3.
        positions: (N, 3) centres (2D: z = 0).
        wxyz: (N, 4) unit quaternions.
        scales: (N, 3) semi-axes (2D: third = 1).
        colours: (N, 3) uint8 colour of each body.
        worst: (N,) int8 worst relation of each body (:class:`core.Relation` codes).
        separate: "shown", "faded" or "hidden".
        budget: triangles of solids per frame.
    """

    def __init__(
        self,
        scene: Any,
        dim: int,
        positions: np.ndarray,
        wxyz: np.ndarray,
        scales: np.ndarray,
        colours: np.ndarray,
        worst: np.ndarray,
        *,
        separate: str = "faded",
        budget: int = TRIANGLE_BUDGET,
    ) -> None:
        self.scene = scene
        self.dim = dim
        self.budget = budget
        self.separate = separate
        self.network: Any = None
        self.pose: ViewPose | None = None
        """The camera the solids were last chosen for (None: none yet)."""
        self.fine = np.zeros(0, np.int64)
        """Bodies drawn as fine solids now."""
        self.coarse = np.zeros(0, np.int64)
        """Bodies drawn as coarse solids now."""
        self.version = 0
        """Counts the times the solids were chosen and sent."""
        self._lock = threading.RLock()
        self._solid_nodes: dict[str, Any] = {}
        self._point_nodes: dict[str, Any] = {}
        lo = positions.min(axis=0) if len(positions) else np.zeros(3)
        hi = positions.max(axis=0) if len(positions) else np.zeros(3)
        self.origin = (lo + hi) / 2
        self.frame = scene.add_frame(ROOT, show_axes=False, position=tuple(float(v) for v in self.origin))
        self.set_bodies(positions, wxyz, scales, colours, worst)

    # ------------------------------------------------------------------ bodies
    def set_bodies(self, positions: np.ndarray, wxyz: np.ndarray, scales: np.ndarray, colours: np.ndarray, worst: np.ndarray) -> None:
        """Show the bodies at these poses in these colours (the points now, the solids re-picked)."""
        with self._lock:
            self.positions = np.asarray(positions, dtype=float)
            self.wxyz = np.asarray(wxyz, dtype=float)
            self.scales = np.asarray(scales, dtype=float)
            self.colours = np.asarray(colours, dtype=np.uint8)
            self.worst = np.asarray(worst)
            self.reach = self.scales[:, :2].max(axis=1) if self.dim == 2 else self.scales.max(axis=1)
            self._draw_points()
            self._draw_solids()

    def shown_colours(self) -> np.ndarray:
        """(N, 3) uint8 colours as drawn (separate bodies paler when faded)."""
        c = self.colours
        if self.separate == "faded":
            sep = (self.worst == Relation.SEPARATE)[:, None]
            pale = np.round(c + FADE * (255 - c.astype(float))).astype(np.uint8)
            c = np.where(sep, pale, c)
        return c

    def _draw_points(self) -> None:
        """Send the point clouds of the bodies as they are now.

        A cloud that keeps its number of points gets its points and colours as new values (a
        timeline step: no node is rebuilt in the browser); others are added, and the clouds left
        empty removed.
        """
        N = len(self.positions)
        wanted: dict[str, tuple[np.ndarray, np.ndarray, int, bool]] = {}
        if N:
            mean = np.exp(np.log(np.maximum(self.scales[:, : self.dim], 1e-300)).mean(axis=1))
            size_class = np.floor(np.log2(mean)).astype(np.int64)
            rel = self.positions - self.origin
            if self.dim == 2:  # just under the discs (drawn at z = 0), so a solid is never behind its point
                rel[:, 2] = -1e-3 * float(np.max(self.reach))
            colours = self.shown_colours()
            sep = self.worst == Relation.SEPARATE
            for group, mask in (("separate", sep), ("contact", ~sep)):
                for k in np.unique(size_class[mask]):
                    sel = mask & (size_class == k)
                    shown = not (group == "separate" and self.separate == "hidden")
                    wanted[points_node(group, int(k))] = (_f32(rel[sel]), colours[sel], int(k), shown)
        for name in [n for n in self._point_nodes if n not in wanted]:
            self._point_nodes.pop(name).remove()
        for name, (pts, cols, k, shown) in wanted.items():
            h = self._point_nodes.get(name)
            if h is not None and len(h.points) == len(pts):
                h.points = pts
                h.colors = cols
                h.visible = shown
                continue
            if h is not None:
                h.remove()
            self._point_nodes[name] = self.scene.add_point_cloud(
                name,
                pts,
                cols,
                point_size=float(2.0 ** (k + 0.5)),  # viser draws a point 2 * point_size across
                point_shape="circle",
                point_shading="gradient" if self.dim == 3 else "flat",
                precision="float32",
                visible=shown,
            )

    # ------------------------------------------------------------------ solids
    def costs(self) -> tuple[int, int]:
        """Triangles of one fine and of one coarse solid."""
        return len(_geometry(self.dim, True)[1]), len(_geometry(self.dim, False)[1])

    def set_pose(self, pose: ViewPose | None) -> None:
        """Choose and send the solids for this camera (None: keep the last camera)."""
        with self._lock:
            if pose is not None:
                self.pose = pose
            self._draw_solids()

    def _draw_solids(self) -> None:
        if self.pose is None:
            fine = coarse = np.zeros(0, np.int64)
        else:
            eligible = None if self.separate != "hidden" else self.worst != Relation.SEPARATE
            fine, coarse = choose_detail(self.pose, self.positions, self.reach, budget=self.budget, costs=self.costs(), eligible=eligible)
        colours = self.shown_colours()
        for name, idx, fine_mesh in ((FINE_NODE, fine, True), (COARSE_NODE, coarse, False)):
            old = self._solid_nodes.pop(name, None)
            if len(idx) == 0:
                if old is not None:
                    old.remove()
                continue
            vertices, faces = _geometry(self.dim, fine_mesh)
            self._solid_nodes[name] = self.scene.add_batched_meshes_simple(
                name,
                vertices,
                faces,
                batched_wxyzs=_f32(self.wxyz[idx]),
                batched_positions=_f32(self.positions[idx] - self.origin),
                batched_scales=_f32(self.scales[idx]),
                batched_colors=colours[idx],
                lod="off",
                side="double" if self.dim == 2 else "front",
                cast_shadow=False,
                receive_shadow=False,
            )
        self.fine, self.coarse = fine, coarse
        self.version += 1

    # ------------------------------------------------------------------ options
    def set_separate(self, mode: str) -> None:
        """Draw separate bodies "shown", "faded" or "hidden"."""
        if mode not in SEPARATE_MODES:
            raise ValueError(f"separate bodies: expected one of {', '.join(SEPARATE_MODES)}, got {mode!r}")
        with self._lock:
            before, self.separate = self.separate, mode
            if "faded" in (before, mode):  # colours change: resend the points
                self._draw_points()
            else:
                for name, h in self._point_nodes.items():
                    if name.startswith(f"{ROOT}/points/separate/"):
                        h.visible = mode != "hidden"
            self._draw_solids()

    def set_network(self, shown: bool, segments: np.ndarray | None = None, colours: np.ndarray | None = None) -> None:
        """Show or hide the contact network: ``segments`` (M, 2, 3) world points, ``colours`` (M, 3)."""
        with self._lock:
            if shown and self.network is None:
                if segments is None or colours is None:
                    raise ValueError("the contact network needs its segments the first time it is shown")
                pts = _f32(np.asarray(segments, dtype=float) - self.origin)
                cols = np.repeat(np.asarray(colours, dtype=np.uint8)[:, None, :], 2, axis=1)
                self.network = self.scene.add_line_segments(NETWORK_NODE, pts, cols, thickness=1.5, thickness_units="screen")
            elif self.network is not None:
                self.network.visible = shown

    def add_box(self, lo: np.ndarray, box: Box) -> None:
        """Draw the periodic box with its lower corner at ``lo`` (world); a tilted box as its parallelepiped."""
        d = box.dimensions
        vectors = np.zeros((3, 3))
        vectors[:d, :d] = box.vectors  # columns a1, a2[, a3]
        corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in ((0, 1) if d == 3 else (0,))], dtype=float)
        pts = lo + corners @ vectors.T - self.origin
        segs = [(a, b) for a in range(len(pts)) for b in range(a + 1, len(pts)) if np.count_nonzero(corners[a] != corners[b]) == 1]
        self.scene.add_line_segments(
            f"{ROOT}/box", _f32(np.array([[pts[a], pts[b]] for a, b in segs])), (90, 90, 90), thickness=1.5, thickness_units="screen"
        )

    def expected_in_browser(self) -> dict[str, int]:
        """Scene name -> instances (solids) or points (point clouds) of every visible node drawn."""
        with self._lock:
            out = {name: int(len(h.batched_positions)) for name, h in self._solid_nodes.items()}
            out.update({name: int(len(h.points)) for name, h in self._point_nodes.items() if h.visible})
            return out

    def drawn(self) -> dict[str, int]:
        """What is drawn now: bodies as fine / coarse solids, as points, and triangles of solids."""
        f, c = self.costs()
        hidden = int(np.count_nonzero(self.worst == Relation.SEPARATE)) if self.separate == "hidden" else 0
        return {"fine": len(self.fine), "coarse": len(self.coarse), "points": len(self.positions) - hidden,
                "triangles": len(self.fine) * f + len(self.coarse) * c}


def relation_colour_rows(relation: np.ndarray) -> np.ndarray:
    """(M, 3) uint8 colour of each contact (tangent amber, overlap red, other grey)."""
    table = {int(Relation.TANGENT): RELATION_COLORS["tangent"], int(Relation.OVERLAP): RELATION_COLORS["overlap"]}
    out = np.full((len(relation), 3), 150, dtype=np.uint8)
    for code, col in table.items():
        out[np.asarray(relation) == code] = col
    return out
