"""A tag's faceplate: everything about one tag in one small window, opened from the picture.

A form element shows a value; the operator who wants to know more (what is this, is it good, how
did it move, what are its alarms) or to act on it should not have to hunt through the alarm list,
the viewer and the Program view. Double-clicking an element bound to a tag, clicking one that
does not write by itself (nor pauses, as a trend does), or pressing Enter on one (Tab moves
between them) opens the tag's
faceplate: name and description, the live value with its quality and unit, the forced state, the
alarm limits with each alarm's state, a trend of the last hour (the archive's, then live), the
setpoint entry, acknowledge and shelve of its alarms, and for whoever may force, force and
unforce. Each action is a command of the station's command layer as the user on duty, greyed
with the role it needs when the layer would refuse it, its refusal said in the faceplate; forces
are confirmed as in the Program view, the unforce question saying that the forced value stays.

The same faceplate opens from the same elements at the local workstation and at a remote console
(`main.py console`); what differs is the seat's `Console`: the in-process runtime's readings, the
archive file and the station's layer, or a station over OPC UA (the readings of the tag's part of
the memory, watched while the faceplate is open; its Historical Access; its WriteTag, ForceTag
and UnforceTag methods, which the station checks and journals with the console's user).
"""

from __future__ import annotations

import datetime as dt
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QEvent, QObject, Qt
from PySide6.QtGui import QKeyEvent, QMouseEvent
from PySide6.QtWidgets import (
    QDialog,
    QFormLayout,
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from app.authority import Action, Answer, Ticket, Who, write_range
from app.gui import words
from app.gui.alarm_summary import AlarmSummary, ShelveDialog
from app.gui.bridge import Answers
from app.gui.series_loader import Series, SeriesLoader
from app.scada.alarms import AlarmDef, AlarmRow, State
from app.scada.forcing import tag_keys
from app.scada.quality import Quality
from app.scada.readings import Readings
from app.scada.tag import Tag, TagType
from hmi_forms.elements.base import Element, Writer
from hmi_forms.elements.target import CommandTarget
from hmi_forms.widgets.base import ElementWidget
from hmi_forms.widgets.form_view import FormView
from hmi_forms.widgets.trend import TrendWidget
from netplc.address import fmt_octal
from registrar.query import SeriesKey, available
from registrar.reading import ArchiveSource

logger = logging.getLogger(__name__)

HOUR = 3600.0
LIVE_POINTS = 7200  # live samples kept: an hour at two a second
TREND_POINTS = 1200  # read from the archive for the hour shown
Operand = tuple[int, int]  # (address, bytes): a tag's `operand`


def tag_of(model: Element, tags: Sequence[Tag]) -> Tag | None:
    """The tag an element shows or writes: a bit tag at its bit, a word tag at its word."""
    return _tag_at([*model.sources(), *_written(model)], tags)


def written_tag(model: Element, tags: Sequence[Tag]) -> Tag | None:
    """The tag an element that writes sets (its OutAddr), if it is one."""
    return _tag_at(_written(model), tags) if _writes(model) else None


def _written(model: Element) -> list[tuple[int, int]]:
    out = getattr(model, "OutAddr", None)
    if out is None:
        return []
    return [(out.hmi, 0)] if hasattr(out, "hmi") else [(out, 2)]


def _tag_at(operands: Sequence[tuple[int, int]], tags: Sequence[Tag]) -> Tag | None:
    for addr, nbytes in operands:
        for tag in tags:
            if tag.address == addr and (tag.type is TagType.BIT) == (nbytes == 0):
                return tag
    return None


def _reads_all(_key: str, _operand: Operand | None) -> None:
    """The in-process runtime's readings hold all of the memory: nothing to ask for."""


def _holds_all(_operand: Operand) -> bool:
    return True


@dataclass
class Console:
    """What a faceplate needs of the seat it opens at, the local workstation or a remote console
    (one faceplate for both: only these differ): the station's command layer as the seat reaches
    it (`CommandTarget`: the station's own layer, or its methods over OPC UA), who is on duty,
    where the answers come back, how it asks, the station's archive (its file, or an
    `ArchiveSource`: a station's Historical Access), the station's alarms (their definitions and
    the seat's summary of their states). `watch(key, operand)` asks the seat's data source for a
    part of the memory while a faceplate shows it (None: no more), `covers(operand)` says whether
    the readings it gives now hold it (a remote console reads only what its views want)."""

    target: CommandTarget
    who: Callable[[], Who]
    answers: Answers
    ask: Callable[[str, str], bool]
    archive: Path | ArchiveSource
    defs: Sequence[AlarmDef]
    summary: AlarmSummary
    watch: Callable[[str, Operand | None], None] = _reads_all
    covers: Callable[[Operand], bool] = _holds_all


class Faceplate(QDialog):
    def __init__(self, tag: Tag, console: Console, settable: bool, parent: QWidget | None = None) -> None:
        """`settable`: a form lets operators set this tag (an element writes it), so may its
        faceplate; a measurement has no entry, its value is the plant's."""
        super().__init__(parent)
        self.setObjectName("faceplate")
        self.tag = tag
        self.console = console
        self.released = False  # closed, or deleted with its window: answers to come are not its own
        self.destroyed.connect(partial(setattr, self, "released", True))
        self.defs = [d for d in console.defs if d.tag == tag.name]
        self.setWindowTitle(self.tr("Faceplate: {0}").format(tag.name))
        self.readings: Readings | None = None
        self.times = np.empty(0)
        self.values = np.empty(0)
        self.live_t: list[float] = []
        self.live_v: list[float] = []

        title = QLabel(f"<b>{tag.name}</b>" + (f" — {tag.description}" if tag.description else ""))
        title.setObjectName("faceplateTitle")
        title.setWordWrap(True)
        self.value = QLabel("?")
        self.value.setObjectName("faceplateValue")
        self.value.setStyleSheet("font-size: 22px; font-weight: bold;")
        self.quality = QLabel()
        self.quality.setObjectName("faceplateQuality")
        self.forced = QLabel()
        self.forced.setObjectName("faceplateForced")
        self.forced.setStyleSheet("color: #e65100; font-weight: bold;")
        head = QHBoxLayout()
        head.addWidget(self.value)
        head.addWidget(self.quality)
        head.addStretch(1)
        head.addWidget(self.forced)

        self.alarm_rows: dict[str, QLabel] = {}
        alarms = QGridLayout()
        for i, d in enumerate(self.defs):
            limit = "" if d.limit is None else f"{'≥' if d.high else '≤'} {tag.format(d.limit)}"
            alarms.addWidget(QLabel(d.id), i, 0)
            alarms.addWidget(QLabel(limit), i, 1)
            state = self.alarm_rows[d.id] = QLabel(words.state(State.NORMAL))
            alarms.addWidget(state, i, 2)
        if not self.defs:
            alarms.addWidget(QLabel(self.tr("No alarms on this tag")), 0, 0)
        self.ack = QPushButton(self.tr("Acknowledge"))
        self.ack.clicked.connect(self.acknowledge)
        self.shelve = QPushButton(self.tr("Shelve…"))
        self.shelve.clicked.connect(self.shelve_dialog)
        alarm_buttons = QHBoxLayout()
        alarm_buttons.addStretch(1)
        alarm_buttons.addWidget(self.ack)
        alarm_buttons.addWidget(self.shelve)

        self.plot = pg.PlotWidget(axisItems={"bottom": pg.DateAxisItem()})
        self.plot.setObjectName("faceplateTrend")
        self.plot.setBackground("w")
        self.plot.setMinimumHeight(140)
        self.plot.showGrid(x=True, y=True, alpha=0.3)
        self.curve = self.plot.plot(pen=pg.mkPen("#0b3d91", width=2), connect="finite")

        lo, hi = write_range(tag)
        self.entry = QLineEdit()
        self.entry.setObjectName("faceplateEntry")
        self.entry.setPlaceholderText(f"{tag.format(lo)} .. {tag.format(hi)}" if tag.type is not TagType.BIT
                                      else "0 / 1")
        self.entry.returnPressed.connect(self.set_value)
        self.set = QPushButton(self.tr("Set"))
        self.set.clicked.connect(self.set_value)
        self.force_entry = QLineEdit()
        self.force_entry.setObjectName("faceplateForceEntry")
        self.force_entry.setPlaceholderText(self.tr("empty: at its value"))
        self.force = QPushButton(self.tr("Force…"))
        self.force.clicked.connect(self.force_value)
        self.unforce = QPushButton(self.tr("Unforce…"))
        self.unforce.clicked.connect(self.unforce_value)
        entry = QHBoxLayout()
        entry.addWidget(self.entry, 1)
        entry.addWidget(self.set)
        forcing = QVBoxLayout()  # the entry a line of its own: its hint is read whole in Russian too
        forcing.addWidget(self.force_entry)
        force_buttons = QHBoxLayout()
        force_buttons.addStretch(1)
        force_buttons.addWidget(self.force)
        force_buttons.addWidget(self.unforce)
        forcing.addLayout(force_buttons)
        form = QFormLayout()
        if settable:
            form.addRow(self.tr("Set to ({0})").format(tag.unit or self.tr("value")), entry)
        else:
            self.entry.hide()
            self.set.hide()
        form.addRow(self.tr("Force"), forcing)

        self.message = QLabel()
        self.message.setObjectName("faceplateMessage")
        self.message.setWordWrap(True)
        self.message.setStyleSheet("color: #c62828;")
        close = QPushButton(self.tr("Close"))
        close.clicked.connect(self.close)
        lay = QVBoxLayout(self)
        lay.addWidget(title)
        lay.addLayout(head)
        lay.addLayout(alarms)
        lay.addLayout(alarm_buttons)
        lay.addWidget(self.plot, 1)
        lay.addLayout(form)
        lay.addWidget(self.message)
        lay.addWidget(close, 0, Qt.AlignmentFlag.AlignRight)
        self.resize(460, 560)
        self.grants = ((self.set, self.entry, Action.WRITE), (self.force, self.force_entry, Action.FORCE),
                       (self.unforce, None, Action.UNFORCE), (self.ack, None, Action.ACKNOWLEDGE),
                       (self.shelve, None, Action.SHELVE))
        self.show_rights()
        self.watching = f"faceplate:{tag.name}"  # the part of the memory it shows, while open
        console.watch(self.watching, tag.operand)
        self.finished.connect(self._release)
        self.loader = SeriesLoader(TREND_POINTS, self)
        self.loader.answered.connect(self._history)
        self.loader.failed.connect(self._answered)  # logged by the loader; the trend shows the live part
        self.asked: set[int] = set()  # the hour's reads not yet answered (`loading`)
        if available(console.archive):
            now, key = dt.datetime.now(), SeriesKey("data", None, None, fmt_octal(tag.address))
            for day in sorted({(now - dt.timedelta(hours=1)).date(), now.date()}):
                self.asked.add(self.loader.request(console.archive, day, key))

    # --- showing ---------------------------------------------------------------------------------

    def show_rights(self) -> None:
        """What the user on duty may do here, as the command layer says; the role it needs in the
        tooltip of what is greyed."""
        who = self.console.who()
        for button, entry, action in self.grants:
            why = self.console.target.denial(who, action, what=button.text().rstrip("…"))
            button.setEnabled(why is None)
            button.setToolTip("" if why is None else words.refusal(why))
            if entry is not None:
                entry.setEnabled(why is None)

    def show_readings(self, readings: Readings) -> None:
        if not self.console.covers(self.tag.operand):  # not yet read for it
            return
        self.readings = readings
        reading = readings.tag(self.tag.name)
        self.value.setText(self.tag.format(reading.value) if not math.isnan(reading.value) else "?")
        quality = reading.quality
        self.quality.setText(words.word(quality.word))
        self.quality.setStyleSheet("" if quality in (Quality.GOOD, Quality.FORCED) else "color: #7a808a;")
        held = {f.key: f for f in readings.snapshot.forces}
        forces = [held.get(k) for k in tag_keys(self.tag)]
        self.forced.setText(self.tr("F forced by {0}").format(forces[0].user)
                            if forces and all(forces) and forces[0] is not None else "")
        rows = {r.id: r for r in self.console.summary.rows}
        for alarm_id, label in self.alarm_rows.items():
            row = rows.get(alarm_id)
            label.setText(words.state(row.state) if row is not None else words.state(State.NORMAL))
            loud = row is not None and not row.acked
            label.setStyleSheet("color: #d32f2f; font-weight: bold;" if loud else "")
        if quality in (Quality.GOOD, Quality.FORCED):
            self.live_t.append(readings.time)
            self.live_v.append(reading.value)
            if len(self.live_t) > LIVE_POINTS:
                del self.live_t[:-LIVE_POINTS], self.live_v[:-LIVE_POINTS]
        self._plot()
        self.show_rights()

    def loading(self) -> bool:
        """Whether the hour of history is still being read (the screenshots wait for it)."""
        return bool(self.asked)

    def _answered(self, token: int, *_: object) -> None:
        self.asked.discard(token)

    def _history(self, token: int, series: Series) -> None:
        self._answered(token)
        _key, ts, raw = series
        values = raw if self.tag.scaling is None else self.tag.scaling.to_phy(raw)
        order = np.argsort(np.concatenate([self.times, ts]), kind="stable")
        self.times = np.concatenate([self.times, ts])[order]
        self.values = np.concatenate([self.values, values])[order]
        self._plot()

    def _plot(self) -> None:
        start = time.time() - HOUR
        live_from = self.live_t[0] if self.live_t else math.inf
        old = (self.times >= start) & (self.times < live_from)
        t = np.concatenate([self.times[old], np.asarray(self.live_t)])
        v = np.concatenate([self.values[old], np.asarray(self.live_v)])
        self.curve.setData(t, v)

    def points(self) -> int:
        """Samples drawn in the trend (tests look)."""
        return len(self.curve.xData) if self.curve.xData is not None else 0

    # --- acting: commands of the station's layer ------------------------------------------------

    def _follow(self, what: str, ticket: Ticket, then: Callable[[Answer], None] | None = None) -> Ticket:
        def said(answer: Answer) -> None:
            if self.released:  # closed before the answer came (its widgets are gone with it): the
                return  # window's status bar says the answer, as it does every answer followed
            self.message.setText("" if answer.ok else words.answer(what, answer))
            if then is not None:
                then(answer)

        return self.console.answers.follow(what, ticket, said)

    def _number(self, text: str) -> float | None:
        try:
            value = float(text.strip().replace(",", "."))
        except ValueError:
            self.message.setText(self.tr("{0} is not a number").format(repr(text)))
            return None
        return value

    def set_value(self) -> Ticket | None:
        """The setpoint or command typed, written as the user on duty; the layer holds it to the
        tag's range and type and says why not."""
        value = self._number(self.entry.text())
        if value is None:
            return None
        what = self.tr("Set {0}").format(self.tag.name)
        return self._follow(what, self.console.target.write_tag(self.console.who(), self.tag, value),
                            lambda a: self.entry.clear() if a.ok else None)

    def force_value(self) -> Ticket | None:
        """Force to the value typed (its range as the Program view's), or at its value; asked first."""
        text = self.force_entry.text().strip()
        phy = None if not text else self._number(text)
        if text and phy is None:
            return None
        tag = self.tag
        if phy is not None:
            lo, hi = write_range(tag)
            if not lo <= phy <= hi:
                self.message.setText(self.tr("{0} is not forced: {1} is outside its range {2} .. {3}").format(
                    tag.name, tag.format(phy), tag.format(lo), tag.format(hi)))
                return None
        to = self.tr("at its value (bumpless)") if phy is None else self.tr("to {0}").format(tag.format(phy))
        if not self.console.ask(self.tr("Force"), self.tr(
                "Force {0} {1}? The program and the nodes no longer change it until it is unforced.").format(
                tag.name, to)):
            return None
        return self._follow(self.tr("Force {0}").format(tag.name),
                            self.console.target.force_tag(self.console.who(), tag, phy))

    def unforce_value(self) -> Ticket | None:
        shown = self.value.text()
        if not self.console.ask(self.tr("Unforce"), self.tr("Unforce {0}?").format(self.tag.name) + " "
                                + words.unforce_stays(shown if shown != "?" else "")):
            return None
        return self._follow(self.tr("Unforce {0}").format(self.tag.name),
                            self.console.target.unforce_tag(self.console.who(), self.tag))

    def unacknowledged(self) -> list[AlarmRow]:
        return [r for r in self.console.summary.rows if r.id in self.alarm_rows and not r.acked]

    def acknowledge(self) -> None:
        self.console.summary.acknowledge([r.id for r in self.unacknowledged()])

    def shelve_dialog(self) -> ShelveDialog | None:
        """Shelve this tag's listed alarms, with a duration and a reason (the summary's dialog)."""
        listed = [r.id for r in self.console.summary.rows if r.id in self.alarm_rows]
        if not listed:
            self.message.setText(self.tr("No alarm of {0} to shelve").format(self.tag.name))
            return None
        dialog = ShelveDialog(", ".join(listed), self)
        dialog.accepted.connect(lambda: [self.console.summary.shelve_alarm(
            i, dialog.minutes.value(), dialog.reason.text()) for i in listed])
        dialog.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
        dialog.open()
        return dialog

    def _release(self) -> None:
        """Closed (or done with Escape): its reads stop, and so does the watch of its tag."""
        self.released = True
        self.loader.close()
        self.console.watch(self.watching, None)

    def closeEvent(self, event: object) -> None:
        self._release()
        super().closeEvent(event)  # type: ignore[arg-type]


class Faceplates(QObject):
    """Opens faceplates from the forms' elements bound to tags, and keeps them live."""

    def __init__(self, console: Console, tags: Sequence[Tag], views: Sequence[FormView],
                 parent: QWidget) -> None:
        super().__init__(parent)
        self.console = console
        self.window = parent
        self.open: dict[str, Faceplate] = {}
        self.bound: dict[ElementWidget, Tag] = {}
        self.settable: set[str] = set()  # tags an element of a form writes
        self.last: Readings | None = None
        for view in views:
            for model, widget in view.pairs:
                tag = tag_of(model, tags)
                if (out := written_tag(model, tags)) is not None:
                    self.settable.add(out.name)
                if tag is not None:
                    self.bound[widget] = tag
                    widget.setFocusPolicy(Qt.FocusPolicy.TabFocus)
                    widget.installEventFilter(self)

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        tag = self.bound.get(watched)  # type: ignore[call-overload]
        if tag is None:
            return False
        kind, model = event.type(), getattr(watched, "model", None)
        if kind == QEvent.Type.MouseButtonDblClick and not getattr(model, "KeepMaxValue", False):
            self.show_tag(tag)  # (a gauge that keeps its maximum resets it on a double-click)
            return True
        if kind == QEvent.Type.MouseButtonRelease and isinstance(event, QMouseEvent) \
                and event.button() == Qt.MouseButton.LeftButton and not _writes(model) \
                and not isinstance(watched, TrendWidget):  # a click pauses a trend
            self.show_tag(tag)
            return False
        if kind == QEvent.Type.KeyPress and isinstance(event, QKeyEvent) \
                and event.key() in (Qt.Key.Key_Return, Qt.Key.Key_Enter):
            self.show_tag(tag)
            return True
        return False

    def show_tag(self, tag: Tag) -> Faceplate:
        """The tag's faceplate, raised if it is open already."""
        plate = self.open.get(tag.name)
        if plate is None:
            plate = self.open[tag.name] = Faceplate(tag, self.console, tag.name in self.settable, self.window)
            plate.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
            plate.destroyed.connect(lambda _=None, n=tag.name: self.open.pop(n, None))
            if self.last is not None:
                plate.show_readings(self.last)
        plate.show()
        plate.raise_()
        return plate

    def show_readings(self, readings: Readings) -> None:
        self.last = readings
        for plate in self.open.values():
            plate.show_readings(readings)

    def close(self) -> None:
        for plate in list(self.open.values()):
            plate.close()
        self.open.clear()


def _writes(model: object) -> bool:
    """Whether the element writes by itself (a button, an entry): a click on it is its own."""
    return isinstance(model, Writer) and bool(getattr(model, "Enabled", True))
