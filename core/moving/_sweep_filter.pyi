"""Types of the compiled extension core.moving._sweep_filter (core/moving/_sweep_module.c, built by setup.py)."""

from typing import Any, Final

NEVER: Final[int]
CONTACT: Final[int]
OVERLAP_AT_START: Final[int]
UNDECIDED: Final[int]

def sweep_pairs(
    d: int,
    bodies: Any,
    pi: Any,
    pj: Any,
    shift: Any | None,
    status: Any,
    t_lo: Any,
    t_hi: Any,
    iterations: Any,
    /,
) -> None:
    """The certified first-contact filter on the M pairs (pi[k], pj[k]) of the rows of bodies.

    bodies: float64 (N, 17) in 3D or (N, 10) in 2D (rows c0, c1, r, q0, q1:
    core.moving.linear.LinearMotions.packed); pi, pj: int64 (M,) in [0, N); shift: float64 (M, d)
    added to pj's body, or None; outputs, written: status int8 (M,), t_lo and t_hi float64 (M,),
    iterations int32 (M,) (core.moving.sweep_filter.FilterResult). Every array C-contiguous (the
    buffer protocol), the outputs apart from the inputs; TypeError or ValueError otherwise,
    MemoryError without memory for the workspace. The GIL is released while the kernel runs.
    """
