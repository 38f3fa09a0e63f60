"""The hand-over from the scan to a publisher: an engine listener that keeps only the newest
snapshot (with its quality) and wakes the publisher once; a publisher that lags skips the
snapshots in between, so the scan never waits for it and it never falls behind."""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np

from app.publish.points import PointReader
from netplc.memory import Snapshot


class LatestSnapshot:
    def __init__(self, reader: PointReader, wake: Callable[[], None]) -> None:
        self.reader = reader
        self.wake = wake
        self.skipped = 0  # snapshots replaced before the publisher took them
        self._item: tuple[Snapshot, np.ndarray] | None = None
        self._lock = threading.Lock()

    def __call__(self, snapshot: Snapshot) -> None:
        """The engine listener (engine thread): O(1), never blocks on the publisher."""
        item = (snapshot, self.reader.quality_now(snapshot))
        with self._lock:
            pending = self._item is not None
            self._item = item
        if pending:
            self.skipped += 1
        else:
            self.wake()

    def take(self) -> tuple[Snapshot, np.ndarray] | None:
        with self._lock:
            item, self._item = self._item, None
        return item
