"""The command line at its edges, through the real program (a subprocess each, as a user runs it).

Outputs are written whole or not at all (Ctrl+C included), pipes work (``-`` for stdin and
stdout, messages on stderr only), and user errors are one line with a non-zero exit status,
never a traceback (issue 21, item 3).
"""

from __future__ import annotations

import csv
import io
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bench.bodies_data import random_bodies
from core import bodies_from_axes, classify, contacts

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(ROOT)}


def run(*argv: str, stdin: bytes | None = None, timeout: float = 300, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[bytes]:
    return subprocess.run(
        [sys.executable, "-m", "app", *argv], input=stdin, capture_output=True, cwd=ROOT, env={**ENV, **(env or {})}, timeout=timeout,
        check=False,
    )


def one_line_error(r: subprocess.CompletedProcess[bytes], status: int, *words: str) -> str:
    """The run failed with ``status`` and exactly one line on stderr, naming ``words``; no traceback."""
    err = r.stderr.decode()
    assert r.returncode == status, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, err
    assert r.stdout == b""
    return err


def bodies_csv(path: Path, n: int = 300, seed: int = 4) -> Path:
    b = random_bodies(n, dim=3, seed=seed)
    rows = np.concatenate([b.centers, b.semi_axes, b.orientations], axis=1)
    path.write_text("x,y,z,a,b,c,qw,qx,qy,qz\n" + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows))
    return path


def no_temporary_files(folder: Path) -> None:
    assert not [p.name for p in folder.iterdir() if p.name.endswith(".part")]


# ----------------------------------------------------------------------------- whole or nothing
def test_a_failed_run_leaves_the_old_output_and_no_temporary_file(tmp_path):
    out = tmp_path / "pairs.csv"
    out.write_text("old\n")
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z,a,b,c,qw,qx,qy,qz\n0,0,0,1,1,1,1,0,0,0\n0,0,oops,1,1,1,1,0,0,0\n")
    one_line_error(run("contacts", str(bad), "--out", str(out)), 2, "bad.csv: line 3, column 3")
    assert out.read_text() == "old\n"
    no_temporary_files(tmp_path)


def _signal_state() -> str:
    """This process's ignored and blocked signal masks (Linux), for a failure message."""
    try:
        return " ".join(ln.strip() for ln in Path("/proc/self/status").read_text().splitlines() if ln.startswith(("SigIgn", "SigBlk")))
    except OSError:
        return "(no /proc)"


SIGINT_AS_A_TERMINAL_GIVES_IT = (
    "import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); "
    "signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT}); os.execv(sys.executable, [sys.executable, *sys.argv[1:]])"
)
"""Run the rest of argv as a command with SIGINT handled by default and not blocked.

An ignored or blocked SIGINT survives exec (a shell's background job gets it ignored on purpose,
and Python then leaves it ignored): the child of a test process that inherited such a state would
finish its run instead of stopping (seen once in a full suite run under load). A small exec
wrapper, not ``preexec_fn`` (unsafe in a process with threads)."""


def test_sigint_during_a_long_contacts_run_exits_130_and_keeps_the_old_file(tmp_path):
    """Start a long run, wait for its progress line on stderr, press Ctrl+C (SIGINT)."""
    b = random_bodies(60_000, dim=3, seed=11)
    np.savez(tmp_path / "many.npz", centers=b.centers, semi_axes=b.semi_axes, orientations=b.orientations)
    out = tmp_path / "pairs.csv"
    out.write_text("old pairs\n")
    p = subprocess.Popen(
        [sys.executable, "-c", SIGINT_AS_A_TERMINAL_GIVES_IT, "-m", "app", "contacts", str(tmp_path / "many.npz"), "--out", str(out),
         "--method", "exact"],
        cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
    )
    parent_state = _signal_state()
    try:
        lines = []
        assert p.stderr is not None
        while True:  # the state to wait for: the progress bar has been drawn
            line = p.stderr.readline().decode()
            assert line, f"the run ended before drawing progress: {''.join(lines)}"
            lines.append(line)
            if line.startswith("classifying ["):
                break
        assert p.poll() is None
        p.send_signal(signal.SIGINT)
        _, rest = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130, f"{rest.decode()}\ntest process: {parent_state}"
    assert "interrupted" in rest.decode() and "Traceback" not in rest.decode()
    assert out.read_text() == "old pairs\n"
    no_temporary_files(tmp_path)


@pytest.mark.parametrize(("sig", "status", "word"), [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")])
def test_a_stop_signal_swallowed_on_its_way_still_stops_the_command(tmp_path, monkeypatch, capsys, sig, status, word):
    """Python raises a signal's exception wherever the main thread is, and C code that calls Python
    and clears its errors can swallow it (numpy looking up a special attribute on an enum did, in a
    clean-clone CI run: Ctrl+C lost, the file written, exit 0). The command still stops: its exit
    status, the old file kept, no temporary file."""
    import core
    from app.cli import main

    real = core.contacts

    def swallowing(*args, **kwargs):
        try:
            signal.raise_signal(sig)  # the handler runs here, inside the try
            for _ in range(100):  # (a few bytecodes later at most)
                pass
        except BaseException:  # what such C code does with any error  # noqa: BLE001, S110
            pass
        return real(*args, **kwargs)

    monkeypatch.setattr(core, "contacts", swallowing)
    out = tmp_path / "pairs.csv"
    out.write_text("old pairs\n")
    assert main(["contacts", str(bodies_csv(tmp_path / "b.csv")), "--out", str(out), "--quiet"]) == status
    assert word in capsys.readouterr().err
    assert out.read_text() == "old pairs\n"
    no_temporary_files(tmp_path)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler or sig != signal.SIGINT  # handlers given back


def test_output_path_errors_are_one_line_and_come_first(tmp_path):
    src = bodies_csv(tmp_path / "b.csv")
    (tmp_path / "folder").mkdir()
    one_line_error(run("contacts", str(src), "--out", str(tmp_path / "folder")), 2, "is a folder")
    one_line_error(run("contacts", str(src), "--out", str(tmp_path / "missing" / "p.csv")), 2, "does not exist")
    one_line_error(run("contacts", str(src), "--out", "/proc/pairs.csv"), 2, "cannot write in /proc")
    one_line_error(run("contacts", str(tmp_path / "nothing.csv"), "--out", str(tmp_path / "p.csv")), 2, "cannot read", "nothing.csv")
    one_line_error(run("contacts", str(tmp_path / "folder"), "--out", str(tmp_path / "p.csv")), 2, "is a folder")
    one_line_error(run("contacts", "/proc/self/status", "--out", str(tmp_path / "p.csv")), 2, "the header must name")
    no_temporary_files(tmp_path)
    assert not (tmp_path / "p.csv").exists()


# ----------------------------------------------------------------------------- pipes
def test_stdin_to_stdout_pipe_carries_only_the_pairs(tmp_path):
    src = bodies_csv(tmp_path / "b.csv", n=400)
    r = run("contacts", "-", "--out", "-", stdin=src.read_bytes())
    assert r.returncode == 0, r.stderr.decode()
    rows = list(csv.DictReader(io.StringIO(r.stdout.decode())))
    b = random_bodies(400, dim=3, seed=4)
    want = contacts(bodies_from_axes(b.centers, b.semi_axes, b.orientations))
    assert [(int(x["i"]), int(x["j"])) for x in rows] == list(zip(want.i.tolist(), want.j.tolist(), strict=True))
    assert {x["certified_by"] for x in rows} <= {"float", "exact"}
    err = r.stderr.decode()
    assert "read 400 ellipsoids from <stdin>" in err and want.summary() in err and "wrote" in err
    quiet = run("contacts", "-", "--out", "-", "--quiet", stdin=src.read_bytes())
    assert quiet.returncode == 0 and quiet.stderr == b"" and quiet.stdout == r.stdout


def test_classify_writes_exactly_the_path_given_and_pipes(tmp_path):
    Q = bodies_from_axes(*(lambda b: (b.centers, b.semi_axes, b.orientations))(random_bodies(200, dim=3, seed=2)))
    np.savez(tmp_path / "pairs.npz", A=Q[:100], B=Q[100:])
    r = run("classify", str(tmp_path / "pairs.npz"), "--out", str(tmp_path / "outdir"))
    assert r.returncode == 0 and r.stdout == b"", r.stderr.decode()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["outdir", "pairs.npz"]  # no outdir.npy
    assert np.array_equal(np.load(tmp_path / "outdir"), classify(Q[:100], Q[100:]))
    assert f"wrote 100 labels to {tmp_path / 'outdir'}" in r.stderr.decode()
    piped = run("classify", "-", "--out", "-", "--quiet", stdin=(tmp_path / "pairs.npz").read_bytes())
    assert piped.returncode == 0 and piped.stderr == b""
    assert np.array_equal(np.load(io.BytesIO(piped.stdout)), classify(Q[:100], Q[100:]))


def test_version_and_help():
    r = run("--version")
    assert r.returncode == 0 and r.stdout.decode().startswith("ellipsoid-interference ")
    assert run("contacts", "--help").returncode == 0


# ----------------------------------------------------------------------------- user errors
def test_bad_npz_files_are_one_line_errors_never_suggesting_pickles(tmp_path):
    Q = bodies_from_axes([[0, 0, 0], [3, 0, 0]], [[1, 1, 1]] * 2)
    np.savez(tmp_path / "good.npz", A=Q, B=Q[::-1])
    data = (tmp_path / "good.npz").read_bytes()
    (tmp_path / "cut.npz").write_bytes(data[: len(data) // 2])
    (tmp_path / "text.npz").write_text("x,y\n1,2\n")
    np.save(tmp_path / "one.npy", Q)
    np.savez(tmp_path / "objects.npz", A=np.array([{"a": 1}], dtype=object), B=Q)
    cases = {
        "cut.npz": "damaged or truncated .npz file",
        "text.npz": "not an .npz file",
        "one.npy": "a single .npy array, not an .npz archive",
        "objects.npz": "array 'A' holds Python objects",
    }
    for name, words in cases.items():
        err = one_line_error(run("classify", str(tmp_path / name), "--out", str(tmp_path / "l.npy")), 2, words)
        assert "allow_pickle" not in err and "pickle=" not in err
        err = one_line_error(run("contacts", str(tmp_path / name), "--format", "npz", "--out", str(tmp_path / "p.csv")), 2)
        assert "allow_pickle" not in err
    no_temporary_files(tmp_path)
    assert not (tmp_path / "l.npy").exists() and not (tmp_path / "p.csv").exists()


def test_screenshot_time_beyond_the_float_range_is_a_message(tmp_path):
    for t in ("1e400", "-1e400", "1e-400"):
        one_line_error(run("screenshot", f"--t={t}", "--out", str(tmp_path / "x.png")), 2, "t out of range")
    assert not (tmp_path / "x.png").exists()


def test_unreachable_scheduler_is_a_message(tmp_path):
    src = bodies_csv(tmp_path / "b.csv", n=50)
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "p.csv"
    out.write_text("old\n")
    r = run("contacts", str(src), "--out", str(out), "--scheduler", f"tcp://127.0.0.1:{port}", "--quiet",
            env={"DASK_ELLIPSOIDS__CONNECT_TIMEOUT": "1s"})  # the documented knob; 10 s by default
    one_line_error(r, 1,
                   f"cannot reach the Dask scheduler at tcp://127.0.0.1:{port}")
    assert out.read_text() == "old\n"
    no_temporary_files(tmp_path)


def test_an_event_is_checked_before_any_browser_starts(tmp_path, monkeypatch):
    """--event K beyond the motion's events, or for static shapes, is refused before a browser starts."""
    import app.screenshot as shot_module
    from app.cli import main

    def no_browser(*a, **k):
        raise AssertionError("a browser was started for an event the motion does not have")

    monkeypatch.setattr(shot_module, "HeadlessScene", no_browser)
    with pytest.raises(ValueError, match=r"^--event 3: this motion has 2 events \(1\.\.2\)$"):
        shot_module.screenshots(shot_module.shots_for(shot_module.SceneConfig.from_dict({"preset": "example-29"}), tmp_path / "a.png", [], [3]))
    static = shot_module.SceneConfig.from_dict({"preset": None, "event": 1})
    with pytest.raises(ValueError, match=r"^--event 1: the scene has no motion"):
        shot_module.screenshots([shot_module.Shot(static, tmp_path / "b.png")])
    assert main(["screenshot", "--preset", "example-29", "--event", "99", "--out", str(tmp_path / "c.png")]) == 2
    assert list(tmp_path.iterdir()) == []


@pytest.mark.browser
def test_screenshot_of_an_event_the_motion_does_not_have_is_refused(tmp_path):
    if not Path("/usr/bin/chromium").exists():
        pytest.skip("needs /usr/bin/chromium")
    r = run("screenshot", "--preset", "example-29", "--event", "99", "--out", str(tmp_path / "x.png"), "--width", "800", "--height", "600")
    one_line_error(r, 2, "--event 99: this motion has 2 events (1..2)")
    assert not (tmp_path / "x.png").exists()
    no_temporary_files(tmp_path)


# ----------------------------------------------------------------------------- large inputs
def _peak_rss_kib(*argv: str) -> int:
    """Peak resident memory (KiB) of the command line run in a fresh process on ``argv``."""
    code = (
        "import resource, runpy, sys\n"
        f"sys.argv = ['app', *{list(argv)!r}]\n"
        "try:\n    runpy.run_module('app', run_name='__main__')\n"
        "except SystemExit as e:\n    assert not e.code, e.code\n"
        "sys.stderr.write('PEAK %d\\n' % resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, cwd=ROOT, env=ENV, timeout=600, check=False)
    assert r.returncode == 0, r.stderr.decode()
    return int(r.stderr.decode().rsplit("PEAK ", 1)[1])


def test_a_large_csv_is_streamed_not_read_whole(tmp_path):
    """200 MB of CSV (an extra text column of 10 kB per row) read with far less memory than that."""
    b = random_bodies(20_000, dim=3, seed=6)
    rows = np.concatenate([b.centers, b.semi_axes, b.orientations], axis=1)
    note = "n" * 10_000
    big = tmp_path / "big.csv"
    with big.open("w") as f:
        f.write("id,x,y,z,a,b,c,qw,qx,qy,qz,note\n")
        for k, r in enumerate(rows.tolist()):
            f.write(f"{k}," + ",".join(map(repr, r)) + f",{note}\n")
    small = bodies_csv(tmp_path / "small.csv", n=20_000, seed=6)
    size_kib = big.stat().st_size // 1024
    base = _peak_rss_kib("contacts", str(small), "--out", str(tmp_path / "a.csv"), "--quiet")
    peak = _peak_rss_kib("contacts", str(big), "--out", str(tmp_path / "b.csv"), "--quiet")
    a = (tmp_path / "a.csv").read_text().splitlines()
    b = [line.split(",") for line in (tmp_path / "b.csv").read_text().splitlines()]
    assert b[0][-2:] == ["id_i", "id_j"] and all(r[-2:] == r[:2] for r in b[1:])  # the id column: the row numbers
    assert a == [",".join(r[:-2]) for r in b]  # the same bodies, the same pairs
    assert peak - base < size_kib // 4, (peak, base, size_kib)


# ----------------------------------------------------------------------------- install without extras
def test_without_playwright_the_library_cli_and_scene_work_and_screenshot_says_what_to_install(tmp_path):
    """Playwright is the ``screenshot`` extra: a shim makes it missing, as after ``pip install .``."""
    shim = tmp_path / "shim" / "playwright"
    shim.mkdir(parents=True)
    (shim / "__init__.py").write_text("raise ImportError(\"No module named 'playwright'\")\n")
    env = {**ENV, "PYTHONPATH": f"{shim.parent}{os.pathsep}{ROOT}"}
    code = "import core, app.cli, app.api, app.scene.server, app.screenshot; print('ok')"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, cwd=ROOT, env=env, timeout=120, check=False)
    assert r.returncode == 0 and r.stdout == b"ok\n", r.stderr.decode()
    r = subprocess.run(
        [sys.executable, "-m", "app", "screenshot", "--preset", "example-29", "--out", str(tmp_path / "x.png")],
        capture_output=True, cwd=ROOT, env=env, timeout=120, check=False,
    )
    if not Path("/usr/bin/chromium").exists():
        pytest.skip("the chromium check comes first")
    one_line_error(r, 1, "pip install 'ellipsoid-interference[screenshot]'")
    assert not (tmp_path / "x.png").exists()
