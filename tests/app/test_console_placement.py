"""The window as kept per screen size: maximized the first time, restored after, full screen in
the operator mode; the zoom of a form chosen on one screen size does not follow to another."""

from __future__ import annotations

import configparser
from pathlib import Path

from PySide6.QtCore import QCoreApplication, QSize, Qt
from PySide6.QtWidgets import QDockWidget, QLabel, QMainWindow

from app.gui.placement import Placement, primary_size, screen_key
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


def on_disk(ini: Path, group: str) -> dict[str, str]:
    """What the ini file holds for a screen size, read from the disk: a QSettings of this process
    would answer from the cache it shares with the window's."""
    kept = configparser.ConfigParser(interpolation=None)
    kept.optionxform = str  # type: ignore[assignment,method-assign]
    kept.read(ini, encoding="utf-8")
    return dict(kept[group]) if kept.has_section(group) else {}


def test_a_resize_writes_nothing_and_the_last_zoom_chosen_is_on_disk_after_the_close(
        qtbot, demo_copy: Path) -> None:
    """A form view says its zoom at every resize: the ini file is written when the choice changes
    (by QSettings, at its own time), not per resize event; a choice made just before the window
    closes is on disk after the close."""
    from app.gui.main_window import MainWindow
    from app.station.runtime import Runtime

    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    window = MainWindow(runtime)
    ini, group = runtime.station.Archive.parent / "workstation.ini", screen_key(primary_size())
    try:
        qtbot.addWidget(window)
        window.resize(1366, 768)
        window.show()
        analog = next(a for a in window.zooms if a.form_view.form.path.stem == "02_analog")
        key = f"zoom\\{analog.form_view.form.path.name}"
        window.tabs.setCurrentWidget(analog)
        analog.set_mode(FIT_WIDTH)
        qtbot.waitUntil(lambda: ini.exists() and on_disk(ini, group).get(key) == FIT_WIDTH, timeout=10_000)
        written = ini.stat().st_mtime_ns
        for width in (1100, 1300, 1150, 1366):
            was = analog.viewport().width()
            window.resize(width, 768)
            qtbot.waitUntil(lambda w=was: analog.viewport().width() != w, timeout=5000)
            QCoreApplication.processEvents()  # where QSettings would write what changed
        assert ini.stat().st_mtime_ns == written, "the ini file was written at a resize"
        analog.zoom_by(1)
        window.close()
        assert on_disk(ini, group)[key] == analog.choice != FIT_WIDTH
    finally:
        window.close()
        runtime.stop()


def test_the_operator_mode_is_a_station_toml_key(tmp_path: Path) -> None:
    write_station(tmp_path, 'NetPlcLoad = false\n[operator]\nfullscreen = true\n')
    assert load_station(tmp_path).operator.fullscreen
    write_station(tmp_path, 'NetPlcLoad = false\n')
    assert not load_station(tmp_path).operator.fullscreen


def test_the_docks_collapse_to_a_strip_and_the_forms_get_the_height(qtbot, demo_copy: Path) -> None:
    from app.gui.main_window import MainWindow
    from app.station.runtime import Runtime

    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    window = MainWindow(runtime)
    try:
        qtbot.addWidget(window)
        window.resize(1366, 768)
        window.show()
        qtbot.waitUntil(lambda: window.tabs.height() > 300, timeout=5000)
        open_height = window.tabs.height()
        window.dock_strip.set_collapsed(True)
        qtbot.waitUntil(lambda: window.tabs.height() > open_height + 100, timeout=5000)
        assert window.summary_dock.isVisible() and not window.summary.isVisible()  # the strip stays
        assert window.summary_dock.height() < 60
        analog = next(a for a in window.zooms if a.form_view.form.path.stem == "02_analog")
        window.tabs.setCurrentWidget(analog)  # drawn for the 1366x768 operator screen: shown nearly 1:1
        qtbot.waitUntil(lambda: analog.transform().m11() > 0.95, timeout=5000)
        qtbot.mousePress(window.summary_dock, Qt.MouseButton.LeftButton)  # a click on the strip opens
        qtbot.waitUntil(lambda: window.summary.isVisible(), timeout=5000)
        window.dock_strip.set_collapsed(True)
        window.close()
        kept = Placement(runtime.station.Archive.parent / "workstation.ini", primary_size())
        assert kept.docks_collapsed() is True  # and so it opens next time on this screen size
    finally:
        window.close()
        runtime.stop()


def test_the_analog_form_at_the_operator_screen_has_no_text_under_12_px(qtbot, demo_copy: Path,
                                                                         monkeypatch) -> None:
    """The demo's analog form at 1366x768 in the operator mode (docks folded): shown at 1:1, its
    smallest text (the gauges' names, the trend's axes, the clock's date) 12 px or more."""
    from app.gui.main_window import MainWindow
    from app.station.runtime import Runtime
    from hmi_forms.widgets import theme

    sizes: list[float] = []
    real = theme.sized_font

    def spy(size_px: float, bold: bool = False, family: str = theme.FAMILY):
        sizes.append(size_px)
        return real(size_px, bold, family)

    monkeypatch.setattr(theme, "sized_font", spy)
    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    window = MainWindow(runtime)
    try:
        qtbot.addWidget(window)
        window.resize(1366, 768)
        window.dock_strip.set_collapsed(True)
        window.show()
        analog = next(a for a in window.zooms if a.form_view.form.path.stem == "02_analog")
        qtbot.waitUntil(lambda: window.tabs.currentWidget() is not None, timeout=5000)
        sizes.clear()
        window.tabs.setCurrentWidget(analog)
        qtbot.waitUntil(lambda: analog.transform().m11() > 0.99, timeout=5000)
        qtbot.waitUntil(lambda: len(sizes) > 20, timeout=10_000)  # drawn
        qtbot.wait(300)
        assert min(sizes) * analog.transform().m11() >= 12.0
    finally:
        window.close()
        runtime.stop()
