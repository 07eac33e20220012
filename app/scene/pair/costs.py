"""Server cost of the two hot paths without a browser: one drag update and one t-step."""

from __future__ import annotations

import time

import numpy as np

from ..common.state import SceneConfig
from .session import Session

__all__ = ["measure_update_costs"]


def measure_update_costs(repeats: int = 200, *, preset: str | None = "example-29") -> dict[str, float]:
    """Server time of one drag update and one t-step, and messages each queues (no browser).

    Starts a private ``ViserServer`` on a free loopback port, builds a :class:`Session` on its
    shared scene, times :meth:`Session.apply_drag` and :meth:`Session.set_t`.

    Returns:
        {"drag_ms": median ms per drag, "drag_messages": messages per drag,
         "t_step_ms"/"t_step_messages": per t-step as the slider does it (panels coalesced to
         20 Hz, their messages included when the timer fires), "t_step_full_ms"/
         "t_step_full_messages": a jump (event button, typed t): readout, bar and t box at once}.
    """
    import viser

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        out: dict[str, float] = {}
        if preset is not None:
            s = Session(server, SceneConfig(preset=preset), count_messages=True)
            s.ready.wait(120)
            lo, hi = s.state.analysis.window if s.state.analysis else (0.0, 1.0)
            for key, defer in (("t_step", True), ("t_step_full", False)):
                times = []
                m0 = s.messages
                for i in range(repeats):
                    t = lo + (hi - lo) * (i + 0.5) / repeats
                    t0 = time.perf_counter()
                    s.set_t(t, defer_panels=defer)
                    times.append(time.perf_counter() - t0)
                out[f"{key}_ms"] = float(np.median(times) * 1e3)
                out[f"{key}_messages"] = (s.messages - m0) / repeats
            s.close()
        s = Session(server, SceneConfig(preset=None), count_messages=True)
        times = []
        m0 = s.messages
        for i in range(repeats):
            x = 2.0 + 2.0 * i / repeats
            t0 = time.perf_counter()
            s.apply_drag("B", (x, 1.0, 0.2), (1.0, 0.0, 0.0, 0.0))
            times.append(time.perf_counter() - t0)
        out["drag_ms"] = float(np.median(times) * 1e3)
        out["drag_messages"] = (s.messages - m0) / repeats
        s.close()
        return out
    finally:
        server.stop()
