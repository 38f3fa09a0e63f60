"""The alarm and journal docks, collapsible to a strip that still counts.

On a 1366x768 screen the docks took 190 px of the 768, and the picture is what the operator
watches. Collapsed, a dock keeps its title bar and its tab (the alarm dock's title counts the
unacknowledged alarms, and the banner in the header shows the first of them), and its contents
give their height to the forms; a click on the strip, View → Collapse docks (F9) or the next
start on a screen of the same size (app/gui/placement.py keeps the choice) brings them back.
The first start on a screen less than 900 px high starts collapsed.
"""

from __future__ import annotations

from collections.abc import Sequence

from PySide6.QtCore import QEvent, QObject, Qt
from PySide6.QtWidgets import QDockWidget, QLabel, QMainWindow, QTabBar

SMALL_SCREEN = 900  # px high: below it the docks start collapsed


class DockStrip(QObject):
    def __init__(self, window: QMainWindow, docks: Sequence[QDockWidget], height: int) -> None:
        super().__init__(window)
        self.window, self.docks, self.height = window, list(docks), height
        self.collapsed = False
        for dock in self.docks:
            dock.installEventFilter(self)

    def set_collapsed(self, collapsed: bool) -> None:
        self.collapsed = collapsed
        for dock in self.docks:
            inner = dock.widget()
            if inner is not None:
                inner.setVisible(not collapsed)
            dock.setTitleBarWidget(_strip(dock) if collapsed else None)
        self._tabs_follow()
        heights = [1 if collapsed else self.height] * len(self.docks)  # 1: as small as the title lets it
        self.window.resizeDocks(self.docks, heights, Qt.Orientation.Vertical)

    def toggle(self) -> None:
        self.set_collapsed(not self.collapsed)

    def _tabs_follow(self) -> None:
        """A click on a tabified dock's tab while collapsed opens the docks (the window makes the
        tab bars as docks are tabified: they are found, not made)."""
        for bar in self.window.findChildren(QTabBar):
            if bar.parent() is self.window and not bar.property("dockStrip"):
                bar.setProperty("dockStrip", True)
                bar.tabBarClicked.connect(self._tab_clicked)

    def _tab_clicked(self, _index: int) -> None:
        if self.collapsed:
            self.set_collapsed(False)

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if self.collapsed and event.type() == QEvent.Type.MouseButtonPress:
            self.set_collapsed(False)
            return True
        return False


def _strip(dock: QDockWidget) -> QLabel:
    """A collapsed dock's title: its title (with its count), a line high, following the dock's."""
    label = QLabel(dock.windowTitle())
    label.setObjectName("dockStrip")
    label.setStyleSheet("#dockStrip { background: #c3c9d2; color: #263445; font-weight: bold; "
                        "padding: 3px 8px; }")
    dock.windowTitleChanged.connect(label.setText)
    return label
