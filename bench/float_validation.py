"""method="float" on the static benchmark's hard sets: exact validation of every undecided pair
(the policy before 91b630c, with today's exact validation) against exact validation only where
the filter's validity proof does not hold.

``python -m bench.float_validation`` prints a markdown table: pairs/s of the tiled stack
(:func:`bench.static.run_method`, quick sizes, one core), near-tangent rows summed over the gaps;
both policies run in the same process on the same data and must give the same answers.
"""

from __future__ import annotations

import numpy as np

import core.fixed.classify as C
from bench import datasets as D
from bench import static


def _never(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The policy before: no pair's validity taken from the filter (every undecided pair validated exactly)."""
    return np.zeros(len(a), dtype=bool)


def main() -> None:
    static.warm_up()
    real = C.certified_valid
    print("| data set | pairs | before pairs/s | after pairs/s | speed-up | undecided | wrong |\n|---|---:|---:|---:|---:|---:|---:|")
    try:
        for dim in (2, 3):
            groups = [(ds.name, [ds]) for ds in [D.tangent_pairs(dim, 300, seed=0)] +
                      [D.extreme_pairs(dim, 500, kind=k, seed=0) for k in ("mixed-sizes", "aspect-1e6", "centres-1e6")]]
            for sign in (1, -1):
                groups.append((f"near {'+' if sign > 0 else '-'} (all gaps) {dim}D",
                               [D.near_tangent_pairs(dim, 200, gap=10.0**-e, sign=sign, seed=0) for e in D.GAP_EXPONENTS]))
            for name, group in groups:
                res = {}
                for label, policy in (("before", _never), ("after", real)):
                    C.certified_valid = policy
                    secs, und, wrong, timed = 0.0, 0, 0, 0
                    for d in group:
                        r = static.run_method("float", d, quick=True)
                        assert r is not None
                        secs += r.timed_pairs / r.pairs_per_s
                        timed += r.timed_pairs
                        und += r.undecided
                        wrong += r.wrong
                    res[label] = (timed / secs, und, wrong, sum(len(d) for d in group))
                b, a = res["before"], res["after"]
                assert (b[1], b[2]) == (a[1], a[2]), name  # the same answers
                print(f"| {name} | {a[3]} | {b[0] / 1e3:,.1f} k | {a[0] / 1e3:,.1f} k | {a[0] / b[0]:,.0f}x | {a[1]} | {a[2]} |", flush=True)
    finally:
        C.certified_valid = real


if __name__ == "__main__":
    main()
