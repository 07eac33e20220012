"""What the scene runs in worker processes: read a typed motion, analyse a motion.

Module-level functions for :class:`app.workers.WorkerPool` (picklable by reference) that import only ``core`` and
the scene's plain modules, so the pool's fork server preloads this module and a job starts in
milliseconds (a child that had to import viser would take half a second).
"""

from __future__ import annotations

from typing import Any

from core.moving.result import MotionAnalysis
from core.shapes.limits import SERVER

from .motion import MotionError, MotionModel, load_motion

__all__ = ["read_motion_job", "analyse_job"]


def read_motion_job(motion: dict[str, Any]) -> MotionModel | tuple[str, str]:
    """Read a typed motion under :data:`core.shapes.limits.SERVER` and build its exact matrices.

    Returns:
        The loaded model (it pickles with its exact matrices), or (message, field) for a
        MotionError (an exception would lose its field on the way back).
    """
    try:
        model = load_motion(preset=None, motion=motion, limits=SERVER)
        for key, m in (("A", model.A), ("B", model.B)):
            try:
                m.matrix()  # built here, under the budget: never in the process serving the tabs
            except ValueError as e:
                raise MotionError(f"motion of {key}: {e}", key) from None
        return model
    except MotionError as e:
        return str(e), e.field


def analyse_job(A: Any, B: Any, interval: tuple[Any, Any], digits: int = 20) -> MotionAnalysis:
    """``core.analyse`` of two motions on I (runs in a worker; the result pickles as it is).

    Raises:
        ValueError: the motion is not an ellipse/ellipsoid somewhere in I, a denominator vanishes
            there, ... (core's message).
    """
    from core.moving.analysis import analyse

    return analyse(A, B, interval, digits=digits)
