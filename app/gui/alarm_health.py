"""The alarm-system health of a chosen day (ISA-18.2 measures, registrar/health.py), in a dialog.

The same report as `main.py alarms-report ARCHIVE --day DD_MM_YYYY`, read from the archive file
read-only, so the operator and the engineer see the same figures. A day of a busy alarm system is
many records: the report is made in the dialog's worker thread (hmi_forms/widgets/worker.py), the
newest day asked for wins.
"""

from __future__ import annotations

import datetime as dt
import sqlite3
from functools import partial
from pathlib import Path

from PySide6.QtCore import QCoreApplication, QDate
from PySide6.QtGui import QFont
from PySide6.QtWidgets import QDateEdit, QDialog, QHBoxLayout, QLabel, QPlainTextEdit, QVBoxLayout, QWidget

from hmi_forms.elements import formats
from hmi_forms.widgets.worker import Worker
from registrar.health import alarm_health
from registrar.query import Archive


def health_text(archive_path: Path, day: dt.date) -> str:
    """The report's lines, or why there is none (no archive yet, unreadable)."""
    try:
        archive = Archive(archive_path)
    except (OSError, sqlite3.Error) as e:
        return QCoreApplication.translate("HealthDialog", "no alarm-system health: {0}").format(e)
    try:
        return "\n".join(alarm_health(archive, day).lines())
    except sqlite3.Error as e:
        return QCoreApplication.translate("HealthDialog", "{0}: cannot read the archive: {1}").format(
            archive_path, e)
    finally:
        archive.close()


class HealthDialog(QDialog):
    def __init__(self, archive_path: Path, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(self.tr("Alarm-system health"))
        self.archive_path = archive_path
        self.worker = Worker("alarm health", (), self)
        self.worker.answered.connect(lambda _token, text: self.report.setPlainText(text))
        self.worker.failed.connect(lambda _token, why: self.report.setPlainText(why))
        self.finished.connect(self.worker.close)
        self.resize(720, 520)
        lay = QVBoxLayout(self)
        bar = QHBoxLayout()
        bar.addWidget(QLabel(self.tr("Day:")))
        self.day = QDateEdit(QDate.currentDate())
        self.day.setCalendarPopup(True)
        self.day.setDisplayFormat(formats.qt_date())
        self.day.dateChanged.connect(self.show_day)
        bar.addWidget(self.day)
        bar.addStretch(1)
        lay.addLayout(bar)
        self.report = QPlainTextEdit()
        self.report.setReadOnly(True)
        self.report.setFont(QFont("DejaVu Sans Mono", 9))
        lay.addWidget(self.report, 1)
        self.show_day()

    def show_day(self) -> None:
        if self.worker.closed:
            return
        self.report.setPlainText(self.tr("reading the archive…"))
        self.worker.submit(partial(health_text, self.archive_path, self.day.date().toPython()), "day")
