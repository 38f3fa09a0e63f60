"""The alarm summary: the operator's list of what needs attention, from the station's alarm system.

It lists the active and unacknowledged alarms by priority, then newest first (ISA-18.2), then the
shelved ones; colour says the priority and blinking says "not acknowledged yet". The operator
acknowledges the selected alarms or all of them, shelves one for a duration with a reason,
unshelves, silences the horn: each is a command of the station's command layer, which checks the
role, applies it on the engine thread and journals it as one 'alarm' record per alarm naming the
alarm and the user (or refuses it, journaled throttled); its answer comes back through `Answers`.
A button the user may not use is disabled, its tooltip naming the role. The header counts the
listed alarms per priority.

The summary only reads its `AlarmSource`'s summary (the station's: `StationAlarms.summary`, an
immutable tuple the engine thread rebuilds when a state changes), and redraws only when its
version moved, so a flood of transitions costs the GUI one table reset per refresh, never one per
transition. The table is a model/view pair: only the visible rows are drawn, whatever the length
of the list.

The sound of a new alarm of priority 1-2 until it is acknowledged or silenced is the station's
horn made audible (app/gui/annunciation.py); the station key `alarm_sound = false` turns it off.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path
from typing import Any

from PySide6.QtCore import (
    QT_TRANSLATE_NOOP,
    QAbstractTableModel,
    QCoreApplication,
    QModelIndex,
    QPersistentModelIndex,
    Qt,
    QTimer,
    Signal,
)
from PySide6.QtGui import QBrush, QColor
from PySide6.QtWidgets import (
    QAbstractItemView,
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QLineEdit,
    QMessageBox,
    QPushButton,
    QTableView,
    QVBoxLayout,
    QWidget,
)

from app.authority import Action, Answer, Commands, Who
from app.gui import words
from app.gui.annunciation import Annunciation
from app.gui.bridge import Answers
from app.gui.rights import Rights
from app.scada.alarms import PRIORITIES, AlarmRow, State
from app.scada.horn import AlarmSource
from hmi_forms.elements import formats
from hmi_forms.widgets.records import cell_width, title_width

logger = logging.getLogger(__name__)

REFRESH_MS = 250  # how often the summary looks for a new version
BLINK_MS = 500
BEEP_MS = 1000
# background and text per priority: critical red, high orange, medium yellow, low blue
COLOURS = {1: ("#c62828", "#ffffff"), 2: ("#ef6c00", "#ffffff"), 3: ("#fdd835", "#263445"),
           4: ("#90caf9", "#263445")}
QUIET = ("#eceff1", "#607d8b")  # shelved
WIDTHS = (90, 150, 130, 170, 90)  # px at least, of the columns before the text
COLUMNS = (QT_TRANSLATE_NOOP("AlarmTableModel", "Priority"), QT_TRANSLATE_NOOP("AlarmTableModel", "Time"),
           QT_TRANSLATE_NOOP("AlarmTableModel", "Alarm"), QT_TRANSLATE_NOOP("AlarmTableModel", "State"),
           QT_TRANSLATE_NOOP("AlarmTableModel", "Value at change"),
           QT_TRANSLATE_NOOP("AlarmTableModel", "Text"))
VALUE_TIP = QT_TRANSLATE_NOOP("AlarmTableModel",
                              "The value when the alarm last changed state, not the value now")

Index = QModelIndex | QPersistentModelIndex


def row_colours(row: AlarmRow, blink_on: bool) -> tuple[QColor, QColor]:
    """Background and text of a row: the priority's colour; an unacknowledged alarm blinks
    (alternates with white), a returned-unacknowledged one shows the colour as text only."""
    if row.state is State.SHELVED:
        back, fore = QUIET
    else:
        back, fore = COLOURS.get(row.priority, COLOURS[4])
    if row.state is State.RTNUN:
        return QColor("#ffffff") if blink_on else QColor("#f5f5f5"), QColor(back)
    if row.state is State.UNACK and not blink_on:
        return QColor("#ffffff"), QColor(back)
    return QColor(back), QColor(fore)


def stamp(ts: float) -> str:
    """The console's one date format (its language's), with the time."""
    return formats.date_time(ts) if ts else ""


class AlarmTableModel(QAbstractTableModel):
    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.rows: list[AlarmRow] = []
        self.blink_on = True

    def set_rows(self, rows: list[AlarmRow]) -> None:
        self.beginResetModel()
        self.rows = rows
        self.endResetModel()

    def rowCount(self, parent: Index = QModelIndex()) -> int:  # noqa: B008 - Qt's signature
        return 0 if parent.isValid() else len(self.rows)

    def columnCount(self, parent: Index = QModelIndex()) -> int:  # noqa: B008
        return 0 if parent.isValid() else len(COLUMNS)

    def headerData(self, section: int, orientation: Qt.Orientation, role: int = 0) -> Any:
        if orientation == Qt.Orientation.Horizontal and role == Qt.ItemDataRole.DisplayRole:
            return QCoreApplication.translate("AlarmTableModel", COLUMNS[section])
        if orientation == Qt.Orientation.Horizontal and role == Qt.ItemDataRole.ToolTipRole and section == 4:
            return QCoreApplication.translate("AlarmTableModel", VALUE_TIP)
        return None

    def data(self, index: Index, role: int = 0) -> Any:
        row = self.rows[index.row()]
        if role == Qt.ItemDataRole.DisplayRole:
            col = index.column()
            if col == 0:
                return f"{row.priority} {words.priority(row.priority)}"
            if col == 1:
                return stamp(row.since or row.changed)
            if col == 2:
                return row.label or row.id
            if col == 3:
                return words.state(row.state)
            if col == 4:
                return row.shown
            if row.state is State.SHELVED and row.shelved_until is not None:  # wrapped, read whole
                note = QCoreApplication.translate("AlarmTableModel", "shelved by {0} until {1}: {2}")
                shelved = note.format(row.shelved_by, stamp(row.shelved_until), row.reason)
                return f"{row.text}\n{shelved}"
            return row.text
        if role == Qt.ItemDataRole.ToolTipRole and index.column() == 2:
            return row.id  # the identity the journal and the publishers use
        if role in (Qt.ItemDataRole.BackgroundRole, Qt.ItemDataRole.ForegroundRole):
            back, fore = row_colours(row, self.blink_on)
            return QBrush(back if role == Qt.ItemDataRole.BackgroundRole else fore)
        return None


SHELVE_REASONS = (QT_TRANSLATE_NOOP("ShelveDialog", "Maintenance of the instrument"),
                  QT_TRANSLATE_NOOP("ShelveDialog", "Instrument faulty, repair requested"),
                  QT_TRANSLATE_NOOP("ShelveDialog", "Nuisance: chattering alarm"),
                  QT_TRANSLATE_NOOP("ShelveDialog", "Start-up or shut-down of the unit"),
                  QT_TRANSLATE_NOOP("ShelveDialog", "Known condition, under observation"))


class ShelveDialog(QDialog):
    """Shelving needs a duration and a reason (ISA-18.2: a shelved alarm comes back by itself).
    The reason is typed or taken from the presets; OK with none says so and keeps the dialog open."""

    def __init__(self, alarm: str, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(self.tr("Shelve {0}").format(alarm))
        lay = QFormLayout(self)
        self.minutes = QDoubleSpinBox()
        self.minutes.setRange(1, 7 * 24 * 60)
        self.minutes.setValue(60)
        self.minutes.setSuffix(self.tr(" min"))
        self.presets = QComboBox()
        self.presets.addItem(self.tr("Choose a usual reason…"), "")
        for reason in SHELVE_REASONS:
            text = self.tr(reason)
            self.presets.addItem(text, text)
        self.presets.activated.connect(self._preset)
        self.reason = QLineEdit()
        self.reason.setPlaceholderText(self.tr("why (required)"))
        self.missing = QLabel(self.tr("Give the reason for shelving: it is journaled with your name."))
        self.missing.setStyleSheet("color: #b00020")
        self.missing.setWordWrap(True)
        self.missing.hide()
        self.reason.textChanged.connect(lambda _text: self.missing.hide())
        lay.addRow(self.tr("Duration"), self.minutes)
        lay.addRow(self.tr("Reason"), self.presets)
        lay.addRow("", self.reason)
        lay.addRow(self.missing)
        ok, cancel = QDialogButtonBox.StandardButton.Ok, QDialogButtonBox.StandardButton.Cancel
        buttons = QDialogButtonBox(ok | cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        lay.addRow(buttons)

    def _preset(self, index: int) -> None:
        if text := self.presets.itemData(index):
            self.reason.setText(text)

    def accept(self) -> None:
        if not self.reason.text().strip():
            self.missing.show()
            self.reason.setFocus()
            return
        super().accept()


class AlarmSummary(QWidget):
    """The summary as a widget (the workstation docks it). It reads `alarms`; what the operator
    does goes to `commands` as `who()`, and each answer to `answers` (the window's status bar)."""

    changed = Signal()  # the rows changed: the banner follows

    def __init__(self, alarms: AlarmSource | None, commands: Commands, who: Callable[[], Who], *,
                 answers: Answers | None = None, sound: bool = True,
                 sounds: tuple[Path | None, Path | None] = (None, None),
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("alarmSummary")
        self.alarms = alarms
        self.commands = commands
        self.who = who
        self.answers = answers or Answers()
        self.rows: list[AlarmRow] = []
        self._version = -1
        self.annunciator = Annunciation(alarms.horn if alarms is not None else None, sound, sounds)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        head = QHBoxLayout()
        self.counts: dict[int, QLabel] = {}
        for priority in PRIORITIES:
            label = QLabel()
            label.setObjectName("alarmCountP")
            back, fore = COLOURS[priority]
            label.setStyleSheet(f"background: {back}; color: {fore}; border-radius: 3px; padding: 2px 8px;")
            label.setToolTip(self.tr("listed alarms of priority {0} ({1})").format(
                priority, words.priority(priority)))
            self.counts[priority] = label
            head.addWidget(label)
        self.filter = QLineEdit()
        self.filter.setPlaceholderText(self.tr("Filter: alarm, text or state"))
        self.filter.setClearButtonEnabled(True)
        self.filter.textChanged.connect(self._apply)
        head.addWidget(self.filter, 1)
        self.ack = QPushButton(self.tr("Acknowledge"))
        self.ack_all = QPushButton(self.tr("Acknowledge all"))
        self.shelve = QPushButton(self.tr("Shelve…"))
        self.unshelve = QPushButton(self.tr("Unshelve"))
        self.silence = QPushButton(self.tr("Silence"))
        for b in (self.ack, self.ack_all, self.shelve, self.unshelve, self.silence):
            head.addWidget(b)
        self.rights = Rights(commands, who)
        for button, action in ((self.ack, Action.ACKNOWLEDGE), (self.ack_all, Action.ACKNOWLEDGE),
                               (self.shelve, Action.SHELVE), (self.unshelve, Action.UNSHELVE)):
            self.rights.add(button, action, button.text().rstrip("…"))
        self.rights.add(self.silence, Action.SILENCE, self.silence.text(),
                        self.tr("Stop the sound; the alarms stay unacknowledged"),
                        also=lambda: self.annunciator.sounding)
        lay.addLayout(head)
        self.model = AlarmTableModel(self)
        self.table = QTableView()
        self.table.setModel(self.model)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.ExtendedSelection)
        self.table.verticalHeader().setVisible(False)
        self.table.verticalHeader().setDefaultSectionSize(22)
        header = self.table.horizontalHeader()
        for col, width in enumerate(WIDTHS):
            self.table.setColumnWidth(col, width)
        header.setSectionResizeMode(len(COLUMNS) - 1, QHeaderView.ResizeMode.Stretch)
        header.sectionResized.connect(lambda col, _old, _new: col == len(COLUMNS) - 1 and self._fit_rows())
        self._fit()
        lay.addWidget(self.table, 1)
        self.ack.clicked.connect(self.acknowledge_selected)
        self.ack_all.clicked.connect(self.acknowledge_all)
        self.shelve.clicked.connect(self._shelve_dialog)
        self.unshelve.clicked.connect(self.unshelve_selected)
        self.silence.clicked.connect(self.silence_sound)
        self._timer = QTimer(self)
        self._timer.setInterval(REFRESH_MS)
        self._timer.timeout.connect(self.refresh)
        self._timer.start()
        self._blink = QTimer(self)
        self._blink.setInterval(BLINK_MS)
        self._blink.timeout.connect(self._toggle_blink)
        self._blink.start()
        self._beep = QTimer(self)
        self._beep.setInterval(BEEP_MS)
        self._beep.timeout.connect(self.annunciator.tick)
        self._beep.start()
        self.refresh()

    # --- data ------------------------------------------------------------------------------------

    def refresh(self) -> None:
        """Take the alarm system's newest summary, if it changed."""
        alarms = self.alarms
        if alarms is None or alarms.version == self._version:
            return
        self._version = alarms.version
        self.rows = list(alarms.summary)
        self.annunciator.update()
        self._apply()
        self.changed.emit()

    def _fit(self) -> None:
        """Widen a column whose title or cells need more room (a longer language, a longer value):
        titles, priorities and states are read whole, whichever come; the text takes what is left."""
        header, table = self.table.horizontalHeader(), self.table
        least = {0: max(cell_width(table, f"{p} {words.priority(p)}") for p in PRIORITIES),
                 3: max(cell_width(table, words.state(s)) for s in State)}
        for col in range(len(COLUMNS) - 1):
            title = self.model.headerData(col, Qt.Orientation.Horizontal, Qt.ItemDataRole.DisplayRole)
            need = max(title_width(header, title), table.sizeHintForColumn(col), least.get(col, 0))
            if need > table.columnWidth(col):
                table.setColumnWidth(col, need)
        self._fit_rows()

    def _fit_rows(self) -> None:
        """A shelved alarm's row is as high as its text and shelving note need, wrapped to the
        text column (a reason can be long); the others keep one line."""
        for i, row in enumerate(self.model.rows):
            if row.state is State.SHELVED:
                self.table.resizeRowToContents(i)

    def _apply(self) -> None:
        typed = self.filter.text().strip().casefold().split()
        rows = [r for r in self.rows
                if all(w in f"{r.id} {r.label} {r.text} {r.state.word} {words.state(r.state)} {r.tag or ''}"
                       .casefold() for w in typed)]
        selected = set(self.selected())
        self.model.set_rows(rows)
        self._fit()
        for i, r in enumerate(rows):
            if r.id in selected:
                self.table.selectRow(i)
        listed = [r for r in self.rows if r.state is not State.SHELVED]
        for priority, label in self.counts.items():
            n = sum(r.priority == priority for r in listed)
            label.setText(f"P{priority} {words.priority(priority)}: {n}")
        self.rights.update()  # Silence: only while it sounds

    def unacknowledged(self) -> list[AlarmRow]:
        """Unacknowledged alarms, highest priority first, newest first: the banner's order."""
        return [r for r in self.rows if not r.acked]

    def selected(self) -> list[str]:
        rows = self.model.rows
        return [rows[i.row()].id for i in self.table.selectionModel().selectedRows() if i.row() < len(rows)]

    # --- operator actions: commands of the station's layer -----------------------------------

    def acknowledge(self, alarm_ids: list[str]) -> None:
        for alarm_id in alarm_ids:
            self.answers.follow(self.tr("Acknowledge {0}").format(alarm_id),
                                self.commands.acknowledge(self.who(), alarm_id))

    def acknowledge_selected(self) -> None:
        self.acknowledge(self.selected())

    def acknowledge_all(self) -> None:
        self.answers.follow(self.tr("Acknowledge all"), self.commands.acknowledge_all(self.who()))

    def shelve_alarm(self, alarm_id: str, minutes: float, reason: str) -> None:
        """A missing reason or duration is refused by the layer, and said as every refusal is."""
        self.answers.follow(self.tr("Shelve {0}").format(alarm_id),
                            self.commands.shelve(self.who(), alarm_id, reason, minutes * 60))

    def unshelve_selected(self) -> None:
        for alarm_id in self.selected():
            self.answers.follow(self.tr("Unshelve {0}").format(alarm_id),
                                self.commands.unshelve(self.who(), alarm_id))

    def _shelve_dialog(self) -> None:
        ids = self.selected()
        if not ids:
            QMessageBox.information(self, self.tr("Shelve"), self.tr("Select the alarm to shelve first."))
            return
        dialog = ShelveDialog(ids[0], self)
        if dialog.exec() != QDialog.DialogCode.Accepted:
            return
        for alarm_id in ids:
            self.shelve_alarm(alarm_id, dialog.minutes.value(), dialog.reason.text())

    def silence_sound(self) -> None:
        """The horn stops here once the layer has taken the command (journaled naming the user)."""
        self.answers.follow(self.tr("Silence"), self.commands.silence(self.who()), self._silenced)

    def _silenced(self, answer: Answer) -> None:
        if answer.ok:  # the layer has silenced the source's horn (app/scada/horn.py AlarmSource)
            self.annunciator.silence()
            self.rights.update()

    def _toggle_blink(self) -> None:
        self.model.blink_on = not self.model.blink_on
        if any(r.state in (State.UNACK, State.RTNUN) for r in self.model.rows):
            self.table.viewport().update()

    def stop(self) -> None:
        for timer in (self._timer, self._blink, self._beep):
            timer.stop()
        self.annunciator.stop()
