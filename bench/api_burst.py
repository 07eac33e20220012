"""A burst of the largest API bodies: does ``/healthz`` keep answering while they are read?

Starts the real server (``python -m app serve --api-only``) and sends ``--burst`` requests of
``--bodies`` bodies together (``/api/contacts``: rows of 10 numbers, 2 MB at 10,000 bodies;
``/api/sweep``: start and end rows, 4 MB), while a thread asks ``/healthz`` every 50 ms::

    python -m bench.api_burst                  # prints the table
    python -m bench.api_burst --bodies 5000 --burst 6

Each body is read and validated in a worker thread, one at a time, in its turn in the line of
large bodies (app/api/line.py: 16 places, 503 beyond, a wait of 10 s), so the event loop answers
``/healthz`` meanwhile; the table gives its worst and median latency, and the answers.
"""

from __future__ import annotations

import argparse
import asyncio
import threading
import time
from typing import Any

import httpx
import numpy as np

from bench.api_load import large_body, serve_api

__all__ = ["run_burst", "format_burst"]


def run_burst(path: str, n: int, burst: int) -> dict[str, Any]:
    """Worst and median /healthz latency (s) during ``burst`` requests of ``n`` bodies to ``path``."""
    content = large_body(path, n)
    with serve_api() as server:
        base = f"http://127.0.0.1:{server.port}"
        latencies: list[float] = []
        stop = threading.Event()

        def probe() -> None:
            with httpx.Client(timeout=60) as c:
                while not stop.is_set():
                    t0 = time.monotonic()
                    c.get(f"{base}/healthz")
                    latencies.append(time.monotonic() - t0)
                    stop.wait(0.05)

        async def send() -> list[int]:
            async with httpx.AsyncClient(timeout=120) as c:
                headers = {"Content-Type": "application/json"}
                answers = await asyncio.gather(*(c.post(f"{base}{path}", content=content, headers=headers) for _ in range(burst)))
            return [r.status_code for r in answers]

        th = threading.Thread(target=probe, daemon=True)
        th.start()
        time.sleep(1.0)  # probes before the burst
        t0 = time.monotonic()
        codes = asyncio.run(send())
        seconds = time.monotonic() - t0
        time.sleep(0.5)
        stop.set()
        th.join(30)
    return {"path": path, "bodies": n, "burst": burst, "megabytes": len(content) / 1e6, "codes": sorted(codes),
            "seconds": seconds, "worst": max(latencies), "median": float(np.median(latencies)), "probes": len(latencies)}


def format_burst(rows: list[dict[str, Any]]) -> str:
    """The Markdown table of :func:`run_burst` results."""
    out = ["| burst | body | answers | burst took | /healthz worst | /healthz median |", "|---|---:|---|---:|---:|---:|"]
    for r in rows:
        codes = ", ".join(f"{r['codes'].count(c)} x {c}" for c in sorted(set(r["codes"])))
        out.append(f"| {r['burst']} x {r['path']}, {r['bodies']:,} bodies | {r['megabytes']:.1f} MB | {codes} | "
                   f"{r['seconds']:.2f} s | {r['worst']:.2f} s | {r['median'] * 1000:.0f} ms |")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bodies", type=int, default=10_000, help="bodies per request (the API's limit: 10,000)")
    ap.add_argument("--burst", type=int, default=12, help="requests sent together")
    args = ap.parse_args(argv)
    rows = [run_burst(path, args.bodies, args.burst) for path in ("/api/contacts", "/api/sweep")]
    print(format_burst(rows))


if __name__ == "__main__":
    main()
