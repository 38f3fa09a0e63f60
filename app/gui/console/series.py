"""A console's trend history: the station's Historical Access in place of an archive file, behind
the `SeriesSource` the local workstation's archive reader has (app/gui/trend_history.py), so the
trend views have one code path.

A trend's series is its raw address's tag at the station, if the station archives it (its NSTORE:
Historizing, app/publish/history.py); the station answers its values in the tag's physical units,
a value not good with the StatusCode of its quality, drawn as a gap. A day is read in the
station's pages (its continuation points) on the worker thread, which waits for the client's loop:
neither the GUI thread nor the client's polls wait for the other.
"""

from __future__ import annotations

import datetime as dt
import math
from functools import partial

import numpy as np

from app.gui.series_loader import Series
from app.publish.console import ConsoleClient
from app.publish.history import ARCHIVED_TYPES
from app.scada.table import TagTable
from hmi_forms.elements.analog import AnalogBase
from hmi_forms.widgets.worker import Worker
from registrar.reading import SeriesKey

READ_S = 60.0  # a day's pages at most: the worker gives up on a station that stopped answering


class StationSeries(Worker):
    def __init__(self, client: ConsoleClient, tags: TagTable) -> None:
        super().__init__("station series", (ConnectionError, TimeoutError))
        self.client = client
        self.archived = {t.address: t.name for t in tags.tags if t.type in ARCHIVED_TYPES}

    def available(self) -> bool:
        """The link up: a trend asked while it is down asks again when the view next wants."""
        return not self.client.error

    def keys(self, model: AnalogBase) -> list[tuple[SeriesKey, bool]]:
        name = self.archived.get(model.InAddr) if model.InAddr is not None else None
        return [(SeriesKey("data", None, None, name), False)] if name else []

    def read(self, day: dt.date, key: SeriesKey) -> int:
        return self.submit(partial(self._load, day, key))

    def _load(self, day: dt.date, key: SeriesKey) -> Series:
        start = dt.datetime.combine(day, dt.time.min).astimezone(dt.UTC)
        values = self.client.history(str(key.source), start, start + dt.timedelta(days=1)).result(READ_S)
        ts = np.array([v.SourceTimestamp.timestamp() for v in values], dtype=np.float64)
        ys = np.array([float(v.Value.Value) if v.StatusCode.is_good() and v.Value is not None
                       and v.Value.Value is not None else math.nan for v in values], dtype=np.float64)
        return key, ts, ys
