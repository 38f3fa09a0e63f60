"""A table model over archive rows, shared by the workstation's journal dock and the viewer.

Rows are shown the way an operator reads a journal: local time first, the type by name, alarms
and operator actions coloured, so a glance down the list finds what matters.
"""

from __future__ import annotations

import time

from PySide6.QtCore import QAbstractTableModel, QModelIndex, QPersistentModelIndex, Qt
from PySide6.QtGui import QBrush, QColor

from netplc.address import fmt_octal
from registrar.query import Row

COLUMNS = ("Time", "Kind", "Group", "Type", "Source", "No.", "Value", "Text")
TYPE_NAMES = {0: "info", 1: "warning", 2: "alarm", 3: "critical"}
_BACK = {
    ("message", 1): QColor(255, 243, 205),
    ("message", 2): QColor(255, 214, 214),
    ("message", 3): QColor(239, 154, 154),
}
_KIND_FORE = {"system": QColor(70, 90, 120), "operator": QColor(20, 90, 160)}
Index = QModelIndex | QPersistentModelIndex


def format_value(value: float | None) -> str:
    if value is None:
        return ""
    return str(int(value)) if value == int(value) else f"{value:.3f}"


class RecordsModel(QAbstractTableModel):
    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.rows: list[Row] = []

    def set_rows(self, rows: list[Row]) -> None:
        self.beginResetModel()
        self.rows = list(rows)
        self.endResetModel()

    def rowCount(self, parent: Index = QModelIndex()) -> int:  # noqa: B008 - Qt API
        return 0 if parent.isValid() else len(self.rows)

    def columnCount(self, parent: Index = QModelIndex()) -> int:  # noqa: B008 - Qt API
        return 0 if parent.isValid() else len(COLUMNS)

    def headerData(self, section: int, orientation: Qt.Orientation,
                   role: int = Qt.ItemDataRole.DisplayRole) -> object:
        if role == Qt.ItemDataRole.DisplayRole and orientation == Qt.Orientation.Horizontal:
            return COLUMNS[section]
        return None

    def data(self, index: Index, role: int = Qt.ItemDataRole.DisplayRole) -> object:
        if not index.isValid():
            return None
        row = self.rows[index.row()]
        col = index.column()
        if role == Qt.ItemDataRole.DisplayRole:
            return self.cell(row, col)
        if role == Qt.ItemDataRole.BackgroundRole:
            color = _BACK.get((row.kind, row.type or 0))
            return QBrush(color) if color else None
        if role == Qt.ItemDataRole.ForegroundRole:
            color = _KIND_FORE.get(row.kind)
            return QBrush(color) if color else None
        if role == Qt.ItemDataRole.TextAlignmentRole and col in (2, 3, 5, 6):
            return int(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        return None

    @staticmethod
    def cell(row: Row, col: int) -> str:
        if col == 0:
            ms = int(row.ts * 1000) % 1000
            return time.strftime("%H:%M:%S", time.localtime(row.ts)) + f".{ms:03d}"
        if col == 1:
            return row.kind
        if col == 2:
            return "" if row.grp is None else str(row.grp)
        if col == 3:
            if row.type is None:
                return ""
            return TYPE_NAMES.get(row.type, str(row.type)) if row.kind == "message" else str(row.type)
        if col == 4:
            return row.source or ""
        if col == 5:
            if row.number is None:
                return ""
            # an operator write names the address it wrote: octal, as everywhere else
            return fmt_octal(row.number) if row.kind == "operator" else str(row.number)
        if col == 6:
            return format_value(row.value)
        return row.text or ""
