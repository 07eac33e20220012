"""A trajectory audit: certified first contacts of N moving bodies over one step, then a whole file.

Run: ``python examples/04_trajectory_audit.py`` (the file part needs the ``formats`` extra).
Two unit spheres, one moving from x = 4 to x = -2 past one at rest: they touch at t = 1/3. Then
``python -m app audit`` checks a two-frame GSD trajectory in which a ball ends inside a rod
(exit status 3: an overlap).
"""

from __future__ import annotations

import csv
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from core import Relation, sweep_contacts


def one_step() -> None:
    """The first contact of two spheres over t in [0, 1], bracketed and exact."""
    start = np.array([[0.0, 0, 0], [4.0, 0, 0]])
    end = np.array([[0.0, 0, 0], [-2.0, 0, 0]])
    res = sweep_contacts(start, end, np.ones((2, 3)))
    print(f"bodies {res.i[0]} and {res.j[0]} first touch in [{res.t_lo[0]}, {res.t_hi[0]}], exactly t = {res.time(0).decimal(20)}")
    assert res.relation[0] == Relation.TANGENT and res.t_lo[0] <= 1 / 3 <= res.t_hi[0]


def audit_file(folder: Path) -> None:
    """Write a two-frame GSD trajectory and audit it with the command line."""
    import gsd.hoomd

    def frame(x: float) -> gsd.hoomd.Frame:
        f = gsd.hoomd.Frame()
        f.configuration.box = [20, 20, 20, 0, 0, 0]
        f.particles.N = 2
        f.particles.position = [[0, 0, 0], [x, 0, 0]]
        f.particles.types = ["rod", "ball"]
        f.particles.typeid = [0, 1]
        f.particles.type_shapes = [{"type": "Ellipsoid", "a": 2, "b": 0.5, "c": 0.5}, {"type": "Sphere", "diameter": 1}]
        return f

    with gsd.hoomd.open(str(folder / "traj.gsd"), "w") as t:
        for x in (5.0, 2.0):
            t.append(frame(x))
    report = folder / "report.csv"
    done = subprocess.run([sys.executable, "-m", "app", "audit", str(folder / "traj.gsd"), "--between", "--jobs", "1",
                           "--out", str(report), "--quiet"], check=False)
    rows = list(csv.DictReader(report.open()))
    for row in rows:
        print(f"  frame {row['frame']}: {row['i']} - {row['j']} {row['relation']} (t in [{row['t_lo']}, {row['t_hi']}])")
    print("exit status", done.returncode, "(3: an overlap)")
    assert done.returncode == 3 and any(r["relation"] == "overlap" for r in rows)


def main() -> None:
    """One step in Python, then a trajectory file with ``python -m app audit``."""
    one_step()
    with tempfile.TemporaryDirectory() as tmp:
        audit_file(Path(tmp))


if __name__ == "__main__":
    main()
