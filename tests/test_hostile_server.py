"""Every route on a budget, bursts queued, SIGTERM quick (issue 21, item 2), against the real server.

``python -m app serve`` runs in a subprocess. Each attack is sent while threads probe ``/healthz``
(every answer under 1.5 s: the event loop stays free) and the memory of the server and all its
processes (under 3 GB together); afterwards the server is alive and no worker process is left.

* ``POST /api/contacts`` with 10,000 bodies at one point: refused (422) at once, saying how many
  pairs the broad phase would examine and the limit (counted before any pair is built); 500
  bodies at one point: refused because the answer would list too many pairs; a lattice of 9,702
  touching spheres (exact arithmetic for every pair): answered or stopped by the budget (503).
* ``POST /api/sweep`` with 10,000 moving bodies at one point: refused (422) at once, as for
  contacts (the swept broad phase counts before it builds); a sweep whose every pair needs exact
  arithmetic, its client leaving after 1 s: the worker is stopped then, not at the budget.
* ``POST /api/contact-scale`` with ``exact`` on a pair whose work grows with its numbers
  (semi-axis ``1e-999``): stopped by the budget in its worker process (503, Retry-After); a
  client that leaves has its work stopped before the budget runs out.
* A burst of 6 ordinary analyses: all 200 (queued, not refused); beyond the queue (2 running,
  16 waiting): 503 with Retry-After at once; clients that leave empty the queue.
* SIGTERM with heavy work in flight (contacts, an analysis, a queued analysis): every
  in-flight client gets 503, the server exits 0 within 5 s, no process is left.

Waits are on states (``/healthz`` counts, process tables); times are failure guards only,
except the two limits the issue sets (/healthz under 1.5 s, exit within 5 s).
"""

from __future__ import annotations

import asyncio
import json
import signal
import threading
import time

import httpx
import numpy as np
import pytest
from test_hostile import (
    Server,
    circle_moving,
    cmdline,
    descendants,
    job_processes,
    slow_motion,
    wait_gone,
)

from bench.machine import tree_rss_mb

HEALTH_S = 1.5
"""Longest /healthz latency tolerated during an attack (the issue's bound)."""
MEMORY_MB = 3 * 1024
"""The server and all its processes together stay below this resident size (the issue's bound)."""
GUARD_S = 60.0
"""Failure guard for an answer (the budgets are 5-20 s; refusals are immediate)."""
SHORT_BUDGET_S = 1.5
"""The request and analysis budgets of the ``short_budget`` server (``serve --request-budget``,
``--analysis-budget``): the tests of work stopped by the budget wait for it, and the default's 5 s
spent ~10 s of the suite."""
EXIT_S = 5.0
"""SIGTERM to exit, with any work in flight (the issue's bound)."""

UNIT_AXES = {"center": [0, 0], "semi_axes": [1, 2]}
HUGE_WORK = {"a": {"center": ["3", "0"], "semi_axes": ["1e-999", "1"]}, "b": UNIT_AXES, "exact": True}
"""A valid pair whose exact contact scale takes far longer than the 5 s budget (numbers of 3,300 bits)."""


class Probes:
    """/healthz every 50 ms and the memory of the server's process tree, in threads."""

    def __init__(self, server: Server) -> None:
        self.server = server
        self.latencies: list[float] = []
        self.failures: list[str] = []
        self.memory: list[float] = []
        self._stop = threading.Event()
        self._first = threading.Event()  # one /healthz answered: the probes run before the attack starts
        self._threads = [threading.Thread(target=self._health, daemon=True), threading.Thread(target=self._rss, daemon=True)]

    def _health(self) -> None:
        with httpx.Client(timeout=30) as c:
            while not self._stop.is_set():
                t0 = time.monotonic()
                try:
                    status = c.get(f"{self.server.api}/healthz").status_code
                    if status != 200:
                        self.failures.append(f"/healthz {status}")
                except httpx.HTTPError as e:
                    self.failures.append(repr(e))
                self.latencies.append(time.monotonic() - t0)
                self._first.set()
                self._stop.wait(0.05)

    def _rss(self) -> None:
        while not self._stop.is_set():
            self.memory.append(tree_rss_mb(self.server.proc.pid))
            self._stop.wait(0.05)

    def __enter__(self) -> Probes:
        for th in self._threads:
            th.start()
        self._first.wait(30)  # a state, not a sleep: on a loaded machine the thread may start late
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        for th in self._threads:
            th.join(30)

    def check(self) -> None:
        assert self.latencies and max(self.latencies) < HEALTH_S, f"/healthz took {max(self.latencies):.2f} s"
        assert not self.failures, self.failures[:3]
        assert self.memory and max(self.memory) < MEMORY_MB, f"{max(self.memory):.0f} MB"


@pytest.fixture(scope="module")
def server():
    s = Server("--cors-origin", "https://example.org")
    yield s
    below = descendants(s.proc.pid)
    s.kill()
    wait_gone(below, 10)


@pytest.fixture(scope="module")
def short_budget():
    """The API alone with a request budget of SHORT_BUDGET_S (the work the budget stops is the same,
    only sooner); the server above keeps the default 5 s, longer than a client that leaves after 1 s."""
    s = Server("--api-only", "--request-budget", f"{SHORT_BUDGET_S:g}", "--analysis-budget", f"{SHORT_BUDGET_S:g}")
    yield s
    below = descendants(s.proc.pid)
    s.kill()
    wait_gone(below, 10)


def health(s: Server) -> dict:
    return httpx.get(f"{s.api}/healthz", timeout=30).json()


def wait_until(predicate, what: str, seconds: float = GUARD_S) -> None:
    """Poll ``predicate`` until it holds (``seconds`` is only a failure guard)."""
    deadline = time.monotonic() + seconds
    while not predicate():
        assert time.monotonic() < deadline, f"timed out waiting for: {what}"
        time.sleep(0.02)


def attack(s: Server, path: str, body: object) -> httpx.Response:
    """Send one request under the probes; then: server alive, probes fine, no worker left.

    The body is encoded before the probes start: encoding ~100,000 numbers holds this process's
    GIL, which delayed the probe thread itself (a loaded run measured /healthz at 1.53 s).
    """
    content = json.dumps(body).encode()
    with Probes(s) as probes:
        r = httpx.post(f"{s.api}{path}", content=content, headers={"Content-Type": "application/json"}, timeout=GUARD_S)
        wait_until(lambda: health(s)["analyses_running"] == 0, "the worker to end")
        time.sleep(0.2)  # a few probes after the answer
    assert s.proc.poll() is None, "the server died"
    probes.check()
    assert wait_gone(job_processes(s.proc.pid), 10) == set(), "a worker process was left behind"
    return r


def crowd(n: int, dim: int) -> list[list[float]]:
    """n unit bodies at one point (3D rows [x, y, z, a, b, c, qw, qx, qy, qz], 2D [x, y, a, b, angle])."""
    return [[0.0] * 3 + [1.0] * 3 + [1.0, 0.0, 0.0, 0.0]] * n if dim == 3 else [[0.0, 0.0, 1.0, 1.0, 0.0]] * n


# --- contacts --------------------------------------------------------------------------------------

@pytest.mark.parametrize("dim", [3, 2])
def test_contacts_crowd_is_refused_before_any_pair_is_built(server, dim):
    """Was: 5.6 GB (3D) / 10.2 GB (2D) and no answer. 10,000 bodies at one point are 49,995,000 pairs."""
    r = attack(server, "/api/contacts", {"bodies": crowd(10_000, dim)})
    assert r.status_code == 422, r.text[:300]
    assert r.json() == {"detail": (
        "10,000 bodies give 49,995,000 pairs to examine (bodies close enough that their bounding spheres may meet), "
        "over the limit of 2,000,000 per request: send fewer or less crowded bodies, or search them with "
        "`python -m app contacts` or `core.contacts`, which have no such limit"
    )}


def test_contacts_answer_over_the_cap_is_refused_before_it_is_built(server):
    """500 bodies at one point: 124,750 overlapping pairs, over the 100,000 pairs of one answer."""
    r = attack(server, "/api/contacts", {"bodies": crowd(500, 3)})
    assert r.status_code == 422, r.text[:300]
    assert r.json()["detail"].startswith(
        "the answer would list 124,750 pairs of the 500 bodies that touch or overlap, over the limit of 100,000 pairs per answer"
    )


def test_contacts_heavy_exact_work_is_answered_or_stopped_by_the_budget(short_budget):
    """9,702 touching spheres: every one of 27,741 pairs needs exact arithmetic (seconds of work)."""
    server = short_budget
    c = np.array(np.meshgrid(np.arange(21.0), np.arange(21.0), np.arange(22.0), indexing="ij")).reshape(3, -1).T
    rows = [[*p, 0.5, 0.5, 0.5, 1.0, 0.0, 0.0, 0.0] for p in c.tolist()]
    r = attack(server, "/api/contacts", {"bodies": rows})
    if r.status_code == 200:
        assert r.json()["counts"]["tangent"] == 27_741
    else:
        assert r.status_code == 503 and r.headers["retry-after"] == "2", r.text[:300]
        detail = r.json()["detail"]
        assert detail.startswith("stopped after ") and detail.endswith(
            f"pairs to examine: over the time budget of {SHORT_BUDGET_S:g} s per request; send fewer bodies per request"
        ), detail


# --- sweep: moving bodies -------------------------------------------------------------------------

@pytest.mark.parametrize("dim", [3, 2])
def test_sweep_crowd_is_refused_before_any_pair_is_built(server, dim):
    """10,000 moving bodies at one point (each moving by one unit): 49,995,000 pairs to examine."""
    start = crowd(10_000, dim)
    end = [[1.0, *row[1:]] for row in start]
    r = attack(server, "/api/sweep", {"start": start, "end": end})
    assert r.status_code == 422, r.text[:300]
    assert r.json() == {"detail": (
        "10,000 moving bodies give 49,995,000 pairs to examine (bodies whose swept volumes may meet during the step), "
        "over the limit of 2,000,000 per request: send fewer or less crowded bodies, or sweep them with "
        "`python -m app sweep` or `core.sweep_contacts`, which have no such limit"
    )}


def test_sweep_answer_over_the_cap_is_refused_before_it_is_built(server):
    """500 moving bodies at one point: 124,750 pairs overlapping at t = 0, over the 100,000 pairs of one answer."""
    r = attack(server, "/api/sweep", {"start": crowd(500, 3), "end": crowd(500, 3)})
    assert r.status_code == 422, r.text[:300]
    assert r.json()["detail"].startswith(
        "the answer would list 124,750 pairs of the 500 moving bodies that touch or overlap during the step, over the "
        "limit of 100,000 pairs per answer"
    )


def grazing_sweep(n: int) -> dict:
    """n pairs of unit spheres, each passing the other at exactly 2, swept exactly (a few ms per pair)."""
    unit = [1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0]
    start, end = [], []
    for k in range(n):
        x = 20.0 * k
        start += [[x, 0.0, 0.0, *unit], [x + 5, 2.0, 0.0, *unit]]
        end += [[x, 0.0, 0.0, *unit], [x - 5, 2.0, 0.0, *unit]]
    return {"start": start, "end": end, "method": "exact"}


def test_work_of_a_sweep_client_that_went_away_is_stopped(server):
    """5,000 exact grazing pairs (10,000 bodies: far over the 5 s budget); the client leaves after 1 s and its worker with it."""
    with Probes(server) as probes:
        t0 = time.monotonic()
        try:
            r = httpx.post(f"{server.api}/api/sweep", json=grazing_sweep(5000), timeout=httpx.Timeout(30, read=1.0))
            pytest.fail(f"answered within 1 s: {r.status_code} {r.text[:200]}")
        except httpx.ReadTimeout:  # the client leaves
            pass
        wait_until(lambda: health(server)["analyses_running"] == 0, "the worker to be stopped")
        seconds = time.monotonic() - t0
    assert seconds < 5.0, "the worker ran to its budget: the disconnect did not stop it"
    probes.check()
    assert wait_gone(job_processes(server.proc.pid), 5) == set()


def test_sweep_heavy_exact_work_is_answered_or_stopped_by_the_budget(short_budget):
    """The same 5,000 exact grazing pairs, waited for: today 503 saying where the budget stopped the
    sweep (a sweep fast enough to answer them within the budget is as good)."""
    server = short_budget
    r = attack(server, "/api/sweep", grazing_sweep(5000))
    if r.status_code == 200:
        assert r.json()["counts"]["tangent"] == 5000
        return
    assert (r.status_code, r.headers.get("retry-after")) == (503, "2"), r.text[:300]
    detail = r.json()["detail"]
    assert detail.startswith("stopped after ") and detail.endswith(
        f"pairs to examine: over the time budget of {SHORT_BUDGET_S:g} s per request; send fewer bodies per request"
    ), detail


# --- witnesses: work that grows with the numbers ---------------------------------------------------

def test_exact_contact_scale_on_huge_numbers_is_answered_or_stopped_by_the_budget(short_budget):
    """Was: a server thread still running 6 minutes after the client left; SIGTERM could not stop it.

    Today this pair takes far longer than the budget (the precision grows with the size of the
    numbers); a faster witness answers it, which is as good.
    """
    server = short_budget
    r = attack(server, "/api/contact-scale", HUGE_WORK)
    if r.status_code == 200:
        assert r.json()["relation"] == "separate"
    else:
        assert (r.status_code, r.headers.get("retry-after")) == (503, "2"), r.text[:300]
        assert r.json() == {"detail": f"stopped: the job exceeded its time budget of {SHORT_BUDGET_S:g} s and was stopped"}


def test_an_analysis_over_the_budget_the_server_was_given_is_stopped(short_budget):
    """``serve --analysis-budget``: a legitimate analysis of several seconds is stopped at the budget
    given (the default is 20 s), its worker killed."""
    r = attack(short_budget, "/api/analyse", slow_motion())
    assert (r.status_code, r.headers.get("retry-after")) == (503, "2"), r.text[:300]
    assert r.json()["detail"].startswith(f"analysis stopped: the job exceeded its time budget of {SHORT_BUDGET_S:g} s"), r.text


def test_work_of_a_witness_client_that_went_away_is_stopped(server):
    """The client gives up after 1 s: its worker is killed then, not at the 5 s budget.

    (The worker is gone within 5 s either way; while the pair takes longer than the budget, as
    today, only the disconnect can end it that early.)
    """
    t0 = time.monotonic()
    try:
        httpx.post(f"{server.api}/api/contact-scale", json=HUGE_WORK, timeout=httpx.Timeout(30, read=1.0))
    except httpx.ReadTimeout:  # the client leaves (a witness fast enough to answer in 1 s is fine too)
        pass
    wait_until(lambda: health(server)["analyses_running"] == 0, "the worker to be stopped")
    assert time.monotonic() - t0 < 5.0, "the worker ran to its budget: the disconnect did not stop it"
    assert wait_gone(job_processes(server.proc.pid), 5) == set()


@pytest.mark.parametrize("path", ["/api/explain", "/api/witness", "/api/separating-plane"])
def test_routes_with_huge_exact_numbers_answer_and_leave_no_worker(server, path):
    """Routes whose work grows with the numbers answer from a worker process and leave none."""
    a = [["1e-200", 0, 0], [0, "1e-200", 0], [0, 0, "-1e-200"]]  # the unit circle, scaled by 1e-200
    r = attack(server, path, {"a": a, "b": [[1, 0, -3], [0, 1, 0], [-3, 0, 8]]})
    assert r.status_code == 200, r.text[:300]
    assert r.json()["relation"] == "separate"


# --- the queue -------------------------------------------------------------------------------------

def test_a_burst_of_six_ordinary_analyses_all_get_200(server):
    """Was: 6 students pressing "Analyse" together got 503s (2 slots, no queue)."""
    body = {"a": circle_moving("t"), "b": circle_moving("-t"), "interval": ["-2", "2"]}

    async def burst() -> list[httpx.Response]:
        async with httpx.AsyncClient(timeout=GUARD_S) as c:
            return await asyncio.gather(*(c.post(f"{server.api}/api/analyse", json=body) for _ in range(6)))

    with Probes(server) as probes:
        answers = asyncio.run(burst())
    assert [r.status_code for r in answers] == [200] * 6, [r.text[:200] for r in answers]
    assert all([e["value"] for e in r.json()["events"]] == ["-1", "1"] for r in answers)
    probes.check()


def test_a_burst_of_the_largest_bodies_leaves_healthz_answering(server):
    """Was: 12 sweeps of 10,000 bodies (4 MB each) read in 12 threads and validated on the event loop
    kept /healthz waiting 2.9 s on a quiet machine; now one body is read and validated at a time,
    off the loop (0.3 s)."""
    rng = np.random.default_rng(3)
    start = np.hstack([rng.random((10_000, 3)) * 400, np.full((10_000, 3), 0.5), np.tile([1.0, 0, 0, 0], (10_000, 1))])
    end = start.copy()
    end[:, 0] += 1.0
    content = json.dumps({"start": start.tolist(), "end": end.tolist()}).encode()

    async def burst() -> list[httpx.Response]:
        async with httpx.AsyncClient(timeout=GUARD_S) as c:
            headers = {"Content-Type": "application/json"}
            return await asyncio.gather(*(c.post(f"{server.api}/api/sweep", content=content, headers=headers) for _ in range(12)))

    with Probes(server) as probes:
        answers = asyncio.run(burst())
    assert {r.status_code for r in answers} <= {200, 503}, [r.text[:200] for r in answers]
    ok = [r.json() for r in answers if r.status_code == 200]
    assert ok and all(a == ok[0] for a in ok)
    probes.check()


def test_beyond_the_queue_is_503_at_once_and_clients_that_leave_empty_it(server):
    """2 slow analyses run and 16 wait; one more is refused with Retry-After; leaving empties the queue."""
    slow = slow_motion()

    async def scenario() -> httpx.Response:
        async with httpx.AsyncClient(timeout=GUARD_S, limits=httpx.Limits(max_connections=64)) as c:
            tasks = []
            for k in range(18):
                tasks.append(asyncio.ensure_future(c.post(f"{server.api}/api/analyse", json=slow)))
                want = (min(k + 1, 2), max(k - 1, 0))
                while True:  # each request is in place (running or queued) before the next: FIFO order
                    h = (await c.get(f"{server.api}/healthz")).json()
                    if (h["analyses_running"], h["analyses_waiting"]) == want:
                        break
                    assert not tasks[-1].done(), tasks[-1].result().text[:300]
                    await asyncio.sleep(0.02)
            refused = await c.post(f"{server.api}/api/analyse", json=slow)
            for t in tasks:  # the clients leave
                t.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)
            return refused

    with Probes(server) as probes:
        refused = asyncio.run(scenario())
        wait_until(lambda: (lambda h: (h["analyses_running"], h["analyses_waiting"]))(health(server)) == (0, 0),
                   "the queue to empty")
    assert (refused.status_code, refused.headers.get("retry-after")) == (503, "2")
    assert refused.json() == {"detail": "all 2 workers are busy and 16 requests are waiting; retry in a moment"}
    probes.check()
    assert wait_gone(job_processes(server.proc.pid), 10) == set()


def test_serve_cors_origin_and_head_healthz(server):
    """``--cors-origin`` reaches the API (opt-in CORS), and HEAD /healthz answers (issue 26)."""
    pre = {"access-control-request-method": "POST", "access-control-request-headers": "content-type"}
    r = httpx.options(f"{server.api}/api/analyse", headers={**pre, "origin": "https://example.org"}, timeout=30)
    assert (r.status_code, r.headers.get("access-control-allow-origin")) == (200, "https://example.org")
    r = httpx.options(f"{server.api}/api/analyse", headers={**pre, "origin": "https://other.example"}, timeout=30)
    assert r.status_code == 400 and "access-control-allow-origin" not in r.headers
    r = httpx.head(f"{server.api}/healthz", timeout=30)
    assert (r.status_code, r.content) == (200, b"")


# --- SIGTERM with heavy work in flight ---------------------------------------------------------------

def test_sigterm_with_heavy_work_in_flight_answers_503_and_exits_within_5_s():
    """Was: the contacts client got 500 and the exit took 14 s.

    Budgets of 60 s: the work must still be in flight when the signal comes (at load 10 the
    contacts job once ran out of the default 5 s before the scene's start-up jobs were done)."""
    s = Server("--request-budget", "60", "--analysis-budget", "60")
    answers: dict[str, object] = {}

    def post(name: str, path: str, body: object) -> None:
        try:
            r = httpx.post(f"{s.api}{path}", json=body, timeout=GUARD_S)
            answers[name] = (r.status_code, r.headers.get("retry-after"), r.json().get("detail"))
        except httpx.HTTPError as e:
            answers[name] = repr(e)

    # 9,842 balls on a face-centred cubic lattice, radius fl(sqrt(1/2)): each of the 54,756
    # neighbouring pairs is tangent but for the rounding of the radius, so every one needs exact
    # arithmetic (~5 s here; the simple cubic lattice of the test above answers in ~2 s since the
    # exact path got faster, too soon to be surely in flight when the signal comes)
    g = np.array(np.meshgrid(np.arange(27.0), np.arange(27.0), np.arange(27.0), indexing="ij")).reshape(3, -1).T
    r = float(np.sqrt(0.5))
    fcc = {"bodies": [[*p, r, r, r, 1.0, 0.0, 0.0, 0.0] for p in g[g.sum(axis=1) % 2 == 0].tolist()]}
    requests = [
        ("contacts", "/api/contacts", fcc),  # seconds of exact arithmetic
        ("analysis", "/api/analyse", slow_motion()),  # ~9 s here
        ("queued analysis", "/api/analyse", slow_motion()),
    ]
    try:
        threads = []
        for k, (name, path, body) in enumerate(requests):
            th = threading.Thread(target=post, args=(name, path, body), daemon=True)
            th.start()
            threads.append(th)
            want = (min(k + 1, 2), max(k - 1, 0))
            wait_until(lambda want=want: (lambda h: (h["analyses_running"], h["analyses_waiting"]))(health(s)) == want,
                       f"{name} in place")
        # the two API jobs, once the scene's start-up jobs (warm-up, preset prefetch) under the
        # same fork server are done
        wait_until(lambda: len(job_processes(s.proc.pid)) == 2, "only the two API jobs running")
        below = descendants(s.proc.pid)
        t0 = time.monotonic()
        s.proc.send_signal(signal.SIGTERM)
        s.proc.wait(30)
        seconds = time.monotonic() - t0
        for th in threads:
            th.join(30)
        assert seconds < EXIT_S, f"exit took {seconds:.1f} s"
        assert s.proc.returncode == 0
        assert answers == {name: (503, "2", "the server is shutting down; retry in a moment") for name, _, _ in requests}
        assert wait_gone(below, 10) == set(), [cmdline(p) for p in below]
    finally:
        s.kill()

