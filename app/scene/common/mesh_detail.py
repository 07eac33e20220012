"""How finely the scene draws a solid (the icosphere's subdivisions), and how large (no viser: the command line reads it).

The drawn mesh of an ellipsoid is a unit icosphere scaled by the semi-axes (:mod:`app.scene.common.shapes`).
Its vertices lie on the sphere, so at any detail a drawing lies inside its shape and two tangent
shapes are never drawn interpenetrating; the detail sets how large the gap drawn at a contact may
be, and what a frame costs where WebGL runs in software.
"""

from __future__ import annotations

__all__ = ["SPHERE_SUBDIVISIONS", "SPHERE_SUBDIVISIONS_RANGE", "check_sphere_subdivisions", "DRAWABLE"]

DRAWABLE = 10**12
"""Largest |coordinate| and semi-axis (and 1 / smallest semi-axis) the scene draws: entries of a
shape's matrix stay below 1e48 and the floats of drawing (poses, camera, readout) finite. A shape
typed in the scene is refused outside it (:func:`app.scene.pair.control_shapes.drawable`); a body of a
file is listed but not drawn (:class:`app.scene.bodies.model.BodiesModel`)."""

SPHERE_SUBDIVISIONS = 5
"""Icosphere subdivisions of a shape's mesh: 20,480 faces, whose planes lie within
:data:`app.scene.common.shapes.MESH_GAP` of the unit sphere (``tests/test_scene.py`` proves the bound)."""

SPHERE_SUBDIVISIONS_RANGE = range(1, 7)
"""Subdivisions a scene accepts (``serve --sphere-subdivisions``): k gives 20 * 4^k faces. Fewer
draw faster where WebGL runs in software (a frame of Example 29 at 1000 x 720, half the pixel
ratio, SwiftShader on a 2-core machine: ~60 ms of CPU with 5, ~23 ms with 3), at the cost of a
larger gap between tangent shapes; only the default is within ``MESH_GAP``."""


def check_sphere_subdivisions(subdivisions: int) -> int:
    """``subdivisions`` if it is in :data:`SPHERE_SUBDIVISIONS_RANGE` (else a ValueError saying so)."""
    if isinstance(subdivisions, bool) or not isinstance(subdivisions, int) or subdivisions not in SPHERE_SUBDIVISIONS_RANGE:
        lo, hi = SPHERE_SUBDIVISIONS_RANGE[0], SPHERE_SUBDIVISIONS_RANGE[-1]
        raise ValueError(f"sphere subdivisions must be an integer in {lo}..{hi}, not {subdivisions!r}")
    return subdivisions
