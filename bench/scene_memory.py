"""Memory of the scene server under a hostile upload and over many tabs (issue 52), no browser.

Starts the real server (``python -m app serve --bodies FILE``: every tab opens the bodies view and
its "Open a file of bodies" button) and drives it with raw websocket clients that speak viser's
msgpack protocol (:class:`RawTab`; viser's ``_messages`` classes serialise themselves):

* **hostile upload**: a client declares a file of 10^12 bytes in 10^6 parts to the upload button,
  then sends 50 parts of 30 MB; the server's resident memory before, at its peak (sampled every
  20 ms) and after the client has left;
* **a full budget**: a client declares 64 MiB (the button's limit) and sends all its parts of
  512 KiB but the last, then leaves: the most one client may make the server keep;
* **tab cycles**: tabs that open (their view built: the server has framed their camera), stay
  ``--hold`` seconds and close, one after another; the server's resident memory every ``--every``
  tabs, for the bodies view and for the two-body view (``--preset example-29``).

Run: ``python -m bench.scene_memory [--tabs 400] [--every 50] [--hold 0.3]``. The table is printed and
written with the command and the machine to ``bench/results/scene_memory.json``; the figures
depend on the machine (and, on a shared one, on its load): tests assert only generous bounds
(tests/test_scene_surfaces.py).
"""

from __future__ import annotations

import argparse
import html
import json
import os
import secrets
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from bench.machine import RESULTS, cores, cpu_model, rss_mb
from bench.render import write_report

__all__ = ["RawTab", "SceneProcess", "camera_message", "free_port", "rss_mb", "hostile_upload", "budget_upload", "tab_cycles",
           "write_small_bodies"]

ROOT = Path(__file__).resolve().parents[1]
TIMEOUT = 120.0
"""Failure guard of every wait (seconds): a loaded machine is slow, a passing run never waits for it."""


def free_port() -> int:
    """A TCP port free on loopback now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def camera_message() -> bytes:
    """A tab's first message: viser counts a client as connected once it has reported its camera."""
    from viser import _messages

    return encode(_messages.ViewerCameraMessage(
        wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, 0.0, 5.0), fov=1.0, near=0.01, far=100.0, image_height=600,
        image_width=800, look_at=(0.0, 0.0, 0.0), up_direction=(0.0, 0.0, 1.0)))


def encode(message: Any) -> bytes:
    """The bytes a browser sends for a viser message (msgpack of its serialisable dict)."""
    import msgspec

    return msgspec.msgpack.encode(message.as_serializable_dict())


def write_small_bodies(path: str | Path, n: int = 4) -> Path:
    """A CSV of ``n`` unit spheres in a row, each touching the next (the server's own file)."""
    rows = ["x,y,z,a,b,c,qw,qx,qy,qz"] + [f"{2 * k},0,0,1,1,1,1,0,0,0" for k in range(n)]
    Path(path).write_text("\n".join(rows) + "\n")
    return Path(path)


class RawTab:
    """A websocket client of a scene that counts as a tab (it reported its camera), with no browser.

    A thread reads the server's windows of messages (zstd-compressed msgpack) and keeps only
    the small ones' decoded messages for :meth:`wait_for` (a mesh's arrays are never decoded).

    Args:
        port: the scene's port.
        path: the page's path (a browser's tab connects from ``/s/<tab id>/``).
    """

    def __init__(self, port: int, path: str = "/") -> None:
        import viser
        from websockets.sync.client import connect

        self.ws = connect(f"ws://127.0.0.1:{port}{path}", subprotocols=[f"viser-v{viser.__version__}"],
                          open_timeout=TIMEOUT, max_size=None, max_queue=None)
        self._seen: list[dict[str, Any]] = []
        self._cond = threading.Condition()
        self.closed = threading.Event()
        """Set when the server has closed the connection (or it broke)."""
        self.close_code: int | None = None
        self._reader = threading.Thread(target=self._read, name="raw-tab", daemon=True)
        self._reader.start()
        self.ws.send(camera_message())

    def _read(self) -> None:
        import msgspec
        import zstandard

        try:
            for raw in self.ws:
                if not isinstance(raw, bytes) or len(raw) < 16:
                    continue
                size, packed = int.from_bytes(raw[:8], "little"), int.from_bytes(raw[8:16], "little")
                if size > 4 << 20:  # a mesh or the like: nothing a test waits for
                    continue
                inner = zstandard.ZstdDecompressor().decompress(raw[16:16 + packed], max_output_size=size)
                messages = msgspec.msgpack.decode(inner)["messages"]
                with self._cond:
                    self._seen.extend(m for m in messages if isinstance(m, dict))
                    del self._seen[:-2000]  # the newest only: a long test keeps no history
                    self._cond.notify_all()
        except Exception:  # noqa: BLE001 - the connection closed or broke: that is what `closed` says
            pass
        finally:
            self.close_code = getattr(self.ws, "close_code", None)
            self.closed.set()
            with self._cond:
                self._cond.notify_all()

    def wait_for(self, pred: Callable[[dict[str, Any]], bool], what: str, timeout: float = TIMEOUT) -> dict[str, Any]:
        """The first message the server sent that satisfies ``pred`` (waits for it; TimeoutError)."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while True:
                for m in self._seen:
                    if pred(m):
                        return m
                left = deadline - time.monotonic()
                if left <= 0 or self.closed.is_set():
                    raise TimeoutError(f"the scene did not send {what}" + (" (the connection closed)" if self.closed.is_set() else ""))
                self._cond.wait(min(left, 0.5))

    def wait_text(self, text: str, timeout: float = TIMEOUT) -> dict[str, Any]:
        """The first message with a text (a markdown's, a label's) holding ``text``, as the page shows it (unescaped)."""
        return self.wait_for(lambda m: any(text in html.unescape(t) for t in _texts(m)), f"a message with {text!r}", timeout)

    def built(self, timeout: float = TIMEOUT) -> None:
        """Wait until the tab's view is built: the server framed the tab's camera (its last step)."""
        self.wait_for(lambda m: m.get("type") == "SetCameraLookAtMessage", "the tab's camera", timeout)

    def upload_button(self, label: str, timeout: float = TIMEOUT, *, not_: str | None = None) -> str:
        """The uuid of the upload button labelled ``label`` in the tab's panel (``not_``: another than that one,
        e.g. the button of a panel built anew)."""
        m = self.wait_for(lambda m: m.get("type") == "GuiUploadButtonMessage" and m.get("props", {}).get("label") == label
                          and m.get("uuid") != not_, f"the upload button {label!r}", timeout)
        return str(m["uuid"])

    def send(self, message: Any) -> None:
        """Send a viser message (as a browser would)."""
        self.ws.send(encode(message))

    def upload(self, button: str, name: str, content: bytes, part: int = 512 * 1024) -> str:
        """Upload ``content`` to ``button`` in parts of ``part`` bytes, as viser's client does; the transfer's id."""
        from viser import _messages

        transfer = secrets.token_hex(8)
        parts = [content[k:k + part] for k in range(0, len(content), part)]
        self.send(_messages.FileTransferStartUpload(source_component_uuid=button, transfer_uuid=transfer, filename=name,
                                                    mime_type="text/csv", part_count=len(parts), size_bytes=len(content)))
        for k, chunk in enumerate(parts):
            self.send(_messages.FileTransferPart(source_component_uuid=button, transfer_uuid=transfer, part_index=k, content=chunk))
        return transfer

    def close(self) -> None:
        """Leave (the server sees the tab close)."""
        self.ws.close()
        self._reader.join(TIMEOUT)

    def __enter__(self) -> RawTab:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class SceneProcess:
    """``python -m app serve`` on free ports, in a process of its own (its memory is the server's alone).

    Args:
        extra: more options (``--bodies FILE``, ``--preset none``).
    """

    def __init__(self, *extra: str) -> None:
        self.port, self.api_port = free_port(), free_port()
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "app", "serve", "--port", str(self.port), "--api-port", str(self.api_port), *extra],
            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        )
        self.output: list[str] = []
        ready = threading.Event()

        def drain() -> None:  # read every line (a full pipe would block the server), note readiness
            assert self.proc.stdout is not None
            for line in self.proc.stdout:
                self.output.append(line)
                del self.output[:-200]
                if line.startswith("API:"):
                    ready.set()
            ready.set()

        threading.Thread(target=drain, name="scene-output", daemon=True).start()
        if not ready.wait(TIMEOUT) or self.proc.poll() is not None:
            self.stop()
            raise RuntimeError("the scene server did not start:\n" + "".join(self.output[-30:]))

    def rss_mb(self) -> float:
        """The server process's resident memory (MB)."""
        return rss_mb(self.proc.pid)

    def stop(self) -> None:
        """SIGTERM, then SIGKILL if it has not exited."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(30)

    def __enter__(self) -> SceneProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


class Peak:
    """The highest value of ``sample()`` every ``period`` seconds, in a thread, while in the block."""

    def __init__(self, sample: Callable[[], float], period: float = 0.02) -> None:
        self.sample, self.period, self.peak = sample, period, 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="peak", daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            self.peak = max(self.peak, self.sample())
            self._stop.wait(self.period)

    def __enter__(self) -> Peak:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(TIMEOUT)
        self.peak = max(self.peak, self.sample())


def settle(sample: Callable[[], float], rounds: int = 10, period: float = 0.2) -> float:
    """The lowest of ``rounds`` samples ``period`` apart (memory freed once the server's tasks finish)."""
    low = sample()
    for _ in range(rounds - 1):
        time.sleep(period)
        low = min(low, sample())
    return low


def settle_after_close(sample: Callable[[], float], period: float = 0.2) -> float:
    """:func:`settle` over a window that holds the server's reclaim of a closed tab.

    The scene reclaims a closed tab's memory RECLAIM_SECONDS after it closes (a timer, a full
    collection, malloc_trim): a window of only that length ended before the pass on a loaded
    machine (a clean-clone CI run read 18 MB kept where the pass gives it back), so the window is
    4 s longer.
    """
    from app.scene.server import RECLAIM_SECONDS

    return settle(sample, rounds=int((RECLAIM_SECONDS + 4.0) / period), period=period)


HOSTILE_SIZE = 10**12
HOSTILE_PARTS = 10**6


def hostile_upload(port: int, sample: Callable[[], float], *, parts: int = 50, part_mb: int = 30,
                   label: str = "Open a file of bodies") -> dict[str, Any]:
    """One client declares a file of 10^12 bytes in 10^6 parts to ``label``, then sends ``parts`` of ``part_mb`` MB.

    Returns:
        ``before``, ``peak``, ``after`` (the server's memory, MB: ``sample()``), ``sent`` (parts the
        server took before it closed the connection), ``message`` (the panel's text on the
        refusal, or None) and ``close_code`` (the server's, None if it kept the connection).
    """
    from viser import _messages

    with RawTab(port) as warm:  # a first tab's one-off cost (imports, the view's code) is not the upload's
        warm.built()
    before = settle(sample, rounds=3)
    payload = b"\0" * (part_mb << 20)
    sent, message = 0, None
    with Peak(sample) as peak:
        tab = RawTab(port)
        try:
            button = tab.upload_button(label)
            tab.built()  # the panel is whole (the button's limit is set as it is made)
            transfer = secrets.token_hex(8)
            tab.send(_messages.FileTransferStartUpload(source_component_uuid=button, transfer_uuid=transfer, filename="huge.csv",
                                                       mime_type="text/csv", part_count=HOSTILE_PARTS, size_bytes=HOSTILE_SIZE))
            try:
                message = next(t for t in _texts(tab.wait_text("the limit is", timeout=30)) if "the limit is" in t)
            except TimeoutError:
                message = None
            for k in range(parts):
                if tab.closed.is_set():
                    break
                try:
                    tab.send(_messages.FileTransferPart(source_component_uuid=button, transfer_uuid=transfer, part_index=k,
                                                        content=payload))
                except Exception:  # noqa: BLE001 - the server closed the connection: nothing more is taken
                    break
                sent += 1
        finally:
            code = tab.close_code
            tab.close()
            code = tab.close_code if code is None else code
    after = settle_after_close(sample)
    return {"before": before, "peak": peak.peak, "after": after, "sent": sent, "message": message, "close_code": code}


def budget_upload(port: int, sample: Callable[[], float], *, label: str = "Open a file of bodies",
                  size: int = 64 << 20, part: int = 512 * 1024) -> dict[str, Any]:
    """One client declares ``size`` bytes (the button's limit) and sends every part but the last, as
    viser's client does, then leaves: the most a client may make the server keep.

    Returns:
        ``before``, ``peak``, ``after`` (the server's memory, MB: ``sample()``) and ``sent`` (parts).
    """
    from viser import _messages

    with RawTab(port) as warm:
        warm.built()
    before = settle(sample, rounds=3)
    chunk = b"\1" * part
    count = -(-size // part)
    with Peak(sample) as peak:
        with RawTab(port) as tab:
            button = tab.upload_button(label)
            tab.built()
            transfer = secrets.token_hex(8)
            tab.send(_messages.FileTransferStartUpload(source_component_uuid=button, transfer_uuid=transfer, filename="full.csv",
                                                       mime_type="text/csv", part_count=count, size_bytes=size))
            for k in range(count - 1):
                tab.send(_messages.FileTransferPart(source_component_uuid=button, transfer_uuid=transfer, part_index=k,
                                                    content=chunk))
            tab.ws.ping().wait(TIMEOUT)  # answered once the server has read every part before it
            time.sleep(0.5)
    after = settle_after_close(sample)
    return {"before": before, "peak": peak.peak, "after": after, "sent": count - 1}


def tab_cycles(port: int, sample: Callable[[], float], n: int, every: int = 50, *, hold: float = 0.0,
               paths: Callable[[int], str] = lambda k: f"/s/tab{k:08d}/") -> Iterator[tuple[int, float]]:
    """Open and close ``n`` tabs one after another: (tabs so far, memory) every ``every``.

    Each tab is built, then kept open ``hold`` seconds (its deferred panel refreshes run, as in a
    browser that looks at it), then closed.
    """
    for k in range(1, n + 1):
        with RawTab(port, paths(k)) as tab:
            tab.built()
            time.sleep(hold)
        if k % every == 0:
            yield k, sample()


def _texts(value: Any) -> Iterator[str]:
    """The strings in a decoded message (its fields, nested)."""
    if isinstance(value, str):
        yield value
    elif isinstance(value, dict):
        for v in value.values():
            yield from _texts(v)
    elif isinstance(value, list | tuple):
        for v in value:
            yield from _texts(v)


def _table(rows: list[tuple[str, ...]], head: tuple[str, ...]) -> str:
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]
    line = lambda r: "  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True)))  # noqa: E731
    return "\n".join([line(head), line(tuple("-" * w for w in widths)), *(line(r) for r in rows)])


def main(argv: list[str] | None = None) -> int:
    """Print the table: the hostile upload, then RSS over the tab cycles (bodies tabs, then two-body tabs)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--tabs", type=int, default=400, help="tabs to open and close (default 400)")
    p.add_argument("--every", type=int, default=50, help="print the memory every this many tabs (default 50)")
    p.add_argument("--hold", type=float, default=0.3, help="seconds each tab stays open once built (default 0.3)")
    args = p.parse_args(argv)
    result: dict[str, Any] = {"command": "python -m bench.scene_memory " + " ".join(argv if argv is not None else sys.argv[1:]),
                              "cpu": cpu_model(), "cores": cores(), "tabs": args.tabs, "hold_s": args.hold}
    with tempfile.TemporaryDirectory() as tmp:
        bodies = write_small_bodies(Path(tmp) / "bodies.csv")
        with SceneProcess("--bodies", str(bodies)) as server:
            r = hostile_upload(server.port, server.rss_mb)
            b = budget_upload(server.port, server.rss_mb)
        result["hostile_upload_mb"] = {k: r[k] for k in ("before", "peak", "after")}
        result["full_budget_upload_mb"] = {k: b[k] for k in ("before", "peak", "after")}
        print("Hostile upload: FileTransferStartUpload(size_bytes=10^12, part_count=10^6), then 50 parts of 30 MB")
        print(_table([(f"{r['before']:.0f}", f"{r['peak']:.0f}", f"{r['after']:.0f}", f"{r['peak'] - r['before']:+.0f}",
                       f"{r['after'] - r['before']:+.0f}", str(r["sent"]), str(r["close_code"]), "yes" if r["message"] else "no")],
                     ("RSS before MB", "peak MB", "after MB", "peak-before", "after-before", "parts taken", "close code", "panel says limit")))
        print()
        print("The most a client may make the server keep: 64 MiB declared, 127 of its 128 parts of 512 KiB sent, then it leaves")
        print(_table([(f"{b['before']:.0f}", f"{b['peak']:.0f}", f"{b['after']:.0f}", f"{b['peak'] - b['before']:+.0f}",
                       f"{b['after'] - b['before']:+.0f}", str(b["sent"]))],
                     ("RSS before MB", "peak MB", "after MB", "peak-before", "after-before", "parts sent")))
        print()
        for what, extra in (("bodies view", ("--bodies", str(bodies))), ("two-body view", ("--preset", "example-29"))):
            with SceneProcess(*extra) as server:
                start = settle(server.rss_mb, rounds=3)
                t0 = time.monotonic()
                rows = [("0", f"{start:.0f}", "")]
                for k, mb in tab_cycles(server.port, server.rss_mb, args.tabs, args.every, hold=args.hold):
                    rows.append((str(k), f"{mb:.0f}", f"{mb - start:+.0f}"))
                seconds = time.monotonic() - t0
            print(f"Tab cycles, {what}: {args.tabs} tabs opened (built, then {args.hold:g} s open) and closed one after another, "
                  f"{seconds:.0f} s")
            print(_table(rows, ("tabs", "RSS MB", "growth MB")))
            print()
            result[f"tab_cycles_{what.split()[0]}_mb"] = {"start": start, "every": args.every,
                                                           "rss": [float(row[1]) for row in rows[1:]], "seconds": seconds}
    out = RESULTS / "scene_memory.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {out} and {write_report()}")  # bench/REPORT.md: the rendering of every result file
    return 0



if __name__ == "__main__":
    raise SystemExit(main())
