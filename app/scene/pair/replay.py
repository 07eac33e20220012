"""A self-contained HTML replay of a scene: a motion played through, for slides and web pages.

:func:`replay_html` loads a configuration into a private scene (no browser, no port to open),
records what the 3D view shows with viser's scene serializer while t sweeps the window of the
motion, and returns viser's standalone player with the recording inside (one HTML file, no
server). Each relation shows as it does in the live scene (colours, labels "B · tangent", the
contact point); every event is shown exactly (the certified tangency at alpha_k, held for a
moment), and a caption above the shapes names t and the certified relation. A static
configuration gives a still scene.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..common.camera import Framing, extent_of
from ..common.markers import vec3
from ..common.mesh_detail import SPHERE_SUBDIVISIONS
from ..common.state import SceneConfig
from .analysis import AnalysisCache
from .session import Session

__all__ = ["replay_html"]


class _InitialCamera:
    """Adapter: :meth:`app.scene.common.camera.Framing.aim` on viser's initial camera of a server."""

    fov: float
    aspect: float
    # set through __setattr__ on viser's initial camera (written by Framing.aim, never read here)
    position: tuple[float, float, float] | np.ndarray
    look_at: tuple[float, float, float] | np.ndarray
    up_direction: tuple[float, float, float] | np.ndarray

    def __init__(self, initial: Any) -> None:
        self._c = initial
        self.fov = float(initial.fov)
        self.aspect = 16 / 9

    def __setattr__(self, name: str, value: Any) -> None:
        if name in ("position", "look_at"):
            setattr(self._c, name, value)
        elif name == "up_direction":
            self._c.up = value
        else:
            object.__setattr__(self, name, value)


def replay_html(
    config: SceneConfig, *, seconds: float = 12.0, frames: int = 240, event_pause: float = 1.2, timeout: float = 120.0,
    sphere_subdivisions: int = SPHERE_SUBDIVISIONS,
) -> str:
    """The standalone HTML replay of ``config`` (a motion swept over its window, or a still scene).

    Args:
        config: what to show (a preset, a typed motion, static shapes).
        seconds: playing time of the sweep (events' pauses come on top).
        frames: time steps recorded over the window.
        event_pause: seconds each event is held.
        timeout: seconds to wait for the analysis.
        sphere_subdivisions: of the icosphere the solids are drawn with
            (:data:`app.scene.common.mesh_detail.SPHERE_SUBDIVISIONS_RANGE`): fewer make a smaller file
            that plays faster without a GPU.

    Raises:
        ValueError: the configuration's motion cannot be read or analysed.
        TimeoutError: the analysis took longer than ``timeout``.
    """
    import viser

    config = SceneConfig.from_dict({**config.to_dict(), "gizmos": False})
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    cache = AnalysisCache()
    try:
        s = Session(server, config, cache=cache, sphere_subdivisions=sphere_subdivisions)
        if not s.ready.wait(timeout):
            raise TimeoutError("the analysis of the motion did not finish")
        st = s.state
        if st.motion is not None and st.analysis is None:
            raise ValueError(next(iter(st.errors.values()), "the motion could not be analysed"))
        if st.motion is None and st.errors:
            raise ValueError(next(iter(st.errors.values())))
        an = st.analysis
        window = an.window if an is not None else None
        pts = st.motion.extent_points(window) if st.motion is not None and window is not None else \
            extent_of((sh.float_pose() for sh in st.shapes.values()), st.dim)
        framing = Framing(pts, st.dim)
        framing.grid(server.scene)
        framing.aim(_InitialCamera(server.initial_camera), free=1.0)  # no panel over the player
        top = framing.hi + np.array([0.0, 0.0, 0.25 * framing.radius])
        if st.dim == 2:
            top = np.array([float(framing.centre[0]), float(framing.hi[1] + 0.15 * framing.radius), 0.0])
        caption = server.scene.add_label("/replay/caption", "", position=vec3(top), anchor="bottom-center")
        rec = server.get_scene_serializer()
        if an is None:
            caption.text = f"static shapes · {(st.relation or 'unknown').upper()}"
            rec.insert_sleep(1.0)
            return rec.as_html()
        lo, hi = window  # type: ignore[misc]
        pending = [e for e in an.events if lo <= e.t <= hi]
        dt = seconds / max(frames - 1, 1)
        for t in np.linspace(lo, hi, frames):
            while pending and pending[0].t <= t:  # the event itself, exactly, before passing it
                ev = pending.pop(0)
                s.jump_to_event(ev.k)
                caption.text = f"t = α{ev.k} {ev.shown} · {ev.relation.upper()} (exact)"
                rec.insert_sleep(event_pause)
            rel = s.set_t(float(t))
            caption.text = f"t = {t:.4f} · {(rel or 'unknown').upper()}"
            rec.insert_sleep(dt)
        return rec.as_html()
    finally:
        s_ = locals().get("s")
        if s_ is not None:
            s_.close()
        server.stop()
        cache.shutdown()
