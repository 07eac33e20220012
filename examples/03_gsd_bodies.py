"""N bodies from a GSD file: every pair that touches or overlaps, across the periodic box's faces.

Run: ``python examples/03_gsd_bodies.py [FILE.gsd]`` (needs the ``formats`` extra). Without a file
it writes a small HOOMD frame first: a rod, a ball at its tip, and two balls touching through the
box's face.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from app.readers import read_bodies
from core import Relation, contacts


def write_frame(path: Path) -> None:
    """Write a one-frame GSD trajectory of four ellipsoids in a periodic box of side 10."""
    import gsd.hoomd

    frame = gsd.hoomd.Frame()
    frame.configuration.box = [10, 10, 10, 0, 0, 0]
    frame.particles.N = 4
    frame.particles.position = [[0, 0, 0], [2.5, 0, 0], [4.5, 3, 0], [-4.5, 3, 0]]
    frame.particles.orientation = [[1, 0, 0, 0]] * 4
    frame.particles.types = ["rod", "ball"]
    frame.particles.typeid = [0, 1, 1, 1]
    frame.particles.type_shapes = [{"type": "Ellipsoid", "a": 2, "b": 0.5, "c": 0.5}, {"type": "Sphere", "diameter": 1}]
    with gsd.hoomd.open(str(path), "w") as trajectory:
        trajectory.append(frame)


def main(argv: list[str] | None = None) -> None:
    """Read the last frame of a GSD file (or of a frame written here) and list its contacts."""
    args = sys.argv[1:] if argv is None else argv
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(args[0]) if args else Path(tmp) / "frame.gsd"
        if not args:
            write_frame(path)
        bodies = read_bodies(str(path), frame=-1)
        res = contacts(bodies)
        print(f"{len(bodies)} bodies, box {bodies.box}")
        images = res.image if res.image is not None else [(0, 0, 0)] * len(res.i)  # None in open space
        for i, j, rel, image in zip(res.i, res.j, res.relation, images, strict=True):
            print(f"  {i} - {j}: {Relation(rel).name}, image {tuple(int(k) for k in image)}")
        if not args:
            assert [(int(i), int(j)) for i, j in zip(res.i, res.j, strict=True)] == [(0, 1), (2, 3)]


if __name__ == "__main__":
    main()
