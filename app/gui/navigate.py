"""From an alarm to the picture: the form that shows its tag, the element marked.

An alarm says what is wrong; the operator then needs to see it in its place among the rest of
the plant. A double-click on an alarm (a row of the alarm summary, the banner in the header, an
alarm record of the journal) brings up the tab of the first form with an element bound to the
alarm's tag, scrolls it into view and marks the element with a blinking frame for a few seconds.
Each tab whose form shows a tag with an unacknowledged alarm carries a mark in the colour of the
highest priority among them, so an alarm on another form is seen without leaving this one.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TypeVar

from PySide6.QtCore import QModelIndex, QObject, QRect, QRectF, Qt, QTimer
from PySide6.QtGui import QColor, QIcon, QPainter, QPaintEvent, QPen, QPixmap
from PySide6.QtWidgets import QTabWidget, QWidget

from app.gui import words
from app.gui.alarm_summary import COLOURS, AlarmSummary
from app.gui.alarms import AlarmBanner
from app.gui.journal import JournalDock
from app.gui.zoom import ZoomArea
from app.scada.alarms import AlarmDef, AlarmRow
from app.scada.tag import Tag
from hmi_forms.widgets.base import ElementWidget

T = TypeVar("T")
BLINKS = 8  # half-periods of the mark's blinking, then it goes
BLINK_MS = 400
MARK = QColor("#3d7bd9")


class Highlight(QWidget):
    """A thick frame around an element, over the form, blinking a few times."""

    def __init__(self, element: ElementWidget) -> None:
        parent = element.parentWidget()
        assert parent is not None
        super().__init__(parent)
        self.setAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        self.setGeometry(element.geometry().adjusted(-5, -5, 5, 5))
        self.left = BLINKS
        self.timer = QTimer(self)
        self.timer.setInterval(BLINK_MS)
        self.timer.timeout.connect(self._blink)
        self.timer.start()
        self.show()
        self.raise_()

    def _blink(self) -> None:
        self.left -= 1
        if self.left <= 0:
            self.timer.stop()
            self.hide()
            self.deleteLater()
            return
        self.setVisible(not self.isVisible())

    def paintEvent(self, event: QPaintEvent) -> None:
        p = QPainter(self)
        try:
            p.setPen(QPen(MARK, 4))
            p.drawRect(QRectF(self.rect()).adjusted(2, 2, -2, -2))
        finally:
            p.end()


class AlarmNavigator(QObject):
    def __init__(self, tabs: QTabWidget, zooms: Sequence[ZoomArea], bound: Mapping[ElementWidget, Tag],
                 defs: Sequence[AlarmDef], parent: QObject) -> None:
        super().__init__(parent)
        self.tabs = tabs
        self.tag_of_alarm = {d.id: d.tag for d in defs if d.tag is not None}
        self.places: dict[str, list[tuple[ZoomArea, ElementWidget]]] = {}  # tag -> where it is shown
        for area in zooms:
            for widget, tag in bound.items():
                if widget.parentWidget() is area.form_view:
                    self.places.setdefault(tag.name, []).append((area, widget))
        self.highlight: Highlight | None = None
        self._icons: dict[int, QIcon] = {}

    def follow(self, summary: AlarmSummary, banner: AlarmBanner, journal: JournalDock) -> None:
        """Double-clicks on the summary's rows, the banner and the journal's alarm records."""
        summary.table.doubleClicked.connect(
            lambda index: self._chosen(summary.model.rows, index, lambda r: r.id))
        banner.chosen.connect(lambda row: self.show_alarm(row.id))
        journal.table.doubleClicked.connect(
            lambda index: self._chosen(journal.model.rows, index,
                                       lambda r: r.source if r.kind == "alarm" else None))

    def _chosen(self, rows: Sequence[T], index: QModelIndex, alarm_of: Callable[[T], str | None]) -> None:
        if 0 <= index.row() < len(rows):
            self.show_alarm(alarm_of(rows[index.row()]))

    def show_alarm(self, alarm_id: str | None) -> ElementWidget | None:
        """Bring up the form showing the alarm's tag and mark the element; None when no form
        shows it (an NMSG alarm, a tag on no form)."""
        tag = self.tag_of_alarm.get(alarm_id or "")
        places = self.places.get(tag or "")
        if not places:
            return None
        area, widget = places[0]
        self.tabs.setCurrentWidget(area)
        area.ensureVisible(area.proxy.mapRectToScene(QRectF(widget.geometry())))
        if self.highlight is not None:
            self.highlight.deleteLater()
        self.highlight = Highlight(widget)
        self.highlight.destroyed.connect(lambda _=None: setattr(self, "highlight", None))
        return widget

    def mark_tabs(self, unacknowledged: Sequence[AlarmRow]) -> None:
        """Each form's tab marked with the highest priority of its tags' unacknowledged alarms."""
        worst: dict[ZoomArea, AlarmRow] = {}
        for row in unacknowledged:
            for area, _ in self.places.get(self.tag_of_alarm.get(row.id) or "", ()):
                if area not in worst or row.priority < worst[area].priority:
                    worst[area] = row
        for i in range(self.tabs.count()):
            area = self.tabs.widget(i)
            row = worst.get(area) if isinstance(area, ZoomArea) else None
            self.tabs.setTabIcon(i, QIcon() if row is None else self._icon(row.priority))
            tip = "" if row is None else f"P{row.priority} {words.priority(row.priority)}: {row.text}"
            self.tabs.setTabToolTip(i, tip)

    def _icon(self, priority: int) -> QIcon:
        icon = self._icons.get(priority)
        if icon is None:
            back, fore = COLOURS.get(priority, COLOURS[4])
            pix = QPixmap(32, 32)
            pix.fill(Qt.GlobalColor.transparent)
            p = QPainter(pix)
            try:
                p.setRenderHint(QPainter.RenderHint.Antialiasing)
                p.setPen(Qt.PenStyle.NoPen)
                p.setBrush(QColor(back))
                p.drawEllipse(QRect(1, 1, 30, 30))
                p.setPen(QColor(fore))
                font = p.font()
                font.setPixelSize(18)
                font.setBold(True)
                p.setFont(font)
                p.drawText(QRect(0, 0, 32, 32), Qt.AlignmentFlag.AlignCenter, str(priority))
            finally:
                p.end()
            icon = self._icons[priority] = QIcon(pix)
        return icon
