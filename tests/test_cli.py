"""The command line ``python -m app``: argument checking, configs, and a real ``serve`` run."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from app.cli import build_parser, config_from_args, main

ROOT = Path(__file__).resolve().parents[1]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_screenshot_contract_parses():
    args = build_parser().parse_args(
        ["screenshot", "--preset", "example-29", "--t", "0.7", "--out", "shot.png", "--width", "800", "--height", "600"]
    )
    cfg = config_from_args(args)
    assert (cfg.preset, cfg.t, args.width, args.height, args.out) == ("example-29", 0.7, 800, 600, "shot.png")


def test_t_accepts_fractions():
    args = build_parser().parse_args(["screenshot", "--t", "3/4", "--out", "x.png"])
    assert config_from_args(args).t == 0.75


@pytest.mark.parametrize(
    "argv, message",
    [
        (["screenshot", "--t", "abc", "--out", "x.png"], "not a number"),
        (["screenshot", "--width", "10", "--out", "x.png"], "size out of range"),
        (["serve", "--port", "70000"], "port out of range"),
        (["screenshot", "--dim", "4", "--out", "x.png"], "invalid choice"),
        (["serve", "--request-budget", "0"], "seconds out of range (0, 86400]: '0'"),
        (["serve", "--analysis-budget", "nan"], "seconds out of range (0, 86400]: 'nan'"),
        (["serve", "--request-budget", "inf"], "seconds out of range"),
        (["serve", "--analysis-budget", "5s"], "not a number of seconds: '5s'"),
        (["screenshot", "--browser", "localhost", "--out", "x.png"], "not a DevTools address (http://HOST:PORT): 'localhost'"),
        (["screenshot", "--browser", "http://127.0.0.1", "--out", "x.png"], "not a DevTools address"),
        (["screenshot", "--browser", "http://127.0.0.1:99999", "--out", "x.png"], "not a DevTools address"),
        (["screenshot", "--browser", "file:///tmp:9222", "--out", "x.png"], "not a DevTools address"),
    ],
)
def test_bad_arguments_exit_2(argv, message, capsys):
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    assert message in capsys.readouterr().err


def test_negative_numbers_are_values_not_options(capsys):
    """``--box -1,2,3`` reaches the box's own check (argparse took it for an option: "expected one argument")."""
    p = build_parser()
    assert p.parse_args(["contacts", "b.csv", "--out", "p.csv", "--box", "10,10,10,-0.5,0,0"]).box == (10, 10, 10, -0.5, 0, 0)
    assert p.parse_args(["screenshot", "--t", "-1/2", "--out", "x.png"]).t == [-0.5]
    assert p.parse_args(["screenshot", "--t", "-.25", "--out", "x.png"]).t == [-0.25]
    assert p.parse_args(["contacts", "b.csv", "--out", "p.csv", "--frame", "-2"]).frame == -2
    for argv in (["contacts", "b.csv", "--out", "p.csv", "--box", "-1,2,3"], ["sweep", "s", "e", "--out", "o", "--box", "-.5,2"]):
        with pytest.raises(SystemExit):
            p.parse_args(argv)
        assert "the sides must be positive" in capsys.readouterr().err


BODIES = "x,y,z,a,b,c,qw,qx,qy,qz\n0,0,0,1,1,1,1,0,0,0\n2,0,0,1,1,1,1,0,0,0\n"
BAD_INPUTS = [
    (["contacts", "{b}", "--out", "{out}", "--box", "-1,2,3"], "argument --box: --box: the sides must be positive, got '-1,2,3'"),
    (["contacts", "{b}", "--out", "{out}", "--box=-1,2,3"], "the sides must be positive"),
    (["sweep", "{b}", "{b}", "--out", "{out}", "--box", "-5,5,5"], "the sides must be positive"),
    (["contacts", "{b}", "--out", "{out}", "--box", "10,10,nan"], "--box takes finite numbers"),
    (["contacts", "{b}", "--out", "{out}", "--scheduler", "notanaddress"], "not a scheduler address"),
    (["contacts", "{dump}", "--out", "{out}"], "NUMBER OF ATOMS is -5"),
    (["sweep", "{b}", "{dump}", "--out", "{out}"], "NUMBER OF ATOMS is -5"),
    (["classify", "{b}", "--out", "{out}"], "not an .npz file"),
    (["export", "--config", "{deep}", "--out", "{out}"], "JSON nested too deeply"),
    (["export", "--config", "{palette}", "--out", "{out}"], "a value of the wrong kind or size"),
    (["export", "--config", "{huge_t}", "--out", "{out}"], "a value of the wrong kind or size"),
    (["screenshot", "--config", "{palette}", "--out", "{out}"], "a value of the wrong kind or size"),
    (["export", "--out", "/proc/no-such-folder/x.html"], "cannot create the folder /proc/no-such-folder"),
    (["export", "--frames", "1", "--out", "{out}"], "--frames in 2..5000"),
]


@pytest.mark.parametrize("argv, message", BAD_INPUTS, ids=[f"{a[0]}-{k}" for k, (a, _) in enumerate(BAD_INPUTS)])
def test_bad_input_of_every_command_exits_2_with_one_line(argv, message, tmp_path, capsys):
    """The README's exit status 2 (bad arguments or input): one line on stderr, no output file.

    The input is checked before any work, so not even the progress line comes first."""
    files = {"b": tmp_path / "b.csv", "dump": tmp_path / "neg.dump", "deep": tmp_path / "deep.json",
             "palette": tmp_path / "palette.json", "huge_t": tmp_path / "t.json", "out": tmp_path / "out" / "result.csv"}
    files["b"].write_text(BODIES)
    files["dump"].write_text("ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n-5\nITEM: BOX BOUNDS pp pp pp\n0 9\n0 9\n0 9\n"
                             "ITEM: ATOMS id type x y z shapex shapey shapez\n1 1 0 0 0 2 2 2\n")
    files["deep"].write_text("[" * 100_000)
    files["palette"].write_text(json.dumps({"palette": [1, 2]}))
    files["huge_t"].write_text('{"t": 1' + "0" * 400 + "}")
    files["out"].parent.mkdir()
    try:
        code = main([a.format(**files) for a in argv])
    except SystemExit as e:  # argparse's errors
        code = e.code
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and message in err, err
    assert os.listdir(files["out"].parent) == []


def test_a_command_run_in_process_gives_back_the_callers_sigterm_handler(tmp_path, capsys):
    """main() makes SIGTERM unwind a command only while it runs: a program that calls it (a test
    runner's worker) keeps its own handler after, so a later SIGTERM is its to handle."""
    import signal

    def mine(signum, frame):  # pragma: no cover - never delivered
        pass

    previous = signal.signal(signal.SIGTERM, mine)
    try:
        bodies = tmp_path / "b.csv"
        bodies.write_text(BODIES)
        assert main(["contacts", str(bodies), "--out", str(tmp_path / "c.csv")]) == 0
        assert signal.getsignal(signal.SIGTERM) is mine
        assert main(["contacts", str(tmp_path / "missing.csv"), "--out", str(tmp_path / "d.csv")]) == 2  # a failing one
        assert signal.getsignal(signal.SIGTERM) is mine
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_serve_budgets_default_to_the_api_settings_and_say_so():
    """``serve --request-budget/--analysis-budget``: absent, the API keeps ApiSettings' budgets, and
    the help states those defaults (one value, read from the settings)."""
    from app.api.settings import ApiSettings

    defaults = ApiSettings()
    args = build_parser().parse_args(["serve"])
    assert (args.request_budget, args.analysis_budget) == (None, None)
    args = build_parser().parse_args(["serve", "--request-budget", "2.5", "--analysis-budget", "60"])
    assert (args.request_budget, args.analysis_budget) == (2.5, 60.0)
    serve = next(a for a in build_parser()._actions if a.dest == "command").choices["serve"]
    helps = {a.dest: a.help for a in serve._actions}
    assert helps["request_budget"].endswith(f"(default {defaults.request_budget_s:g})")
    assert helps["analysis_budget"].endswith(f"(default {defaults.time_budget_s:g})")


def test_bad_config_file_is_a_clear_error(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["screenshot", "--config", str(bad), "--out", str(tmp_path / "x.png")]) == 2
    assert "not valid JSON" in capsys.readouterr().err
    wrong = tmp_path / "wrong.json"
    wrong.write_text(json.dumps({"dim": 3, "A": {"center": [0, 0, 0], "semi_axes": [1, -1, 1]}}))
    assert main(["screenshot", "--config", str(wrong), "--out", str(tmp_path / "x.png")]) == 2
    assert "A.semi_axes: must be positive" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_screenshot_with_no_browser_at_the_address_is_one_line_naming_it(tmp_path, capsys):
    """``--browser URL`` where no Chromium listens: exit 1, one line that names the address, no file
    (the scene started for it is stopped)."""
    pytest.importorskip("playwright")
    url = f"http://127.0.0.1:{free_port()}"
    out = tmp_path / "x.png"
    assert main(["screenshot", "--preset", "none", "--out", str(out), "--browser", url, "--timeout", "20"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: no Chromium answers at {url}: "), err
    assert not out.exists()


def test_config_file_and_dim_override(tmp_path):
    f = tmp_path / "c.json"
    f.write_text(json.dumps({"dim": 3, "preset": None, "B": {"center": ["5/2", 0, 0], "semi_axes": [1, 1, 1]}}))
    cfg = config_from_args(build_parser().parse_args(["screenshot", "--config", str(f), "--out", "x.png"]))
    assert str(cfg.shapes()[1].center[0]) == "5/2" and cfg.preset is None
    cfg2 = config_from_args(build_parser().parse_args(["screenshot", "--config", str(f), "--dim", "2", "--out", "x.png"]))
    assert cfg2.dim == 2 and len(cfg2.shapes()[0].center) == 2


def test_help_runs_as_module():
    r = subprocess.run([sys.executable, "-m", "app", "--help"], cwd=ROOT, capture_output=True, text=True, timeout=60, check=False)
    assert r.returncode == 0
    assert "screenshot" in r.stdout and "serve" in r.stdout


def test_serve_starts_scene_and_api():
    scene_port, api_port = free_port(), free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.Popen(
        [sys.executable, "-m", "app", "serve", "--port", str(scene_port), "--api-port", str(api_port), "--preset", "none"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
    )
    try:
        deadline = time.monotonic() + 60
        ok_scene = ok_api = False
        while time.monotonic() < deadline and not (ok_scene and ok_api):
            time.sleep(0.3)
            assert p.poll() is None, p.stdout.read() if p.stdout else ""
            try:
                r = httpx.get(f"http://127.0.0.1:{scene_port}/", timeout=2, follow_redirects=True)
                # the root redirects each new tab to an address of its own, /s/<tab id>/
                ok_scene = ok_scene or (r.status_code == 200 and r.url.path.startswith("/s/") and "<html" in r.text)
                ok_api = ok_api or httpx.get(f"http://127.0.0.1:{api_port}/healthz", timeout=2).status_code == 200
            except httpx.HTTPError:
                pass
        assert ok_scene and ok_api
    finally:
        p.terminate()
        try:
            out, _ = p.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            p.kill()
            out, _ = p.communicate()
    assert f"http://127.0.0.1:{scene_port}/" in out
    assert f"http://127.0.0.1:{api_port}/" in out


def test_serve_hands_its_scene_and_api_options_on(monkeypatch, capsys):
    """``serve --sphere-subdivisions/--request-budget/--analysis-budget`` reach the scene server and
    the API's settings (both stubbed here: nothing listens)."""
    import app.lifecycle
    import app.scene.server

    seen: dict[str, object] = {}

    class Scene:
        url = "http://127.0.0.1:1/"

        def stop(self) -> None:
            seen["stopped"] = True

    def start_scene(host, port, config, **kw):
        seen["scene"] = kw
        return Scene()

    monkeypatch.setattr(app.scene.server, "start_scene", start_scene)
    monkeypatch.setattr(app.lifecycle, "serve", lambda api, host, port, stop: seen.setdefault("settings", api.state.settings))
    assert main(["serve", "--preset", "none", "--sphere-subdivisions", "2", "--request-budget", "3", "--analysis-budget", "45"]) == 0
    assert seen["scene"]["sphere_subdivisions"] == 2 and seen["stopped"]
    settings = seen["settings"]
    assert (settings.request_budget_s, settings.time_budget_s) == (3.0, 45.0)
    capsys.readouterr()


def test_export_hands_its_sphere_subdivisions_on(monkeypatch, tmp_path, capsys):
    """``export --sphere-subdivisions K`` reaches the replay (stubbed here); the default is the scene's."""
    import app.scene.pair.replay
    from app.scene.common.mesh_detail import SPHERE_SUBDIVISIONS

    seen: list[int] = []

    def replay_html(config, **kw):
        seen.append(kw["sphere_subdivisions"])
        return "<!doctype html>"

    monkeypatch.setattr(app.scene.pair.replay, "replay_html", replay_html)
    assert main(["export", "--preset", "example-29", "--sphere-subdivisions", "2", "--out", str(tmp_path / "a.html")]) == 0
    assert main(["export", "--preset", "example-29", "--out", str(tmp_path / "b.html")]) == 0
    assert seen == [2, SPHERE_SUBDIVISIONS]
    capsys.readouterr()


def test_no_subcommand_means_serve():
    from app.cli import build_parser

    # main() prepends "serve"; check the options it then accepts
    args = build_parser().parse_args(["serve", "--host", "0.0.0.0", "--port", "9001", "--api-port", "9002", "--api-only"])
    assert (args.host, args.port, args.api_port, args.api_only) == ("0.0.0.0", 9001, 9002, True)
    with pytest.raises(SystemExit) as e:
        main(["--port", "not-a-port"])
    assert e.value.code == 2


def test_busy_scene_port_is_an_error_not_a_move(tmp_path):
    """A taken scene port stops the start with a message; viser must not drift onto the next
    port (which may be the API's: start-up then failed with a confusing error)."""
    scene_port, api_port = free_port(), free_port()
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", scene_port))
        busy.listen()
        r = subprocess.run(
            [sys.executable, "-m", "app", "serve", "--port", str(scene_port), "--api-port", str(api_port), "--preset", "none"],
            cwd=ROOT, capture_output=True, text=True, timeout=60, env={**os.environ, "PYTHONPATH": str(ROOT)}, check=False,
        )
    assert r.returncode == 1
    assert f"the scene's port {scene_port} on 127.0.0.1 is already in use" in r.stderr
