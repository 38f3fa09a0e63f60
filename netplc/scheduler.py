"""Runs an engine's scan on its tick in a thread of its own (NetPlc itself and simulated nodes).

Scans are scheduled on absolute deadlines of the monotonic clock, so a slow scan shortens the
next wait instead of drifting the tick; a scan that misses its deadline is counted by the engine's
overrun statistics and the schedule catches up without bursts.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from netplc.engine import Engine

logger = logging.getLogger(__name__)


class ScanThread:
    def __init__(self, engine: Engine, tick: float | None = None, name: str = "netplc-scan",
                 on_error: Callable[[Exception], None] | None = None) -> None:
        self.engine = engine
        self.tick = tick if tick is not None else engine.tick
        engine.tick = self.tick  # overruns are counted against the tick the scans really run on
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name=name, daemon=True)
        self._on_error = on_error
        self.lock = threading.Lock()  # held during a scan: take it to run something between scans

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout)

    @property
    def running(self) -> bool:
        return self._thread.is_alive()

    def _loop(self) -> None:
        """Scan on the tick. A scan that raises is reported and the thread goes on; the same fault
        at every scan is logged with its traceback once, until a scan succeeds or the fault changes."""
        deadline = time.monotonic()
        last_fault = ""
        while not self._stop.is_set():
            try:
                with self.lock:
                    self.engine.scan()
                last_fault = ""
            except Exception as e:
                if repr(e) != last_fault:
                    last_fault = repr(e)
                    logger.exception("scan %d failed", self.engine.scan_counter)
                if self._on_error:
                    self._on_error(e)
            deadline += self.tick
            now = time.monotonic()
            if deadline < now:
                deadline = now  # missed: start the next scan at once, do not burst
            self._stop.wait(deadline - now)
