"""The journal dock: today's records from the archive, newest first, refreshed while the station runs.

It reads the archive file read-only like any other reader, so what the operator sees is what has
really been committed to disk, not what is still in a queue.
"""

from __future__ import annotations

import datetime as dt
import sqlite3
from pathlib import Path

from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QCheckBox, QDockWidget, QHBoxLayout, QLabel, QVBoxLayout, QWidget

from hmi_forms.elements.journal import EVENT_KINDS
from hmi_forms.widgets.records import RecordsModel, records_view
from registrar.query import Archive, Filter

JOURNAL_ROWS = 500
REFRESH_MS = 1500


class JournalDock(QDockWidget):
    def __init__(self, archive_path: Path, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(self.tr("Journal — today"))
        self.setObjectName("journalDock")
        self.archive_path = archive_path
        self._archive: Archive | None = None
        body = QWidget()
        lay = QVBoxLayout(body)
        lay.setContentsMargins(4, 4, 4, 4)
        bar = QHBoxLayout()
        self.messages_only = QCheckBox(self.tr("Events only (messages, operator actions, system)"))
        self.messages_only.setChecked(True)  # data records are for the viewer's plots
        self.messages_only.toggled.connect(self._filter_changed)
        self.summary = QLabel()
        bar.addWidget(self.messages_only)
        bar.addStretch(1)
        bar.addWidget(self.summary)
        lay.addLayout(bar)
        self.model = RecordsModel(parent=self)
        self.table = records_view(self.model, row_height=22)
        lay.addWidget(self.table)
        self.setWidget(body)
        self.setAllowedAreas(Qt.DockWidgetArea.BottomDockWidgetArea | Qt.DockWidgetArea.RightDockWidgetArea)
        self._timer = QTimer(self)
        self._timer.setInterval(REFRESH_MS)
        self._timer.timeout.connect(self.refresh)
        self._timer.start()
        self._last: tuple[int, int] | None = None

    def refresh(self) -> None:
        archive = self._open()
        if archive is None:
            self.summary.setText(self.tr("no archive yet"))
            return
        flt = Filter(kinds=frozenset(EVENT_KINDS)) if self.messages_only.isChecked() else None
        today = dt.date.today()
        try:
            total = archive.count(today, flt)
            rows = archive.records(today, flt, 0, JOURNAL_ROWS)
        except sqlite3.Error as e:
            self.summary.setText(self.tr("archive unreadable: {0}").format(e))
            return
        newest = rows[0].id if rows else 0
        if self._last != (newest, total):
            self._last = (newest, total)
            self.model.set_rows(rows)
        shown = self.tr(", newest {0} shown").format(len(rows)) if total > len(rows) else ""
        self.summary.setText(self.tr("{0} records today").format(total) + shown)

    def _filter_changed(self) -> None:
        self._last = None
        self.refresh()

    def _open(self) -> Archive | None:
        if self._archive is None and self.archive_path.exists():
            try:
                self._archive = Archive(self.archive_path)
            except sqlite3.Error:
                return None
        return self._archive

    def close_archive(self) -> None:
        self._timer.stop()
        if self._archive is not None:
            self._archive.close()
            self._archive = None
