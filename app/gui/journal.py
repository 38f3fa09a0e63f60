"""The journal dock: today's records from the archive, newest first, refreshed while the station runs.

It reads the archive file read-only like any other reader, so what the operator sees is what has
really been committed to disk, not what is still in a queue. The reads run in the dock's worker
thread (hmi_forms/widgets/worker.py), with the MessageJournal element's reader: every 1.5 s a
page of 500 rows and the day's count, which on a busy day or a slow disk takes longer than a
frame, and a window waiting for them stops repainting. The newest request wins, so a slow read
never piles refreshes up behind it; an unreadable archive is said in the dock's summary.

The archive is the dock's reader: the local station's file (`JournalReader`), or at a remote console
the station's journal over OPC UA (app/gui/console/source.py `RemoteJournal`, the same `page`).
"""

from __future__ import annotations

import datetime as dt
import logging
import sqlite3
from functools import partial
from pathlib import Path
from typing import Protocol

from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QCheckBox, QDockWidget, QHBoxLayout, QLabel, QVBoxLayout, QWidget

from hmi_forms.elements.journal import EVENT_KINDS
from hmi_forms.widgets.journal import JournalReader, Page
from hmi_forms.widgets.records import RecordsModel, records_view
from hmi_forms.widgets.worker import Worker
from registrar.query import Filter

logger = logging.getLogger(__name__)

JOURNAL_ROWS = 500
REFRESH_MS = 1500
PAGE = "page"  # the worker's one topic: a newer refresh supersedes an older one still waiting


class Reader(Protocol):
    def page(self, day: dt.date, flt: Filter, limit: int, count: bool) -> Page | None: ...

    def close(self) -> None: ...


class JournalDock(QDockWidget):
    def __init__(self, archive: Path | Reader, parent: QWidget | None = None) -> None:
        """`archive`: the station's archive file, or a reader of the station's journal."""
        super().__init__(parent)
        self.setWindowTitle(self.tr("Journal — today"))
        self.setObjectName("journalDock")
        self.reader = JournalReader(archive) if isinstance(archive, Path) else archive
        self.worker = Worker("journal dock", (sqlite3.Error, OSError), self, on_close=self.reader.close)
        self.worker.answered.connect(self._shown)
        self.worker.failed.connect(self._failed)
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
        """Ask for today's newest page and its count; the answer is shown when it arrives."""
        if self.worker.closed:
            return  # the window is closing
        flt = Filter(kinds=frozenset(EVENT_KINDS)) if self.messages_only.isChecked() else Filter()
        self.worker.submit(partial(self.reader.page, dt.date.today(), flt, JOURNAL_ROWS, True), PAGE)

    def _shown(self, _token: int, page: Page | None) -> None:
        if page is None:
            self.summary.setText(self.tr("no archive yet"))
            return
        rows, total = page.rows, page.total if page.total is not None else len(page.rows)
        newest = rows[0].id if rows else 0
        if self._last != (newest, total):
            self._last = (newest, total)
            self.model.set_rows(rows)
        shown = self.tr(", newest {0} shown").format(len(rows)) if total > len(rows) else ""
        self.summary.setText(self.tr("{0} records today").format(total) + shown)

    def _failed(self, _token: int, why: str) -> None:
        self.summary.setText(self.tr("archive unreadable: {0}").format(why))

    def _filter_changed(self) -> None:
        self._last = None
        self.refresh()

    def close_archive(self) -> None:
        """Stop reading (the window closes): the timer, the worker and the archive."""
        self._timer.stop()
        self.worker.close()
