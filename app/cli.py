"""The command line: ``python -m app [serve | screenshot] ...``.

* ``python -m app``: start the scene (http://127.0.0.1:8080) and the API (http://127.0.0.1:8000)
  with defaults and print the URLs; the scene opens on Example 29 just before the first touch.
* ``python -m app serve --host H --port SCENE_PORT --api-port P [--api-only] [--shared]
  [--allow-origin URL ...]``: the same with options; uvicorn serves the API in the main thread,
  viser serves the scene from its own thread; ``--shared`` is the presenter mode (one scene for
  every tab); ``--allow-origin`` lets pages at another origin open scene sessions
  (:mod:`app.scene.common.origin`). SIGTERM/SIGINT stop the running analyses and exit within seconds
  (:mod:`app.lifecycle`).
* ``python -m app screenshot --preset example-29 --t 0.7 --out shot.png [--config file.json]
  [--width W --height H] [--dim 2|3] [--event K]``: render a configuration to PNG headlessly;
  several ``--t``/``--event``/``--config`` render one image each in one browser session
  (``--out`` a folder); ``--browser URL`` draws in a tab of a Chromium that already runs.
* ``python -m app export --preset example-29 --out ex29.html [--config file.json]``: a
  self-contained HTML replay of the motion (viser's scene recording and player; no server).
* ``python -m app contacts BODIES --out PAIRS.csv [--box Lx,Ly,Lz]`` and ``python -m app
  classify PAIRS.npz --out LABELS.npy``: many bodies and files of pairs (:mod:`app.bodies_cli`);
  ``serve --bodies FILE`` / ``screenshot --bodies FILE`` show many bodies in the scene, and
  ``serve --bodies START --to END`` / ``screenshot --bodies START --to END [--t T] [--event K]``
  moving bodies over one step (the timeline, the contact events: :mod:`app.scene.bodies.sweep_view`).
* ``python -m app sweep START.csv END.csv --out EVENTS.csv``: first contact times of moving
  bodies (:mod:`app.sweep_cli`).
* ``python -m app audit TRAJECTORY --out REPORT.csv [--between]``: a certified check of a
  hard-particle trajectory, frame by frame; exit status 3 when a pair overlaps (:mod:`app.audit_cli`).
* ``python -m app --version``. The console script ``ellipsoids`` is the same command.

Exit status: 0 done; 1 the work could not be done here (a missing optional package or
browser, an unreachable Dask scheduler, a render that timed out); 2 bad arguments or input (a
one-line message on stderr, never a traceback); 130 interrupted by Ctrl+C (SIGINT), 143
terminated (SIGTERM), 141 standard output closed early (a pipe): in these three no output file
is left half written (:mod:`app.output`). Messages and progress go to stderr, data to the files
(or to stdout with ``--out -``).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import re
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from .interrupt import Terminated, unwinding
from .scene.common.mesh_detail import SPHERE_SUBDIVISIONS, SPHERE_SUBDIVISIONS_RANGE

if TYPE_CHECKING:  # imported where used: the command line starts without viser
    from .scene.common.state import SceneConfig

__all__ = ["main", "run", "build_parser", "config_from_args", "EXIT_OK", "EXIT_FAILED", "EXIT_USAGE", "EXIT_INTERRUPTED"]

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_TERMINATED, EXIT_PIPE = 0, 1, 2, 130, 143, 141
"""Exit statuses (module docstring)."""


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors ("python -m app contacts: error: ...; see --help"), exit 2.

    A value that starts with a minus and a digit is a value, never an option: ``--box -1,2,3``
    and ``--t -0.5`` (Python 3.13's rule; before it only ``-1`` and ``-1.5`` were, so ``--box
    -1,2,3`` was "expected one argument"). No option of this program starts with a digit.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"-\.?\d")  # argparse reads it (and sub-parsers are _Parsers)

    def error(self, message: str) -> None:  # type: ignore[override]
        """Print one line to stderr and exit with status 2."""
        sys.stderr.write(f"{self.prog}: error: {message} (see {self.prog} --help)\n")
        raise SystemExit(EXIT_USAGE)


def _port(text: str) -> int:
    try:
        p = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
    if not 0 <= p <= 65535:
        raise argparse.ArgumentTypeError(f"port out of range 0..65535: {p}")
    return p


def _origin(text: str) -> str:
    from .scene.common.origin import normalise_origin

    try:
        return normalise_origin(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _seconds(text: str) -> float:
    """A time budget for ``serve``: a finite number of seconds > 0 (at most a day)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of seconds: {text!r}") from None
    if not 0 < v <= 86_400:  # also refuses nan and inf
        raise argparse.ArgumentTypeError(f"seconds out of range (0, 86400]: {text!r}")
    return v


def _cors_origin(text: str) -> str:
    """An origin for ``--cors-origin`` (as browsers send it), or "*" for any."""
    return "*" if text.strip() == "*" else _origin(text)


def _size(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a pixel size: {text!r}") from None
    if not 200 <= v <= 8000:
        raise argparse.ArgumentTypeError(f"size out of range 200..8000: {v}")
    return v


def _devtools_address(text: str) -> str:
    """``--browser``: the DevTools address of a running Chromium, ``http://HOST:PORT`` (or ws://, https://)."""
    from urllib.parse import urlsplit

    try:
        parts = urlsplit(text)
        ok = parts.scheme in ("http", "https", "ws", "wss") and bool(parts.hostname) and parts.port is not None
    except ValueError:  # a port out of range or not a number
        ok = False
    if not ok:
        raise argparse.ArgumentTypeError(f"not a DevTools address (http://HOST:PORT): {text!r}")
    return text


def _time(text: str) -> float:
    from core.shapes.numbers import to_fmpq

    try:
        q = to_fmpq(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    try:
        t = float(q.p) / float(q.q)
    except OverflowError:  # numerator or denominator beyond the float range
        t = math.inf
    if not math.isfinite(t) or (t == 0 and q != 0):
        raise argparse.ArgumentTypeError(f"t out of range: {text!r}")
    return t


def _add_sphere_subdivisions(parser: argparse.ArgumentParser, why: str) -> None:
    """``--sphere-subdivisions K`` (app.scene.common.mesh_detail): how finely the ellipsoids are drawn."""
    lo, hi = SPHERE_SUBDIVISIONS_RANGE[0], SPHERE_SUBDIVISIONS_RANGE[-1]
    parser.add_argument(
        "--sphere-subdivisions", type=int, choices=SPHERE_SUBDIVISIONS_RANGE, default=SPHERE_SUBDIVISIONS, metavar="K",
        help=f"icosphere subdivisions of the drawn ellipsoids, {lo}..{hi} (20 * 4^K faces; {why})",
    )


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (sub-commands ``serve``, ``screenshot`` and ``export``)."""
    p = _Parser(
        prog="ellipsoids" if os.path.basename(sys.argv[0]) == "ellipsoids" else "python -m app",
        description="Certified ellipse/ellipsoid interference: viser scene, HTTP API, screenshots, contacts among many bodies.",
        epilog="Exit status: 0 done, 1 could not be done here, 2 bad arguments or input, 130 interrupted (Ctrl+C).",
    )
    p.add_argument("--version", action="version", version=f"ellipsoid-interference {_version()}")
    sub = p.add_subparsers(dest="command")
    s = sub.add_parser("serve", help="serve the scene and the API (the default command)")
    s.add_argument("--host", default="127.0.0.1", help="interface (default 127.0.0.1; 0.0.0.0 to share on a network)")
    s.add_argument("--port", type=_port, default=8080, help="scene (viser) port, default 8080")
    s.add_argument("--api-port", type=_port, default=8000, help="API port, default 8000")
    s.add_argument("--api-only", action="store_true", help="serve the API alone (no scene)")
    s.add_argument("--preset", default=None, help="preset the scene opens on (default example-29; 'none' for static shapes)")
    s.add_argument("--config", default=None, help="JSON configuration the scene opens on")
    s.add_argument("--shared", action="store_true", help="presenter mode: every tab sees and drives one scene")
    s.add_argument("--lesson", default=None, metavar="NAME|FILE",
                   help="every new tab opens on this lesson's first step: 'paper' (the paper step by step) or a lesson JSON file")
    s.add_argument(
        "--allow-origin", action="append", default=[], type=_origin, metavar="URL",
        help="also accept scene connections from pages at this origin, e.g. https://example.org "
        "(repeatable; default: only the scene's own pages, and clients that send no Origin)",
    )
    s.add_argument(
        "--cors-origin", action="append", default=[], type=_cors_origin, metavar="URL",
        help="let web pages at this origin call the API from a browser (CORS), e.g. https://example.org, "
        "or '*' for any (repeatable; default: no CORS headers)",
    )
    _add_sphere_subdivisions(
        s, f"default {SPHERE_SUBDIVISIONS}: tangent shapes drawn within a pixel up to 3,000 pixels across; "
        "fewer draw faster where the browser has no GPU",
    )
    s.add_argument(
        "--request-budget", type=_seconds, default=None, metavar="SECONDS",
        help="time budget of one API request (classify, explain, witnesses, contacts, sweep): "
        "the work is stopped and answered with 503 (default 5)",
    )
    s.add_argument(
        "--analysis-budget", type=_seconds, default=None, metavar="SECONDS",
        help="time budget of one motion analysis of the API (/api/analyse); its worker is killed (default 20)",
    )

    sh = sub.add_parser(
        "screenshot", help="render a configuration to PNG with headless Chromium (several --t/--event/--config: "
        "one browser, one image each, --out a folder)",
    )
    sh.add_argument("--preset", default=None, help="motion preset, e.g. example-29 ('none' for static shapes)")
    sh.add_argument("--t", type=_time, action="append", default=None, help="time to show (number or fraction); repeatable")
    sh.add_argument("--event", type=int, action="append", default=None, help="show the K-th event (1-based) exactly; repeatable")
    sh.add_argument("--config", action="append", default=None, help="JSON configuration file (any scene); repeatable")
    sh.add_argument("--dim", type=int, choices=(2, 3), default=None, help="2 (ellipses) or 3 (ellipsoids)")
    sh.add_argument("--width", type=_size, default=1400, help="image width in px (default 1400)")
    sh.add_argument("--height", type=_size, default=900, help="image height in px (default 900)")
    sh.add_argument("--no-plots", action="store_true", help="hide the live plots")
    sh.add_argument("--out", required=True, help="output PNG path, or a folder for several images")
    sh.add_argument("--timeout", type=float, default=120.0, help="seconds to wait for rendering")
    sh.add_argument("--lesson", default=None, metavar="NAME|FILE", help="draw a lesson's steps: 'paper' or a lesson JSON file")
    sh.add_argument("--step", type=int, action="append", default=None,
                    help="the lesson's step K (1-based; repeatable; default every step, --out a folder)")
    sh.add_argument("--reveal", action="store_true",
                    help="--lesson: draw each step after 'Reveal the answer' (default: before, as the class sees it first)")
    sh.add_argument(
        "--browser", type=_devtools_address, default=None, metavar="URL",
        help="DevTools address of a Chromium that already runs (chromium --headless --remote-debugging-port=PORT: "
        "http://127.0.0.1:PORT): the images are drawn in a tab of it, closed afterwards, instead of in a browser "
        "launched for the command",
    )

    ex = sub.add_parser("export", help="write a self-contained HTML replay of a scene (a motion played through)")
    ex.add_argument("--preset", default=None, help="motion preset, e.g. example-29 ('none' for static shapes)")
    ex.add_argument("--config", action="append", default=None, help="JSON configuration file (any scene)")
    ex.add_argument("--dim", type=int, choices=(2, 3), default=None, help="2 (ellipses) or 3 (ellipsoids)")
    ex.add_argument("--seconds", type=float, default=12.0, help="playing time of the sweep over I (default 12)")
    ex.add_argument("--frames", type=int, default=240, help="time steps recorded (default 240)")
    ex.add_argument("--out", required=True, help="output HTML path")
    ex.add_argument("--lesson", default=None, metavar="NAME|FILE",
                    help="write a lesson instead: every step's picture and words in one offline page ('paper' or a JSON file)")
    ex.add_argument("--width", type=_size, default=1280, help="--lesson: picture width in px (default 1280)")
    ex.add_argument("--height", type=_size, default=720, help="--lesson: picture height in px (default 720)")
    _add_sphere_subdivisions(ex, f"default {SPHERE_SUBDIVISIONS}; fewer make a smaller file")
    from .bodies_cli import add_body_file_options, add_parsers, box_argument, frame_argument

    for parser in (s, sh):  # many bodies (issue 14): the scene opens on the bodies of a file
        parser.add_argument("--bodies", default=None, help="file of many bodies to show (app.readers: CSV, Parquet, NPZ, GSD, LAMMPS, XYZ)")
        parser.add_argument("--box", type=box_argument, default=None, help="periodic box Lx,Ly[,Lz] of --bodies (default: the file's)")
        add_body_file_options(parser)
        parser.add_argument(  # moving bodies (issue 25): --bodies at t = 0, --to at t = 1
            "--to", default=None, metavar="END",
            help="the same bodies at t = 1 (any format of --bodies): the scene animates the step t in [0, 1] and lists "
            "its contact events (python -m app sweep's input)",
        )
        parser.add_argument("--end-frame", type=frame_argument, default=None, help="frame of --to when it is a trajectory (default: --frame)")
    add_parsers(sub)
    from .sweep_cli import add_parser as add_sweep_parser

    add_sweep_parser(sub)
    from .audit_cli import add_parser as add_audit_parser

    add_audit_parser(sub)
    return p


def _version() -> str:
    """The installed package's version (the source tree's pyproject when not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("ellipsoid-interference")
    except PackageNotFoundError:
        return "(not installed)"


def config_from_args(args: argparse.Namespace, path: str | None = None) -> SceneConfig:
    """SceneConfig from ``--config``/``--preset``/``--t``/``--event``/``--dim`` (later override earlier).

    Args:
        args: the parsed command line.
        path: the configuration file to start from (default: the first ``--config``).

    Raises:
        ValueError: unreadable config file or bad values.
    """
    from .scene.common.state import SceneConfig

    configs = _listed(getattr(args, "config", None))
    path = path or (configs[0] if configs else None)
    try:
        cfg = SceneConfig.from_json_file(path) if path else SceneConfig()
    except RecursionError:
        raise ValueError(f"config file {path}: JSON nested too deeply") from None
    except (TypeError, OverflowError, KeyError, AttributeError) as e:  # a value of the wrong kind the reader let through
        raise ValueError(f"config file {path}: a value of the wrong kind or size ({type(e).__name__}: {e})") from None
    if getattr(args, "dim", None) is not None and args.dim != cfg.dim:
        d = cfg.to_dict()
        d.update(dim=args.dim, A=None, B=None, preset=None)
        cfg = SceneConfig.from_dict({k: v for k, v in d.items() if v is not None or k == "preset"})
    if getattr(args, "preset", None) is not None:
        cfg.preset = None if args.preset.lower() in ("none", "static") else args.preset
        cfg.motion = None
    ts, events = _listed(getattr(args, "t", None)), _listed(getattr(args, "event", None))
    if any(k < 1 for k in events):
        raise ValueError("--event is 1-based")
    if len(ts) + len(events) == 1:  # one image: the configuration itself shows it
        if ts:
            cfg.t = ts[0]
        else:
            cfg.event = events[0]
    if getattr(args, "no_plots", False):
        cfg.show_plots = False
    return cfg


def _listed(value: object) -> list[Any]:
    """A repeatable option as a list (None: empty; a single value from older callers: [value])."""
    if value is None:
        return []
    return list(value) if isinstance(value, list | tuple) else [value]


def _serve(args: argparse.Namespace) -> int:
    from .lifecycle import serve

    scene = None
    scene_url = None
    if not args.api_only:
        from .scene.server import start_scene

        lesson = _lesson(args)
        scene = start_scene(
            args.host, args.port, config_from_args(args), shared=args.shared, allow_origins=args.allow_origin,
            bodies=_bodies_model(args), sphere_subdivisions=args.sphere_subdivisions,
        )
        scene_url = scene.url
        if lesson is not None:
            from .scene.common.lesson import step_link

            scene.lesson = lesson.name
            print(f"Lesson: {lesson.title} ({len(lesson.steps)} steps): {scene_url}{step_link(lesson, 1)}", flush=True)
        print(f"Scene (open in a browser): {scene_url}", flush=True)
    try:
        from .api import ApiSettings, create_api
        from .api.budget import STOPPING
    except ImportError as e:
        if args.api_only:
            print(f"error: the API package is not available: {e}", file=sys.stderr)
            return 2
        print(f"(API not available: {e}); serving the scene only. Ctrl+C stops.", flush=True)
        _wait_forever()
        if scene is not None:
            scene.stop()
        return 0
    budgets = {name: v for name, v in (("request_budget_s", args.request_budget), ("time_budget_s", args.analysis_budget)) if v is not None}
    api = create_api(ApiSettings(scene_url=scene_url, cors_origins=tuple(args.cors_origin), **budgets))

    def stop_work() -> None:
        """On SIGTERM/SIGINT: fail every request budget, kill the analysis workers (API, scene)."""
        STOPPING.set()
        api.state.workers.shutdown()
        if scene is not None:
            scene.cache.shutdown()

    shown = "127.0.0.1" if args.host in ("0.0.0.0", "::") else args.host
    if scene is not None:  # the panel's "What am I seeing?" and a lesson's tutorial link to the guide the API serves
        scene.guide = f"http://{shown}:{args.api_port}/guide/"
    print(f"API: http://{shown}:{args.api_port}/  (docs: http://{shown}:{args.api_port}/docs)", flush=True)
    try:
        serve(api, args.host, args.api_port, stop_work)
    finally:
        if scene is not None:
            scene.stop()
    return 0


def _wait_forever() -> None:
    import threading

    try:
        threading.Event().wait()
    except KeyboardInterrupt:
        pass


def _bodies_model(args: argparse.Namespace) -> object:
    """The bodies of ``--bodies FILE`` with their contacts (``--box``), or None.

    With ``--to END``: the moving bodies of a step (:class:`app.scene.bodies.sweep_model.SweepModel`,
    START and END read as ``python -m app sweep`` reads them).
    """
    if getattr(args, "to", None) is not None:
        if getattr(args, "bodies", None) is None:
            raise ValueError("--to END needs --bodies START (the bodies at t = 0)")
        from .scene.bodies.sweep_model import SweepModel
        from .sweep_cli import read_moving_bodies

        moving = read_moving_bodies(
            args.bodies, args.to, frame=getattr(args, "frame", None), end_frame=getattr(args, "end_frame", None),
            format=getattr(args, "format", None), box=args.box, on_invalid="mark",
        )
        sweep = SweepModel(moving)
        print(f"Moving bodies: {sweep.result.summary()}", file=sys.stderr, flush=True)
        return sweep
    if getattr(args, "bodies", None) is None:
        return None
    from .scene.bodies.bodies_view import load_model

    model = load_model(args.bodies, args.box, frame=getattr(args, "frame", None), format=getattr(args, "format", None))
    print(f"Bodies: {model.result.summary()}", file=sys.stderr, flush=True)
    return model


def _lesson(args: argparse.Namespace) -> Any:
    """The lesson of ``--lesson`` (registered: links name it), or None."""
    if getattr(args, "lesson", None) is None:
        return None
    if getattr(args, "shared", False) or getattr(args, "bodies", None) is not None:
        raise ValueError("--lesson shows one tab's scene: not with --shared or --bodies")
    from .scene.common.lesson import load_lesson, register

    lesson = load_lesson(args.lesson)
    register(lesson)
    return lesson


def _lesson_screenshots(args: argparse.Namespace, lesson: Any) -> int:
    """``screenshot --lesson L [--step K ...]``: one PNG per step (a folder for several)."""
    from pathlib import Path

    from .lesson_export import step_pictures

    steps = _listed(args.step) or list(range(1, len(lesson.steps) + 1))
    for k in steps:
        lesson.step(k)  # ValueError: no such step
    one = len(steps) == 1 and not args.out.endswith(("/", os.sep))
    written = []
    for k, png in step_pictures(lesson, steps, width=args.width, height=args.height, timeout=args.timeout, cdp=args.browser,
                                reveal=args.reveal):
        path = Path(args.out) if one else Path(args.out) / f"step-{k:02d}.png"
        target = _output_file(path)
        with target as f:
            f.write(png)
        written.append(path)
    for path in written:
        print(f"wrote {path}", file=sys.stderr)
    return 0


def _output_file(path: Any) -> Any:
    from .output import Output

    return Output(path, binary=True, make_folders=True)


def _screenshot(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .screenshot import screenshots, shots_for

    lesson = _lesson(args)
    if lesson is not None:
        return _lesson_screenshots(args, lesson)
    if getattr(args, "step", None):
        raise ValueError("--step is a lesson's step: give --lesson too")
    if getattr(args, "reveal", False):
        raise ValueError("--reveal draws a lesson's step after Reveal: give --lesson too")
    configs = _listed(args.config)
    ts, events = _listed(args.t), _listed(args.event)
    if getattr(args, "to", None) is not None:  # moving bodies: --t in the step, --event K the K-th contact event
        if any(not 0.0 <= t <= 1.0 for t in ts):
            raise ValueError("--t: moving bodies are shown over the step t in [0, 1]")
        if any(k < 1 for k in events):
            raise ValueError("--event is 1-based (the K-th contact event in time order)")
        shots = shots_for(config_from_args(args), args.out, ts, events)
    elif len(configs) > 1:  # a list of configurations: one image each, named after the file
        shots = []
        for path in configs:
            cfg = config_from_args(args, path)
            shots += shots_for(cfg, Path(args.out) / Path(path).stem, ts, events) if ts or events else \
                shots_for(cfg, Path(args.out) / f"{Path(path).stem}.png", [], [])
    else:
        cfg = config_from_args(args)
        shots = shots_for(cfg, args.out, ts if len(ts) + len(events) > 1 else [], events if len(ts) + len(events) > 1 else [])

    with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet):  # the scene server's banner: not for a screenshot
        written = screenshots(shots, width=args.width, height=args.height, timeout=args.timeout, bodies=_bodies_model(args),
                              cdp=args.browser)
    for path in written:
        print(f"wrote {path}", file=sys.stderr)
    return 0


def _export(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .scene.pair.replay import replay_html

    if not 0 < args.seconds <= 600 or not 2 <= args.frames <= 5000:
        raise ValueError("--seconds must be in (0, 600] and --frames in 2..5000")
    from .output import Output

    out = Path(args.out)
    lesson = _lesson(args)
    if lesson is not None:  # every step's picture and words in one offline page
        from .lesson_export import lesson_html, step_shots

        target = Output(out, make_folders=True)
        with target as f:
            steps = list(range(1, len(lesson.steps) + 1))
            shots = list(step_shots(lesson, steps, width=args.width, height=args.height, after=True))
            page = lesson_html(lesson, {k: a for k, a, _ in shots if a is not None}, {k: b for k, _, b in shots if b is not None})
            f.write(page)
        print(f"wrote {out} ({len(page) // 1024} kB, {len(lesson.steps)} steps; open it in a browser, no server needed)",
              file=sys.stderr)
        return 0
    target = Output(out, make_folders=True)  # documented: the folders are created; checked before the replay is built
    with target as f:
        html = replay_html(config_from_args(args), seconds=args.seconds, frames=args.frames,
                           sphere_subdivisions=args.sphere_subdivisions)
        f.write(html)
    print(f"wrote {out} ({len(html) // 1024} kB; open it in a browser, no server needed)", file=sys.stderr)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (module docstring: 0, 1, 2, 130, 141, 143)."""
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    from .bodies_cli import COMMANDS

    if not argv or (argv[0] not in ("serve", "screenshot", "export", "sweep", "audit", *COMMANDS) and argv[0] not in ("-h", "--help", "--version")):
        argv = ["serve", *argv]  # no sub-command: serve with the given options (or defaults)
    args = parser.parse_args(argv)
    if args.command == "serve" or args.command is None:
        return _run(args)  # serve has its own shutdown (app.lifecycle)
    try:
        with unwinding():
            return _run(args)
    except Terminated:  # between the command's end and the handlers' restoring
        return _fail("terminated (SIGTERM): no output written", EXIT_TERMINATED)
    except KeyboardInterrupt:
        return _fail("interrupted (Ctrl+C): no output written", EXIT_INTERRUPTED)


def _run(args: argparse.Namespace) -> int:
    """The parsed command, its failures turned into one line on stderr and the exit status."""
    from .bodies_cli import run_classify, run_contacts

    try:
        if args.command == "screenshot":
            return _screenshot(args)
        if args.command == "export":
            return _export(args)
        if args.command == "contacts":
            return run_contacts(args)
        if args.command == "classify":
            return run_classify(args)
        if args.command == "sweep":
            from .sweep_cli import run_sweep

            return run_sweep(args)
        if args.command == "audit":
            from .audit_cli import run_audit

            return run_audit(args)
        return _serve(args)
    except ValueError as e:
        return _fail(f"error: {e}", EXIT_USAGE)
    except (RuntimeError, TimeoutError, ImportError) as e:
        return _fail(f"error: {e}", EXIT_FAILED)
    except MemoryError:
        return _fail("error: out of memory (try fewer bodies per file, or --scheduler to spread the work)", EXIT_FAILED)
    except KeyboardInterrupt:
        return _fail("interrupted (Ctrl+C): no output written", EXIT_INTERRUPTED)
    except Terminated:
        return _fail("terminated (SIGTERM): no output written", EXIT_TERMINATED)
    except BrokenPipeError:
        # the reader of stdout went away (e.g. | head): say nothing more to it
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_PIPE
    except OSError as e:  # the machine's, not the input's: a full disk, a vanished file system...
        return _fail(f"error: {e.strerror or e}" + (f": {e.filename}" if e.filename else ""), EXIT_FAILED)


def run() -> None:
    """Entry point of the ``ellipsoids`` console script: :func:`main`, then exit with its status."""
    raise SystemExit(main())


_MESSAGE_CHARS = 1000
"""Longest message printed: a longer one (a value quoted from a file) is cut in the middle."""


def _fail(message: str, status: int) -> int:
    """One line on stderr (the first line of the message, at most :data:`_MESSAGE_CHARS`), and the exit status."""
    line = message.splitlines()[0] if message else "error"
    if len(line) > _MESSAGE_CHARS:
        line = f"{line[: _MESSAGE_CHARS // 2]} ... {line[-_MESSAGE_CHARS // 2 :]}"
    print(line, file=sys.stderr, flush=True)
    return status
