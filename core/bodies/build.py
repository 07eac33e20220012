"""Many bodies from their parameters: the matrices of N ellipses or ellipsoids at once.

:func:`bodies_from_axes` is :func:`core.shapes.quadrics.quadric_from_axes` for N shapes: the float
matrices are built by the one vectorised routine (:func:`core.shapes.quadrics.quadrics_from_axes`),
bit for bit what the one-shape function gives, so a body found in a packing and the same shape
opened alone (the scene's two-body view, the API) are the same matrix with the same certified
label.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from ..options import ON_INVALID, check_choice
from ..shapes.quadrics import _axes_arrays, axes_row_errors, quadrics_from_axes

__all__ = ["bodies_from_axes", "matrices_and_errors"]


def bodies_from_axes(
    centers: Any,
    semi_axes: Any,
    orientations: Any = None,
    *,
    on_invalid: Literal["raise", "mark"] = "raise",
) -> np.ndarray:
    """Matrices (N, d+1, d+1) of N ellipses (d = 2) or ellipsoids (d = 3) from their parameters.

    Args:
        centers: (N, d) floats.
        semi_axes: (N, d) positive floats.
        orientations: 3D: (N, 4) unit or non-unit quaternions wxyz; 2D: (N,) angles in radians
            (or (N, 4) quaternions (w, 0, 0, z)); None: axis-aligned.
        on_invalid: "raise" a ValueError naming the first bad row, or "mark": such rows become
            NaN matrices, which :func:`core.bodies.contacts` reports as invalid bodies (the
            reasons: :func:`core.shapes.quadrics.axes_row_errors`, and
            :func:`core.shapes.quadrics.unrepresentable` for a shape no float64 matrix holds).

    Returns:
        float64 array (N, d+1, d+1); row k equals ``quadric_from_axes(centers[k], semi_axes[k],
        orientations[k])`` bit for bit.

    Raises:
        ValueError: wrong array shapes, an unknown ``on_invalid``, or (with "raise") a row with a
            non-finite number, a semi-axis <= 0 or a zero quaternion, or one no float64 matrix holds.

    Examples:
        >>> Q = bodies_from_axes([[0, 0], [2, 0]], [[1, 1], [1, 1]], [0.0, 0.0])
        >>> Q.shape
        (2, 3, 3)
        >>> bodies_from_axes([[0, 0], [2, 0]], [[1, 1], [1, -1]])
        Traceback (most recent call last):
        ...
        ValueError: row 1: semi-axes must be positive, got [1.0, -1.0]
        >>> bool(np.isnan(bodies_from_axes([[0, 0], [2, 0]], [[1, 1], [1, -1]], on_invalid="mark")[1]).all())
        True
    """
    check_choice(on_invalid, ON_INVALID, "on_invalid")
    if on_invalid == "raise":
        return quadrics_from_axes(centers, semi_axes, orientations)
    return matrices_and_errors(centers, semi_axes, orientations)[0]


def matrices_and_errors(centers: Any, semi_axes: Any, orientations: Any = None) -> tuple[np.ndarray, dict[int, str]]:
    """(matrices, row -> reason): :func:`bodies_from_axes` with ``on_invalid="mark"`` and its reasons, checked once.

    The parameters are checked once (:func:`core.shapes.quadrics.axes_row_errors`) and the
    builder told so: :class:`core.Bodies` keeps both, so a trial move's parameters are not
    checked again by the later stages (a third of a batch of trial moves' time was the checks).

    Examples:
        >>> Q, errors = matrices_and_errors([[0, 0], [2, 0]], [[1, 1], [1, -1]])
        >>> bool(np.isnan(Q[1]).all()), errors
        (True, {1: 'semi-axes must be positive, got [1.0, -1.0]'})
    """
    c, r, o = _axes_arrays(centers, semi_axes, orientations)
    errors = axes_row_errors(c, r, o)
    if not errors:
        return quadrics_from_axes(c, r, o, unrepresentable_rows="nan", checked=True), errors
    # bad rows get harmless stand-in parameters, then NaN: one builder for every row
    bad = np.array(sorted(errors))
    c, r = c.copy(), r.copy()
    c[bad], r[bad] = 0.0, 1.0
    if o is not None:
        o = o.copy()
        o[bad] = 0.0 if o.ndim == 1 else (1.0, 0.0, 0.0, 0.0)
    out = quadrics_from_axes(c, r, o, unrepresentable_rows="nan", checked=True)
    out[bad] = np.nan
    return out, errors
