"""The operator console on the demo station: a screen that does not move under the hand, and
fits a 1366x768 screen whatever the forms hold."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from PySide6.QtWidgets import QPlainTextEdit

from app.config import load_station
from app.gui.main_window import MainWindow
from app.runtime import Runtime

LEVEL = 0o4010
BROKEN = ('{"form": {"title": "broken", "width": 100, "height": 100}, "elements": [{"type": "StaticText", '
          '"Name": "' + "a_very_long_element_name_" * 40 + '", "x": "not a number"}]}')


@pytest.fixture
def console(qtbot, demo_copy: Path) -> Iterator[MainWindow]:
    (demo_copy / "forms" / "99_broken.hmi").write_text(BROKEN, encoding="utf-8")
    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    window = MainWindow(runtime)
    qtbot.addWidget(window)
    window.resize(1366, 768)
    window.show()
    try:
        yield window
    finally:
        window.close()
        runtime.stop()


def test_a_broken_form_does_not_widen_the_window(qtbot, console: MainWindow) -> None:
    qtbot.waitUntil(lambda: console.health.isVisible(), timeout=5000)
    assert "a_very_long_element_name_" in console.health.label.text()
    assert console.minimumSizeHint().width() <= 1366
    assert console.width() == 1366
    assert console.health.label.shown().endswith("…")  # elided, the whole of it one click away
    dialog = console.health.show_details()
    details = dialog.findChild(QPlainTextEdit)
    assert "a_very_long_element_name_" in details.toPlainText()
    dialog.close()


def test_the_forms_stay_put_when_an_alarm_comes(qtbot, console: MainWindow) -> None:
    runtime = console.runtime
    qtbot.waitUntil(lambda: runtime.status().nodes_up == 1, timeout=10_000)
    top = console.tabs.mapTo(console, console.tabs.rect().topLeft())
    assert not console.alarms.alarms
    runtime.simulators[0].engine.write_word(LEVEL, 3700)
    qtbot.waitUntil(lambda: bool(console.alarms.alarms), timeout=5000)
    qtbot.wait(50)
    assert console.alarms.isVisible()
    assert console.tabs.mapTo(console, console.tabs.rect().topLeft()) == top
    console.alarms.acknowledge_all()
    qtbot.wait(50)
    assert console.tabs.mapTo(console, console.tabs.rect().topLeft()) == top
