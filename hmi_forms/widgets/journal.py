"""The MessageJournal widget: a table over the registrar archive with filters and a day picker.

The archive is read through `registrar.query.Archive` (read-only, never blocking the writer).
Today's view is re-read when the model says so (every RefreshTicks ticks); a past day is read
once per change of filter. Rows are coloured by message type: warnings amber, alarms red,
critical solid red, so an alarm stands out in a long list.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path
from typing import Any

from PySide6.QtCore import QAbstractTableModel, QDate, QModelIndex, QPersistentModelIndex, Qt
from PySide6.QtGui import QColor
from PySide6.QtWidgets import (
    QAbstractItemView,
    QComboBox,
    QDateEdit,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QPushButton,
    QSpinBox,
    QTableView,
    QVBoxLayout,
    QWidget,
)

from hmi_forms.elements.journal import KINDS, MessageJournal
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import Images, SelfPainted
from registrar.query import Archive, Filter, Row

COLUMNS = ("Time", "Kind", "Group", "Type", "Source", "Text", "Value")
TYPE_NAMES = {0: "info", 1: "warning", 2: "alarm", 3: "critical"}
TYPE_BACK = {1: QColor("#fff4d6"), 2: QColor("#fde0dc"), 3: theme.ALARM}
TYPE_FORE = {2: QColor("#8e1b1b"), 3: QColor("#ffffff")}
MIN_TYPES = (("all types", None), ("warnings and worse", 1), ("alarms and worse", 2), ("critical", 3))
ModelIndex = QModelIndex | QPersistentModelIndex


class JournalTable(QAbstractTableModel):
    def __init__(self) -> None:
        super().__init__()
        self.rows: list[Row] = []

    def set_rows(self, rows: list[Row]) -> None:
        if [r.id for r in rows] == [r.id for r in self.rows]:
            return
        self.beginResetModel()
        self.rows = rows
        self.endResetModel()

    def rowCount(self, parent: ModelIndex = QModelIndex()) -> int:  # noqa: B008 - Qt API
        return 0 if parent.isValid() else len(self.rows)

    def columnCount(self, parent: ModelIndex = QModelIndex()) -> int:  # noqa: B008 - Qt API
        return 0 if parent.isValid() else len(COLUMNS)

    def headerData(self, section: int, orientation: Qt.Orientation,
                   role: int = Qt.ItemDataRole.DisplayRole) -> Any:
        if role == Qt.ItemDataRole.DisplayRole and orientation == Qt.Orientation.Horizontal:
            return COLUMNS[section]
        return None

    def data(self, index: ModelIndex, role: int = Qt.ItemDataRole.DisplayRole) -> Any:
        row = self.rows[index.row()]
        if role == Qt.ItemDataRole.DisplayRole:
            return self.cell(row, index.column())
        if role == Qt.ItemDataRole.BackgroundRole:
            return TYPE_BACK.get(row.type) if row.kind == "message" else None
        if role == Qt.ItemDataRole.ForegroundRole:
            return TYPE_FORE.get(row.type) if row.kind == "message" else None
        return None

    @staticmethod
    def cell(row: Row, column: int) -> str:
        if column == 0:
            return row.time.strftime("%H.%M.%S")
        if column == 1:
            return row.kind
        if column == 2:
            return "" if row.grp is None else str(row.grp)
        if column == 3:
            return "" if row.type is None else TYPE_NAMES.get(row.type, str(row.type))
        if column == 4:
            return row.source or ""
        if column == 5:
            return row.text or ("" if row.number is None else f"message {row.number}")
        return "" if row.value is None else f"{row.value:g}"


class JournalWidget(SelfPainted):
    model: MessageJournal

    def __init__(self, model: MessageJournal, images: Images, archive_path: Path | None,
                 parent: QWidget | None = None) -> None:
        super().__init__(model, images, parent)
        self.archive_path = archive_path
        self.archive: Archive | None = None
        layout = QVBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.setSpacing(4)
        bar = QHBoxLayout()
        self.date = QDateEdit(QDate.currentDate())
        self.date.setCalendarPopup(True)
        self.date.setDisplayFormat("dd.MM.yyyy")
        self.date.dateChanged.connect(self._day_chosen)
        today = QPushButton("Today")
        today.clicked.connect(lambda: self.date.setDate(QDate.currentDate()))
        self.kind = QComboBox()
        self.kind.addItem("all kinds", KINDS)
        for k in KINDS:
            self.kind.addItem(k, (k,))
        self.kind.addItem("as configured", model.Kinds)
        self.kind.setCurrentIndex(self.kind.count() - 1)
        self.kind.currentIndexChanged.connect(self._filter_changed)
        self.min_type = QComboBox()
        for text, value in MIN_TYPES:
            self.min_type.addItem(text, value)
        self.min_type.setCurrentIndex([v for _, v in MIN_TYPES].index(model.MinType))
        self.min_type.currentIndexChanged.connect(self._filter_changed)
        self.group = QSpinBox()
        self.group.setRange(-1, 65535)
        self.group.setSpecialValueText("all groups")
        self.group.setPrefix("group ")
        self.group.setValue(-1 if model.Group is None else model.Group)
        self.group.valueChanged.connect(self._filter_changed)
        self.status = QLabel("")
        self.status.setStyleSheet(f"color: {theme.TEXT_DIM.name()};")
        for w in (self.date, today, self.kind, self.min_type, self.group):
            bar.addWidget(w)
        bar.addStretch(1)
        bar.addWidget(self.status)
        layout.addLayout(bar)
        self.table = JournalTable()
        self.view = QTableView()
        self.view.setModel(self.table)
        self.view.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.view.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.view.verticalHeader().setVisible(False)
        self.view.verticalHeader().setDefaultSectionSize(20)
        self.view.setAlternatingRowColors(True)
        header = self.view.horizontalHeader()
        for col, width in enumerate((70, 70, 50, 64, 110, 0, 60)):
            if width:
                header.resizeSection(col, width)
        header.setSectionResizeMode(5, QHeaderView.ResizeMode.Stretch)
        layout.addWidget(self.view, 1)
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

    def _open(self) -> Archive | None:
        """Open the archive once it exists (the registrar creates it with the first batch)."""
        if self.archive is None and self.archive_path is not None:
            try:
                self.archive = Archive(self.archive_path)
            except (FileNotFoundError, OSError):
                return None
        return self.archive

    def reload(self, count: bool = True) -> None:
        """Query the chosen day; counting a whole day is left to changes of day or filter."""
        archive = self._open()
        if archive is None:
            self.status.setText("no archive yet" if self.archive_path else "no archive configured")
            self.table.set_rows([])
            return
        m = self.model
        day = m.day or dt.date.today()
        if m.day is None and self.date.date() != QDate(day.year, day.month, day.day):
            self.date.blockSignals(True)  # today moved on past midnight: follow it
            self.date.setDate(QDate(day.year, day.month, day.day))
            self.date.blockSignals(False)
        flt = Filter(kinds=frozenset(m.kinds), grp=m.group, min_type=m.min_type)
        try:
            rows = archive.records(day, flt, limit=m.Rows)
            total = len(rows) if len(rows) < m.Rows else archive.count(day, flt) if count else None
        except Exception as e:
            self.status.setText(f"archive unreadable: {e}")
            return
        self.table.set_rows(rows)
        if total is not None:
            self.status.setText(f"{len(rows)} of {total} records, {day:%d.%m.%Y}" if total > len(rows)
                                else f"{total} records, {day:%d.%m.%Y}")

    def close_archive(self) -> None:
        if self.archive is not None:
            self.archive.close()
            self.archive = None
