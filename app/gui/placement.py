"""Where the workstation's window is, per screen size: geometry, docks and each form's zoom.

A station is seen on a 1366x768 panel in the control room and on a 1920x1080 desk: what the
operator arranged on one must not spoil the other ("fit width" chosen on the desk opened scrolled
to the middle on the panel), so everything is kept under the size of the screen it was chosen on,
beside the station's archive (a folder the station writes), in `workstation.ini`. The first start
on a screen size opens maximized; the operator mode (`--fullscreen`, `[operator] fullscreen`)
opens full screen with no window chrome, whatever was kept.
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QByteArray, QSettings, QSize
from PySide6.QtGui import QGuiApplication
from PySide6.QtWidgets import QMainWindow

from app.gui.zoom import FIT_WINDOW


def screen_key(size: QSize | None) -> str:
    """The settings group of a screen size ("1366x768"); "any" when there is no screen."""
    return "any" if size is None else f"{size.width()}x{size.height()}"


def primary_size() -> QSize | None:
    screen = QGuiApplication.primaryScreen()
    return None if screen is None else screen.size()


class Placement:
    """The settings of one screen size."""

    def __init__(self, file: Path, screen: QSize | None) -> None:
        self.settings = QSettings(str(file), QSettings.Format.IniFormat)
        self.group = screen_key(screen)

    def zoom(self, form: Path) -> str:
        return str(self.settings.value(f"{self.group}/zoom/{form.name}", FIT_WINDOW))

    def put_zoom(self, form: Path, choice: str) -> None:
        """Kept when it changes, written when QSettings writes (soon after, or at `save`): a form
        view says its zoom at every resize, the same choice each time but the operator's."""
        if choice != self.zoom(form):
            self.settings.setValue(f"{self.group}/zoom/{form.name}", choice)

    def docks_collapsed(self) -> bool | None:
        """Whether the docks were left collapsed on this screen size; None: never chosen here."""
        value = self.settings.value(f"{self.group}/docks_collapsed")
        return None if value is None else str(value).lower() == "true"

    def put_docks_collapsed(self, collapsed: bool) -> None:
        if collapsed != self.docks_collapsed():
            self.settings.setValue(f"{self.group}/docks_collapsed", collapsed)

    def restore(self, window: QMainWindow) -> bool:
        """The geometry and docks kept for this screen size; False at the first start on it."""
        geometry = self.settings.value(f"{self.group}/geometry")
        if not isinstance(geometry, QByteArray) or not window.restoreGeometry(geometry):
            return False
        state = self.settings.value(f"{self.group}/state")
        if isinstance(state, QByteArray):
            window.restoreState(state)
        return True

    def save(self, window: QMainWindow) -> None:
        """The window's geometry and docks, and whatever else was kept, on disk now (at its close)."""
        self.settings.setValue(f"{self.group}/geometry", window.saveGeometry())
        self.settings.setValue(f"{self.group}/state", window.saveState())
        self.settings.sync()

    def show(self, window: QMainWindow, fullscreen: bool) -> str:
        """Show the window as kept, maximized the first time, or full screen in the operator
        mode; returns how ("fullscreen", "restored", "maximized")."""
        if fullscreen:
            window.showFullScreen()
            return "fullscreen"
        if self.restore(window):
            window.show()
            return "restored"
        window.showMaximized()
        return "maximized"
