"""Trend history: at start a trend is filled with what the archive holds of it, and scrolling back
past its live samples reads the day scrolled to, in a worker thread, so the window never waits for
the disk or the network. The views have one code path; what differs is the archive `ArchiveSeries`
reads (app/gui/series_loader.py, through `registrar.query.Archive`): the station's own archive
file at the local workstation, the station's Historical Access at a remote console
(app/gui/console/archive.py).

A trend's series is found by what wrote it: an element with RegData journals its physical value
under its own name; otherwise an NSTORE of the trend's address (source = the octal address) holds
the raw word, which is converted with the element's scaling. Bit trends (Graph) have no series.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path

from PySide6.QtCore import QObject

from app.gui.series_loader import Series, SeriesLoader
from hmi_forms.elements.analog import AnalogBase
from hmi_forms.widgets.form_view import FormView
from hmi_forms.widgets.trend import TrendWidget
from netplc.address import fmt_octal
from registrar.query import SeriesKey, available
from registrar.reading import ArchiveSource

POINTS = 4000  # per day read: enough for a plot a few thousand pixels wide


def series_keys(model: AnalogBase) -> list[tuple[SeriesKey, bool]]:
    """Where the archive may hold this trend, with whether the values are raw words."""
    keys = [(SeriesKey("data", None, None, model.Name), False)] if model.RegData else []
    if model.InAddr is not None:
        keys.append((SeriesKey("data", None, None, fmt_octal(model.InAddr)), True))
    return keys


class ArchiveSeries(SeriesLoader):
    """The station's archive: its file at the local workstation, its Historical Access at a remote
    console (an `ArchiveSource`, app/gui/console/archive.py)."""

    def __init__(self, path: Path | ArchiveSource) -> None:
        super().__init__(POINTS)
        self.path = path

    def available(self) -> bool:
        return available(self.path)

    def keys(self, model: AnalogBase) -> list[tuple[SeriesKey, bool]]:
        return series_keys(model)

    def read(self, day: dt.date, key: SeriesKey) -> int:
        return self.request(self.path, day, key)


class TrendHistory(QObject):
    def __init__(self, source: ArchiveSeries, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.loader = source
        source.setParent(self)
        self.loader.answered.connect(self._loaded)
        self.loader.failed.connect(self._failed)
        self._asked: dict[int, tuple[TrendWidget, bool]] = {}
        self._days: dict[TrendWidget, dt.date] = {}
        self._found: dict[TrendWidget, SeriesKey] = {}

    def attach(self, view: FormView) -> None:
        view.history_wanted = self.want
        for trend in view.trends:
            if isinstance(trend.model, AnalogBase):
                self._request(trend, dt.date.today())

    def want(self, trend: TrendWidget, t0: float, _t1: float) -> None:
        if isinstance(trend.model, AnalogBase):
            self._request(trend, dt.date.fromtimestamp(t0))

    def _request(self, trend: TrendWidget, day: dt.date) -> None:
        if self._days.get(trend) == day or not self.loader.available():
            return
        self._days[trend] = day
        assert isinstance(trend.model, AnalogBase)
        for key, raw in self.loader.keys(trend.model):
            if trend in self._found and self._found[trend] != key:
                continue
            self._asked[self.loader.read(day, key)] = (trend, raw)

    def _failed(self, token: int, _why: str) -> None:
        """Logged by the loader; the day is read again when next wanted (a station back, a file
        readable again)."""
        asked = self._asked.pop(token, None)
        if asked is not None:
            self._days.pop(asked[0], None)

    def _loaded(self, token: int, series: Series) -> None:
        key, ts, values = series
        asked = self._asked.pop(token, None)
        if asked is None or not len(ts):
            return
        trend, raw = asked
        if trend in self._found and self._found[trend] != key:
            return  # the element's own series was found first
        self._found[trend] = key
        model = trend.model
        assert isinstance(model, AnalogBase)
        trend.set_history(ts, model.scaling.to_phy(values) if raw else values)

    def close(self) -> None:
        self.loader.close()
