"""A confirmation carries its title in the box itself, where no window manager cuts it."""

from __future__ import annotations

from PySide6.QtCore import QTimer
from PySide6.QtWidgets import QApplication, QMessageBox, QWidget

from app.gui.notice import confirm


def test_a_confirmation_shows_its_title_in_bold_and_defaults_to_no(qtbot) -> None:
    parent = QWidget()
    qtbot.addWidget(parent)
    seen: list[tuple[str, str, str]] = []

    def answer() -> None:
        box = QApplication.activeModalWidget()
        assert isinstance(box, QMessageBox)
        seen.append((box.windowTitle(), box.text(), box.informativeText()))
        box.defaultButton().click()

    QTimer.singleShot(0, answer)
    title = "Stop NetPlc on the plant's main station"
    assert confirm(parent, title, "Stop the NetPlc program?") is False
    assert seen == [(title, f"<b>{title}</b>", "Stop the NetPlc program?")]


def test_a_journal_column_is_never_narrower_than_its_title(qtbot) -> None:
    from PySide6.QtCore import Qt
    from PySide6.QtGui import QFont, QFontMetrics

    from hmi_forms.widgets.records import JOURNAL_COLUMNS, RecordsModel, records_view

    model = RecordsModel(JOURNAL_COLUMNS)
    view = records_view(model, 20)
    qtbot.addWidget(view)
    bold = QFont(view.horizontalHeader().font())
    bold.setBold(True)
    metrics = QFontMetrics(bold)
    for col, column in enumerate(JOURNAL_COLUMNS):
        if column.width:
            title = model.headerData(col, Qt.Orientation.Horizontal, Qt.ItemDataRole.DisplayRole)
            assert view.horizontalHeader().sectionSize(col) > metrics.horizontalAdvance(title), title
