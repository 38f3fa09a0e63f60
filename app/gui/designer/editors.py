"""One editor per kind of property value: what the engineer types or picks becomes the JSON value of
the file, and a value the loader would refuse is refused here, with the loader's reason.

Each editor emits `edited(value)` for a finished edit and asks `check(value)` while the engineer
types (addresses are validated keystroke by keystroke); `MISSING` removes the property, so
clearing a field gives the property back its default.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QStringListModel, Qt, Signal
from PySide6.QtGui import QColor, QFont
from PySide6.QtWidgets import (
    QCheckBox,
    QColorDialog,
    QComboBox,
    QCompleter,
    QFontDialog,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from app.gui.designer.commands import MISSING
from hmi_forms.elements import props as p

Check = Callable[[Any], str | None]
NUMBER = re.compile(r"[-+]?\d+")
REFUSED_STYLE = "QLineEdit { border: 1px solid #d32f2f; background: #fdecea; }"


def kind_of(parser: Any) -> str:
    """The editor kind for a property's parser (the element models declare them)."""
    if parser in (p.bit, p.word, p.sync_type):
        return "address"
    named = {p.color: "color", p.font: "font", p.image_file: "image_file", p.image_index: "image_index",
             p.boolean: "bool", p.number: "number", p.text: "text"}
    if parser in named:
        return named[parser]
    free = parser.__code__.co_freevars if hasattr(parser, "__code__") else ()
    if "options" in free:
        return "choice"
    if {"lo", "hi"} <= set(free) or "bounded" in free:
        return "integer"
    return "json"


def choices(parser: Any) -> tuple[str, ...]:
    """The options of a `props.choice` parser."""
    cells = dict(zip(parser.__code__.co_freevars, (c.cell_contents for c in parser.__closure__)))
    return tuple(cells["options"])


def shown(value: Any) -> str:
    """A JSON value as it appears in a line editor."""
    if value is MISSING or value is None:
        return ""
    return value if isinstance(value, str) else json.dumps(value, ensure_ascii=False)


def from_text(kind: str, text: str) -> Any:
    """What a typed text stands for: numbers as JSON numbers (1 stays an integer), addresses and
    text as strings, anything else as JSON when it parses. An empty field removes the property."""
    t = text.strip() if kind != "text" else text
    if t == "":
        return MISSING
    if kind in ("integer", "number"):
        if NUMBER.fullmatch(t):
            return int(t)
        try:
            return float(t.replace(",", "."))
        except ValueError:
            return t
    if kind == "address":
        return 0 if t == "0" else t
    if kind == "json":
        try:
            return json.loads(t)
        except json.JSONDecodeError:
            return t
    return t


class Editor(QWidget):
    edited = Signal(object)

    def __init__(self, check: Check, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.check = check
        self._reason: QLabel | None = None
        self.row = QHBoxLayout()
        self.row.setContentsMargins(0, 0, 0, 0)
        self.column = QVBoxLayout(self)
        self.column.setContentsMargins(0, 0, 0, 0)
        self.column.setSpacing(1)
        self.column.addLayout(self.row)

    @property
    def reason(self) -> QLabel:
        """The line under the editor saying why a value was refused, made the first time one is: a
        panel has dozens of editors, and most are never refused (hidden, it takes no room)."""
        if self._reason is None:
            self._reason = QLabel()
            self._reason.setObjectName("refusal")
            self._reason.setWordWrap(True)
            self._reason.setStyleSheet("color: #b71c1c;")
            self._reason.hide()
            self.column.addWidget(self._reason)
        return self._reason

    def set_value(self, value: Any, mixed: bool = False) -> None:
        raise NotImplementedError

    def refuse(self, reason: str | None) -> None:
        """Show why the last value was refused (None: clear the mark)."""
        if reason or self._reason is not None:
            self.reason.setText(reason or "")
            self.reason.setVisible(bool(reason))

    def submit(self, value: Any) -> None:
        self.edited.emit(value)


def _restyle(widget: QWidget, sheet: str) -> None:
    """Set a widget's style sheet unless it has it already: setting one, even the same or an empty
    one, polishes the widget again, and a panel's refresh sets each of its editors'."""
    if widget.styleSheet() != sheet:
        widget.setStyleSheet(sheet)


class LineEditor(Editor):
    """Text, numbers, addresses (with completion of symbols and tags) and JSON values."""

    def __init__(self, kind: str, check: Check, names: list[str] | None = None,
                 parent: QWidget | None = None) -> None:
        super().__init__(check, parent)
        self.kind = kind
        self.line = QLineEdit()
        self.row.addWidget(self.line)
        self._shown = ""
        if names:
            completer = QCompleter(QStringListModel(names, self), self)
            completer.setCaseSensitivity(Qt.CaseSensitivity.CaseInsensitive)
            completer.setFilterMode(Qt.MatchFlag.MatchContains)
            self.line.setCompleter(completer)
        self.line.textEdited.connect(self._typed)
        self.line.editingFinished.connect(self._finished)

    def set_value(self, value: Any, mixed: bool = False) -> None:
        self._shown = "" if mixed else shown(value)
        self.line.setText(self._shown)
        self.line.setPlaceholderText("(several values)" if mixed else "")
        _restyle(self.line, "")
        self.refuse(None)

    def _typed(self, text: str) -> None:
        reason = self.check(from_text(self.kind, text))
        _restyle(self.line, REFUSED_STYLE if reason else "")
        self.refuse(reason)

    def _finished(self) -> None:
        text = self.line.text()
        if text == self._shown:
            return
        self.submit(from_text(self.kind, text))

    def refuse(self, reason: str | None) -> None:
        super().refuse(reason)
        if reason:
            self.line.setStyleSheet(REFUSED_STYLE)

    def submit(self, value: Any) -> None:
        self._shown = self.line.text()
        super().submit(value)


class BoolEditor(Editor):
    def __init__(self, check: Check, parent: QWidget | None = None) -> None:
        super().__init__(check, parent)
        self.box = QCheckBox()
        self.row.addWidget(self.box)
        self.box.clicked.connect(lambda on: self.submit(bool(on)))

    def set_value(self, value: Any, mixed: bool = False) -> None:
        self.box.setTristate(mixed)
        self.box.setCheckState(Qt.CheckState.PartiallyChecked if mixed else
                               Qt.CheckState.Checked if value is True else Qt.CheckState.Unchecked)
        self.box.setTristate(False)
        self.refuse(None)


class ComboEditor(Editor):
    """A pick from a list; the first entry "(default)" removes the property."""

    def __init__(self, options: list[tuple[str, Any]], check: Check, editable: bool = False,
                 parent: QWidget | None = None) -> None:
        super().__init__(check, parent)
        self.combo = QComboBox()
        self.combo.setEditable(editable)
        self.combo.addItem(self.tr("(default)"), MISSING)
        for label, value in options:
            self.combo.addItem(label, value)
        self.options = self.combo.count()  # those after them are values set_value added
        self.row.addWidget(self.combo)
        self.combo.activated.connect(lambda i: self.submit(self.combo.itemData(i)))
        if editable:
            self.combo.lineEdit().editingFinished.connect(self._typed)

    def _typed(self) -> None:
        text = self.combo.currentText().strip()
        i = self.combo.findText(text)
        value = self.combo.itemData(i) if i >= 0 else (text or MISSING)
        self.submit(value)

    def set_value(self, value: Any, mixed: bool = False) -> None:
        while self.combo.count() > self.options:  # another element's value, not one to offer
            self.combo.removeItem(self.combo.count() - 1)
        i = -1 if mixed else next((k for k in range(self.combo.count())
                                   if self.combo.itemData(k) == value), -1)
        if i < 0 and not mixed and value is not MISSING:
            self.combo.addItem(shown(value), value)
            i = self.combo.count() - 1
        self.combo.setCurrentIndex(i)
        self.refuse(None)


class ColorEditor(LineEditor):
    """`#RRGGBB` typed, or picked in the colour dialog."""

    def __init__(self, check: Check, parent: QWidget | None = None) -> None:
        super().__init__("text", check, parent=parent)
        self.pick = QPushButton("…")
        self.pick.setFixedWidth(28)
        self.pick.setToolTip(self.tr("Pick a colour"))
        self.row.addWidget(self.pick)
        self.pick.clicked.connect(self._dialog)

    def set_value(self, value: Any, mixed: bool = False) -> None:
        super().set_value(value, mixed)
        try:
            r, g, b, a = p.color(value, None)  # type: ignore[arg-type]
            _restyle(self.pick, f"background: rgba({r},{g},{b},{a});")
        except p.PropError:
            _restyle(self.pick, "")

    def _dialog(self) -> None:
        color = QColorDialog.getColor(QColor(self.line.text() or "#ffffff"), self, self.tr("Colour"),
                                      QColorDialog.ColorDialogOption.ShowAlphaChannel)
        if color.isValid():
            self.line.setText(color_text(color))
            self.submit(color_text(color))


def color_text(color: QColor) -> str:
    if color.alpha() == 255:
        return color.name(QColor.NameFormat.HexRgb)
    return color.name(QColor.NameFormat.HexArgb)


class FontEditor(Editor):
    """The font dialog; the value is the form's `{"Family", "Size", "Bold", "Italic"}`."""

    def __init__(self, check: Check, parent: QWidget | None = None) -> None:
        super().__init__(check, parent)
        self.button = QPushButton()
        self.clear = QPushButton("×")
        self.clear.setFixedWidth(28)
        self.clear.setToolTip(self.tr("Back to the default font"))
        self.row.addWidget(self.button, 1)
        self.row.addWidget(self.clear)
        self.value: Any = MISSING
        self.button.clicked.connect(self._dialog)
        self.clear.clicked.connect(lambda: self.submit(MISSING))

    def set_value(self, value: Any, mixed: bool = False) -> None:
        self.value = value
        if mixed:
            self.button.setText("(several fonts)")
        elif isinstance(value, dict):
            style = " ".join(k.lower() for k in ("Bold", "Italic") if value.get(k))
            size = value.get("Size", p.Font.Size)
            self.button.setText(f'{value.get("Family", p.Font.Family)} {size:g} {style}'.strip())
        else:
            self.button.setText(self.tr("(default)"))
        self.refuse(None)

    def _dialog(self) -> None:
        try:
            f = p.font(self.value, None) if isinstance(self.value, dict) else p.Font()  # type: ignore[arg-type]
        except p.PropError:
            f = p.Font()
        start = QFont(f.Family)
        start.setPointSizeF(f.Size)
        start.setBold(f.Bold)
        start.setItalic(f.Italic)
        ok, font = QFontDialog.getFont(start, self, self.tr("Font"))
        if ok:
            self.submit(font_value(font))


def font_value(font: QFont) -> dict[str, Any]:
    size = font.pointSizeF()
    value: dict[str, Any] = {"Family": font.family(), "Size": int(size) if size.is_integer() else size}
    if font.bold():
        value["Bold"] = True
    if font.italic():
        value["Italic"] = True
    return value
