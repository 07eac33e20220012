"""Hostile input against the real server (issue 11): short text can neither crash nor freeze it.

One ``python -m app serve`` (scene + API) runs for the module. Each hostile request is sent while
a thread probes ``/healthz``: the request is answered with a 4xx (or a 503 from a budget) within
seconds, ``/healthz`` never stalls, the server's memory stays bounded, it is alive afterwards and
no worker process is left behind. Then the scene's websocket Origin rule, and the lifecycle:
SIGTERM ends a running analysis and exits within 5 s; after SIGKILL no worker survives.

Bounds are generous (seconds, hundreds of MB): these tests catch freezes of tens of seconds and
gigabyte allocations, not speed.
"""

from __future__ import annotations

import asyncio
import json
import os
import random
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import httpx
import pytest

from bench.machine import rss_mb

ROOT = Path(__file__).resolve().parents[1]
SEMIPRIME_100 = (10**50 + 151) * (10**50 + 447)
ANSWER_S = 8.0
"""A hostile request is answered within this (the worker budgets are 5-20 s; refusals are instant)."""
HEALTH_S = 1.0
"""Longest /healthz latency tolerated while a hostile request runs."""
RSS_MB = 1500
"""The server process (not its workers) stays below this resident size."""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


# --- processes ---------------------------------------------------------------------------------

def _ppid_map() -> dict[int, int]:
    out = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
            except OSError:
                continue
            fields = stat[stat.rindex(")") + 2 :].split()
            if fields[0] != "Z":  # zombies have exited
                out[int(d.name)] = int(fields[1])
    return out


def descendants(pid: int) -> set[int]:
    """Live processes below ``pid`` (children, grandchildren, ...)."""
    ppid = _ppid_map()
    found, frontier = set(), {pid}
    while frontier:
        frontier = {p for p, pp in ppid.items() if pp in frontier} - found
        found |= frontier
    return found


def cmdline(pid: int) -> str:
    try:
        return (Path("/proc") / str(pid) / "cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def job_processes(server_pid: int) -> set[int]:
    """Analysis workers: children of the fork server (not the fork server or resource tracker)."""
    ppid = _ppid_map()
    forkservers = {p for p in descendants(server_pid) if "forkserver" in cmdline(p) and ppid.get(p) == server_pid}
    return {p for p, pp in ppid.items() if pp in forkservers}


def wait_gone(pids: set[int], seconds: float) -> set[int]:
    deadline = time.monotonic() + seconds
    alive = set(pids)
    while alive and time.monotonic() < deadline:
        time.sleep(0.1)
        live = _ppid_map()
        alive = {p for p in alive if p in live}
    return alive


class Server:
    """``python -m app serve`` on free ports (scene and API), stopped with SIGKILL at the end."""

    def __init__(self, *extra: str) -> None:
        self.scene_port, self.api_port = free_port(), free_port()
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "app", "serve", "--port", str(self.scene_port), "--api-port", str(self.api_port),
             "--preset", "none", *extra],
            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        )
        self.api = f"http://127.0.0.1:{self.api_port}"
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            assert self.proc.poll() is None, self.proc.stdout.read() if self.proc.stdout else ""
            try:
                if httpx.get(f"{self.api}/healthz", timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            time.sleep(0.2)
        else:
            raise RuntimeError("server did not start")

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)


@pytest.fixture(scope="module")
def server():
    s = Server("--allow-origin", "https://example.org")
    yield s
    below = descendants(s.proc.pid)
    s.kill()
    wait_gone(below, 10)


class HealthProbe:
    """Polls /healthz every 50 ms in a thread; records the worst latency."""

    def __init__(self, api: str) -> None:
        self.api = api
        self.latencies: list[float] = []
        self.failures: list[str] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        with httpx.Client(timeout=10) as c:
            while True:  # at least one probe, however late this thread starts on a loaded machine
                t0 = time.monotonic()
                try:
                    ok = c.get(f"{self.api}/healthz").status_code == 200
                except httpx.HTTPError as e:
                    ok = False
                    self.failures.append(repr(e))
                self.latencies.append(time.monotonic() - t0)
                if not ok:
                    self.failures.append("not 200")
                if self._stop.wait(0.05):
                    break

    def __enter__(self) -> HealthProbe:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(15)


def short(v: object) -> str:
    """Short test id for a long parameter."""
    text = str(v)
    return text if len(text) <= 40 else f"{text[:30]}...({len(text)})"


def circle_moving(x: str) -> dict:
    return {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": [x, "0"]}


def send_hostile(server: Server, path: str, *, json_body: object = None, content: str | None = None) -> httpx.Response:
    """Send one hostile request while probing /healthz; check the server's invariants around it."""
    with HealthProbe(server.api) as probe:
        t0 = time.monotonic()
        with httpx.Client(timeout=60) as c:
            if content is not None:
                r = c.post(f"{server.api}{path}", content=content, headers={"content-type": "application/json"})
            else:
                r = c.post(f"{server.api}{path}", json=json_body)
        seconds = time.monotonic() - t0
        time.sleep(0.2)  # a few probes after the answer too
    assert seconds < ANSWER_S, (seconds, r.status_code, r.text[:300])
    assert probe.latencies and max(probe.latencies) < HEALTH_S, max(probe.latencies)
    assert not probe.failures, probe.failures[:3]
    assert server.proc.poll() is None, "the server died"
    assert rss_mb(server.proc.pid) < RSS_MB
    assert wait_gone(job_processes(server.proc.pid), 5) == set(), "a worker process was left behind"
    return r


# --- hostile motion text (/api/analyse: parsed in a worker under the server limits) -----------------

@pytest.mark.parametrize(
    "text, fragment",
    [
        ("((((1e1400)^64)^64)^64)^64*t", "exponent out of range in '1e1400': |e| <= 1000 after 'e'"),
        ("(((1e1400)^64)^64)^64*t", "exponent out of range in '1e1400': |e| <= 1000 after 'e'"),
        ("((((1e1000)^64)^64)^64)^64*t", "constant too large: about 2^"),
        ("(((9e999)^64)^64)^64*t", "constant too large: about 2^"),
        ("(t+1e999)^64*(t+2e999)^64/(t+1e999)^63", "constant too large: about 2^"),
        ("(t+1e99)^64*(t+2e99)^64/(t+1e99)^63", "constant too large: about 2^"),
        ("1/(t^64+1e80*t+3)^4 + 1/(t^64+7e80*t+1)^4", "degree in t too high: 512 (limit 256)"),
        ("t" + "*(t+1)" * 300, "degree in t too high: 257 (limit 256)"),
        ("(" * 200 + "t" + ")" * 200, "nested too deeply (> 60)"),
        ("1" * 500 + "*t", "number string too long (500 > 400 characters)"),
        ("t" + "+t" * 1500, "expression too long (3001 > 2000 characters)"),
    ],
    ids=short,
)
def test_hostile_motion_text_is_refused_quickly(server, text, fragment):
    r = send_hostile(server, "/api/analyse", json_body={"a": circle_moving(text), "b": circle_moving("-t")})
    assert r.status_code == 422, r.text[:300]
    assert r.json()["detail"].startswith("a.translation[0]: ")
    assert fragment in r.json()["detail"]


@pytest.mark.parametrize("n", [SEMIPRIME_100, SEMIPRIME_100 * (10**80 + 129), 10**399 + 1], ids=short)
def test_sqrt_of_a_large_integer_is_not_factored(server, n):
    """Was: the parser factored n (a 100-digit semiprime froze the server for good)."""
    r = send_hostile(server, "/api/analyse", json_body={"a": circle_moving(f"sqrt({n})*t - 3"), "b": circle_moving("-t")})
    assert r.status_code == 200, r.text[:300]
    assert [e["value"][:6] for e in r.json()["events"]] != []


def test_hostile_classify_batches(server):
    a = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, -1]]
    b = [[1, 0, 0, "-1e1400"], [0, 1, 0, 0], [0, 0, 1, 0], ["-1e1400", 0, 0, "1e2800"]]
    r = send_hostile(server, "/api/classify", json_body={"pairs": [{"a": a, "b": b}] * 1000})
    assert r.status_code == 422 and "|e| <= 1000 after 'e'" in r.text
    # the largest numbers the edge accepts, 400 digits and exponent 1000: answered or cut off by the budget
    rng = random.Random(0)
    pairs = []
    for _ in range(300):
        c = "".join(rng.choice("123456789") for _ in range(390)) + "e600"
        d = "".join(rng.choice("123456789") for _ in range(390)) + "e-600"
        pairs.append({"a": [[d, 0, 0], [0, 1, 0], [0, 0, "-1"]], "b": [[1, 0, c], [0, 1, 0], [c, 0, "1e1000"]]})
    body = json.dumps({"pairs": pairs})
    assert len(body) > 250_000
    r = send_hostile(server, "/api/classify", content=body)
    assert r.status_code in (200, 422, 503), r.text[:300]
    if r.status_code == 503:
        assert "over the time budget of 5 s per request" in r.json()["detail"]


@pytest.mark.parametrize(
    "content, status, fragment",
    [
        ("[" * 100_000 + "]" * 100_000, 400, "JSON nested too deeply"),
        ('{"a": [[1,0,0],[0,1,0],[0,0,-1]], "b": [[1,0,0],[0,1,0],[0,0,1e-400]]}', 422, "underflows to 0 as a float"),
        ('{"a": [[1,0,0],[0,1,0],[0,0,-1]], "b": [[1,0,0],[0,1,0],[0,0,' + "7" * 5000 + "]]}", 422, "integer too large"),
    ],
    ids=short,
)
def test_hostile_json(server, content, status, fragment):
    r = send_hostile(server, "/api/classify", content=content)
    assert r.status_code == status and fragment in r.text


def test_server_is_alive_and_exact_afterwards(server):
    r = httpx.post(f"{server.api}/api/classify", json={"a": [[1, 0, 0], [0, 1, 0], [0, 0, -1]], "b": [[1, 0, -2], [0, 1, 0], [-2, 0, 3]]})
    assert (r.status_code, r.json()["relation"]) == (200, "tangent")
    assert job_processes(server.proc.pid) == set()


# --- the scene's websocket: Origin -------------------------------------------------------------------

def handshake(port: int, origin: str | None) -> int:
    """HTTP status of a websocket handshake with this Origin (101 = accepted)."""
    import websockets

    async def go() -> int:
        try:
            async with websockets.connect(f"ws://127.0.0.1:{port}/", origin=origin, subprotocols=["viser-v1.1.1"],
                                          open_timeout=10):
                return 101
        except websockets.exceptions.InvalidStatus as e:
            return e.response.status_code

    return asyncio.run(go())


def test_scene_websocket_origin_rule(server):
    p = server.scene_port
    assert handshake(p, None) == 101  # scripts and tests send no Origin
    assert handshake(p, f"http://127.0.0.1:{p}") == 101
    assert handshake(p, f"http://localhost:{p}") == 101
    assert handshake(p, "https://example.org") == 101  # --allow-origin
    assert handshake(p, "http://evil.example") == 403
    assert handshake(p, f"http://evil.example:{p}") == 403  # DNS rebinding: a foreign name on our port
    assert handshake(p, f"http://localhost:{p + 1}") == 403  # another local service's page
    assert handshake(p, "https://example.org:8443") == 403
    assert handshake(p, "null") == 403
    page = httpx.get(f"http://127.0.0.1:{p}/", timeout=10, follow_redirects=True)
    assert page.status_code == 200  # plain HTTP (the page itself, at the tab's own address) is unaffected


# --- lifecycle -----------------------------------------------------------------------------------------

def slow_motion() -> dict:
    """A legitimate analysis that takes several seconds (degree-10 translation, 50-digit rationals)."""
    rng = random.Random(3)

    def poly(deg: int) -> str:
        return " + ".join(f"{rng.randint(1, 10**50)}/{rng.randint(1, 10**50)}*t^{k}" for k in range(deg + 1))

    a = {"shape": {"center": [0, 0, 0], "semi_axes": [1, 2, 3]}, "translation": [poly(10), poly(10), "0"],
         "rotation": {"quaternion": ["1", poly(2), "0", "0"]}}
    return {"a": a, "b": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 1, 1]}}}


def start_slow_analysis(s: Server) -> threading.Thread:
    def post() -> None:
        try:
            httpx.post(f"{s.api}/api/analyse", json=slow_motion(), timeout=60)
        except httpx.HTTPError:
            pass

    th = threading.Thread(target=post, daemon=True)
    th.start()
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        if httpx.get(f"{s.api}/healthz", timeout=5).json()["analyses_running"] == 1 and job_processes(s.proc.pid):
            return th
        time.sleep(0.05)
    raise AssertionError("the analysis did not start")


def test_work_of_a_client_that_went_away_is_stopped(server):
    """The client gives up after 1 s: its analysis worker is killed (was: ran to its budget)."""
    with pytest.raises(httpx.ReadTimeout):
        httpx.post(f"{server.api}/api/analyse", json=slow_motion(), timeout=httpx.Timeout(30, read=1.0))
    t0 = time.monotonic()
    while httpx.get(f"{server.api}/healthz").json()["analyses_running"] and time.monotonic() - t0 < 5:
        time.sleep(0.05)
    assert time.monotonic() - t0 < 3.0  # the slow analysis takes ~9 s here: it was stopped, not finished
    assert wait_gone(job_processes(server.proc.pid), 2) == set()


def test_sigterm_ends_a_running_analysis_and_exits_within_5_s():
    s = Server()
    try:
        start_slow_analysis(s)
        below = descendants(s.proc.pid)
        assert job_processes(s.proc.pid)
        t0 = time.monotonic()
        s.proc.send_signal(signal.SIGTERM)
        s.proc.wait(10)
        assert time.monotonic() - t0 < 5.0
        assert s.proc.returncode == 0
        assert wait_gone(below, 5) == set(), [cmdline(p) for p in below]
    finally:
        s.kill()


def test_workers_die_with_a_killed_server():
    s = Server()
    try:
        start_slow_analysis(s)
        below = descendants(s.proc.pid)
        jobs = job_processes(s.proc.pid)
        assert jobs
        s.proc.kill()
        s.proc.wait(10)
        assert wait_gone(below, 5) == set(), [cmdline(p) for p in below]
    finally:
        s.kill()


# --- the scene: typed motions are read in a worker, edge messages ------------------------------------

@pytest.fixture(scope="module")
def scene_session():
    viser = pytest.importorskip("viser")
    from app.scene.common.state import SceneConfig
    from app.scene.pair.analysis import AnalysisCache
    from app.scene.pair.session import Session

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    cache = AnalysisCache(processes=True)
    s = Session(server, SceneConfig(preset="circles-crossing"), cache=cache)
    assert s.ready.wait(120)
    yield s
    s.close()
    cache.shutdown()
    server.stop()


def type_motion(s, a: str, b: str = "-t", interval: str = "-2, 2") -> float:
    s.ui.motion.fields["A"].value = json.dumps(circle_moving(a))
    s.ui.motion.fields["B"].value = json.dumps(circle_moving(b))
    s.ui.motion.fields["interval"].value = interval
    t0 = time.monotonic()
    s.motion_ctl.on_analyse()
    return time.monotonic() - t0


def test_scene_reads_typed_motions_in_a_worker(scene_session, monkeypatch):
    """The scene process never parses a tab's motion: with the parser broken here, it still works."""
    import core.moving.motions

    def broken(*a, **k):
        raise AssertionError("parsed in the scene process")

    monkeypatch.setattr(core.moving.motions, "parse_expression", broken)
    s = scene_session
    s.ready.clear()
    assert type_motion(s, "t") < ANSWER_S
    assert not s.ui.motion.errors["A"].visible
    assert s.ready.wait(60) and [e.t for e in s.state.analysis.events] == [-1.0, 1.0]


@pytest.mark.parametrize(
    "a, interval, field, fragment",
    [
        ("(t+1e999)^64*(t+2e999)^64/(t+1e999)^63", "-2, 2", "A", "constant too large: about 2^"),
        ("((((1e1400)^64)^64)^64)^64*t", "-2, 2", "A", "|e| &lt;= 1000 after &#x27;e&#x27;"),
        ("t", "1e400, 1e401", "interval", "beyond the range of the time slider"),
        ("t", "1e-400, 1e-399", "interval", "too close for the time slider"),
        ("t", "0, 1e1001", "interval", "|e| &lt;= 1000 after &#x27;e&#x27;"),
    ],
    ids=short,
)
def test_scene_hostile_typed_motion_gets_a_message(scene_session, a, interval, field, fragment):
    s = scene_session
    seconds = type_motion(s, a, interval=interval)
    assert seconds < ANSWER_S
    assert s.ui.motion.errors[field].visible, {k: m.content for k, m in s.ui.motion.errors.items()}
    assert fragment in s.ui.motion.errors[field].content


def test_scene_sqrt_of_a_semiprime(scene_session):
    s = scene_session
    s.ready.clear()
    assert type_motion(s, f"sqrt({SEMIPRIME_100})*t - 3", interval="-inf, inf") < ANSWER_S
    assert not s.ui.motion.errors["A"].visible
    assert s.ready.wait(60) and len(s.state.analysis.events) == 2
