"""One bounded line for every request body: places, read timeouts, the one reader, and shutdown.

Issue 52: a body over 64 kB used to be read whole as soon as it arrived and then wait, unbounded
and unbudgeted, for the one thread that parses large bodies (60 concurrent ``/api/contacts`` of
2,000 bodies: answers after up to 36.8 s, nobody told to retry; server memory 178 -> 732 MB with
120 large sweeps). Now :class:`RequestLine`, the outermost middleware of the API, does this for
every request:

* a declared ``Content-Length`` over the path's limit is 413 at once, nothing read;
* a body over :data:`INLINE_BYTES` (declared, or counted as a chunked body arrives) first takes
  one of :attr:`Line.places` places, else 503 with ``Retry-After`` at once, before more of it is
  read: uvicorn holds at most ~64 kB of a body nobody reads (it stops reading the socket), so
  the memory of request bodies is bounded by ``places x body limit`` (a place is held until the
  answer is sent: receiving, parsing, waiting for a worker, running);
* bytes are counted before they are kept (over the limit: 413); a body that stops arriving for
  :attr:`Line.stall_s` seconds, or is not whole within :attr:`Line.read_s`, is answered 408 and
  its connection closed (it never holds the reader or a worker, only its place, until then);
* once the body is whole the request's wait starts: it may wait :attr:`Line.wait_s` seconds in
  all, for the one reader of large bodies (:meth:`Line.parse`, first come first served) and
  then for a worker (:func:`app.api.budget.run_job` passes the same deadline to the pool), then
  503 with ``Retry-After``;
* when the server is stopping, a request not yet answered is answered 503 "shutting down": at
  once while it is received or waits for the reader, and even when uvicorn cancels it at the
  end of its graceful wait (uvicorn answers a cancelled request with a bare 500).
"""

from __future__ import annotations

import asyncio
import threading
import time
import weakref
from collections import deque
from collections.abc import Awaitable, Callable
from typing import Any, TypeVar

import anyio
from fastapi import Request
from fastapi.responses import JSONResponse
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from .budget import RETRY_AFTER_S, STOPPING, WAIT_UNTIL, unavailable

__all__ = ["INLINE_BYTES", "Line", "RequestLine", "SHUTTING_DOWN"]

T = TypeVar("T")

INLINE_BYTES = 64 * 1024
"""Bodies up to this size are read where they arrive, without a place in the line, and parsed on
the event loop (microseconds); larger ones take a place and are parsed and validated in a worker
thread, one at a time (:meth:`Line.parse`): 10,000 moving bodies (4 MB) take ~0.2 s to read and
~0.15 s to validate on a quiet core."""

SHUTTING_DOWN = "the server is shutting down; retry in a moment"
"""The 503 detail of every request that the server's stop ends (as :mod:`app.api.budget` says it)."""

_POLL_S = 0.1
"""How often a wait (for bytes, for the reader) checks the stop signal and the client."""


class _Turns:
    """One holder at a time, the others served first come first served (one per event loop).

    A waiter that leaves (deadline, stop, disconnect, cancellation) loses its place only; a turn
    granted to a waiter that is leaving at that moment is passed on.
    """

    def __init__(self) -> None:
        self._held = False
        self._queue: deque[asyncio.Future[None]] = deque()

    async def acquire(self, deadline: float | None, check: Callable[[], Awaitable[None]]) -> None:
        """Take the turn, waiting until ``deadline`` (monotonic; None: no limit).

        Raises:
            TimeoutError: the deadline passed first.
            Exception: whatever ``check`` raises (it runs every :data:`_POLL_S` while waiting).
        """
        if not self._held and not self._queue:
            self._held = True
            return
        turn: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self._queue.append(turn)
        try:
            while True:
                left = _POLL_S if deadline is None else min(_POLL_S, deadline - time.monotonic())
                if left <= 0:
                    raise TimeoutError
                done, _ = await asyncio.wait({turn}, timeout=left)
                if done:
                    return
                await check()
        except BaseException:
            if turn.done() and not turn.cancelled():  # granted as we left: the next one's turn
                self.release()
            else:
                turn.cancel()
                self._queue.remove(turn)
            raise

    def release(self) -> None:
        """Hand the turn to the first waiter still waiting, else free it."""
        while self._queue:
            turn = self._queue.popleft()
            if not turn.done():
                turn.set_result(None)
                return
        self._held = False


class Line:
    """The places of large bodies in one API, and the one reader that parses them.

    Args:
        places: requests with a body over :data:`INLINE_BYTES` the server holds at once.
        wait_s: longest wait of a request, from its whole body to its work (the reader, a worker).
        stall_s: longest pause while a body arrives.
        read_s: longest time for a whole body to arrive.
    """

    def __init__(self, places: int, wait_s: float, stall_s: float, read_s: float) -> None:
        self.places = places
        self.wait_s = wait_s
        self.stall_s = stall_s
        self.read_s = read_s
        self._taken = 0
        self._lock = threading.Lock()
        self._turns: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, _Turns] = weakref.WeakKeyDictionary()

    @property
    def taken(self) -> int:
        """Places taken now (large bodies being received, parsed, waiting for a worker or running)."""
        return self._taken

    def take(self) -> bool:
        """Take a place if one is free."""
        with self._lock:
            if self._taken >= self.places:
                return False
            self._taken += 1
            return True

    def give(self) -> None:
        """Free a place taken with :meth:`take`."""
        with self._lock:
            self._taken -= 1

    def _reader(self) -> _Turns:
        """The reader's turns on the running event loop (a future serves the loop it was made in)."""
        loop = asyncio.get_running_loop()
        turns = self._turns.get(loop)
        if turns is None:
            turns = self._turns[loop] = _Turns()
        return turns

    async def parse(self, request: Request, fn: Callable[..., T], *args: Any) -> T:
        """``fn(*args)`` in a worker thread when it is this request's turn (one at a time).

        One reader at a time: a reader holds the interpreter lock most of the time, and with 12
        bodies of 4 MB read in 12 threads /healthz took 2.9 s on a quiet machine (0.3 s with one).

        Raises:
            HTTPException: 503 with Retry-After when the request's wait (:data:`WAIT_UNTIL`) runs
                out first, the client went away, or the server is stopping.
        """
        deadline: float | None = request.scope.get(WAIT_UNTIL)

        async def check() -> None:
            if STOPPING.is_set():
                raise unavailable(SHUTTING_DOWN)
            if await request.is_disconnected():
                raise unavailable("the client went away while its body waited to be read")

        reader = self._reader()
        try:
            await reader.acquire(deadline, check)
        except TimeoutError:
            raise unavailable(f"waited {self.wait_s:g} s in line for its body to be read; retry in a moment") from None
        try:
            return await anyio.to_thread.run_sync(fn, *args)
        finally:
            reader.release()


class _Answered(Exception):
    """The middleware answered the request itself (413, 408, 503) or the client left."""


class _Place:
    """A request's place in the line, if it took one; :meth:`free` is idempotent."""

    def __init__(self, line: Line) -> None:
        self.line = line
        self.taken = False

    async def take(self, send: Send) -> None:
        """Take a place for a large body, else answer 503 at once (:class:`_Answered`)."""
        if self.line.take():
            self.taken = True
            return
        await _answer(send, 503, f"{self.line.places} requests with large bodies (over {INLINE_BYTES // 1024} kB) are "
                                 "being received, read or worked on, the most this server holds; retry in a moment",
                      retry=True)
        raise _Answered

    def free(self) -> None:
        if self.taken:
            self.taken = False
            self.line.give()


class RequestLine:
    """ASGI middleware: body limits, places, read timeouts and the wait's start (module docstring).

    Args:
        app: the application.
        line: the app's :class:`Line`.
        max_bytes: the largest body (413 above).
        per_path: paths with their own limit (``/api/contacts`` and ``/api/sweep`` take
            thousands of bodies).
    """

    def __init__(self, app: ASGIApp, line: Line, max_bytes: int, per_path: dict[str, int] | None = None) -> None:
        self.app = app
        self.line = line
        self.max_bytes = max_bytes
        self.per_path = dict(per_path or {})

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Receive the body within its limits and place, then pass the request on."""
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = False

        async def tracked(message: Message) -> None:
            nonlocal started
            started = started or message["type"] == "http.response.start"
            await send(message)

        place = _Place(self.line)
        try:
            limit = self.per_path.get(scope.get("path", ""), self.max_bytes)
            declared = _content_length(scope)
            if declared is not None and declared > limit:
                await _answer(tracked, 413, _too_large(limit))
                return
            if STOPPING.is_set():
                await _answer(tracked, 503, SHUTTING_DOWN, retry=True)
                return
            if declared is not None and declared > INLINE_BYTES:
                await place.take(tracked)
            body = await self._receive(receive, tracked, limit, place)
            scope[WAIT_UNTIL] = time.monotonic() + self.line.wait_s  # the wait starts when the body is whole
            replayed = False

            async def replay() -> Message:
                nonlocal replayed, body
                if not replayed:
                    replayed = True
                    message: Message = {"type": "http.request", "body": body, "more_body": False}
                    body = b""  # the app holds it now; this closure keeps no copy
                    return message
                return await receive()

            await self.app(scope, replay, tracked)
        except _Answered:
            return
        except asyncio.CancelledError:  # uvicorn's graceful wait at shutdown ran out
            if not started:
                try:
                    await _answer(tracked, 503, SHUTTING_DOWN, retry=True)
                except Exception:  # the connection is gone: nothing to tell
                    pass
            raise
        finally:
            place.free()

    async def _receive(self, receive: Receive, send: Send, limit: int, place: _Place) -> bytes:
        """The whole body, its bytes counted before they are kept.

        Raises:
            _Answered: it was answered here (413 over the limit, 503 no place or stopping, 408
                too slow) or the client left.
        """
        chunks: list[bytes] = []
        size = 0
        start = time.monotonic()
        while True:
            message = await self._next(receive, send, start)
            if message["type"] != "http.request":  # http.disconnect: nobody to answer
                raise _Answered
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > limit:
                await _answer(send, 413, _too_large(limit))
                raise _Answered
            if not place.taken and size > INLINE_BYTES:  # a chunked body grew large: a place before more is read
                await place.take(send)
            chunks.append(chunk)
            if not message.get("more_body", False):
                return b"".join(chunks)

    async def _next(self, receive: Receive, send: Send, start: float) -> Message:
        """The next message of the body, within the stall and read limits, unless the server stops."""
        line = self.line
        stall = time.monotonic() + line.stall_s
        total = start + line.read_s
        task = asyncio.ensure_future(receive())
        try:
            while True:
                now = time.monotonic()
                if STOPPING.is_set():
                    detail, status, retry = SHUTTING_DOWN, 503, True
                    break
                end = min(stall, total)
                if now >= end:
                    status, retry = 408, False
                    detail = (f"request body timed out: nothing arrived for {line.stall_s:g} s" if stall <= total else
                              f"request body timed out: not received whole within {line.read_s:g} s")
                    break
                done, _ = await asyncio.wait({task}, timeout=min(_POLL_S, end - now))
                if done:
                    return task.result()
        finally:
            if not task.done():
                task.cancel()
        await _answer(send, status, detail, retry=retry, close=True)
        raise _Answered


def _content_length(scope: Scope) -> int | None:
    """The declared body size, or None (chunked, absent or unreadable: h11 refuses the latter)."""
    for name, value in scope.get("headers") or ():
        if name == b"content-length":
            try:
                return int(value)
            except ValueError:
                return None
    return None


def _too_large(limit: int) -> str:
    return f"request body too large: the limit is {limit} bytes"


async def _answer(send: Send, status: int, detail: str, *, retry: bool = False, close: bool = False) -> None:
    """Answer ``{"detail": detail}`` from the middleware.

    ``retry``: with ``Retry-After``; ``close``: end the connection after it (a body stopped half-way).
    """
    headers = {}
    if retry:
        headers["Retry-After"] = str(RETRY_AFTER_S)
    if close:
        headers["Connection"] = "close"
    response = JSONResponse(status_code=status, content={"detail": detail}, headers=headers)

    async def nothing() -> Message:  # a response that never reads the request
        return {"type": "http.disconnect"}

    await response({"type": "http"}, nothing, send)
