"""A motion: the paper's Example 29, every event exactly, and the relation at any t.

Run: ``python examples/02_motion.py``. Two ellipsoids move on straight lines for t in [0, 1];
they touch at t = (12 - 2*sqrt(2))/17, overlap, touch again and part.
"""

from __future__ import annotations

from core import Relation, analyse, preset


def main() -> None:
    """Analyse Example 29 and print its events, intervals and the sign table's rules."""
    p = preset("example-29")
    r = analyse(p["A"], p["B"], interval=p["interval"], digits=15)
    for ev in r.events:
        print(f"event at t = {ev.value}: {ev.relation} ({ev.kind})")
    print("intervals:", [str(i.relation) for i in r.intervals])
    for row in r.sign_table:
        print(f"  {row.rule}")
    assert [ev.relation for ev in r.events] == [Relation.TANGENT, Relation.TANGENT]
    assert r.relation_at("1/2") == Relation.SEPARATE and r.relation_at("7/10") == Relation.OVERLAP


if __name__ == "__main__":
    main()
