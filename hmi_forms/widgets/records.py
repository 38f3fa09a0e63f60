"""One table model over archive rows, for the MessageJournal element, the journal dock and the viewer.

Rows are shown the way an operator reads a journal: time first, the message type by name, and
colour left for what matters. What differs between the three places is which columns they show
(the form's journal is narrow and names a message by its text; the workstation adds milliseconds
and the number column) and the palette (a form follows the HMI theme, the workstation its own), so
those are the options; the rules for reading a row are written once here.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from PySide6.QtCore import (
    QT_TRANSLATE_NOOP,
    QAbstractTableModel,
    QCoreApplication,
    QModelIndex,
    QPersistentModelIndex,
    Qt,
)
from PySide6.QtGui import QColor, QFont, QFontMetrics
from PySide6.QtWidgets import QAbstractItemView, QHeaderView, QTableView

from app.scada.alarms import State
from hmi_forms.elements import formats
from netplc.address import fmt_octal
from registrar.query import Row

TYPE_NAMES = {0: QT_TRANSLATE_NOOP("records", "info"), 1: QT_TRANSLATE_NOOP("records", "warning"),
              2: QT_TRANSLATE_NOOP("records", "alarm"), 3: QT_TRANSLATE_NOOP("records", "critical")}
# the column heads, for the translation sources (RecordsModel translates them as shown)
HEADS = (QT_TRANSLATE_NOOP("records", "Time"), QT_TRANSLATE_NOOP("records", "Kind"),
         QT_TRANSLATE_NOOP("records", "Group"), QT_TRANSLATE_NOOP("records", "Type"),
         QT_TRANSLATE_NOOP("records", "Source"), QT_TRANSLATE_NOOP("records", "No."),
         QT_TRANSLATE_NOOP("records", "Value"), QT_TRANSLATE_NOOP("records", "Text"))
Index = QModelIndex | QPersistentModelIndex


def format_value(value: float | None) -> str:
    if value is None:
        return ""
    return str(int(value)) if value == int(value) else f"{value:.3f}"


STATES = frozenset(int(s) for s in State)
HEADER_PADDING = 18  # px beside a column title: its margins and the sort mark
CELL_PADDING = 10  # px beside a cell's text: the item's margins


def type_name(row: Row) -> str:
    """Message types by name, an alarm's new state by its word; other kinds keep their number (a
    data record's type is not a severity)."""
    if row.type is None:
        return ""
    if row.kind == "alarm" and row.type in STATES:
        return QCoreApplication.translate("words", State(row.type).word)  # app/gui/words.py lists them
    if row.kind != "message" or row.type not in TYPE_NAMES:
        return str(row.type)
    return QCoreApplication.translate("records", TYPE_NAMES[row.type])


def number(row: Row) -> str:
    if row.number is None:
        return ""
    # an operator write names the address it wrote: octal, as everywhere else
    return fmt_octal(row.number) if row.kind == "operator" else str(row.number)


def clock_ms(row: Row) -> str:
    """The wall clock where the record was written (the archive's zone)."""
    return formats.clock_ms(row.ts, row.tz)


@dataclass(frozen=True)
class Column:
    title: str
    text: Callable[[Row], str]
    width: int = 0  # 0: the column takes the spare width
    right: bool = False
    fits: tuple[str, ...] = ()  # words the column shows whole, in the console's language ("records")


TIME = Column("Time", clock_ms, 96)
KINDS = (QT_TRANSLATE_NOOP("records", "data"), QT_TRANSLATE_NOOP("records", "message"),
         QT_TRANSLATE_NOOP("records", "operator"), QT_TRANSLATE_NOOP("records", "system"))
KIND = Column("Kind", lambda r: QCoreApplication.translate("records", r.kind), 76, fits=(*KINDS, "alarm"))
GROUP = Column("Group", lambda r: "" if r.grp is None else str(r.grp), 64, right=True)
TYPE = Column("Type", type_name, 64, right=True, fits=tuple(TYPE_NAMES.values()))
SOURCE = Column("Source", lambda r: r.source or "", 120)
NUMBER = Column("No.", number, 64, right=True)
VALUE = Column("Value", lambda r: format_value(r.value), 84, right=True)
TEXT = Column("Text", lambda r: r.text or "")

ARCHIVE_COLUMNS = (TIME, KIND, GROUP, TYPE, SOURCE, NUMBER, VALUE, TEXT)
"""The workstation's columns: every field of a record, text last to take the spare width."""

JOURNAL_COLUMNS = (
    Column("Time", lambda r: formats.clock(r.ts), 70),
    Column("Kind", KIND.text, 70, fits=KIND.fits),
    Column("Group", GROUP.text, 50),
    Column("Type", type_name, 64, fits=TYPE.fits),
    Column("Source", SOURCE.text, 110),
    Column("Text", lambda r: r.text or ("" if r.number is None else QCoreApplication.translate(
        "records", "message {0}").format(r.number))),
    Column("Value", VALUE.text, 60),
)
"""A form's journal: seconds are enough, and a message without text is named by its number."""


@dataclass(frozen=True)
class Palette:
    """Message rows are coloured by type; other rows may take a text colour by kind."""

    back: Mapping[int, QColor]
    fore: Mapping[int, QColor] = field(default_factory=dict)
    kind_fore: Mapping[str, QColor] = field(default_factory=dict)


ARCHIVE_PALETTE = Palette(
    back={1: QColor(255, 243, 205), 2: QColor(255, 214, 214), 3: QColor(239, 154, 154)},
    kind_fore={"system": QColor(70, 90, 120), "operator": QColor(20, 90, 160), "alarm": QColor(170, 30, 30)},
)


class RecordsModel(QAbstractTableModel):
    def __init__(self, columns: Sequence[Column] = ARCHIVE_COLUMNS,
                 palette: Palette = ARCHIVE_PALETTE, parent: Any = None) -> None:
        super().__init__(parent)
        self.columns = tuple(columns)
        self.palette = palette
        self.rows: list[Row] = []

    def set_rows(self, rows: list[Row]) -> None:
        """Reset only when the rows differ: a reset loses the operator's selection and scroll."""
        if [(r.id, r.station) for r in rows] == [(r.id, r.station) for r in self.rows]:
            return
        self.beginResetModel()
        self.rows = list(rows)
        self.endResetModel()

    def rowCount(self, parent: Index = QModelIndex()) -> int:  # noqa: B008 - Qt API
        return 0 if parent.isValid() else len(self.rows)

    def columnCount(self, parent: Index = QModelIndex()) -> int:  # noqa: B008 - Qt API
        return 0 if parent.isValid() else len(self.columns)

    def headerData(self, section: int, orientation: Qt.Orientation,
                   role: int = Qt.ItemDataRole.DisplayRole) -> Any:
        if role == Qt.ItemDataRole.DisplayRole and orientation == Qt.Orientation.Horizontal:
            return QCoreApplication.translate("records", self.columns[section].title)
        return None

    def data(self, index: Index, role: int = Qt.ItemDataRole.DisplayRole) -> Any:
        if not index.isValid():
            return None
        row = self.rows[index.row()]
        if role in (Qt.ItemDataRole.DisplayRole, Qt.ItemDataRole.ToolTipRole):  # the tip: a cut text whole
            return self.columns[index.column()].text(row)
        message = row.kind == "message"
        if role == Qt.ItemDataRole.BackgroundRole:
            return self.palette.back.get(row.type or 0) if message else None
        if role == Qt.ItemDataRole.ForegroundRole:
            return self.palette.fore.get(row.type or 0) if message else self.palette.kind_fore.get(row.kind)
        if role == Qt.ItemDataRole.TextAlignmentRole and self.columns[index.column()].right:
            return int(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        return None


def title_width(header: QHeaderView, title: str) -> int:
    """The room a column's title needs: the style sheet's headers are bold, in any language."""
    bold = QFont(header.font())
    bold.setBold(True)
    return QFontMetrics(bold).horizontalAdvance(title) + HEADER_PADDING


def cell_width(view: QTableView, text: str) -> int:
    return view.fontMetrics().horizontalAdvance(text) + CELL_PADDING


def records_view(model: RecordsModel, row_height: int) -> QTableView:
    """A read-only, row-selecting table sized by the model's columns."""
    view = QTableView()
    view.setModel(model)
    view.setAlternatingRowColors(True)
    view.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
    view.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
    view.verticalHeader().setVisible(False)
    view.verticalHeader().setDefaultSectionSize(row_height)
    header = view.horizontalHeader()
    header.setSectionResizeMode(QHeaderView.ResizeMode.Interactive)
    for col, column in enumerate(model.columns):
        if column.width:
            title = str(model.headerData(col, Qt.Orientation.Horizontal, Qt.ItemDataRole.DisplayRole) or "")
            words = (cell_width(view, QCoreApplication.translate("records", w)) for w in column.fits)
            header.resizeSection(col, max(column.width, title_width(header, title), *words))
        else:
            header.setSectionResizeMode(col, QHeaderView.ResizeMode.Stretch)
    return view
