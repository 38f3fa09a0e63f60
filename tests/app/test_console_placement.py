"""The window as kept per screen size: maximized the first time, restored after, full screen in
the operator mode; the zoom of a form chosen on one screen size does not follow to another."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QSize, Qt
from PySide6.QtWidgets import QDockWidget, QLabel, QMainWindow

from app.gui.placement import Placement
from app.gui.zoom import FIT_WIDTH, FIT_WINDOW
from app.station.config import load_station
from tests.app.conftest import write_station

PANEL, DESK = QSize(1366, 768), QSize(1920, 1080)


def window(qtbot) -> QMainWindow:
    w = QMainWindow()
    w.setCentralWidget(QLabel("form"))
    dock = QDockWidget("Journal", w)
    dock.setObjectName("journal")
    w.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, dock)
    qtbot.addWidget(w)
    return w


def test_first_start_maximized_then_as_kept_per_screen_size(qtbot, tmp_path: Path) -> None:
    ini = tmp_path / "workstation.ini"
    first = window(qtbot)
    assert Placement(ini, PANEL).show(first, fullscreen=False) == "maximized"
    assert first.isMaximized()
    first.showNormal()
    first.setGeometry(40, 50, 800, 500)
    Placement(ini, PANEL).save(first)
    again = window(qtbot)
    assert Placement(ini, PANEL).show(again, fullscreen=False) == "restored"
    # as kept, give or take the frame the platform adds
    qtbot.waitUntil(lambda: abs(again.width() - 800) <= 8 and abs(again.height() - 500) <= 8, timeout=5000)
    assert not again.isMaximized()
    assert Placement(ini, DESK).show(window(qtbot), fullscreen=False) == "maximized"  # another screen
    operator = window(qtbot)
    assert Placement(ini, PANEL).show(operator, fullscreen=True) == "fullscreen"
    assert operator.isFullScreen()


def test_the_zoom_is_kept_per_screen_size(tmp_path: Path) -> None:
    ini, form = tmp_path / "workstation.ini", tmp_path / "forms" / "02_analog.hmi"
    Placement(ini, DESK).put_zoom(form, FIT_WIDTH)
    assert Placement(ini, DESK).zoom(form) == FIT_WIDTH
    assert Placement(ini, PANEL).zoom(form) == FIT_WINDOW


def test_the_operator_mode_is_a_station_toml_key(tmp_path: Path) -> None:
    write_station(tmp_path, 'NetPlcLoad = false\n[operator]\nfullscreen = true\n')
    assert load_station(tmp_path).operator.fullscreen
    write_station(tmp_path, 'NetPlcLoad = false\n')
    assert not load_station(tmp_path).operator.fullscreen
