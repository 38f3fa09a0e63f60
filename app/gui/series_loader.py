"""Archive series read off the GUI thread, so that ticking a series never freezes the viewer.

A full day of a 10 Hz NSTORE is close to a million rows: reading and reducing them takes most of a
second, which on the GUI thread is a window that stops repainting and answering. The reads run in
one worker thread, each on a read-only connection of its own (opening one costs about a
millisecond, and a reload or a copied-over file is then always read as it is now); each result comes
back to the GUI thread as a queued signal carrying the request's token, and the viewer keeps only
the answer to the newest request for a series.
"""

from __future__ import annotations

import datetime as dt
import sqlite3
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

from PySide6.QtCore import QObject, Signal

from registrar.query import Archive, SeriesKey
from registrar.reading import ArchiveError


class SeriesLoader(QObject):
    loaded = Signal(int, object, object, object)  # token, SeriesKey, times (s), values
    failed = Signal(int, object, str)  # token, SeriesKey, why

    def __init__(self, points: int, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.points = points
        self._pool = ThreadPoolExecutor(1, thread_name_prefix="series")
        self._token = 0
        self._queued: list[Future] = []

    def request(self, path: str | Path, day: dt.date, key: SeriesKey) -> int:
        """Queue a read of `key` on `day`; the token that its `loaded` or `failed` will carry."""
        self._token += 1
        self._queued = [f for f in self._queued if not f.done()]
        self._queued.append(self._pool.submit(self._load, self._token, path, day, key))
        return self._token

    def close(self) -> None:
        """Drop the queued reads and wait for the one under way (a second call does nothing)."""
        for future in self._queued:
            future.cancel()  # only those not yet started
        self._pool.shutdown(wait=True)

    def _load(self, token: int, path: str | Path, day: dt.date, key: SeriesKey) -> None:
        """`path`: a file, or a plant archive's URL (kept a str: Path would fold its //)."""
        of_station = {"station": key.station} if key.station is not None else {}
        try:
            with Archive(path) as archive:
                ts, values = archive.series(day, grp=key.grp, type=key.type, source=key.source,
                                            points=self.points, **of_station)
        except (sqlite3.Error, OSError, ArchiveError) as e:
            self.failed.emit(token, key, str(e))
            return
        self.loaded.emit(token, key, ts, values)
