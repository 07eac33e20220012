"""Many bodies in a real browser: frame time while orbiting, "Open pair", screenshots.

Random ellipsoids (``bench.bodies_data.random_bodies``, packing fraction 0.3, seed 1) are shown
with ``python -m app serve --bodies`` 's view (:mod:`app.scene.bodies.bodies_view`) in headless Debian
Chromium (software WebGL, SwiftShader), 1200 x 800 pixels:

* **first picture**: server and browser start until every body is drawn (points, and the
  solids chosen for the tab's camera);
* **orbit frame**: the camera turned by 0.05 rad in the page (camera-controls, as a drag does),
  then the time until the next frame is rendered and finished (a 1-pixel ``readPixels``);
  median and worst of several steps, while the server re-picks the solids as the camera moves.
  Again with the contact network shown (a line per contact pair);
* **open pair**: the click on "Open pair" until the two-body view shows both shapes in the
  certified colour with the readout's word (and that word is checked against ``core.contacts``);
* **back**: the click on "← All bodies" until every body is drawn again;
* **screenshot --bodies**: the whole command (read the file, search the contacts, browser,
  picture).

Moving bodies (``serve --bodies START --to END``, :mod:`app.scene.bodies.sweep_view`; random moving,
turning ellipsoids ``bench.sweep_data.moving_bodies``, seed 1):

* **model**: both files read and swept (forward, and backward for the last contacts);
* **t-step (server)**: ``SweepTimeline.set_time``: the bodies' poses and the colours the sweep
  decides at t (:meth:`SweepModel.moment`), and the points and solids sent; then **frame**: from
  the step until the browser has the new points and has rendered a frame with them;
* **colours certified**: until exact arithmetic has decided every pair a colour needs at t (the
  pairs between their first and last contact), with how many pairs that was.

Target (issue 22): 100,000 bodies orbit at interactive rates; "Open pair" < 1 s.
Run: ``python -m bench.bodies_browser [--quick] [--sizes N,...] [--moving N,...] [--json]`` (imports are light: a worker process
re-imports the main module).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

__all__ = ["run_bodies_browser", "format_bodies_browser", "run_in_subprocess", "target_rows", "TARGETS", "measure_moving"]

TARGETS = {"orbit frame ms": 500.0, "open pair ms": 1000.0}
"""An orbit frame under 0.5 s (2 frames a second on a loaded 2-core machine without a GPU) is
what we call interactive here; "Open pair" under 1 s (issue 22)."""

ORBIT_JS = """async (steps) => {
  const m = window.__viserMutable, info = window.__viserTestpoints.rendererInfo;
  const gl = m.canvas.getContext('webgl2');
  const px = new Uint8Array(4);
  const out = [];
  for (let k = 0; k < steps; k++) {
    const f0 = info.render.frame;
    const t0 = performance.now();
    m.cameraControl.rotate(0.05, 0.0, false);
    while (info.render.frame <= f0) await new Promise((r) => requestAnimationFrame(r));
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    out.push(performance.now() - t0);
  }
  return out;
}"""
"""Turn the camera ``steps`` times; the milliseconds from each turn to its frame finished."""


def _write_bodies(n: int, folder: Path) -> Path:
    from app.bodyfiles import write_bodies_csv
    from bench.bodies_data import random_bodies

    b = random_bodies(n, seed=1)
    path = folder / f"random-{n}.csv"
    write_bodies_csv(path, b.centers, b.semi_axes, b.orientations)
    return path


def _orbit(page: Any, steps: int) -> list[float]:
    return [float(v) for v in page.evaluate(ORBIT_JS, steps)]


def measure(n: int, folder: Path, *, steps: int = 8) -> dict[str, Any]:
    """All the measurements for n random bodies (one server and one browser)."""
    from app.scene.bodies.bodies_view import load_model
    from app.scene.common.state import SceneConfig
    from app.screenshot import _DRAWN_JS, HeadlessScene
    from core import Relation

    path = _write_bodies(n, folder)
    t0 = time.perf_counter()
    model = load_model(str(path))
    out: dict[str, Any] = {"bodies": n, "contacts": len(model.result), "model_s": time.perf_counter() - t0}
    t0 = time.perf_counter()
    with HeadlessScene(SceneConfig(), bodies=model, width=1200, height=800, timeout=600) as hs:
        out["first_s"] = time.perf_counter() - t0
        view, page = hs.session, hs.page
        out["drawn"] = view.layers.drawn()
        frames = _orbit(page, steps)
        out["orbit_ms"] = frames
        hs.wait_settled()
        out["drawn_after_orbit"] = view.layers.drawn()
        opens, backs = [], []
        for _ in range(3):
            button = page.get_by_role("button", name="Open pair").bounding_box()
            t0 = time.perf_counter()  # a user's click: no Playwright actionability wait (it spans frames)
            page.mouse.click(button["x"] + button["width"] / 2, button["y"] + button["height"] / 2)
            while view.pair is None or not view.ready.is_set() or not view.session.ready.is_set():
                time.sleep(0.002)
            out.setdefault("open_server_ms", []).append((time.perf_counter() - t0) * 1e3)
            s = view.session
            k = view.pair
            poses, colours, word = hs.expected(s)
            page.wait_for_function(_DRAWN_JS, arg=[poses, colours, word], polling="raf")
            opens.append((time.perf_counter() - t0) * 1e3)
            if s.state.relation != str(Relation(int(model.result.relation[k]))):
                raise AssertionError("the two-body view disagrees with core.contacts")
            hs.wait_settled()
            button = page.get_by_role("button", name="← All bodies").bounding_box()
            t0 = time.perf_counter()
            page.mouse.click(button["x"] + button["width"] / 2, button["y"] + button["height"] / 2)
            while view.pair is not None or not view.ready.is_set():
                time.sleep(0.002)
            hs.wait_settled()
            backs.append(time.perf_counter() - t0)
        out["open_pair_ms"], out["back_s"] = opens, backs
        page.get_by_text("Contact network", exact=True).click()
        while view.layers.network is None:
            time.sleep(0.01)
        page.wait_for_function("(n) => window.__viserMutable?.nodeRefFromName?.[n] != null", arg="/bodies/network")
        hs.wait_settled()
        out["orbit_network_ms"] = _orbit(page, max(3, steps // 2))
    from app.cli import main

    t0 = time.perf_counter()
    shot = folder / f"bodies-{n}.png"
    if main(["screenshot", "--bodies", str(path), "--out", str(shot), "--width", "1200", "--height", "800"]) != 0:
        raise RuntimeError("screenshot --bodies failed")
    out["screenshot_s"] = time.perf_counter() - t0
    return out


POINTS_SIGNATURE_JS = """() => {
  const m = window.__viserMutable?.nodeRefFromName;
  if (!m) return null;
  let s = 0, n = 0;
  for (const [name, r] of Object.entries(m)) {
    if (!name.startsWith('/bodies/points/') || !r) continue;
    r.traverse((o) => {
      const p = o.isPoints ? o.geometry.attributes.position : null;
      if (!p) return;
      for (let i = 0; i < p.count; i += Math.max(1, Math.floor(p.count / 64))) { s += p.getX(i) * (i + 1) + p.getY(i); n += 1; }
    });
  }
  return [s, n];
}"""
"""A checksum of the bodies' points as three.js has them (changes when a t-step's points arrive)."""

FINISH_FRAME_JS = """async () => {
  const m = window.__viserMutable, info = window.__viserTestpoints.rendererInfo;
  const f0 = info.render.frame;
  while (info.render.frame <= f0) await new Promise((r) => requestAnimationFrame(r));
  const gl = m.canvas.getContext('webgl2');
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
}"""
"""The next frame rendered and finished (a 1-pixel readPixels)."""


def _write_moving(n: int, folder: Path) -> tuple[Path, Path]:
    from app.bodyfiles import write_bodies_csv
    from bench.sweep_data import moving_bodies

    mv = moving_bodies(n, rotate=True, seed=1)
    start, end = folder / f"moving-{n}-start.csv", folder / f"moving-{n}-end.csv"
    write_bodies_csv(start, mv.centers0, mv.semi_axes, mv.orientations0)
    write_bodies_csv(end, mv.centers1, mv.semi_axes, mv.orientations1)
    return start, end


def measure_moving(n: int, folder: Path, *, times: tuple[float, ...] = (0.25, 0.5, 0.75)) -> dict[str, Any]:
    """Moving bodies: a t-step's server time, the frame that shows it, the certified colours."""
    from app.scene.bodies.sweep_model import SweepModel
    from app.scene.common.state import SceneConfig
    from app.screenshot import HeadlessScene
    from app.sweep_cli import read_moving_bodies

    start, end = _write_moving(n, folder)
    t0 = time.perf_counter()
    model = SweepModel(read_moving_bodies(str(start), str(end), on_invalid="mark"))
    out: dict[str, Any] = {"bodies": n, "events": len(model.result), "model_s": time.perf_counter() - t0}
    with HeadlessScene(SceneConfig(), bodies=model, width=1200, height=800, timeout=1200) as hs:
        view, page = hs.session, hs.page
        for t in times:
            before = page.evaluate(POINTS_SIGNATURE_JS)
            t0 = time.perf_counter()
            m = view.timeline.set_time(t)
            out.setdefault("step_ms", []).append((time.perf_counter() - t0) * 1e3)
            page.wait_for_function(f"(b) => JSON.stringify(({POINTS_SIGNATURE_JS})()) !== JSON.stringify(b)", arg=before, polling="raf")
            page.evaluate(FINISH_FRAME_JS)
            out.setdefault("frame_ms", []).append((time.perf_counter() - t0) * 1e3)
            if not m.done.wait(1200):
                raise TimeoutError(f"the colours at t = {t} were not certified in 20 minutes")
            out.setdefault("certified_s", []).append(time.perf_counter() - t0)
            out.setdefault("exact_pairs", []).append(m.exact)
            out.setdefault("sweep_pairs", []).append(m.by_sweep)
            hs.wait_settled()
        k = int(model.order[len(model.order) // 2])  # an event in the middle of the step
        t0 = time.perf_counter()
        view.open_pair(k)
        if not view.session.ready.wait(600):
            raise TimeoutError("the event's pair did not open")
        out["open_event_s"] = time.perf_counter() - t0
        hs.wait_settled()
        out["open_event_drawn_s"] = time.perf_counter() - t0
        view.show_bodies()
    return out


def run_bodies_browser(
    *, quick: bool = False, sizes: list[int] | None = None, moving: list[int] | None = None, keep: Path | None = None
) -> dict[str, Any]:
    """Measure every size (default 20,000 and 100,000 bodies; quick: 2,000) and moving bodies
    (default 2,000 and 20,000; quick: 500); PNGs kept in ``keep``."""
    sizes = sizes if sizes is not None else ([2_000] if quick else [20_000, 100_000])
    moving = moving if moving is not None else ([500] if quick else [2_000, 20_000])
    load = os.getloadavg()
    rows, moving_rows = [], []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) if keep is None else keep
        folder.mkdir(parents=True, exist_ok=True)
        for n in sizes:
            rows.append(measure(n, folder, steps=4 if quick else 8))
        for n in moving:
            moving_rows.append(measure_moving(n, folder, times=(0.5,) if quick else (0.25, 0.5, 0.75)))
    return {"rows": rows, "moving": moving_rows, "load": [round(v, 2) for v in load]}


def format_bodies_browser(out: dict[str, Any]) -> str:
    """A markdown table of the measurements against the targets."""
    lines = [
        "| bodies (contacts) | drawn: solids / points (triangles) | first picture | orbit frame, median / worst "
        "| with contact network | open pair, median / worst | back to all bodies | `screenshot --bodies` (whole command) |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ] if out["rows"] else []
    for r in out["rows"]:
        d = r["drawn"]
        o, net, op = r["orbit_ms"], r["orbit_network_ms"], r["open_pair_ms"]
        ok_o = "meets" if max(o) < TARGETS["orbit frame ms"] else "**misses**"
        ok_p = "meets" if max(op) < TARGETS["open pair ms"] else "**misses**"
        lines.append(
            f"| {r['bodies']:,} ({r['contacts']:,}) | {d['fine'] + d['coarse']:,} / {d['points']:,} ({d['triangles']:,}) "
            f"| {r['first_s']:.1f} s | {statistics.median(o):.0f} / {max(o):.0f} ms ({ok_o}) "
            f"| {statistics.median(net):.0f} / {max(net):.0f} ms | {statistics.median(op):.0f} / {max(op):.0f} ms ({ok_p}) "
            f"| {statistics.median(r['back_s']):.1f} s | {r['screenshot_s']:.1f} s |"
        )
    if out.get("moving"):
        lines += [
            *([""] if lines else []),
            "| moving bodies (events) | model: read + sweep forward and back | t-step, server (median / worst) "
            "| t-step to its frame in the browser | colours certified at t (pairs decided exactly) | open an event (pair analysed, drawn) |",
            "|---|---:|---:|---:|---:|---:|",
        ]
        for r in out["moving"]:
            st, fr, ce = r["step_ms"], r["frame_ms"], r["certified_s"]
            lines.append(
                f"| {r['bodies']:,} ({r['events']:,}) | {r['model_s']:.1f} s | {statistics.median(st):.0f} / {max(st):.0f} ms "
                f"| {statistics.median(fr):.0f} / {max(fr):.0f} ms | {statistics.median(ce):.1f} / {max(ce):.1f} s "
                f"({statistics.median(r['exact_pairs']):,.0f}) | {r['open_event_s']:.2f} s, {r['open_event_drawn_s']:.1f} s |"
            )
    lines.append("")
    lines.append(f"Load average (1, 5, 15 min) at the start: {' '.join(str(v) for v in out['load'])} on 2 cores. "
                 f"Targets: an orbit frame < {TARGETS['orbit frame ms']:.0f} ms (worst), open pair < "
                 f"{TARGETS['open pair ms']:.0f} ms (worst).")
    return "\n".join(lines)


def target_rows(out: dict[str, Any]) -> list[tuple[str, str, str, bool | None]]:
    """The rows of bench/REPORT.md's target table (for ``bench.report``)."""
    rows: list[tuple[str, str, str, bool | None]] = []
    for r in out["rows"]:
        o, op = r["orbit_ms"], r["open_pair_ms"]
        ok = max(o) < TARGETS["orbit frame ms"]
        rows.append((f"{r['bodies']:,} bodies orbit at interactive rates: a frame < {TARGETS['orbit frame ms']:g} ms (headless Chromium, "
                     "software WebGL)", f"median {statistics.median(o):.0f} ms, worst {max(o):.0f} ms", "met" if ok else "missed", ok))
        ok = max(op) < TARGETS["open pair ms"]
        rows.append((f"{r['bodies']:,} bodies: \"Open pair\" < {TARGETS['open pair ms']:g} ms (click -> two-body view drawn with its label)",
                     f"median {statistics.median(op):.0f} ms, worst {max(op):.0f} ms (the first open builds the view)",
                     "met" if ok else "missed", ok))
    return rows


def run_in_subprocess(*, quick: bool = False, timeout: float = 1800.0) -> dict[str, Any]:
    """Run this benchmark in a fresh ``python -m bench.bodies_browser --json``."""
    import subprocess

    root = Path(__file__).resolve().parents[1]
    cmd = [sys.executable, "-m", "bench.bodies_browser", "--json"] + (["--quick"] if quick else [])
    r = subprocess.run(cmd, cwd=root, capture_output=True, text=True, timeout=timeout, check=False,
                       env={**os.environ, "PYTHONPATH": str(root)})
    if r.returncode != 0:
        raise RuntimeError(f"bench.bodies_browser failed: {r.stderr[-400:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description="Many bodies in headless Chromium: orbit frame time, open pair, screenshots.")
    ap.add_argument("--quick", action="store_true", help="2,000 bodies only, fewer steps")
    ap.add_argument("--sizes", default=None, help="comma-separated numbers of bodies (default 20000,100000)")
    ap.add_argument("--moving", default=None, help="comma-separated numbers of moving bodies (default 2000,20000; 0: none)")
    ap.add_argument("--keep", default=None, help="folder to keep the bodies files and screenshots in")
    ap.add_argument("--json", action="store_true", help="print one JSON line (for bench.report)")
    a = ap.parse_args()
    sizes = [int(v) for v in a.sizes.split(",") if int(v)] if a.sizes else None
    moving = [int(v) for v in a.moving.split(",") if int(v)] if a.moving else None
    out = run_bodies_browser(quick=a.quick, sizes=sizes, moving=moving, keep=Path(a.keep) if a.keep else None)
    print(json.dumps(out) if a.json else format_bodies_browser(out))


if __name__ == "__main__":
    main()
