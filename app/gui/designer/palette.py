"""The element palette: every element type of the manual with an icon and one line of help, dragged
onto the canvas or double-clicked."""

from __future__ import annotations

import re
from collections.abc import Callable

from PySide6.QtCore import QT_TRANSLATE_NOOP, QMimeData, QRectF, QSize, Qt
from PySide6.QtGui import QColor, QIcon, QPainter, QPixmap
from PySide6.QtWidgets import QAbstractItemView, QListWidget, QListWidgetItem, QWidget

from app.gui.designer.canvas import ELEMENT_MIME
from hmi_forms.elements import ELEMENT_TYPES

HINTS = {  # one line of help each, under the type's name
    "SyncGenerator": QT_TRANSLATE_NOOP("Palette", "pulses on OutAddr: scan mod Period = Phase (Fig. 2.4.3)"),
    "SyncTimer": QT_TRANSLATE_NOOP("Palette", "a sync generator enabled by Ainput"),
    "DiscreteBase": QT_TRANSLATE_NOOP("Palette", "a bit as text, image and lamp; a button when Enabled"),
    "DiscreteColorLabel": QT_TRANSLATE_NOOP("Palette", "a bit with colours per state"),
    "DiscreteControlledEnable": QT_TRANSLATE_NOOP("Palette", "its state only while EnableAddr is 1"),
    "DiscreteAnimation": QT_TRANSLATE_NOOP("Palette", "cycles ImageFirst..ImageLast while the bit is 1"),
    "AnalogBase": QT_TRANSLATE_NOOP("Palette", "a tag's value with its unit: digital, bar, dial, graph"),
    "AnalogOutput": QT_TRANSLATE_NOOP("Palette", "the operator's setpoint, converted and written"),
    "StaticPicture": QT_TRANSLATE_NOOP("Palette", "a picture from the form's folder"),
    "StaticText": QT_TRANSLATE_NOOP("Palette", "a caption"),
    "Graph": QT_TRANSLATE_NOOP("Palette", "a bit trend, one sample per scan"),
    "MessageJournal": QT_TRANSLATE_NOOP("Palette", "the archive's records of a day"),
    "DateTime": QT_TRANSLATE_NOOP("Palette", "time, date and the time since start"),
}
# the icon's glyph and colour per type (drawn, so that no image files are needed)
GLYPHS = {
    "SyncGenerator": ("\u03a0", "#6d4c41"), "SyncTimer": ("\u25f4", "#6d4c41"),
    "DiscreteBase": ("\u25c9", "#2e7d32"), "DiscreteColorLabel": ("\u25a3", "#2e7d32"),
    "DiscreteControlledEnable": ("\u25d0", "#2e7d32"), "DiscreteAnimation": ("\u21bb", "#2e7d32"),
    "AnalogBase": ("\u25d4", "#1565c0"), "AnalogOutput": ("\u270e", "#1565c0"),
    "StaticPicture": ("\u25a8", "#5a6270"), "StaticText": ("T", "#5a6270"),
    "Graph": ("\u223f", "#8e24aa"), "MessageJournal": ("\u2630", "#8e24aa"),
    "DateTime": ("\u25f7", "#8e24aa"),
}
ICON = 28


def icon(kind: str) -> QIcon:
    glyph, colour = GLYPHS[kind]
    pixmap = QPixmap(ICON, ICON)
    pixmap.fill(Qt.GlobalColor.transparent)
    p = QPainter(pixmap)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    p.setPen(Qt.PenStyle.NoPen)
    p.setBrush(QColor(colour))
    p.drawRoundedRect(QRectF(1, 1, ICON - 2, ICON - 2), 5, 5)
    font = p.font()
    font.setPixelSize(18)
    font.setBold(True)
    p.setFont(font)
    p.setPen(QColor("#ffffff"))
    p.drawText(QRectF(0, 0, ICON, ICON), int(Qt.AlignmentFlag.AlignCenter), glyph)
    p.end()
    return QIcon(pixmap)


def breakable(name: str) -> str:
    """A type name that may wrap between its words (DiscreteControlled|Enable) where the dock is
    narrow: a zero-width space before each capital but the first."""
    return re.sub(r"(?<=[a-z])(?=[A-Z])", "\u200b", name)


class DragList(QListWidget):
    """A list whose entries are dragged onto the canvas as `mime`, each carrying its UserRole text
    (an element type, a tag's name); a double-click calls `add` with it, if it may be dragged."""

    def __init__(self, mime: str, add: Callable[[str], object], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.mime = mime
        self.setDragEnabled(True)
        self.setDragDropMode(QAbstractItemView.DragDropMode.DragOnly)
        # entries wrapped to the dock's width, a long type name anywhere: nothing cut at the right
        self.setWordWrap(True)
        self.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.setResizeMode(QListWidget.ResizeMode.Adjust)
        self.setTextElideMode(Qt.TextElideMode.ElideNone)
        self.itemDoubleClicked.connect(lambda item: self._add(item, add))

    @staticmethod
    def _add(item: QListWidgetItem, add: Callable[[str], object]) -> None:
        if item.flags() & Qt.ItemFlag.ItemIsDragEnabled:
            add(item.data(Qt.ItemDataRole.UserRole))

    def mimeTypes(self) -> list[str]:
        return [self.mime]

    def mimeData(self, items: list[QListWidgetItem]) -> QMimeData:
        data = QMimeData()
        if items:
            data.setData(self.mime, items[0].data(Qt.ItemDataRole.UserRole).encode())
        return data


class Palette(DragList):
    def __init__(self, add: Callable[[str], object], parent: QWidget | None = None) -> None:
        super().__init__(ELEMENT_MIME, add, parent)
        self.setIconSize(QSize(ICON, ICON))
        for kind in ELEMENT_TYPES:
            hint = self.tr(HINTS[kind])
            item = QListWidgetItem(icon(kind), f"{breakable(kind)}\n{hint}")
            item.setData(Qt.ItemDataRole.UserRole, kind)
            tip = self.tr("{0}: {1}\nDrag onto the form, or double-click to add")
            item.setToolTip(tip.format(kind, hint))
            self.addItem(item)
