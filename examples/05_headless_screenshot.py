"""A headless screenshot: the scene in a headless browser, Example 29 at its first tangency.

Run: ``python examples/05_headless_screenshot.py [OUT.png]`` (needs the ``screenshot`` extra and
Debian's chromium). The picture waits until the browser shows exactly the tab's state: both shapes
at their poses, in their certified colour.
"""

from __future__ import annotations

import sys
from pathlib import Path

from app.scene import SceneConfig
from app.screenshot import HeadlessScene


def main(argv: list[str] | None = None) -> None:
    """Draw Example 29 at its first event and save the PNG."""
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0] if args else "example-29-tangent.png")
    config = SceneConfig.from_dict({"preset": "example-29", "event": 1})
    with HeadlessScene(config, width=800, height=500, sphere_subdivisions=3) as hs:
        hs.save(out)
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    print(f"wrote {out} ({len(data) // 1024} kB)")


if __name__ == "__main__":
    main()
