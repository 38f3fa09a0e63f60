"""The offline journal viewer: an archive opened read-only, without a running station.

It needs only the archive file (the message texts are stored in it), so an archive copied from a
plant PC opens on any machine; at a remote console it reads the station's archive over its
Historical Access instead (app/gui/console/archive.py), through the same views. Records are paged
from SQLite rather than loaded whole, so a day of a million records opens as fast as a day of ten.
Given a postgresql:// URL it opens the plant archive read-only instead: a list of stations to
tick, and series of several stations on one plot.
Days and From/To are read in the zone the archive was written in (stored in its meta).

A page and its count are read in the viewer's worker thread (hmi_forms/widgets/worker.py), as the
series are (series_loader.py): counting a filtered day of a million records, or any read of a plant
archive across the network, takes longer than a frame, and a window waiting for it stops answering.
The newest request wins, and a read that fails (SQLite, or the plant archive's `ArchiveError`) is
said under the table; the viewer keeps running.
"""

from __future__ import annotations

import datetime as dt
import logging
import sqlite3
import sys
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QT_TRANSLATE_NOOP, Qt
from PySide6.QtGui import QAction, QColor, QKeySequence
from PySide6.QtWidgets import (
    QComboBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QListWidget,
    QListWidgetItem,
    QMainWindow,
    QMessageBox,
    QPushButton,
    QSpinBox,
    QSplitter,
    QTabWidget,
    QTimeEdit,
    QVBoxLayout,
    QWidget,
)

from app.gui import i18n
from app.gui.application import application
from app.gui.designer.station import find_station
from app.gui.series_loader import Series, SeriesLoader
from app.scada.tag import Tag
from app.station.config import DEMO_STATION, ConfigError, load_station, read_station, station_file
from hmi_forms.elements import formats
from hmi_forms.widgets.records import (
    ARCHIVE_COLUMNS,
    SOURCE,
    VALUE,
    Column,
    RecordsModel,
    format_value,
    records_view,
)
from hmi_forms.widgets.worker import Worker
from netplc.address import parse_octal
from netplc.program import read_symbols
from registrar.plant.url import is_url
from registrar.query import Archive, Filter, SeriesKey
from registrar.reading import ArchiveError, ArchiveReader, ArchiveSource, Row

logger = logging.getLogger(__name__)

READ_ERRORS = (sqlite3.Error, OSError, ArchiveError)  # an archive gone, unreadable or out of reach
PAGE = 500
PAGES = "page"  # the pager's one topic: a newer page request supersedes the older ones
SERIES_POINTS = 4000
KINDS = ("all", "data", "message", "alarm", "operator", "system")
# a severity and everything worse, as alarm consoles filter: "2 alarm" keeps the critical ones too
TYPES = (QT_TRANSLATE_NOOP("ViewerWindow", "any"), QT_TRANSLATE_NOOP("ViewerWindow", "0 info and above"),
         QT_TRANSLATE_NOOP("ViewerWindow", "1 warning and above"),
         QT_TRANSLATE_NOOP("ViewerWindow", "2 alarm and above"),
         QT_TRANSLATE_NOOP("ViewerWindow", "3 critical"))
STATION = Column("Station", lambda r: r.station or "", 100)  # shown for a plant archive only
PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#17becf", "#8c564b", "#e377c2")


def series_label(key: SeriesKey, tag: Tag | None = None, symbol: str = "") -> str:
    """How a series is named: by its tag (name, description, unit) where the archive has one, else
    by the symbol of symbols.csv its address has."""
    parts = [f"group {key.grp}" if key.grp is not None else "",
             f"type {key.type}" if key.type is not None else "", key.source or ""]
    raw = " / ".join(p for p in parts if p) or key.kind
    if tag is None:
        return f"{symbol} ({raw})" if symbol else raw
    described = f"{tag.name} {tag.description}".strip() + (f", {tag.unit}" if tag.unit else "")
    return f"{described} ({raw})"


def physical(tag: Tag | None, values: np.ndarray) -> np.ndarray:
    """A tag's stored raw words as its physical values (the one conversion of app/scada/)."""
    if tag is None:
        return values
    return np.array([tag.word_value(int(v)) if np.isfinite(v) else np.nan for v in values], dtype=np.float64)


def station_symbols(archive: Path | str | ArchiveSource) -> dict[int, str]:
    """The symbols of the station an archive file belongs to (its station.toml in the archive's
    folder or the two above), by address, to name the series and sources that have no tag.
    {}: a plant archive or a station's at a console, or no station or symbols beside it."""
    if not isinstance(archive, Path):
        return {}
    toml = find_station(archive.resolve())
    station = read_station(toml)[0] if toml is not None else None
    if station is None or station.Symbols is None:
        return {}
    return {addr: name for name, addr in read_symbols(station.Symbols)[0].items()}


@dataclass(frozen=True)
class Page:
    offset: int
    total: int  # records of the day under the filter
    rows: list[Row]


class PageReader:
    """The archive as the pager's worker thread reads it, on a connection of its own (the GUI
    thread's serves the day list, the series list and export): opened at the first page, and
    again after a failed read (a plant archive's dropped connection) or a reload."""

    def __init__(self) -> None:
        self.target: Path | str | ArchiveSource | None = None
        self.archive: ArchiveReader | None = None

    def page(self, target: Path | str | ArchiveSource, day: dt.date, flt: Filter, offset: int) -> Page:
        if self.archive is None or self.target != target:
            self.close()
            self.archive, self.target = Archive(target), target
        try:
            total = self.archive.count(day, flt)
            rows = self.archive.records(day, flt, offset, PAGE, newest_first=False)
        except READ_ERRORS:
            self.close()  # the next page opens it anew
            raise
        return Page(offset, total, rows)

    def close(self) -> None:
        if self.archive is not None:
            self.archive.close()
            self.archive = None


class ViewerWindow(QMainWindow):
    def __init__(self, archive_path: Path | str | ArchiveSource | None = None, parent: QWidget | None = None,
                 symbols: dict[int, str] | None = None) -> None:
        """`symbols`: names by address for what has no tag (None: those of the archive's station)."""
        super().__init__(parent)
        self.symbols = symbols
        self.setWindowTitle(self.tr("NetPlc Station — journal viewer"))
        self.archive: Archive | None = None
        self.archive_path: Path | str | ArchiveSource | None = None  # a file, a URL, a station's
        self.offset = 0
        self.total = 0
        self.curves: dict[SeriesKey, pg.PlotDataItem] = {}
        self.tags: dict[str, Tag] = {}  # the archive's tags by the source of their data series
        self.tag_names: dict[str, Tag] = {}  # the same by name (an alarm's source is TAG.LIMIT)
        self.loading: dict[SeriesKey, int] = {}  # series asked for and not yet plotted: their token
        self.loader = SeriesLoader(SERIES_POINTS, self)
        self.loader.answered.connect(self._series_loaded)
        self.loader.failed.connect(self._series_failed)
        self.pages = PageReader()
        self.pager = Worker("viewer pages", READ_ERRORS, self, on_close=self.pages.close)
        self.pager.answered.connect(self._page_read)
        self.pager.failed.connect(self._page_failed)
        self.paging: int | None = None  # the token of the page asked for and not yet shown
        self._build()
        self.resize(1280, 820)
        if archive_path is not None:
            self.open_archive(archive_path)

    # --- building ------------------------------------------------------------------------------

    def _build(self) -> None:
        menu = self.menuBar().addMenu(self.tr("&Archive"))
        open_ = QAction(self.tr("&Open…"), self)
        open_.setShortcut(QKeySequence.StandardKey.Open)
        open_.triggered.connect(self._choose_archive)
        self.act_export = QAction(self.tr("&Export selection to CSV…"), self)
        self.act_export.setShortcut(QKeySequence("Ctrl+E"))
        self.act_export.triggered.connect(self._choose_export)
        reload_ = QAction(self.tr("&Reload"), self)
        reload_.setShortcut(QKeySequence.StandardKey.Refresh)
        reload_.triggered.connect(self.reload)
        close = QAction(self.tr("&Close"), self)
        close.setShortcut(QKeySequence.StandardKey.Close)
        close.triggered.connect(self.close)
        for a in (open_, self.act_export, reload_):
            menu.addAction(a)
        menu.addSeparator()
        menu.addAction(close)

        side = QWidget()
        side.setObjectName("viewerSide")
        side_lay = QVBoxLayout(side)
        self.path_label = QLabel(self.tr("no archive"))
        self.path_label.setWordWrap(True)
        side_lay.addWidget(QLabel(self.tr("<b>Days</b>")))
        self.days = QListWidget()
        self.days.currentRowChanged.connect(self._day_changed)
        side_lay.addWidget(self.days, 1)
        self.stations_label = QLabel(self.tr("<b>Stations</b>"))
        self.stations = QListWidget()
        self.stations.setMaximumHeight(120)
        self.stations.itemChanged.connect(lambda _item: self.apply_filter())
        side_lay.addWidget(self.stations_label)
        side_lay.addWidget(self.stations)
        self.stations_label.hide()
        self.stations.hide()
        side_lay.addWidget(QLabel(self.tr("<b>Filter</b>")))
        form = QFormLayout()
        self.kind = QComboBox()
        self.kind.addItems(KINDS)
        self.group = QSpinBox()
        self.group.setRange(-1, 65535)
        self.group.setSpecialValueText("any")
        self.group.setValue(-1)
        self.type = QComboBox()
        self.type.addItems([self.tr(t) for t in TYPES])
        self.type.setToolTip(self.tr("A message's type and worse; an alarm record by the priority of that "
                                     "severity (3 critical: priority 1, 2 alarm: 1-2, 1 warning: 1-3); "
                                     "a data record by its type"))
        self.source = QLineEdit()
        self.source.setPlaceholderText("exact source")
        self.text = QLineEdit()
        self.text.setPlaceholderText("text contains")
        self.since = QTimeEdit()
        self.since.setDisplayFormat("HH:mm:ss")
        self.until = QTimeEdit()
        self.until.setDisplayFormat("HH:mm:ss")
        self.until.setTime(self.until.maximumTime())
        for label, w in ((self.tr("Kind"), self.kind), (self.tr("Group"), self.group),
                         (self.tr("Type"), self.type), (self.tr("Source"), self.source),
                         (self.tr("Text"), self.text), (self.tr("From"), self.since),
                         (self.tr("To"), self.until)):
            form.addRow(label, w)
        side_lay.addLayout(form)
        apply = QPushButton(self.tr("Apply filter"))
        apply.clicked.connect(self.apply_filter)
        self.source.returnPressed.connect(self.apply_filter)
        self.text.returnPressed.connect(self.apply_filter)
        export = QPushButton(self.tr("Export CSV…"))
        export.clicked.connect(self._choose_export)
        side_lay.addWidget(apply)
        side_lay.addWidget(export)
        side_lay.addWidget(self.path_label)

        self.tabs = QTabWidget()
        records = QWidget()
        rec_lay = QVBoxLayout(records)
        columns = [Column(SOURCE.title, self.source_text, SOURCE.width) if c is SOURCE
                   else Column(VALUE.title, self.value_text, 110, right=True) if c is VALUE else c
                   for c in ARCHIVE_COLUMNS]
        self.model = RecordsModel((*columns, STATION), parent=self)
        self.table = records_view(self.model, row_height=22)
        rec_lay.addWidget(self.table, 1)
        pager = QHBoxLayout()
        self.first = QPushButton(self.tr("\u00ab First"))
        self.prev = QPushButton(self.tr("\u2039 Previous"))
        self.next = QPushButton(self.tr("Next \u203a"))
        self.page_label = QLabel()
        self.page_label.setWordWrap(True)
        for b, step in ((self.first, None), (self.prev, -PAGE), (self.next, PAGE)):
            b.clicked.connect(lambda _=False, s=step: self.page(s))
            pager.addWidget(b)
        pager.addStretch(1)
        pager.addWidget(self.page_label)
        rec_lay.addLayout(pager)
        self.tabs.addTab(records, self.tr("Records"))

        plots = QSplitter(Qt.Orientation.Horizontal)
        self.series_list = QListWidget()
        self.series_list.itemChanged.connect(self._series_toggled)
        self.plot = pg.PlotWidget(axisItems={"bottom": pg.DateAxisItem()})
        self.plot.setBackground("w")
        self.plot.showGrid(x=True, y=True, alpha=0.25)
        self.plot.addLegend(offset=(10, 10))
        self.plot.setLabel("left", "value (physical for a tag, else as stored)")
        self.plot.setTitle("NSTORE and element series — drag to pan, wheel to zoom")
        plots.addWidget(self.series_list)
        plots.addWidget(self.plot)
        plots.setSizes([260, 1000])
        self.tabs.addTab(plots, self.tr("Series"))

        split = QSplitter(Qt.Orientation.Horizontal)
        split.addWidget(side)
        split.addWidget(self.tabs)
        split.setSizes([280, 1000])
        self.setCentralWidget(split)

    # --- archive and day -----------------------------------------------------------------------

    def open_archive(self, path: Path | str | ArchiveSource) -> bool:
        try:
            archive = Archive(path)
            days = archive.days()
            stations = archive.stations()
        except (sqlite3.Error, OSError, ValueError, ArchiveError) as e:
            QMessageBox.warning(self, self.tr("Journal viewer"), f"Cannot open {path}:\n{e}")
            return False
        if self.archive is not None:
            self.archive.close()
        self.archive, self.archive_path = archive, path
        if not self.pager.closed:
            self.pager.submit(self.pages.close)  # the pages read the archive as it is now, too
        self.tags = archive.tags()
        self.tag_names = {t.name: t for t in self.tags.values()}
        if self.symbols is None:
            self.symbols = station_symbols(path)
        self.path_label.setText(f"<small>{path}</small>")
        self.group.setEnabled("grp" not in archive.unfiltered)
        self.group.setToolTip("" if self.group.isEnabled() else
                              self.tr("the records of this archive carry no group"))
        self.stations.blockSignals(True)
        self.stations.clear()
        for name in stations:
            item = QListWidgetItem(name)
            item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
            item.setCheckState(Qt.CheckState.Checked)
            self.stations.addItem(item)
        self.stations.blockSignals(False)
        self.stations_label.setVisible(bool(stations))
        self.table.setColumnHidden(len(ARCHIVE_COLUMNS), not stations)
        self.stations.setVisible(bool(stations))
        self.days.blockSignals(True)
        self.days.clear()
        for day in days:
            item = QListWidgetItem(f"{formats.date(day)}  ({day:%a})")
            item.setData(Qt.ItemDataRole.UserRole, day)
            self.days.addItem(item)
        self.days.blockSignals(False)
        if days:
            self.days.setCurrentRow(0)
        return True

    @property
    def day(self) -> dt.date | None:
        item = self.days.currentItem()
        return item.data(Qt.ItemDataRole.UserRole) if item else None

    def reload(self) -> None:
        if self.archive_path is not None:
            day = self.day
            self.open_archive(self.archive_path)
            for i in range(self.days.count()):
                if self.days.item(i).data(Qt.ItemDataRole.UserRole) == day:
                    self.days.setCurrentRow(i)

    def _day_changed(self, _row: int) -> None:
        self.apply_filter()
        self._load_series_keys()

    # --- records -------------------------------------------------------------------------------

    def chosen_stations(self) -> frozenset[str] | None:
        """The ticked stations of a plant archive (None: all of them, or a station's archive)."""
        items = [self.stations.item(i) for i in range(self.stations.count())]
        ticked = frozenset(i.text() for i in items if i.checkState() == Qt.CheckState.Checked)
        return None if len(ticked) == len(items) else ticked

    def current_filter(self) -> Filter:
        kind = self.kind.currentText()
        day = self.day or dt.date.today()
        # both bounds are whole seconds as shown, in the zone the archive was written in:
        # To 10:00:05 takes 10:00:05.999, never 10:00:06
        tz = self.archive.tz if self.archive is not None else None
        since, until = (dt.datetime.combine(day, e.time().toPython().replace(microsecond=0), tz).timestamp()
                        for e in (self.since, self.until))
        until += 1
        return Filter(
            kinds=None if kind == "all" else {kind},
            grp=None if self.group.value() < 0 else self.group.value(),
            min_type=None if self.type.currentIndex() == 0 else self.type.currentIndex() - 1,
            source=self.source.text().strip() or None,
            text=self.text.text().strip() or None,
            since=since,
            until=until,
            stations=self.chosen_stations(),
        )

    def apply_filter(self) -> None:
        """Read the records again under the filter, and the plotted series within its From/To."""
        self.offset = 0
        self._load_page()
        for key in [*self.curves, *self.loading]:
            self.show_series(key)

    def window(self) -> tuple[float, float]:
        """From/To of the filter, as the series are cut to them."""
        flt = self.current_filter()
        assert flt.since is not None and flt.until is not None
        return flt.since, flt.until

    # what the Records table shows of a record: a tag's name and physical value with its unit
    def record_tag(self, r: Row) -> Tag | None:
        if r.kind == "data":
            return self.tags.get(r.source or "")
        if r.kind == "alarm":
            return self.tag_names.get((r.source or "").partition(".")[0])
        return None

    def source_text(self, r: Row) -> str:
        source = r.source or ""
        if r.kind != "data":
            return source
        tag = self.tags.get(source)
        name = tag.name if tag is not None else self.symbol_of(source)
        return f"{name} ({source})" if name else source

    def value_text(self, r: Row) -> str:
        tag = self.record_tag(r)
        if tag is None or r.value is None:
            return format_value(r.value)
        return tag.format(tag.word_value(int(r.value)) if r.kind == "data" else r.value)

    def symbol_of(self, source: str) -> str:
        try:
            return (self.symbols or {}).get(parse_octal(source), "")
        except ValueError:
            return ""

    def page(self, step: int | None) -> None:
        if step is None:
            self.offset = 0
        else:
            self.offset = min(max(0, self.offset + step), max(0, self.total - 1) // PAGE * PAGE)
        self._load_page()

    def _load_page(self) -> None:
        """Ask for the page at `offset` as the filter is now; it is shown when it arrives."""
        day = self.day
        if self.archive is None or self.archive_path is None or day is None:
            self.paging = None  # an answer still on its way is not shown
            self._show_page(Page(0, 0, []), "no records")
            return
        if self.pager.closed:
            return  # the window is closing
        job = partial(self.pages.page, self.archive_path, day, self.current_filter(), self.offset)
        self.paging = self.pager.submit(job, PAGES)
        self.page_label.setText(self.tr("reading…"))

    def _page_read(self, token: int, page: Page) -> None:
        if token == self.paging:
            self.paging = None
            first, last = page.offset + 1 if page.rows else 0, page.offset + len(page.rows)
            self._show_page(page, f"records {first}–{last} of {page.total}")

    def _page_failed(self, token: int, why: str) -> None:
        if token == self.paging:
            self.paging = None
            self._show_page(Page(0, 0, []), self.tr("archive unreadable: {0}").format(why))

    def _show_page(self, page: Page, say: str) -> None:
        self.total = page.total
        self.model.set_rows(page.rows)
        self.page_label.setText(say)
        last = page.offset + len(page.rows)
        self.prev.setEnabled(page.offset > 0)
        self.first.setEnabled(page.offset > 0)
        self.next.setEnabled(last < page.total)

    def export_csv(self, path: Path) -> int:
        day = self.day
        if self.archive is None or day is None:
            return 0
        return self.archive.export_csv(path, day, self.current_filter())

    def _choose_export(self) -> None:
        day = self.day
        if day is None:
            return
        name, _ = QFileDialog.getSaveFileName(self, self.tr("Export selection"),
                                              f"journal_{day:%d_%m_%Y}.csv",
                                              "CSV files (*.csv)")
        if name:
            try:
                n = self.export_csv(Path(name))
            except READ_ERRORS as e:
                logger.warning("export to %s: %s", name, e)
                self.statusBar().showMessage(f"nothing exported to {name}: {e}", 15000)
                return
            self.statusBar().showMessage(f"{n} records exported to {name}", 8000)

    def _choose_archive(self) -> None:
        name, _ = QFileDialog.getOpenFileName(self, self.tr("Open archive"), "",
                                              "Archives (*.sqlite *.db);;All files (*)")
        if name:
            self.open_archive(Path(name))

    # --- series --------------------------------------------------------------------------------

    def _load_series_keys(self) -> None:
        for curve in self.curves.values():
            self.plot.removeItem(curve)
        self.curves.clear()
        self.loading.clear()
        self.series_list.blockSignals(True)
        self.series_list.clear()
        day = self.day
        if self.archive is not None and day is not None:
            try:
                keys = self.archive.series_keys(day)
            except READ_ERRORS as e:
                logger.warning("series of %s: %s", day, e)
                self.statusBar().showMessage(f"series of {formats.date(day)} unreadable: {e}", 15000)
                keys = []
            for key in keys:
                if key.kind != "data":
                    continue
                item = QListWidgetItem(f"{key.station}: {self.label(key)}" if key.station
                                       else self.label(key))
                item.setData(Qt.ItemDataRole.UserRole, key)
                item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
                item.setCheckState(Qt.CheckState.Unchecked)
                self.series_list.addItem(item)
        self.series_list.blockSignals(False)

    def _series_toggled(self, item: QListWidgetItem) -> None:
        key = item.data(Qt.ItemDataRole.UserRole)
        self.show_series(key, item.checkState() == Qt.CheckState.Checked)

    def show_series(self, key: SeriesKey, shown: bool = True) -> None:
        """Plot (or remove) one series of the current day, downsampled to SERIES_POINTS. The read
        runs in the loader's thread; the curve appears when it is done (see `loading`)."""
        self.loading.pop(key, None)
        curve = self.curves.pop(key, None)
        if curve is not None:
            self.plot.removeItem(curve)
        day = self.day
        if not shown or self.archive_path is None or day is None:
            return
        self.loading[key] = self.loader.request(self.archive_path, day, key, topic=key, window=self.window())
        self.statusBar().showMessage(f"reading {self.label(key)}…")

    def _series_loaded(self, token: int, series: Series) -> None:
        key, ts, values = series
        if self.loading.get(key) != token:
            return  # unticked, asked for again, or another day chosen since
        del self.loading[key]
        color = QColor(PALETTE[len(self.curves) % len(PALETTE)])
        xs, ys = np.asarray(ts, dtype=np.float64), np.asarray(values, dtype=np.float64)
        ys = physical(self.tag_of(key), ys)
        name = f"{key.station}: {self.label(key)}" if key.station else self.label(key)
        self.curves[key] = self.plot.plot(xs, ys, pen=pg.mkPen(color, width=1.5), name=name,
                                          connect="finite")
        self.plot.enableAutoRange()
        if not self.loading:
            self.statusBar().showMessage(f"{self.label(key)}: {len(ts)} points", 5000)

    def _series_failed(self, token: int, why: str) -> None:
        key = next((k for k, t in self.loading.items() if t == token), None)
        if key is not None:
            del self.loading[key]
            self.statusBar().showMessage(f"{self.label(key)} could not be read: {why}", 10000)

    def tag_of(self, key: SeriesKey) -> Tag | None:
        return self.tags.get(key.source or "") if key.kind == "data" else None

    def label(self, key: SeriesKey) -> str:
        symbol = self.symbol_of(key.source or "") if key.kind == "data" else ""
        return series_label(key, self.tag_of(key), symbol)

    def check_series(self, row: int) -> None:
        """Tick a series in the list (what a click does), for scripts and tests."""
        self.series_list.item(row).setCheckState(Qt.CheckState.Checked)

    def closeEvent(self, event) -> None:
        self.loader.close()
        self.pager.close()
        if self.archive is not None:
            self.archive.close()
            self.archive = None
        super().closeEvent(event)


def archive_of(target: str | None) -> Path | str:
    """The archive named on the command line: a file, a station folder, the demo station's, or a
    plant archive's URL."""

    if is_url(target):
        return target
    if target is None:
        return load_station(DEMO_STATION).Archive
    p = Path(target)
    if p.is_dir() or p.suffix == ".toml":
        return load_station(station_file(p)).Archive
    return p


def run_viewer(target: str | None) -> int:
    try:
        path = archive_of(target)
    except ConfigError as e:
        print("\n".join(e.problems), file=sys.stderr)
        return 2
    if isinstance(path, Path) and not path.is_file():
        print(f"{path}: no archive here (run the station first, or name an archive file)", file=sys.stderr)
        return 2
    app = application()
    i18n.install(app)  # the viewer has no station file: the system locale decides
    window = ViewerWindow(path)
    window.show()
    return app.exec()
