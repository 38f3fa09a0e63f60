"""The workstation's look: a calm grey plant-room palette where only state colours stand out.

Operators watch these screens for hours; colour is kept for meaning (red alarm, amber attention,
green healthy) so that a change of state is what catches the eye.
"""

from __future__ import annotations

from PySide6.QtGui import QFont
from PySide6.QtWidgets import QApplication

STYLE = """
QMainWindow, #central { background: #d9dde3; }
#header { background: #263445; border-bottom: 2px solid #3d7bd9; }

#headerTitle { color: #ffffff; font-size: 13pt; font-weight: bold; }
#headerLabel { color: #b8c4d4; }
#headerClock { color: #ffffff; font-family: "DejaVu Sans Mono"; font-size: 10pt; }
#headerUser { color: #ffffff; font-weight: bold; padding-right: 4px; }
#headerLogin { padding: 3px 12px; }
#alarmBanner { background: #b71c1c; border-bottom: 1px solid #7f0000; }
#alarmBanner[blink="true"] { background: #d32f2f; }
#alarmIcon { color: #ffeb3b; font-size: 16pt; }
#alarmText { color: #ffffff; font-size: 11pt; font-weight: bold; }
#alarmCount { color: #b71c1c; background: #ffcdd2; font-weight: bold; border-radius: 9px; padding: 1px 7px;
              margin: 0 6px; }
#alarmAck { background: #ffffff; color: #b71c1c; font-weight: bold; border: 1px solid #7f0000;
            border-radius: 3px; padding: 4px 8px; }
#alarmAck:hover { background: #ffebee; }
#alarmAck:disabled { background: #e8b4b4; color: #7f3b3b; }
#healthStrip { background: #ffe082; border-bottom: 1px solid #c79a00; }
#healthText { color: #4e3b00; font-weight: bold; }
#healthDetails { padding: 1px 10px; }
#quietLine { color: #9fb0c4; }
QTabWidget#forms::pane { border: none; background: #d9dde3; }
QTabBar::tab { background: #c3c9d2; color: #263445; padding: 7px 18px; margin-right: 1px;
               border-top-left-radius: 3px; border-top-right-radius: 3px; }
QTabBar::tab:selected { background: #f4f6f8; font-weight: bold; border-bottom: 3px solid #3d7bd9; }
QTabBar::tab:hover:!selected { background: #d3d8df; }
QStatusBar { background: #263445; color: #dde3ea; }
QStatusBar::item { border: none; }
#pill { border-radius: 9px; padding: 2px 10px; margin: 3px 2px; color: #ffffff;
        font-family: "DejaVu Sans Mono"; font-size: 9pt; }
#pill[level="ok"] { background: #2e7d32; }
#pill[level="warn"] { background: #b7791f; }
#pill[level="bad"] { background: #c62828; }
#pill[level="idle"] { background: #546173; }
QDockWidget { font-weight: bold; color: #263445; }
QDockWidget::title { background: #c3c9d2; padding: 4px 8px; }
QTableView { background: #ffffff; alternate-background-color: #f3f5f8; gridline-color: #dfe3e8;
             selection-background-color: #3d7bd9; font-size: 9pt; }
QHeaderView::section { background: #e6e9ee; color: #263445; border: none;
                       border-right: 1px solid #cfd5dc; padding: 3px 6px; font-weight: bold; }
"""


def apply_style(app: QApplication) -> None:
    """Idempotent: replacing the QStyle of a running application deletes the one its widgets use."""
    if app.property("netplc_styled"):
        return
    app.setProperty("netplc_styled", True)
    app.setStyle("Fusion")
    font = QFont("DejaVu Sans", 9)
    app.setFont(font)
    app.setStyleSheet(STYLE)
