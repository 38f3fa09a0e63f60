"""The thread our Modbus TCP servers answer on: one selector over non-blocking sockets, a queue of
calls, timers in a heap.

It is not asyncio because an answer is one recv and one send, and asyncio's loop costs three times
the CPU of a bare selector loop around them (a 64-register read, one in flight on each of 32
connections: 57-80 us of the serving thread's CPU per answer with asyncio's transports, the
bare Protocol included, against 18-26 us here, at load 11-19 on 2 cores). The exchange's side of the
wire is served the same way (netplc/tcp_exchange.py). Many simulated nodes may share one reactor.
"""

from __future__ import annotations

import contextlib
import heapq
import itertools
import logging
import selectors
import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future
from typing import Protocol, TypeVar

logger = logging.getLogger(__name__)

T = TypeVar("T")
READ, WRITE = selectors.EVENT_READ, selectors.EVENT_WRITE


class Ready(Protocol):
    """What is registered with a socket: told the selector's events for it."""

    def ready(self, events: int) -> None: ...


class Timer:
    """A call due at `when` (reactor time); `cancel()` drops it."""

    __slots__ = ("cancelled", "fn", "when")

    def __init__(self, when: float, fn: Callable[[], None]) -> None:
        self.when, self.fn, self.cancelled = when, fn, False

    def cancel(self) -> None:
        self.cancelled = True


class Reactor:
    """`start()` runs the thread; `run(fn)` calls fn on it and waits for its result; `call(fn)`
    queues fn from any thread; `soon(fn)` and `later(delay, fn)` from the thread itself. A callback's
    exception is logged and the thread goes on."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.selector = selectors.DefaultSelector()
        self._inbox: deque[Callable[[], None]] = deque()  # other threads -> this thread
        self._soon: deque[Callable[[], None]] = deque()  # this thread: after this round of events
        self._timers: list[tuple[float, int, Timer]] = []
        self._seq = itertools.count()
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self.selector.register(self._wake_r, READ, None)
        self._stopping = False
        self._thread: threading.Thread | None = None

    @property
    def running(self) -> bool:
        return self._thread is not None and not self._stopping

    def time(self) -> float:
        return time.monotonic()

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name=self.name, daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        """The sending end of the wake-up is closed here, after the join, never by the thread."""
        if self._thread is None or self._stopping:
            return
        self._stopping = True
        self._wake()
        self._thread.join(timeout)
        self._wake_w.close()

    def call(self, fn: Callable[[], None]) -> None:
        """Any thread: run fn on the thread soon (nothing once it has stopped)."""
        if self._stopping:
            return
        self._inbox.append(fn)
        self._wake()

    def run(self, fn: Callable[[], T], timeout: float = 10.0) -> T:
        """Call fn on the thread and wait for its result (or its exception)."""
        if self._thread is None or self._stopping:
            raise RuntimeError(f"{self.name} is not running")
        if threading.current_thread() is self._thread:
            return fn()
        future: Future[T] = Future()

        def call() -> None:
            try:
                future.set_result(fn())
            except Exception as e:  # no log: handed to the caller, who raises it
                future.set_exception(e)

        self.call(call)
        return future.result(timeout)

    def soon(self, fn: Callable[[], None]) -> None:
        """On the thread: fn after the events of this round (another connection's turn first)."""
        self._soon.append(fn)

    def later(self, delay: float, fn: Callable[[], None]) -> Timer:
        timer = Timer(self.time() + delay, fn)
        heapq.heappush(self._timers, (timer.when, next(self._seq), timer))
        return timer

    def _wake(self) -> None:
        try:
            self._wake_w.send(b"\0")
        except BlockingIOError:  # full of wake-ups already
            pass
        except OSError:
            if not self._stopping:
                raise

    def _run(self) -> None:
        select, timers, inbox, soon = self.selector.select, self._timers, self._inbox, self._soon
        try:
            while not self._stopping:
                if inbox or soon:
                    timeout: float | None = 0.0
                else:
                    timeout = max(0.0, timers[0][0] - time.monotonic()) if timers else None
                for key, events in select(timeout):
                    target = key.data
                    if target is None:
                        with contextlib.suppress(BlockingIOError):
                            self._wake_r.recv(4096)
                        continue
                    try:
                        target.ready(events)
                    except Exception:  # a bug must not end the service of the other connections
                        logger.exception("%s: serving a socket failed", self.name)
                for queue in (inbox, soon):
                    for _ in range(len(queue)):  # what a call queues waits for the next round
                        self._call(queue.popleft())
                now = time.monotonic()
                while timers and timers[0][0] <= now:
                    timer = heapq.heappop(timers)[2]
                    if not timer.cancelled:
                        self._call(timer.fn)
        finally:
            self.selector.close()
            self._wake_r.close()

    def _call(self, fn: Callable[[], None]) -> None:
        try:
            fn()
        except Exception:
            logger.exception("%s: a call failed", self.name)
