"""The scene's lighting: plain default lights, no environment map and no shadow maps.

No shape casts a shadow (a shadow would hide the overlap a teacher points at), so the default
lights' cascaded shadow maps drew nothing visible. They still cost a shadow pass and a
per-pixel lookup every frame: in software WebGL (headless Chromium) that was half of each
frame (91 -> 47 ms at 1200x800). The HDRI environment arrives seconds after the first frame
and changes the colours a screenshot catches.
"""

from __future__ import annotations

import viser

__all__ = ["light_scene"]


HEMISPHERE = ((255, 255, 255), (150, 150, 165), 1.6)
"""Sky colour, ground colour and intensity of the hemisphere light (issue 55: the default lights alone
left the lower half of every solid black; from below, a solid is now lit grey-blue, not black)."""


def light_scene(scene: viser.SceneApi) -> None:
    """Configure ``scene`` (a tab's or the shared one): z up, default lights and a hemisphere light, no shadows, no HDRI."""
    scene.configure_environment_map(hdri=None)
    scene.configure_default_lights(enabled=True, cast_shadow=False)
    scene.set_up_direction("+z")
    sky, ground, intensity = HEMISPHERE
    # three.js takes a hemisphere light's position as its sky direction: +z, the scene's up
    scene.add_light_hemisphere("/lights/hemisphere", sky_color=sky, ground_color=ground, intensity=intensity, position=(0.0, 0.0, 1.0))
