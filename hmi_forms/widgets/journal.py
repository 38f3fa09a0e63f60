"""The MessageJournal widget: a table over the registrar archive with filters and a day picker.

The archive is read through `registrar.query.Archive` (read-only, never blocking the writer), in
the widget's worker thread (hmi_forms/widgets/worker.py): a page may hold 100,000 rows, and the
GUI thread never waits for SQLite. Each read is a request for the page as chosen now; the newest
wins, so a tick, a new filter and another day never show an older choice's rows. Today's view is
re-read when the model says so (every RefreshTicks ticks); a past day is read once per change of
filter. Rows are coloured by message type: warnings amber, alarms red, critical solid red, so an
alarm stands out in a long list.
"""

from __future__ import annotations

import datetime as dt
import logging
import sqlite3
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from PySide6.QtCore import QT_TRANSLATE_NOOP, QCoreApplication, QDate, Qt
from PySide6.QtGui import QColor
from PySide6.QtWidgets import (
    QComboBox,
    QDateEdit,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from hmi_forms.elements import formats
from hmi_forms.elements.journal import KINDS, MessageJournal
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import Images, SelfPainted
from hmi_forms.widgets.records import JOURNAL_COLUMNS, Palette, RecordsModel, records_view
from hmi_forms.widgets.worker import Worker
from registrar.query import Archive, Filter, Row

logger = logging.getLogger(__name__)

MIN_TYPES = ((QT_TRANSLATE_NOOP("JournalWidget", "all types"), None),
             (QT_TRANSLATE_NOOP("JournalWidget", "warnings and worse"), 1),
             (QT_TRANSLATE_NOOP("JournalWidget", "alarms and worse"), 2),
             (QT_TRANSLATE_NOOP("JournalWidget", "critical"), 3))
PALETTE = Palette(back={1: QColor("#fff4d6"), 2: QColor("#fde0dc"), 3: theme.ALARM},
                  fore={2: QColor("#8e1b1b"), 3: QColor("#ffffff")})
PAGE = "page"  # the worker's one topic: a newer page request supersedes the older ones


@dataclass(frozen=True)
class Page:
    day: dt.date
    rows: list[Row]
    total: int | None  # None: not counted (a tick of today counts only when the page is short)


class JournalReader:
    """The archive as the worker thread reads it: opened once it exists (the registrar creates
    it with the first batch), closed with the worker."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.archive: Archive | None = None

    def page(self, day: dt.date, flt: Filter, limit: int, count: bool) -> Page | None:
        """The newest `limit` records of `day`; None while there is no archive yet."""
        if self.archive is None:
            if not self.path.is_file():
                return None
            self.archive = Archive(self.path)
        rows = self.archive.records(day, flt, limit=limit)
        total = len(rows) if len(rows) < limit else self.archive.count(day, flt) if count else None
        return Page(day, rows, total)

    def close(self) -> None:
        if self.archive is not None:
            self.archive.close()
            self.archive = None


class JournalWidget(SelfPainted):
    model: MessageJournal

    def __init__(self, model: MessageJournal, images: Images, archive_path: Path | None,
                 parent: QWidget | None = None) -> None:
        super().__init__(model, images, parent)
        self.archive_path = archive_path
        self.reader = JournalReader(archive_path) if archive_path is not None else None
        self.worker = Worker("journal", (sqlite3.Error, OSError), self,
                             on_close=self.reader.close if self.reader is not None else None)
        self.worker.answered.connect(self._shown)
        self.worker.failed.connect(self._failed)
        self._count = True  # a count is owed (day or filter changed) until a counted page arrives
        layout = QVBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.setSpacing(4)
        bar = QHBoxLayout()
        self.date = QDateEdit(QDate.currentDate())
        self.date.setCalendarPopup(True)
        self.date.setDisplayFormat(formats.qt_date())
        self.date.dateChanged.connect(self._day_chosen)
        today = QPushButton(QCoreApplication.translate("JournalWidget", "Today"))
        today.clicked.connect(lambda: self.date.setDate(QDate.currentDate()))
        self.kind = QComboBox()
        self.kind.addItem(QCoreApplication.translate("JournalWidget", "all kinds"), KINDS)
        for k in KINDS:
            self.kind.addItem(QCoreApplication.translate("records", k), (k,))
        self.kind.addItem(QCoreApplication.translate("JournalWidget", "as configured"), model.Kinds)
        self.kind.setCurrentIndex(self.kind.count() - 1)
        self.kind.currentIndexChanged.connect(self._filter_changed)
        self.min_type = QComboBox()
        for text, value in MIN_TYPES:
            self.min_type.addItem(QCoreApplication.translate("JournalWidget", text), value)
        self.min_type.setCurrentIndex([v for _, v in MIN_TYPES].index(model.MinType))
        self.min_type.currentIndexChanged.connect(self._filter_changed)
        self.group = QSpinBox()
        self.group.setRange(-1, 65535)
        self.group.setSpecialValueText(QCoreApplication.translate("JournalWidget", "all groups"))
        self.group.setPrefix(QCoreApplication.translate("JournalWidget", "group "))
        self.group.setValue(-1 if model.Group is None else model.Group)
        self.group.valueChanged.connect(self._filter_changed)
        self.status = QLabel("")
        self.status.setStyleSheet(f"color: {theme.TEXT_DIM.name()};")
        for w in (self.date, today, self.kind, self.min_type, self.group):
            bar.addWidget(w)
        bar.addStretch(1)
        layout.addLayout(bar)
        self.table = RecordsModel(JOURNAL_COLUMNS, PALETTE)
        self.view = records_view(self.table, row_height=20)
        layout.addWidget(self.view, 1)
        layout.addWidget(self.status, 0, Qt.AlignmentFlag.AlignRight)  # under the table: the bar for filters
        self.stale_mark.raise_()
        self.reload()

    def _day_chosen(self, date: QDate) -> None:
        day = dt.date(date.year(), date.month(), date.day())
        self.model.day = None if day == dt.date.today() else day
        self.reload()

    def _filter_changed(self) -> None:
        self.model.kinds = tuple(self.kind.currentData())
        self.model.min_type = self.min_type.currentData()
        self.model.group = None if self.group.value() < 0 else self.group.value()
        self.reload()

    def sync(self) -> None:
        super().sync()
        self.reload(count=False)

    def reload(self, count: bool = True) -> None:
        """Ask for the chosen day's page; counting a whole day is left to changes of day or filter."""
        if self.reader is None:
            self.status.setText(QCoreApplication.translate("JournalWidget", "no archive configured"))
            return
        if self.worker.closed:
            return  # the window is closing
        m = self.model
        day = m.day or dt.date.today()
        if m.day is None and self.date.date() != QDate(day.year, day.month, day.day):
            self.date.blockSignals(True)  # today moved on past midnight: follow it
            self.date.setDate(QDate(day.year, day.month, day.day))
            self.date.blockSignals(False)
        self._count = self._count or count
        flt = Filter(kinds=frozenset(m.kinds), grp=m.group, min_type=m.min_type)
        self.worker.submit(partial(self.reader.page, day, flt, m.Rows, self._count), PAGE)

    def _shown(self, _token: int, page: Page | None) -> None:
        if page is None:
            self.status.setText(QCoreApplication.translate("JournalWidget", "no archive yet"))
            self.table.set_rows([])
            return
        self.table.set_rows(page.rows)
        if page.total is not None:
            self._count = False
            n, total = len(page.rows), page.total  # of the day the picker beside it shows
            shown = QCoreApplication.translate("JournalWidget", "{0} of {1} records").format(n, total)
            self.status.setText(shown if total > n else
                                QCoreApplication.translate("JournalWidget", "{0} records").format(total))

    def _failed(self, _token: int, why: str) -> None:
        self.status.setText(QCoreApplication.translate("JournalWidget", "archive unreadable: {0}").format(
            why))

    def close_archive(self) -> None:
        """Stop reading (the window closes): the worker and the archive close."""
        self.worker.close()
