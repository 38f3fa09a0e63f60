"""The event-loop thread of the asyncio clients: serial lines and pymodbus in the exchange, the monitors."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable, Coroutine
from typing import Any, TypeVar

T = TypeVar("T")


class LoopThread:
    """An asyncio event loop on a thread of its own: the clients run there, so
    neither the scan thread nor the GUI thread ever waits on a socket."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        loop = asyncio.new_event_loop()
        self.loop = loop
        self._thread = threading.Thread(target=self._run, args=(loop,), name=self.name, daemon=True)
        self._thread.start()

    @staticmethod
    def _run(loop: asyncio.AbstractEventLoop) -> None:
        asyncio.set_event_loop(loop)
        loop.run_forever()
        loop.run_until_complete(loop.shutdown_asyncgens())
        loop.close()

    def run(self, coro: Coroutine[Any, Any, T], timeout: float = 10.0) -> T:
        """Run `coro` on the loop and wait for its result (from another thread)."""
        if self.loop is None:
            raise RuntimeError(f"{self.name} is not started")
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result(timeout)

    def call(self, fn: Callable[..., object], *args: object) -> None:
        """Schedule `fn(*args)` on the loop (thread-safe, does not wait)."""
        if self.loop is not None:
            self.loop.call_soon_threadsafe(fn, *args)

    def stop(self, timeout: float = 5.0) -> None:
        loop, self.loop = self.loop, None
        if loop is None:
            return

        async def cancel_all() -> None:
            # Cancel again while anything is left: on Python 3.11 asyncio.wait_for (used inside
            # pymodbus) swallows a cancellation that arrives as its inner future completes.
            for _ in range(20):
                tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task() and not t.done()]
                if not tasks:
                    return
                for t in tasks:
                    t.cancel()
                await asyncio.wait(tasks, timeout=0.1)

        try:
            asyncio.run_coroutine_threadsafe(cancel_all(), loop).result(timeout)
        finally:
            loop.call_soon_threadsafe(loop.stop)
            if self._thread is not None:
                self._thread.join(timeout)
