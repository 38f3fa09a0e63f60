"""The hand-over from the scan to a publisher: a watcher of the station (`Runtime.watch`) that keeps
only the newest `Readings` (values and quality of one scan) and wakes the publisher once; a
publisher that lags skips the scans in between, so the scan never waits for it and it never falls
behind."""

from __future__ import annotations

import threading
from collections.abc import Callable

from app.scada.readings import Readings

Watch = Callable[[Callable[[Readings], None]], Callable[[], None]]  # Runtime.watch: -> unsubscribe


class LatestReadings:
    def __init__(self, wake: Callable[[], None]) -> None:
        self.wake = wake
        self.skipped = 0  # scans replaced before the publisher took them
        self.scan = -1  # the newest scan handed over (an int, read from any thread)
        self._item: Readings | None = None
        self._lock = threading.Lock()

    def __call__(self, readings: Readings) -> None:
        """The watcher (engine thread): O(1), never blocks on the publisher."""
        with self._lock:
            pending = self._item is not None
            self._item = readings
        self.scan = readings.snapshot.scan
        if pending:
            self.skipped += 1
        else:
            self.wake()

    def take(self) -> Readings | None:
        with self._lock:
            item, self._item = self._item, None
        return item
