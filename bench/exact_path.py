"""The exact path's cost per escalated pair: what a stack of tangent or near-tangent pairs pays.

``python -m bench.exact_path`` prints a markdown table: ``classify`` (adaptive) on near-tangent
pairs at a relative gap of 1e-15 (over 99 % escalated to exact arithmetic), microseconds per pair,
best of 5 on one core; and ``contacts`` on 9,702 touching unit-diameter spheres on a lattice
(27,741 exact tangencies: the API's hostile heavy request), seconds, best of 3, every core.
"""

from __future__ import annotations

import time

import numpy as np

import core
from bench import datasets as D


def _best(fn, repeat: int) -> float:  # type: ignore[no-untyped-def]
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def lattice_spheres() -> np.ndarray:
    """9,702 spheres of radius 0.5 at the integer points of a 21 x 21 x 22 box: each touches its neighbours."""
    c = np.array(np.meshgrid(np.arange(21.0), np.arange(21.0), np.arange(22.0), indexing="ij")).reshape(3, -1).T
    return core.bodies_from_axes(c, np.full((len(c), 3), 0.5), np.tile([1.0, 0.0, 0.0, 0.0], (len(c), 1)))


def main() -> None:
    print("| workload | cost |\n|---|---:|")
    core.set_threads(1)
    for dim in (3, 2):
        ds = D.near_tangent_pairs(dim, 200, gap=1e-15, sign=1, seed=5)
        A, B = np.tile(ds.A, (5, 1, 1)), np.tile(ds.B, (5, 1, 1))
        st = core.Stats()
        core.classify(A, B, stats=st)
        assert st.escalated >= 0.99 * len(A), st
        dt = _best(lambda A=A, B=B: core.classify(A, B), 5)
        print(f"| adaptive, near-tangent {dim}D (gap 1e-15, {st.escalated} of {len(A)} escalated) | {dt * 1e6 / len(A):.1f} us/pair |")
    core.set_threads(None)
    Q = lattice_spheres()
    counts = core.contacts(Q).counts
    assert counts["tangent"] == 27_741, counts
    dt = _best(lambda: core.contacts(Q), 3)
    print(f"| contacts, 9,702 touching spheres (27,741 exact tangencies), every core | {dt:.2f} s |")


if __name__ == "__main__":
    main()
