"""The run-time trend: tags the operator picks, drawn from the station's archive on to their live
values, with two cursors, the statistics of the range shown, saved per user, exported.

A pen is a tag: its archive series is the NSTORE of the tag's address (the raw word, converted
with the tag's scaling, as the faceplate reads it), each day of the range shown read once, in the
series loader's worker thread (app/gui/series_loader.py), so panning back a week never stops the
window; a range zoomed into (under six hours, within a day, not live) is read again at its own
detail, so zooming shows the samples rather than the day's reduction. The archive is the
station's file at the workstation, its Historical Access at a remote console (app/gui/console/
archive.py), read the same way. The live values come from each scan's readings, the runtime
bridge's or a remote station's (good or forced ones only). The plot and the table are redrawn
twice a second, not at every scan. The cursors' table gives each pen's value at A and at B (the
last sample at or before), B − A, and the minimum, maximum and mean of the samples in the visible
range; the CSV export holds those samples.
"""

from __future__ import annotations

import csv
import datetime as dt
import logging
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt, QTimer, Signal, SignalInstance
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QFileDialog,
    QHBoxLayout,
    QInputDialog,
    QLabel,
    QLineEdit,
    QListWidget,
    QListWidgetItem,
    QPushButton,
    QSplitter,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.gui.designer.tag_browser import matches
from app.gui.series_loader import DAY_S, Series, SeriesLoader, Window
from app.scada.quality import Quality
from app.scada.readings import Readings
from app.scada.tag import Tag
from app.scada.trends import (
    SPANS,
    Pen,
    SavedTrend,
    TrendBook,
    TrendFileError,
    colour_for,
    csv_rows,
    stats,
    value_at,
)
from netplc.address import fmt_octal
from registrar.query import SeriesKey, available
from registrar.reading import ArchiveSource

logger = logging.getLogger(__name__)

POINTS = 4000  # read of a day: a plot a few thousand pixels wide
MAX_DAYS = 31  # read for one range shown: a month back at most
DETAIL_BELOW = DAY_S / 4  # a range shorter than this, within one day, is read again at its own detail
DETAIL_MS = 300  # after the last pan or zoom step
REDRAW_MS = 500
LIVE_POINTS = 36_000  # live samples kept per pen: an hour at ten a second
COLUMNS = 7  # pen, A, B, B − A, min, max, mean


class PenData:
    """A pen's samples: the archive's by day, then the live ones."""

    def __init__(self, tag: Tag, colour: str) -> None:
        self.tag = tag
        self.colour = colour
        self.days: dict[dt.date, tuple[np.ndarray, np.ndarray]] = {}
        self.asked: set[dt.date] = set()
        self.detail: tuple[Window, np.ndarray, np.ndarray] | None = None  # the range zoomed into
        self.live_t: list[float] = []
        self.live_v: list[float] = []

    def samples(self) -> tuple[np.ndarray, np.ndarray]:
        """Times and values in time order: the archive's up to the first live sample, then live."""
        live_from = self.live_t[0] if self.live_t else math.inf
        parts = [self.days[d] for d in sorted(self.days)]
        ts = np.concatenate([p[0] for p in parts]) if parts else np.empty(0)
        vs = np.concatenate([p[1] for p in parts]) if parts else np.empty(0)
        if self.detail is not None:  # the day's reduction replaced by the range's own points
            (w0, w1), dts, dvs = self.detail
            outside = (ts < w0) | (ts >= w1)
            ts, vs = np.concatenate([ts[outside], dts]), np.concatenate([vs[outside], dvs])
            order = np.argsort(ts, kind="stable")
            ts, vs = ts[order], vs[order]
        old = ts < live_from
        return (np.concatenate([ts[old], np.asarray(self.live_t, dtype=np.float64)]),
                np.concatenate([vs[old], np.asarray(self.live_v, dtype=np.float64)]))

    def heading(self) -> str:
        return f"{self.tag.name}, {self.tag.unit}" if self.tag.unit else self.tag.name


class TrendWindow(QWidget):
    # the tags whose live values the window shows now (none once closed): a source that reads only
    # what its views show (a remote console) watches them too
    watching = Signal(list)

    def __init__(self, readings: SignalInstance, tags: Sequence[Tag], archive: Path | ArchiveSource,
                 book: TrendBook, user: Callable[[], str], parent: QWidget | None = None) -> None:
        """`readings`: each scan's `Readings` (the runtime bridge's, a remote station's);
        `archive`: the station's (its file, or its Historical Access at a console); `book`: where
        the user's named trends are kept."""
        super().__init__(parent, Qt.WindowType.Window)
        self.setObjectName("trendWindow")
        self.setWindowTitle(self.tr("Run-time trend"))
        self.readings = readings
        self.tags = {t.name: t for t in tags}
        self.archive = archive
        self.user = user
        self.book = book
        self.pens: dict[str, PenData] = {}
        self.asked: dict[int, tuple[PenData, dt.date, Window | None]] = {}
        self.dirty = True
        self.loader = SeriesLoader(POINTS, self)
        self.loader.answered.connect(self._loaded)
        self.loader.failed.connect(self._failed)

        self.search = QLineEdit()
        self.search.setPlaceholderText(self.tr("Search tags: name, description, unit"))
        self.search.setClearButtonEnabled(True)
        self.search.textChanged.connect(self.show_matching)
        self.tag_list = QListWidget()
        self.tag_list.setObjectName("trendTags")
        self.tag_list.itemActivated.connect(lambda item: self.add_pen(item.data(Qt.ItemDataRole.UserRole)))
        add = QPushButton(self.tr("Add to the trend"))
        add.clicked.connect(self._add_current)
        picker = QWidget()
        side = QVBoxLayout(picker)
        side.setContentsMargins(0, 0, 0, 0)
        side.addWidget(self.search)
        side.addWidget(self.tag_list, 1)
        side.addWidget(add)

        self.span = QComboBox()
        for seconds in SPANS:
            self.span.addItem(self._span_text(seconds), seconds)
        self.span.setCurrentIndex(SPANS.index(3600.0))
        self.span.currentIndexChanged.connect(lambda _: self.follow_live())
        self.live = QCheckBox(self.tr("Live"))
        self.live.setToolTip(self.tr("Follow the live values; panning or zooming the plot stops following"))
        self.live.setChecked(True)
        self.live.toggled.connect(lambda on: self.follow_live() if on else None)
        self.saved = QComboBox()
        self.saved.setObjectName("savedTrends")
        self.saved.setMinimumContentsLength(12)
        self.saved.setToolTip(self.tr("The trends saved by the user on duty"))
        open_ = QPushButton(self.tr("Open"))
        open_.clicked.connect(lambda: self.saved.count() and self.open_trend(self.saved.currentText()))
        save = QPushButton(self.tr("Save as…"))
        save.clicked.connect(self._ask_save)
        remove = QPushButton(self.tr("Remove pen"))
        remove.clicked.connect(self._remove_current)
        png = QPushButton(self.tr("Export PNG…"))
        png.clicked.connect(lambda: self._ask_export(self.tr("PNG image (*.png)"), ".png", self.export_png))
        csv_ = QPushButton(self.tr("Export CSV…"))
        csv_.clicked.connect(lambda: self._ask_export(self.tr("CSV (*.csv)"), ".csv", self.export_csv))
        bar = QHBoxLayout()
        bar.addWidget(QLabel(self.tr("Span")))
        bar.addWidget(self.span)
        bar.addWidget(self.live)
        bar.addStretch(1)
        bar.addWidget(self.saved)
        bar.addWidget(open_)
        bar.addWidget(save)
        bar.addWidget(remove)
        bar.addWidget(png)
        bar.addWidget(csv_)

        self.plot = pg.PlotWidget(axisItems={"bottom": pg.DateAxisItem()})
        self.plot.setObjectName("trendPlot")
        self.plot.setBackground("w")
        self.plot.showGrid(x=True, y=True, alpha=0.3)
        self.legend = self.plot.addLegend(offset=(10, 10))
        self.curves: dict[str, pg.PlotDataItem] = {}
        self.cursors = tuple(pg.InfiniteLine(angle=90, movable=True, label=name,
                                             pen=pg.mkPen("#444", width=1, style=style),
                                             labelOpts={"position": 0.95, "color": "#444"})
                             for name, style in (("A", Qt.PenStyle.SolidLine), ("B", Qt.PenStyle.DashLine)))
        for line in self.cursors:
            self.plot.addItem(line, ignoreBounds=True)
            line.sigPositionChanged.connect(self._touch)
        view = self.plot.getViewBox()
        view.sigRangeChangedManually.connect(lambda *_: self.live.setChecked(False))
        view.sigXRangeChanged.connect(lambda *_: self._range_changed())
        self.settled = QTimer(self)
        self.settled.setSingleShot(True)
        self.settled.setInterval(DETAIL_MS)
        self.settled.timeout.connect(self._want_detail)

        self.cursor_text = QLabel()
        self.cursor_text.setObjectName("trendCursors")
        self.table = QTableWidget(0, COLUMNS)
        self.table.setObjectName("trendTable")
        self.table.setHorizontalHeaderLabels([self.tr("Pen"), "A", "B", "B − A", self.tr("Min"),
                                              self.tr("Max"), self.tr("Mean")])
        self.table.verticalHeader().hide()
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QTableWidget.SelectionBehavior.SelectRows)
        self.table.setMaximumHeight(160)
        self.message = QLabel()
        self.message.setObjectName("trendMessage")
        self.message.setWordWrap(True)

        right = QWidget()
        main = QVBoxLayout(right)
        main.setContentsMargins(0, 0, 0, 0)
        main.addLayout(bar)
        main.addWidget(self.plot, 1)
        main.addWidget(self.cursor_text)
        main.addWidget(self.table)
        main.addWidget(self.message)
        split = QSplitter()
        split.addWidget(picker)
        split.addWidget(right)
        split.setStretchFactor(1, 1)
        split.setSizes([240, 900])
        lay = QVBoxLayout(self)
        lay.addWidget(split)
        self.resize(1200, 700)

        self.show_matching()
        self.list_saved()
        self.follow_live()
        readings.connect(self.show_readings)
        self.timer = QTimer(self)
        self.timer.setInterval(REDRAW_MS)
        self.timer.timeout.connect(self.redraw)
        self.timer.start()

    # --- picking ----------------------------------------------------------------------------------

    def _span_text(self, seconds: float) -> str:
        return (self.tr("{0} min").format(round(seconds / 60)) if seconds < 3600
                else self.tr("{0} h").format(round(seconds / 3600)))

    def show_matching(self, words: str = "") -> None:
        self.tag_list.clear()
        for tag in self.tags.values():
            if matches(tag, words):
                unit = f", {tag.unit}" if tag.unit else ""
                item = QListWidgetItem(f"{tag.name}  {tag.description}{unit}".rstrip())
                item.setData(Qt.ItemDataRole.UserRole, tag.name)
                item.setToolTip(self.tr("Double-click to add {0} to the trend").format(tag.name))
                self.tag_list.addItem(item)

    def _add_current(self) -> None:
        item = self.tag_list.currentItem()
        if item is not None:
            self.add_pen(item.data(Qt.ItemDataRole.UserRole))

    def add_pen(self, name: str, colour: str | None = None) -> PenData | None:
        """A pen for the tag (its own colour unless given), its history asked of the archive."""
        if name in self.pens:
            return self.pens[name]
        tag = self.tags.get(name)
        if tag is None:
            self.message.setText(self.tr("{0}: no such tag in this station").format(name))
            return None
        pen = self.pens[name] = PenData(tag, colour or colour_for([p.colour for p in self.pens.values()]))
        self.curves[name] = self.plot.plot(name=pen.heading(), pen=pg.mkPen(pen.colour, width=2),
                                           connect="finite")
        self._axis_units()
        self._want_history()
        self._touch()
        self.watching.emit([p.tag for p in self.pens.values()])
        return pen

    def remove_pen(self, name: str) -> None:
        if self.pens.pop(name, None) is not None:
            self.plot.removeItem(self.curves.pop(name))
            self._axis_units()
            self._touch()
            self.watching.emit([p.tag for p in self.pens.values()])

    def _remove_current(self) -> None:
        row = self.table.currentRow()
        if 0 <= row < len(self.pens):
            self.remove_pen(list(self.pens)[row])

    def _axis_units(self) -> None:
        """The left axis names the pens' units, each in its pen's colour."""
        units: dict[str, str] = {}
        for pen in self.pens.values():
            units.setdefault(pen.tag.unit or pen.tag.name, pen.colour)
        self.plot.getAxis("left").setLabel(" / ".join(
            f'<span style="color:{colour}">{unit}</span>' for unit, colour in units.items()))

    # --- data -------------------------------------------------------------------------------------

    def _range_changed(self) -> None:
        self._want_history()
        if not self.live.isChecked():  # live, the recent part comes from the readings
            self.settled.start()
        self._touch()

    def _want_detail(self) -> None:
        """A range zoomed into, within one day: its own points rather than the day's reduction (the
        loader reads up to 50 times the day's points for it, the last request of a pen superseding
        the one before)."""
        x0, x1 = self.visible()
        day = dt.date.fromtimestamp(max(x0, 0.0))
        if self.live.isChecked() or x1 - x0 > DETAIL_BELOW or dt.date.fromtimestamp(max(x1, 0.0)) != day \
                or not available(self.archive):
            return
        for pen in self.pens.values():
            key = SeriesKey("data", None, None, fmt_octal(pen.tag.address))
            token = self.loader.request(self.archive, day, key, ("detail", pen.tag.name), (x0, x1))
            # the request it supersedes is answered no more
            self.asked = {t: a for t, a in self.asked.items() if a[0] is not pen or a[2] is None}
            self.asked[token] = (pen, day, (x0, x1))

    def _want_history(self) -> None:
        """Ask the archive for each day of the range shown that no pen has read yet."""
        if not available(self.archive):
            return
        x0, x1 = self.plot.getViewBox().viewRange()[0]
        first = dt.date.fromtimestamp(max(x0, x1 - MAX_DAYS * 86_400.0, 0.0))
        last = dt.date.fromtimestamp(max(min(x1, time.time()), 0.0))
        days = [first + dt.timedelta(days=i) for i in range((last - first).days + 1)]
        for pen in self.pens.values():
            key = SeriesKey("data", None, None, fmt_octal(pen.tag.address))
            for day in days:
                if day not in pen.asked:
                    pen.asked.add(day)
                    self.asked[self.loader.request(self.archive, day, key)] = (pen, day, None)

    def _loaded(self, token: int, series: Series) -> None:
        pen, day, window = self.asked.pop(token, (None, None, None))
        if pen is None or day is None or self.pens.get(pen.tag.name) is not pen:
            return  # removed while it loaded
        _key, ts, raw = series
        values = raw if pen.tag.scaling is None else pen.tag.scaling.to_phy(raw)
        if window is None:
            pen.days[day] = (ts, values)
        else:
            pen.detail = (window, ts, values)
        self._touch()

    def _failed(self, token: int, why: str) -> None:
        pen, day, window = self.asked.pop(token, (None, None, None))  # logged by the loader
        if pen is not None and day is not None:
            if window is None:
                pen.asked.discard(day)
            self.message.setText(self.tr("The archive of {0} could not be read: {1}").format(day, why))

    def loading(self) -> bool:
        return bool(self.asked)

    def show_readings(self, readings: Readings) -> None:
        for pen in self.pens.values():
            reading = readings.tag(pen.tag.name)
            if reading.quality in (Quality.GOOD, Quality.FORCED):
                pen.live_t.append(readings.time)
                pen.live_v.append(reading.value)
                if len(pen.live_t) > LIVE_POINTS:
                    del pen.live_t[:-LIVE_POINTS], pen.live_v[:-LIVE_POINTS]
        self.dirty = True

    # --- showing ----------------------------------------------------------------------------------

    def _touch(self, *_: object) -> None:
        self.dirty = True

    def follow_live(self) -> None:
        if self.live.isChecked():
            now = time.time()
            self.plot.setXRange(now - float(self.span.currentData()), now, padding=0)

    def set_range(self, t0: float, t1: float) -> None:
        """Show [t0, t1] (no longer following the live values), as a pan or zoom of the operator."""
        self.live.setChecked(False)
        self.plot.setXRange(t0, t1, padding=0)
        self.redraw()

    def set_cursors(self, a: float, b: float) -> None:
        self.cursors[0].setValue(a)
        self.cursors[1].setValue(b)
        self.redraw()

    def visible(self) -> tuple[float, float]:
        x0, x1 = self.plot.getViewBox().viewRange()[0]
        return float(x0), float(x1)

    def redraw(self) -> None:
        if not self.dirty:
            return
        self.dirty = False
        self.follow_live()
        x0, x1 = self.visible()
        a, b = (float(c.value()) for c in self.cursors)
        if not x0 <= a <= x1 or not x0 <= b <= x1:  # brought back into sight
            a, b = x0 + (x1 - x0) / 3, x0 + 2 * (x1 - x0) / 3
            for line, t in zip(self.cursors, (a, b), strict=True):
                line.blockSignals(True)
                line.setValue(t)
                line.blockSignals(False)
        self.cursor_text.setText(self.tr("A {0}   B {1}   B − A {2} s").format(
            _clock(a), _clock(b), f"{b - a:.1f}"))
        self.table.setRowCount(len(self.pens))
        for row, (name, pen) in enumerate(self.pens.items()):
            ts, vs = pen.samples()
            self.curves[name].setData(ts, vs)
            va, vb = value_at(ts, vs, a), value_at(ts, vs, b)
            s = stats(ts, vs, x0, x1)
            d = pen.tag.decimals
            cells = [pen.heading(), _num(va, d), _num(vb, d), _num(vb - va, d),
                     *((_num(s.min, d), _num(s.max, d), _num(s.mean, d)) if s else ("", "", ""))]
            for col, text in enumerate(cells):
                item = QTableWidgetItem(text)
                if col == 0:
                    item.setForeground(pg.mkColor(pen.colour))
                self.table.setItem(row, col, item)

    def cell(self, name: str, column: str) -> str:
        """The table's text of a pen's column ("A", "B", "B − A", "Min", "Max", "Mean"; tests read)."""
        columns = {"A": 1, "B": 2, "B − A": 3, "Min": 4, "Max": 5, "Mean": 6}
        item = self.table.item(list(self.pens).index(name), columns[column])
        return item.text() if item is not None else ""

    # --- saving and exporting ---------------------------------------------------------------------

    def list_saved(self) -> None:
        self.saved.clear()
        try:
            self.saved.addItems(self.book.names(self.user()))
        except TrendFileError as e:
            logger.exception("saved trends not listed")
            self.message.setText(str(e))

    def save_as(self, name: str) -> None:
        """Keep the pens and the span under `name` for the user on duty."""
        trend = SavedTrend(name, [Pen(p.tag.name, p.colour) for p in self.pens.values()],
                           float(self.span.currentData()))
        try:
            self.book.put(self.user(), trend)
        except (TrendFileError, OSError) as e:
            logger.exception("trend %s not saved", name)
            self.message.setText(self.tr("The trend was not saved: {0}").format(e))
            return
        self.setWindowTitle(self.tr("Run-time trend: {0}").format(name))
        self.list_saved()
        self.saved.setCurrentText(name)

    def _ask_save(self) -> None:
        name, ok = QInputDialog.getText(self, self.tr("Save trend"), self.tr("Name of the trend"),
                                        text=self.saved.currentText())
        if ok and name.strip():
            self.save_as(name.strip())

    def open_trend(self, name: str) -> bool:
        """The user's trend `name` in place of the pens shown, following its live values."""
        try:
            trend = self.book.get(self.user(), name)
        except TrendFileError as e:
            logger.exception("trend %s not opened", name)
            self.message.setText(str(e))
            return False
        if trend is None:
            self.message.setText(self.tr("No trend {0} of this user").format(name))
            return False
        for old in list(self.pens):
            self.remove_pen(old)
        if trend.span in SPANS:
            self.span.setCurrentIndex(SPANS.index(trend.span))
        self.live.setChecked(True)
        for pen in trend.pens:
            self.add_pen(pen.tag, pen.colour)
        self.setWindowTitle(self.tr("Run-time trend: {0}").format(name))
        self.redraw()
        return True

    def _ask_export(self, kind: str, suffix: str, export: Callable[[Path], None]) -> None:
        path, _ = QFileDialog.getSaveFileName(self, self.tr("Export"), "trend" + suffix, kind)
        if path:
            export(Path(path))

    def export_png(self, path: Path) -> None:
        """The plot as it is shown, with its legend and cursors."""
        if not self.plot.grab().save(str(path), "PNG"):
            self.message.setText(self.tr("{0} could not be written").format(path))

    def export_csv(self, path: Path) -> None:
        """The samples of the visible range, one column per pen."""
        x0, x1 = self.visible()
        rows = csv_rows([(p.heading(), *p.samples()) for p in self.pens.values()], x0, x1)
        try:
            with path.open("w", newline="", encoding="utf-8") as f:
                csv.writer(f).writerows(rows)
        except OSError as e:
            logger.exception("trend CSV not written")
            self.message.setText(self.tr("{0} could not be written: {1}").format(path, e))

    def closeEvent(self, event: object) -> None:
        if self.timer.isActive():  # closed once: by the operator, then with the workstation
            self.timer.stop()
            self.settled.stop()
            self.readings.disconnect(self.show_readings)
            self.loader.close()
            self.watching.emit([])
        super().closeEvent(event)  # type: ignore[arg-type]


def _clock(t: float) -> str:
    return dt.datetime.fromtimestamp(t).strftime("%H:%M:%S") if t > 0 else ""


def _num(v: float, decimals: int) -> str:
    """With the tag's decimals, as its value is shown everywhere else."""
    return "" if math.isnan(v) else f"{v:.{decimals}f}"
