"""HTTP API throughput: a batch of 1,000 pairs, single-pair classify at concurrency 32, and the line.

Starts the real server (``python -m app serve --api-only``) in a subprocess and drives it from
this process over keep-alive HTTP/1.1 connections (a minimal asyncio client, so that the
client's own cost on the shared cores stays small next to the server's)::

    python -m bench.api_load            # prints the JSON result
    python -m bench.api_load --quick
    python -m bench.api_load --line [--write]   # large bodies (issue 52); --write: bench/REPORT.md

Latencies are client-side wall times (request written to response read). Used by
``python -m bench.report`` for the rows "API batch of 1,000 pairs" and "single-pair classify at
concurrency 32 (p50/p99)".

``--line`` measures the one bounded line of request bodies (``app/api/line.py``): bursts of
large bodies sent together (60 ``/api/contacts`` of 2,000 bodies, 120 ``/api/sweep`` of 10,000)
and 32 / 64 clients at once, half of them sending large bodies back to back (waiting
``Retry-After`` after a 503), half single pairs: per kind and status, p50 / p99 / max latency,
the reasons of the 503s, the server's peak memory (its process and its workers, resident) and
the worst ``/healthz`` meanwhile. ``--write`` puts the table in the ``api_line`` section of
bench/REPORT.md.
"""

from __future__ import annotations

import argparse
import asyncio
import http.client
import json
import os
import re
import shlex
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from bench.machine import tree_rss_mb

__all__ = ["run_api_load", "format_api", "TARGET_P99_MS", "serve_api", "run_line_load", "format_line"]

ROOT = Path(__file__).resolve().parents[1]
TARGET_P99_MS = 100.0
"""Single-pair classify at concurrency 32: p99 latency target."""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class serve_api:
    """Context manager: the API alone in a subprocess on a free port (``.port``, ``.proc``).

    ``root``: the checkout whose ``app`` is served (default: this one; another, e.g. an earlier
    commit with its compiled filters, to compare).
    """

    def __init__(self, *extra: str, root: Path = ROOT) -> None:
        self.port = _free_port()
        self.extra = extra
        self.root = root
        self.proc: subprocess.Popen[bytes] | None = None

    def __enter__(self) -> serve_api:
        env = {**os.environ, "PYTHONPATH": str(self.root)}
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "app", "serve", "--api-only", "--api-port", str(self.port), *self.extra],
            cwd=self.root, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                status, _ = asyncio.run(_one_request(self.port, "GET", "/healthz", b""))
                if status == 200:
                    return self
            except OSError:
                pass
            time.sleep(0.2)
        self.__exit__()
        raise RuntimeError("the API did not start within 60 s")

    def __exit__(self, *exc: Any) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


# --- a minimal keep-alive HTTP/1.1 client ---------------------------------------------------------

_SLICE = 256 * 1024
"""A large body is written in slices of this size, each drained before the next."""


class _Conn:
    def __init__(self, port: int) -> None:
        self.port = port
        self.reader: asyncio.StreamReader | None = None
        self.writer: asyncio.StreamWriter | None = None

    async def request(self, method: str, path: str, body: bytes) -> tuple[int, bytes]:
        status, _, data = await self.exchange(method, path, body)
        return status, data

    async def exchange(self, method: str, path: str, body: bytes) -> tuple[int, dict[str, str], bytes]:
        """Status, headers (lower-case names) and body of one request on this connection."""
        if self.writer is None:
            self.reader, self.writer = await asyncio.open_connection("127.0.0.1", self.port)
        assert self.reader is not None
        head = (f"{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{self.port}\r\ncontent-type: application/json\r\n"
                f"content-length: {len(body)}\r\n\r\n").encode()
        if len(body) <= _SLICE:
            self.writer.write(head + body)
        else:  # in slices, drained: the client's buffers hold no copy of a large body
            self.writer.write(head)
            view = memoryview(body)
            for i in range(0, len(body), _SLICE):
                self.writer.write(view[i:i + _SLICE])
                await self.writer.drain()
        status_line = await self.reader.readline()
        status = int(status_line.split()[1])
        headers: dict[str, str] = {}
        while True:
            line = await self.reader.readline()
            if line in (b"\r\n", b""):
                break
            k, _, v = line.partition(b":")
            headers[k.strip().lower().decode()] = v.strip().decode()
        data = await self.reader.readexactly(int(headers.get("content-length", 0)))
        if headers.get("connection") == "close":
            self.close()
            self.writer = None
        return status, headers, data

    def close(self) -> None:
        if self.writer is not None:
            self.writer.close()


async def _one_request(port: int, method: str, path: str, body: bytes) -> tuple[int, bytes]:
    c = _Conn(port)
    try:
        return await c.request(method, path, body)
    finally:
        c.close()


# --- inputs ---------------------------------------------------------------------------------------

def _random_pairs(n: int, dim: int, seed: int) -> list[dict[str, Any]]:
    """Random float ellipses (dim 2) or ellipsoids (dim 3) as matrices (JSON numbers)."""
    from bench.datasets import quadrics, rotations

    rng = np.random.default_rng([seed, dim, 11])
    c = rng.uniform(-4, 4, (2, n, dim))
    r = rng.uniform(0.2, 3.0, (2, n, dim))
    A = quadrics(c[0], r[0], rotations(rng, dim, n))
    B = quadrics(c[1], r[1], rotations(rng, dim, n))
    return [{"a": a.tolist(), "b": b.tolist()} for a, b in zip(A, B, strict=True)]


# --- measurements ---------------------------------------------------------------------------------

def _batch_timing(port: int, pairs: list[dict[str, Any]], repeats: int) -> dict[str, Any]:
    body = json.dumps({"pairs": pairs}).encode()

    async def go() -> list[float]:
        c = _Conn(port)
        times = []
        try:
            for _ in range(repeats):
                t0 = time.perf_counter()
                status, data = await c.request("POST", "/api/classify", body)
                times.append(time.perf_counter() - t0)
                if status != 200 or len(json.loads(data)) != len(pairs):
                    raise RuntimeError(f"batch request failed: {status} {data[:200]!r}")
        finally:
            c.close()
        return times

    times = asyncio.run(go())
    return {"pairs": len(pairs), "bytes": len(body), "best_ms": 1e3 * min(times), "median_ms": 1e3 * float(np.median(times))}


def _concurrency(port: int, pairs: list[dict[str, Any]], concurrency: int, per_client: int) -> dict[str, Any]:
    bodies = [json.dumps(p).encode() for p in pairs]

    async def client(k: int, lat: list[float]) -> None:
        c = _Conn(port)
        try:
            for i in range(per_client):
                body = bodies[(k * per_client + i) % len(bodies)]
                t0 = time.perf_counter()
                status, data = await c.request("POST", "/api/classify", body)
                lat.append(time.perf_counter() - t0)
                if status != 200:
                    raise RuntimeError(f"classify failed: {status} {data[:200]!r}")
        finally:
            c.close()

    async def go() -> tuple[list[float], float]:
        lat: list[float] = []
        t0 = time.perf_counter()
        await asyncio.gather(*(client(k, lat) for k in range(concurrency)))
        return lat, time.perf_counter() - t0

    asyncio.run(go())  # warm-up round (connections, numba, caches)
    lat, wall = asyncio.run(go())
    ms = 1e3 * np.asarray(lat)
    return {
        "concurrency": concurrency,
        "requests": len(lat),
        "p50_ms": float(np.percentile(ms, 50)),
        "p99_ms": float(np.percentile(ms, 99)),
        "max_ms": float(ms.max()),
        "requests_per_s": len(lat) / wall,
    }


def run_api_load(
    *,
    quick: bool = False,
    seed: int = 0,
    log: Any = print,
    batch_pairs: int = 1000,
    concurrency: int = 32,
    per_client: int | None = None,
) -> dict[str, Any]:
    """Start the API, time the batch and the concurrent single-pair requests; returns a dict.

    Keys ``batch_2d``/``batch_3d`` (pairs, bytes, best_ms, median_ms) and ``concurrency``
    (concurrency, requests, p50_ms, p99_ms, max_ms, requests_per_s).
    """
    out: dict[str, Any] = {}
    with serve_api() as srv:
        for dim in (2, 3):
            pairs = _random_pairs(batch_pairs, dim, seed + dim)
            out[f"batch_{dim}d"] = _batch_timing(srv.port, pairs, repeats=3 if quick else 7)
            log(f"api batch {dim}D: {out[f'batch_{dim}d']}")
        singles = _random_pairs(200, 3, seed + 7)
        per = per_client if per_client is not None else (10 if quick else 40)
        out["concurrency"] = _concurrency(srv.port, singles, concurrency, per)
        log(f"api concurrency: {out['concurrency']}")
    return out


def format_api(d: dict[str, Any]) -> str:
    """Markdown table of the API measurements."""
    rows = ["| measurement | result |", "|---|---|"]
    for dim in (2, 3):
        b = d.get(f"batch_{dim}d")
        if b:
            kind = "ellipse" if dim == 2 else "ellipsoid"
            rows.append(f"| API batch of {b['pairs']:,} {kind} pairs (one request, {b['bytes'] / 1e3:.0f} KB) | "
                        f"best {b['best_ms']:.1f} ms, median {b['median_ms']:.1f} ms |")
    c = d.get("concurrency")
    if c:
        rows.append(f"| single-pair classify at concurrency {c['concurrency']} ({c['requests']} requests) | "
                    f"p50 {c['p50_ms']:.1f} ms, p99 {c['p99_ms']:.1f} ms, max {c['max_ms']:.1f} ms, "
                    f"{c['requests_per_s']:.0f} requests/s |")
    return "\n".join(rows)


# --- large bodies: the one bounded line (issue 52) ----------------------------------------------------

def _rows(n: int, seed: int) -> np.ndarray:
    """n ellipsoids spread over a 400-wide box (few contacts: the line is what is measured)."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return np.hstack([rng.random((n, 3)) * 400, rng.random((n, 3)) * 0.5 + 0.1, q])


def large_body(path: str, n: int, seed: int = 1) -> bytes:
    """A body of n bodies for ``/api/contacts`` (rows) or ``/api/sweep`` (start and end rows)."""
    start = _rows(n, seed)
    if path == "/api/contacts":
        return json.dumps({"bodies": start.tolist()}).encode()
    end = start.copy()
    end[:, 0] += 1.0
    return json.dumps({"start": start.tolist(), "end": end.tolist()}).encode()


class _Watch:
    """In a thread: the server tree's resident memory and the latency of ``/healthz``, every 50 ms."""

    def __init__(self, port: int, pid: int) -> None:
        self.port, self.pid = port, pid
        self.memory: list[float] = []
        self.health: list[float] = []
        self.places: list[int] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=60)
        while not self._stop.is_set():
            self.memory.append(tree_rss_mb(self.pid))
            t0 = time.perf_counter()
            conn.request("GET", "/healthz")
            answer = json.loads(conn.getresponse().read())
            self.health.append(time.perf_counter() - t0)
            self.places.append(int(answer.get("large_bodies", -1)))
            self._stop.wait(0.05)
        conn.close()

    def __enter__(self) -> _Watch:
        self._thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self._stop.set()
        self._thread.join(60)


_REASONS = (
    ("line full", re.compile(r"requests with large bodies .* the most this server holds")),
    ("waited to be read", re.compile(r"^waited .* in line for its body to be read")),
    ("waited for a worker", re.compile(r"^waited .* in the queue for one of")),
    ("workers and queue full", re.compile(r"^all \d+ workers are busy")),
    ("over the budget", re.compile(r"over the time budget")),
)


def _reason(status: int, data: bytes) -> str:
    """The answer's status, and for a 503 which limit it met."""
    if status != 503:
        return str(status)
    try:
        detail = str(json.loads(data).get("detail", ""))
    except ValueError:
        detail = ""
    return "503 " + next((name for name, rx in _REASONS if rx.search(detail)), detail[:60])


def _summary(answers: list[tuple[str, str, float]]) -> dict[str, Any]:
    """Per kind and answer: count, p50 / p99 / max latency (ms)."""
    out: dict[str, Any] = {}
    for kind, reason in sorted({(k, r) for k, r, _ in answers}):
        ms = 1e3 * np.asarray([t for k, r, t in answers if (k, r) == (kind, reason)])
        out[f"{kind}: {reason}"] = {"n": int(ms.size), "p50_ms": float(np.percentile(ms, 50)),
                                    "p99_ms": float(np.percentile(ms, 99)), "max_ms": float(ms.max())}
    return out


def _burst(port: int, path: str, body: bytes, clients: int) -> list[tuple[str, str, float]]:
    """``clients`` requests of ``body`` sent together, one per connection."""

    async def one() -> tuple[str, str, float]:
        c = _Conn(port)
        try:
            t0 = time.perf_counter()
            status, _, data = await c.exchange("POST", path, body)
            return path, _reason(status, data), time.perf_counter() - t0
        finally:
            c.close()

    async def go() -> list[tuple[str, str, float]]:
        return list(await asyncio.gather(*(one() for _ in range(clients))))

    return asyncio.run(go())


def _mixed(port: int, clients: int, large: bytes, small: list[bytes], per_large: int, per_small: int) -> list[tuple[str, str, float]]:
    """``clients`` connections at once: half send ``large`` to /api/contacts ``per_large`` times
    (after a 503 they wait its Retry-After), half single pairs ``per_small`` times."""

    async def client(k: int) -> list[tuple[str, str, float]]:
        c = _Conn(port)
        out = []
        try:
            heavy = k % 2 == 0
            for i in range(per_large if heavy else per_small):
                path, body = ("/api/contacts", large) if heavy else ("/api/classify", small[(k * per_small + i) % len(small)])
                t0 = time.perf_counter()
                status, headers, data = await c.exchange("POST", path, body)
                out.append(("large /api/contacts" if heavy else "single pair", _reason(status, data), time.perf_counter() - t0))
                if status == 503:
                    await asyncio.sleep(float(headers.get("retry-after", 1)))
        finally:
            c.close()
        return out

    async def go() -> list[tuple[str, str, float]]:
        return [a for part in await asyncio.gather(*(client(k) for k in range(clients))) for a in part]

    return asyncio.run(go())


def _commit(root: Path) -> str:
    """The short commit of a checkout (``+`` when it has changes), else its folder's name."""
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return root.name
    return head + ("+" if dirty else "")


def run_line_load(*, quick: bool = False, log: Any = print, root: Path = ROOT, server: str | None = None) -> dict[str, Any]:
    """The line under load: the issue's two bursts, then 32 and 64 mixed clients; one server each.

    Returns ``{"rows": [...], "load": (1, 5, 15 min)}``; each row has ``server`` (its label),
    ``name``, ``bytes`` (the large body), ``answers`` (:func:`_summary`), ``idle_mb``/``peak_mb``
    (server tree resident memory), ``health_worst_ms``, ``places_max`` (-1: a server without the
    line) and ``seconds``. ``root``: the checkout served (:class:`serve_api`); ``server``: its
    label (default: its commit).
    """
    server = server or _commit(root)
    small = [json.dumps(p).encode() for p in _random_pairs(200, 3, 7)]
    contacts = large_body("/api/contacts", 500 if quick else 2000)
    sweep = large_body("/api/sweep", 2000 if quick else 10_000)
    scenarios: list[tuple[str, bytes, Any]] = [
        (f"{30 if quick else 60} together x /api/contacts", contacts,
         lambda port: _burst(port, "/api/contacts", contacts, 30 if quick else 60)),
        (f"{30 if quick else 120} together x /api/sweep", sweep,
         lambda port: _burst(port, "/api/sweep", sweep, 30 if quick else 120)),
    ]
    for clients in (32, 64):
        scenarios.append((f"{clients} clients, half large /api/contacts, half single pairs", contacts,
                          lambda port, clients=clients: _mixed(port, clients, contacts, small, 2 if quick else 4,
                                                               10 if quick else 40)))
    rows = []
    for name, body, run in scenarios:
        with serve_api(root=root) as srv:
            assert srv.proc is not None
            asyncio.run(_one_request(srv.port, "POST", "/api/contacts", contacts))  # warm: a worker, the reader
            idle = tree_rss_mb(srv.proc.pid)
            t0 = time.perf_counter()
            with _Watch(srv.port, srv.proc.pid) as watch:
                answers = run(srv.port)
            row = {"server": server, "name": name, "bytes": len(body), "answers": _summary(answers), "idle_mb": idle,
                   "peak_mb": max(watch.memory), "health_worst_ms": 1e3 * max(watch.health),
                   "places_max": max(watch.places), "seconds": time.perf_counter() - t0}
        log(f"api line: {row}")
        rows.append(row)
    return {"rows": rows, "load": os.getloadavg()}


def format_line(d: dict[str, Any]) -> str:
    """Markdown table of :func:`run_line_load`."""
    out = ["| load | server | body | answers: count, p50 / p99 / max latency | server memory: idle -> peak | "
           "/healthz worst | large bodies held (most) |", "|---|---|---:|---|---:|---:|---:|"]
    for r in sorted(d["rows"], key=lambda r: [x["name"] for x in d["rows"]].index(r["name"])):
        answers = "<br>".join(f"{k}: {v['n']}, {v['p50_ms'] / 1e3:.2f} / {v['p99_ms'] / 1e3:.2f} / {v['max_ms'] / 1e3:.2f} s"
                              for k, v in r["answers"].items())
        places = "n/a" if r["places_max"] < 0 else str(r["places_max"])
        out.append(f"| {r['name']} | {r['server']} | {r['bytes'] / 1e6:.1f} MB | {answers} | {r['idle_mb']:.0f} -> {r['peak_mb']:.0f} MB | "
                   f"{r['health_worst_ms']:.0f} ms | {places} |")
    return "\n".join(out)


BEGIN, END = "<!-- api_line:begin -->", "<!-- api_line:end -->"


def write_section(text: str) -> None:
    """Put ``text`` between the ``api_line`` markers of bench/REPORT.md (after the HTTP API section
    the first time; ``python -m bench.report`` keeps such sections)."""
    path = ROOT / "bench" / "REPORT.md"
    report = path.read_text()
    block = f"{BEGIN}\n{text.strip()}\n{END}\n"
    pattern = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END) + "\n?", re.S)
    if pattern.search(report):
        report = pattern.sub(lambda _: block, report)
    else:
        anchor = report.find("\n## ", report.index("## HTTP API: batch and concurrent requests") + 1)
        report = report[:anchor] + "\n" + block + report[anchor:] if anchor >= 0 else report + "\n" + block
    path.write_text(report)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--line", action="store_true", help="large bodies: bursts and 32 / 64 mixed clients (issue 52)")
    ap.add_argument("--write", action="store_true", help="with --line: write bench/results/api-line.json, render bench/REPORT.md")
    ap.add_argument("--against", type=Path, help="with --line: also serve this checkout (e.g. an earlier commit, "
                                                   "with its compiled filters) and give its rows")
    ap.add_argument("--against-label", help="the name of --against's rows (default: its commit)")
    a = ap.parse_args(argv)
    log = lambda s: print(s, file=sys.stderr)  # noqa: E731
    if a.line:
        load0 = os.getloadavg()
        t0 = time.perf_counter()
        d = run_line_load(quick=a.quick, log=log)
        if a.against:
            before = run_line_load(quick=a.quick, log=log, root=a.against.resolve(), server=a.against_label or a.against.name)
            d = {"rows": d["rows"] + before["rows"], "load": before["load"]}
        table = format_line(d)
        print(table)
        if a.write:
            command = ("python -m bench.api_load --line" + (" --quick" if a.quick else "") +
                       (f" --against CHECKOUT --against-label {shlex.quote(a.against_label)}" if a.against_label else
                        " --against CHECKOUT" if a.against else "") + " --write")
            from .render import publish

            load = f"{load0[0]:.1f} at the start, {d['load'][0]:.1f} at the end"
            path = publish("api-line", command=command, markdown=table, load_average=load)
            print(f"wrote {path} in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
        return
    d = run_api_load(quick=a.quick, log=log)
    print(json.dumps(d, indent=1))
    print(format_api(d))


if __name__ == "__main__":
    main()
