"""The element palette: every element type of the manual, dragged onto the canvas or double-clicked."""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtCore import QMimeData, Qt
from PySide6.QtWidgets import QAbstractItemView, QListWidget, QListWidgetItem, QWidget

from app.gui.designer.canvas import ELEMENT_MIME
from hmi_forms.elements import ELEMENT_TYPES

HINTS = {
    "SyncGenerator": "pulses on OutAddr: scan mod Period = Phase (Fig. 2.4.3)",
    "SyncTimer": "a sync generator enabled by Ainput",
    "DiscreteBase": "a bit as text, image and lamp; a button when Enabled",
    "DiscreteColorLabel": "a bit with colours per state",
    "DiscreteControlledEnable": "shows its state only while EnableAddr is 1",
    "DiscreteAnimation": "cycles ImageFirst..ImageLast while the bit is 1",
    "AnalogBase": "a word converted to a physical value: digital, bar, dial, graph",
    "AnalogOutput": "the operator's setpoint, converted and written",
    "StaticPicture": "a picture from the form's folder",
    "StaticText": "a caption",
    "Graph": "a bit trend, one sample per scan",
    "MessageJournal": "the archive's records of a day",
    "DateTime": "time, date and the time since start",
}


class Palette(QListWidget):
    def __init__(self, add: Callable[[str], object], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setDragEnabled(True)
        self.setDragDropMode(QAbstractItemView.DragDropMode.DragOnly)
        for kind in ELEMENT_TYPES:
            item = QListWidgetItem(kind)
            item.setData(Qt.ItemDataRole.UserRole, kind)
            item.setToolTip(f"{kind}: {HINTS[kind]}\nDrag onto the form, or double-click to add")
            self.addItem(item)
        self.itemDoubleClicked.connect(lambda item: add(item.data(Qt.ItemDataRole.UserRole)))

    def mimeTypes(self) -> list[str]:
        return [ELEMENT_MIME]

    def mimeData(self, items: list[QListWidgetItem]) -> QMimeData:
        data = QMimeData()
        if items:
            data.setData(ELEMENT_MIME, items[0].data(Qt.ItemDataRole.UserRole).encode())
        return data
