"""The AnalogOutput widget: the present value, an entry field, and a message line.

The model checks the entry (a number, inside PhyMin..PhyMax) before anything is written. Typing
is not blocked by a validator: a refused entry must be explained, not silently eaten. A
rejected entry stays in the field, marked red, with the reason in words below it, so the operator
can correct it. An accepted one shows the value actually written (after conversion to the
hardware word).
"""

from __future__ import annotations

from PySide6.QtCore import QT_TRANSLATE_NOOP, QCoreApplication, Qt
from PySide6.QtWidgets import QHBoxLayout, QLabel, QLineEdit, QPushButton, QVBoxLayout, QWidget

from hmi_forms.elements.analog import AnalogOutput
from hmi_forms.elements.sentence import Sentence
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import Images, SelfPainted

OK_STYLE = f"color: {theme.ON.name()};"
BAD_STYLE = f"color: {theme.ALARM.name()}; font-weight: bold;"
EDIT_BAD = f"QLineEdit {{ border: 2px solid {theme.ALARM.name()}; background: #fdecea; }}"
SENTENCES = (  # the model's (hmi_forms/elements/analog.py), for the translations
    QT_TRANSLATE_NOOP("AnalogOutput", "Input is disabled for this element"),
    QT_TRANSLATE_NOOP("AnalogOutput", '"{0}" is not a number'),
    QT_TRANSLATE_NOOP("AnalogOutput", "{0} is out of range {1} … {2}{3}"),
    QT_TRANSLATE_NOOP("AnalogOutput", "Set to {0}{1}"),
)


def said(text: str) -> str:
    """The model's sentence in the console's language; a refusal comes translated already."""
    if isinstance(text, Sentence):
        return QCoreApplication.translate("AnalogOutput", text.source).format(*text.values)
    return text


class AnalogOutputWidget(SelfPainted):
    model: AnalogOutput

    def __init__(self, model: AnalogOutput, images: Images, parent: QWidget | None = None) -> None:
        super().__init__(model, images, parent)
        lo, hi = model.scaling.phy_range
        units = f" {model.Units}" if model.Units else ""
        layout = QVBoxLayout(self)
        layout.setContentsMargins(6, 4, 6, 4)
        layout.setSpacing(3)
        head = QHBoxLayout()
        name = QLabel(model.Name)
        name.setFont(theme.sized_font(12, bold=True))
        name.setStyleSheet(f"color: {theme.TEXT_DIM.name()};")
        self.current = QLabel("---")
        self.current.setFont(theme.sized_font(13, bold=True, family=theme.MONO))
        self.current.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        head.addWidget(name)
        head.addWidget(self.current, 1)
        layout.addLayout(head)
        row = QHBoxLayout()
        self.edit = QLineEdit()
        self.edit.setPlaceholderText(f"{model.format(lo)} … {model.format(hi)}{units}")
        self.edit.setFont(theme.sized_font(13, family=theme.MONO))
        self.edit.setEnabled(model.Enabled)
        self.edit.returnPressed.connect(self.submit)
        self.edit.textEdited.connect(self._clear_mark)
        self.button = QPushButton(QCoreApplication.translate("AnalogOutput", "Set"))
        self.button.setEnabled(model.Enabled)
        self.button.clicked.connect(self.submit)
        row.addWidget(self.edit, 1)
        row.addWidget(self.button)
        layout.addLayout(row)
        self.message = QLabel("")
        self.message.setFont(theme.sized_font(12))
        self.message.setWordWrap(True)
        layout.addWidget(self.message)
        layout.addStretch(1)
        self.stale_mark.raise_()
        word = oct(model.OutAddr or 0)[2:].rjust(5, "0")
        tip = QCoreApplication.translate("AnalogOutput", "{0}: writes word {1}; range {2} … {3}{4}")
        self.setToolTip(tip.format(model.Name, word, model.format(lo), model.format(hi), units))

    def sync(self) -> None:
        units = f" {self.model.Units}" if self.model.Units else ""
        self.current.setText((self.model.text or "---") + units)
        super().sync()

    def submit(self) -> None:
        ok, text = self.model.submit(self.edit.text())
        self.message.setText(said(text))
        self.message.setStyleSheet(OK_STYLE if ok else BAD_STYLE)
        self.edit.setStyleSheet("" if ok else EDIT_BAD)
        if ok:
            self.edit.clear()

    def _clear_mark(self) -> None:
        self.edit.setStyleSheet("")
