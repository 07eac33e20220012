"""Single pairs of JSON numbers, classified together off the event loop.

A single-pair ``/api/classify`` of JSON numbers is bounded work (the float filter, at worst one
exact classification of doubles), but deciding it on the event loop made every other request
wait behind it (p99 2.7 s at concurrency 32 on a loaded machine), and a thread hop per pair
costs about as much as the pair. :class:`PairBatcher` keeps one thread that takes every pair
waiting at that moment and classifies them in one vectorised call
(:func:`app.api.convert.classify_items`), so the event loop only parses, queues and answers, and
a burst of single pairs costs one filter call. A batch that holds a bad pair is answered pair by
pair, so each request gets its own message. The request budget still applies (and fails at once
when the server is stopping: :data:`app.api.budget.STOPPING`).
"""

from __future__ import annotations

import asyncio
import queue
import threading
from dataclasses import dataclass

from .budget import Budget
from .convert import Plain, classify_items
from .schemas import ClassifyOut, PairItem

__all__ = ["PairBatcher"]

_MOST = 512
"""Pairs classified in one call at most (a burst larger than this is served in several)."""


@dataclass
class _Item:
    pair: PairItem
    method: str
    plain: Plain
    """The route's :func:`app.api.convert.plain_shapes` of the pair (not decided again)."""
    future: asyncio.Future[ClassifyOut]
    loop: asyncio.AbstractEventLoop


class PairBatcher:
    """One thread classifying the single pairs queued by the event loop, in batches.

    Args:
        budget_s: the request budget of each batch (``ApiSettings.request_budget_s``).
    """

    def __init__(self, budget_s: float) -> None:
        self.budget_s = budget_s
        self._queue: queue.SimpleQueue[_Item | None] = queue.SimpleQueue()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    async def classify(self, pair: PairItem, method: str, plain: Plain) -> ClassifyOut:
        """The relation of one pair of JSON numbers (raises what :func:`classify_items` raises).

        ``plain``: the route's :func:`app.api.convert.plain_shapes` of the pair, passed on.
        """
        self._start()
        loop = asyncio.get_running_loop()
        future: asyncio.Future[ClassifyOut] = loop.create_future()
        self._queue.put(_Item(pair, method, plain, future, loop))
        return await future

    def stop(self) -> None:
        """End the thread once the pairs queued before are answered (it restarts on demand)."""
        with self._lock:
            if self._thread is not None:
                self._queue.put(None)
                self._thread = None

    def _start(self) -> None:
        with self._lock:
            if self._thread is None:
                self._thread = threading.Thread(target=self._serve, name="pair-batcher", daemon=True)
                self._thread.start()

    def _serve(self) -> None:
        while True:
            first = self._queue.get()
            if first is None:
                return
            items = [first]
            while len(items) < _MOST:
                try:
                    item = self._queue.get_nowait()
                except queue.Empty:
                    break
                if item is None:
                    self._queue.put(None)  # stop after this batch
                    break
                items.append(item)
            for method in {it.method for it in items}:
                self._answer([it for it in items if it.method == method], method)

    def _answer(self, items: list[_Item], method: str) -> None:
        try:
            outs = classify_items([it.pair for it in items], method, Budget(self.budget_s), batch=False, plain=[it.plain for it in items])
        except BaseException:  # noqa: BLE001 - a bad pair (422) or a stop: each request gets its own answer
            for it in items:
                try:
                    _settle(it, classify_items([it.pair], method, Budget(self.budget_s), batch=False, plain=[it.plain])[0], None)
                except BaseException as e:  # noqa: BLE001 - delivered to the request, which raises it
                    _settle(it, None, e)
            return
        for it, out in zip(items, outs, strict=True):
            _settle(it, out, None)


def _settle(item: _Item, result: ClassifyOut | None, error: BaseException | None) -> None:
    """Hand the answer to the request's event loop (a request that went away is skipped)."""

    def done() -> None:
        if item.future.done():
            return
        if error is not None:
            item.future.set_exception(error)
        else:
            item.future.set_result(result)  # type: ignore[arg-type]

    try:
        item.loop.call_soon_threadsafe(done)
    except RuntimeError:  # the loop is closed (the server stopped)
        pass
