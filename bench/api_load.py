"""HTTP API throughput: a batch of 1,000 pairs, and single-pair classify at concurrency 32.

Starts the real server (``python -m app serve --api-only``) in a subprocess and drives it from
this process over keep-alive HTTP/1.1 connections (a minimal asyncio client, so that the
client's own cost on the shared cores stays small next to the server's)::

    python -m bench.api_load            # prints the JSON result
    python -m bench.api_load --quick

Latencies are client-side wall times (request written to response read). Used by
``python -m bench.report`` for the rows "API batch of 1,000 pairs" and "single-pair classify at
concurrency 32 (p50/p99)".
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["run_api_load", "format_api", "TARGET_P99_MS", "serve_api"]

ROOT = Path(__file__).resolve().parents[1]
TARGET_P99_MS = 100.0
"""Single-pair classify at concurrency 32: p99 latency target."""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class serve_api:
    """Context manager: the API alone in a subprocess on a free port (``.port``, ``.proc``)."""

    def __init__(self, *extra: str) -> None:
        self.port = _free_port()
        self.extra = extra
        self.proc: subprocess.Popen[bytes] | None = None

    def __enter__(self) -> serve_api:
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "app", "serve", "--api-only", "--api-port", str(self.port), *self.extra],
            cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
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

class _Conn:
    def __init__(self, port: int) -> None:
        self.port = port
        self.reader: asyncio.StreamReader | None = None
        self.writer: asyncio.StreamWriter | None = None

    async def request(self, method: str, path: str, body: bytes) -> tuple[int, bytes]:
        if self.writer is None:
            self.reader, self.writer = await asyncio.open_connection("127.0.0.1", self.port)
        assert self.reader is not None
        head = (f"{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{self.port}\r\ncontent-type: application/json\r\n"
                f"content-length: {len(body)}\r\n\r\n").encode()
        self.writer.write(head + body)
        status_line = await self.reader.readline()
        status = int(status_line.split()[1])
        length = 0
        while True:
            line = await self.reader.readline()
            if line in (b"\r\n", b""):
                break
            k, _, v = line.partition(b":")
            if k.strip().lower() == b"content-length":
                length = int(v)
        data = await self.reader.readexactly(length)
        return status, data

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


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(argv)
    d = run_api_load(quick=a.quick, log=lambda s: print(s, file=sys.stderr))
    print(json.dumps(d, indent=1))
    print(format_api(d))


if __name__ == "__main__":
    main()
