"""The alarm banner: the highest-priority unacknowledged alarm of the station's alarm system.

An alarm stays on the banner until an operator acknowledges it, even after its condition has
gone, because the operator must know it happened. The banner takes its alarms from the alarm
summary (app/gui/alarm_summary.py), so NMSG alarms (types 2 and 3 of the catalog), limit,
discrete and quality alarms are one list in one order: priority, then newest first.
Acknowledging is a command of the station's command layer, sent by the window as the user on
duty and journaled by the alarm system with the user's name, one record per alarm; the banner
only shows and asks (the window greys its buttons for a user who may not acknowledge).
"""

from __future__ import annotations

import logging

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QMouseEvent
from PySide6.QtWidgets import (
    QDialog,
    QDialogButtonBox,
    QFrame,
    QHBoxLayout,
    QLabel,
    QPlainTextEdit,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from app.gui import words
from app.gui.elided import ElidedLabel
from app.scada.alarms import AlarmRow
from hmi_forms.elements import formats

logger = logging.getLogger(__name__)


class AlarmBanner(QFrame):
    """A red strip with the first unacknowledged alarm, the count, and Acknowledge / Acknowledge all."""

    acknowledged = Signal(object)  # AlarmRow
    acknowledged_all = Signal()
    chosen = Signal(object)  # AlarmRow: double-clicked, to be shown on its form (app/gui/navigate.py)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("alarmBanner")
        self.alarms: list[AlarmRow] = []  # unacknowledged, highest priority first
        self._blink = False
        lay = QHBoxLayout(self)
        lay.setContentsMargins(12, 6, 8, 6)
        self.icon = QLabel("\u26a0")
        self.icon.setObjectName("alarmIcon")
        self.text = ElidedLabel()
        self.text.setObjectName("alarmText")
        self.count = QLabel()
        self.count.setObjectName("alarmCount")
        self.ack = QPushButton(self.tr("Acknowledge"))
        self.ack.setObjectName("alarmAck")
        self.ack_all = QPushButton(self.tr("Acknowledge all"))
        self.ack_all.setObjectName("alarmAck")
        lay.addWidget(self.icon)
        lay.addWidget(self.text, 1)
        lay.addWidget(self.count)
        lay.addWidget(self.ack)
        lay.addWidget(self.ack_all)
        self.ack.clicked.connect(self.acknowledge_newest)
        self.ack_all.clicked.connect(self.acknowledge_all)
        self._timer = QTimer(self)
        self._timer.setInterval(500)
        self._timer.timeout.connect(self._toggle_blink)
        self._show()

    def show_alarms(self, unacknowledged: list[AlarmRow]) -> None:
        self.alarms = list(unacknowledged)
        self._show()

    def acknowledge_newest(self) -> None:
        """Acknowledge the alarm shown (the highest-priority one); it leaves the banner at once."""
        if self.alarms:
            self.acknowledged.emit(self.alarms.pop(0))
            self._show()

    def acknowledge_all(self) -> None:
        if self.alarms:
            self.alarms.clear()
            self.acknowledged_all.emit()
        self._show()

    def _show(self) -> None:
        if not self.alarms:
            self.setVisible(False)
            self._timer.stop()
            return
        first = self.alarms[0]
        when = formats.clock(first.since or first.changed)
        kind = words.priority(first.priority).upper()
        self.text.setText(f"{when}  P{first.priority} {kind}  {first.text}  "
                          f"[{first.id}, {words.state(first.state)}]")
        many = len(self.alarms) > 1
        # a badge: the banner shares the header's one line, and its alarm needs the width
        self.count.setText(str(len(self.alarms)) if many else "")
        self.count.setToolTip(self.tr("{0} unacknowledged").format(len(self.alarms)) if many else "")
        self.ack_all.setVisible(len(self.alarms) > 1)
        self.setVisible(True)
        if not self._timer.isActive():
            self._timer.start()

    def mouseDoubleClickEvent(self, event: QMouseEvent) -> None:
        if self.alarms:
            self.chosen.emit(self.alarms[0])

    def _toggle_blink(self) -> None:
        self._blink = not self._blink
        self.setProperty("blink", self._blink)
        self.style().unpolish(self)
        self.style().polish(self)

    def sizeHint(self):
        hint = super().sizeHint()
        hint.setHeight(max(hint.height(), 40))
        return hint


class HealthStrip(QFrame):
    """A yellow strip listing what is wrong with the station itself: program stopped, node down,
    archive failing. Shown only while something is wrong, on one line elided to the window's
    width; Details shows every problem in full."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("healthStrip")
        self.problems: list[str] = []
        lay = QHBoxLayout(self)
        lay.setContentsMargins(12, 2, 6, 2)
        self.label = ElidedLabel()
        self.label.setObjectName("healthText")
        self.details = QPushButton(self.tr("Details…"))
        self.details.setObjectName("healthDetails")
        self.details.clicked.connect(self.show_details)
        lay.addWidget(self.label, 1)
        lay.addWidget(self.details)
        self.setVisible(False)

    def show_problems(self, problems: list[str]) -> None:
        self.problems = list(problems)
        self.label.setText("   \u2022   ".join(problems))
        self.setVisible(bool(problems))

    def show_details(self) -> QDialog:
        dialog = QDialog(self.window())
        dialog.setWindowTitle(self.tr("Station problems"))
        dialog.resize(760, 360)
        lay = QVBoxLayout(dialog)
        text = QPlainTextEdit("\n".join(self.problems))
        text.setReadOnly(True)
        lay.addWidget(text)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close)
        buttons.rejected.connect(dialog.reject)
        lay.addWidget(buttons)
        dialog.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
        dialog.show()
        return dialog
