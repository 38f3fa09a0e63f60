"""Archive series read off the GUI thread, so that ticking a series never freezes the viewer.

A full day of a 10 Hz NSTORE is close to a million rows: reading and reducing them takes most of a
second, which on the GUI thread is a window that stops repainting and answering. The reads run in
the loader's worker thread (hmi_forms/widgets/worker.py), each on a read-only connection of its own
(opening one costs about a millisecond, and a reload or a copied-over file is then always read as
it is now); `answered` carries the request's token and (key, times, values): the points within the
viewer's From/To, broken where the station restarted.
"""

from __future__ import annotations

import datetime as dt
import sqlite3
from collections.abc import Hashable, Sequence
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np
from PySide6.QtCore import QObject

from app.scada.words import TEXTS, Words
from hmi_forms.widgets.worker import Worker
from registrar.query import Archive, SeriesKey
from registrar.reading import ArchiveError, ArchiveSource, Filter

Series = tuple[SeriesKey, np.ndarray, np.ndarray]  # key, times (s), values
Window = tuple[float, float]  # [since, until): seconds since the epoch
# the record each start of a station writes (app/station/runtime.py), in any of its languages (the
# station's `Language` may have changed within a day): a series breaks there
RESTARTS = tuple(Filter(kinds=frozenset({"system"}), source="station",
                        text=Words(language)("starting", path="")) for language in TEXTS)
MAX_RESTARTS = 1000  # of one day
DAY_S = 86_400
MAX_ZOOM = 50  # a window narrower than a 50th of the day reads no more than 50 times the points


def cut(ts: np.ndarray, values: np.ndarray, window: Window | None,
        breaks: Sequence[float] = ()) -> tuple[np.ndarray, np.ndarray]:
    """The points inside `window`, with a gap (NaN) at each of `breaks` that falls among them, so
    no line is drawn across a time when nothing was recorded (a station's restart)."""
    if window is not None:
        inside = (ts >= window[0]) & (ts < window[1])
        ts, values = ts[inside], values[inside]
    if len(ts) and len(breaks):
        b = np.asarray(breaks, dtype=np.float64)
        b = b[(b > ts[0]) & (b <= ts[-1])]
        if len(b):
            ts = np.concatenate((b, ts))  # a break before a point of the same time
            values = np.concatenate((np.full(len(b), np.nan), values))
            order = np.argsort(ts, kind="stable")
            ts, values = ts[order], values[order]
    return ts, values


class SeriesLoader(Worker):
    def __init__(self, points: int, parent: QObject | None = None) -> None:
        super().__init__("series", (sqlite3.Error, OSError, ArchiveError), parent)
        self.points = points

    def points_for(self, window: Window | None) -> int:
        """As many points over the day as keep `points` within the window: the day is reduced in
        equal time buckets, and a window of an hour would otherwise keep a 24th of them."""
        if window is None:
            return self.points
        share = max((window[1] - window[0]) / DAY_S, 1 / MAX_ZOOM)
        return round(self.points / min(share, 1.0))

    def request(self, path: str | Path | ArchiveSource, day: dt.date, key: SeriesKey,
                topic: Hashable | None = None, window: Window | None = None) -> int:
        """Queue a read of `key` on `day` within `window` (superseding the last one of `topic`, if
        given); the token that its `answered` or `failed` will carry."""
        return self.submit(partial(self._load, path, day, key, window), topic)

    def _load(self, path: str | Path | ArchiveSource, day: dt.date, key: SeriesKey,
              window: Window | None) -> Series:
        """`path`: a file, a plant archive's URL (kept a str: Path would fold its //), or a
        station's archive at a console."""
        of_station = {"station": key.station} if key.station is not None else {}
        restarts = RESTARTS if key.station is None else \
            tuple(replace(r, stations=frozenset({key.station})) for r in RESTARTS)
        with Archive(path) as archive:
            ts, values = archive.series(day, grp=key.grp, type=key.type, source=key.source,
                                        points=self.points_for(window), **of_station)
            starts = sorted(r.ts for f in restarts
                            for r in archive.records(day, f, 0, MAX_RESTARTS, newest_first=False))
        return key, *cut(ts, values, window, starts)
