"""A tag's faceplate, opened from an element of the demo's forms: the live value with its
quality and unit, the tag's alarms, a trend, and the actions the user's role allows, each a
command of the station's layer."""

from __future__ import annotations

from PySide6.QtCore import Qt

from app.gui.faceplate import Faceplate
from app.gui.main_window import MainWindow
from tests.app.test_console import Answers, console, element, shared_console  # noqa: F401 - fixtures

SETPOINT = 0o4030


def open_plate(qtbot, window: MainWindow, name: str) -> Faceplate:
    _, widget = element(window, name)
    qtbot.mouseDClick(widget, Qt.MouseButton.LeftButton)
    plate = window.faceplates.open[window.faceplates.bound[widget].name]
    assert isinstance(plate, Faceplate) and plate.isVisible()
    return plate


def test_a_double_click_opens_the_tags_faceplate_live(qtbot, console: MainWindow) -> None:  # noqa: F811
    plate = open_plate(qtbot, console, "Температура")
    assert plate.tag.name == "TEMP" and "Температура" in plate.windowTitle() + plate.findChild(
        type(plate.value), "faceplateTitle").text()
    qtbot.waitUntil(lambda: plate.value.text().endswith("°C") and plate.quality.text() == "good",
                    timeout=10_000)
    assert set(plate.alarm_rows) == {"TEMP.HH", "TEMP.H", "TEMP.BAD"}  # limits and quality
    qtbot.waitUntil(lambda: plate.points() >= 2, timeout=10_000)  # the trend runs
    assert plate.set.isHidden()  # a measurement: no form sets it, nor does its faceplate
    assert not plate.force.isEnabled() and "needs the engineer role" in plate.force.toolTip()
    plate.grab()
    again = open_plate(qtbot, console, "Температура, °C")  # one faceplate per tag
    assert again is plate


def test_the_faceplate_sets_forces_and_unforces_as_the_user_on_duty(qtbot, console: MainWindow) -> None:  # noqa: F811
    engine = console.runtime.engine
    console.login("operator", "operator")
    plate = open_plate(qtbot, console, "Уставка температуры")
    assert plate.tag.name == "TEMP_SP" and not plate.set.isHidden()
    qtbot.waitUntil(lambda: plate.set.isEnabled(), timeout=5000)
    assert not plate.force.isEnabled()
    plate.entry.setText("100")
    plate.set_value()
    qtbot.waitUntil(lambda: engine.snapshot.get_word(SETPOINT) == round(150 / 200 * 4095), timeout=5000)
    plate.entry.setText("900")  # outside PhyMin..PhyMax: the layer refuses, in words
    plate.set_value()
    qtbot.waitUntil(lambda: "outside" in plate.message.text(), timeout=5000)

    console.login("engineer", "engineer")
    qtbot.waitUntil(lambda: plate.force.isEnabled(), timeout=5000)
    console.ask = asked = Answers(True)
    plate.force_entry.setText("1000")
    assert plate.force_value() is None and not asked.asked  # refused before asking
    assert plate.message.text() == ("TEMP_SP is not forced: 1000.0 °C is outside its range "
                                    "-50.0 °C .. 150.0 °C")
    plate.force_entry.setText("20")
    plate.force_value()
    assert asked.asked[-1].startswith("Force: Force TEMP_SP to 20.0 °C?")
    qtbot.waitUntil(lambda: plate.forced.text() == "F forced by engineer", timeout=5000)
    qtbot.waitUntil(lambda: plate.value.text() == "20.0 °C", timeout=5000)
    plate.unforce_value()
    assert asked.asked[-1] == ("Unforce: Unforce TEMP_SP? The memory keeps 20.0 °C, the forced value, until "
                               "the program, a node or an operator writes it.")
    qtbot.waitUntil(lambda: plate.forced.text() == "", timeout=5000)
    assert plate.value.text() == "20.0 °C"  # the forced value stays
