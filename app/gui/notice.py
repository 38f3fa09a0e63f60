"""Words the operator must read whole: a confirmation's question, a refusal.

A confirmation's title used to be the window title of a small message box, cut by the window
manager ("Stop NetP…"), and a refusal the status bar's message, cut where the status pills begin
("Refused: Quit: needs"). The question now carries its title in bold in the box itself, and a
refusal also shows as a note over the bottom of the window, wrapped to its width, for as long as
the status bar keeps it.
"""

from __future__ import annotations

from PySide6.QtCore import QEvent, QObject, Qt, QTimer
from PySide6.QtWidgets import QLabel, QMessageBox, QWidget

MARGIN = 10


def confirm(parent: QWidget | None, title: str, text: str) -> bool:
    """Yes or No to `text`, with `title` in bold at the top of the box (never cut)."""
    box = QMessageBox(QMessageBox.Icon.Question, title, f"<b>{title}</b>", QMessageBox.StandardButton.Yes
                      | QMessageBox.StandardButton.No, parent)
    box.setTextFormat(Qt.TextFormat.RichText)
    box.setInformativeText(text)
    box.setDefaultButton(QMessageBox.StandardButton.No)
    return box.exec() == QMessageBox.StandardButton.Yes


class Note(QLabel):
    """A wrapped note over the bottom of `parent`, hidden again after a while or on a click."""

    def __init__(self, parent: QWidget) -> None:
        super().__init__(parent)
        self.setObjectName("note")
        self.setWordWrap(True)
        self.setStyleSheet("#note { background: #b71c1c; color: #ffffff; font-weight: bold; "
                           "padding: 6px 10px; border-radius: 4px; }")
        self.timer = QTimer(self)
        self.timer.setSingleShot(True)
        self.timer.timeout.connect(self.hide)
        parent.installEventFilter(self)
        self.hide()

    def say(self, text: str, ms: int) -> None:
        self.setText(text)
        self._place()
        self.show()
        self.raise_()
        self.timer.start(ms)

    def _place(self) -> None:
        self.ensurePolished()  # the style sheet's padding counts in the height, from the first note on
        parent = self.parentWidget()
        assert parent is not None
        width = max(100, parent.width() - 2 * MARGIN)
        self.setFixedWidth(width)
        height = self.heightForWidth(width)
        self.setFixedHeight(height if height > 0 else self.sizeHint().height())
        self.move(MARGIN, parent.height() - self.height() - MARGIN)

    def mousePressEvent(self, event: object) -> None:
        self.hide()

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.Resize and self.isVisible():
            self._place()
        return False
