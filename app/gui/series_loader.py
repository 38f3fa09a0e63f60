"""Archive series read off the GUI thread, so that ticking a series never freezes the viewer.

A full day of a 10 Hz NSTORE is close to a million rows: reading and reducing them takes most of a
second, which on the GUI thread is a window that stops repainting and answering. The reads run in
the loader's worker thread (hmi_forms/widgets/worker.py), each on a read-only connection of its own
(opening one costs about a millisecond, and a reload or a copied-over file is then always read as
it is now); `answered` carries the request's token and (key, times, values).
"""

from __future__ import annotations

import datetime as dt
import sqlite3
from collections.abc import Hashable
from functools import partial
from pathlib import Path

import numpy as np
from PySide6.QtCore import QObject

from hmi_forms.widgets.worker import Worker
from registrar.query import Archive, SeriesKey
from registrar.reading import ArchiveError

Series = tuple[SeriesKey, np.ndarray, np.ndarray]  # key, times (s), values


class SeriesLoader(Worker):
    def __init__(self, points: int, parent: QObject | None = None) -> None:
        super().__init__("series", (sqlite3.Error, OSError, ArchiveError), parent)
        self.points = points

    def request(self, path: str | Path, day: dt.date, key: SeriesKey,
                topic: Hashable | None = None) -> int:
        """Queue a read of `key` on `day` (superseding the last one of `topic`, if given); the
        token that its `answered` or `failed` will carry."""
        return self.submit(partial(self._load, path, day, key), topic)

    def _load(self, path: str | Path, day: dt.date, key: SeriesKey) -> Series:
        """`path`: a file, or a plant archive's URL (kept a str: Path would fold its //)."""
        of_station = {"station": key.station} if key.station is not None else {}
        with Archive(path) as archive:
            ts, values = archive.series(day, grp=key.grp, type=key.type, source=key.source,
                                        points=self.points, **of_station)
        return key, ts, values
