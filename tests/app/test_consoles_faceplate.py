"""A tag's faceplate at a remote console: the workstation's own faceplate, opened from the same
elements, its data the station's (the tag's part of the memory watched while it is open, the hour
from the station's Historical Access, the alarms as the console lists them) and every action the
station's command as the console's user. The demo station runs headless on loopback; the consoles
are real asyncua clients of it, their windows really rendered (tests/app/test_consoles.py)."""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np
import pytest
from PySide6.QtCore import Qt

from app.gui.console.window import ConsoleWindow
from app.gui.faceplate import Faceplate
from app.publish.memory_items import ranges_of
from netplc.records import Record
from registrar.store import Store
from tests.app.conftest import copy_demo
from tests.app.test_console import Answers, element
from tests.app.test_consoles import ANALOG, WAIT, Attach, Station, attach, serving, watched  # noqa: F401

TEMP_RAW = 0o4012  # TEMP's word (0..1000 raw = -50..150 °C)
SETPOINT = 0o4030  # TEMP_SP's word (0..4095 raw = -50..150 °C)


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Station, list[float]]]:
    """The demo station whose archive holds TEMP's NSTORE series of the half hour before it started:
    a raw 500 (50.0 °C) a minute."""
    folder = tmp_path_factory.mktemp("faceplate")
    store = Store(copy_demo(folder / "st") / "archive" / "journal.sqlite")
    store.start()
    now = time.time()
    times = [now - 1800 + 60 * k for k in range(25)]
    for ts in times:
        store.put(Record(ts, "data", grp=1, type=2, source="04012", value=500))
    store.close()
    with serving(folder) as st:
        yield st, times


def open_plate(qtbot, window: ConsoleWindow, name: str) -> Faceplate:
    """The faceplate of the element `name` of the analog form, opened as an operator does."""
    window.tabs.setCurrentIndex(ANALOG)
    _, widget = element(window, name)  # type: ignore[arg-type]
    qtbot.mouseDClick(widget, Qt.MouseButton.LeftButton)
    assert window.faceplates is not None
    tag = window.faceplates.bound[widget]
    plate = window.faceplates.open[tag.name]
    assert plate.isVisible()
    return plate


def test_the_consoles_faceplate_shows_the_stations_value_and_hour_and_watches_its_tag_while_open(
        qtbot, station: tuple[Station, list[float]], attach: Attach) -> None:  # noqa: F811
    st, times = station
    console = attach(st, "viewer")
    plate = open_plate(qtbot, console, "Температура")
    temp = plate.tag
    assert temp.name == "TEMP" and set(plate.alarm_rows) == {"TEMP.HH", "TEMP.H", "TEMP.BAD"}
    qtbot.waitUntil(lambda: plate.quality.text() == "good" and plate.value.text() == temp.format(
        st.runtime.readings().tag("TEMP").value), timeout=WAIT)  # the station's value, with its unit
    assert plate.value.text().endswith(" °C")
    if time.time() - times[0] < 3600:  # (the hour read from the station's history)
        qtbot.waitUntil(lambda: np.isin(np.round(times, 3), np.round(plate.times, 3)).all(), timeout=WAIT)
        at = np.isin(np.round(plate.times, 3), np.round(times, 3))
        assert plate.values[at] == pytest.approx(50.0)
    qtbot.waitUntil(lambda: plate.points() >= len(times) + 2, timeout=WAIT)  # the hour, then live
    assert plate.set.isHidden()  # a measurement: no form sets it, nor does its faceplate
    qtbot.waitUntil(lambda: not plate.force.isEnabled(), timeout=WAIT)  # as the station answers

    operand = ranges_of([temp.operand])
    console.tabs.setCurrentIndex(0)  # a form without TEMP: the open faceplate keeps it watched
    qtbot.waitUntil(lambda: watched(st, console) == console.reads[0] | operand, timeout=WAIT)
    shown = len(plate.live_t)
    qtbot.waitUntil(lambda: len(plate.live_t) > shown, timeout=WAIT)  # and live
    plate.close()
    qtbot.waitUntil(lambda: watched(st, console) == console.reads[0], timeout=WAIT)  # released
    assert console.client.wanted == console.reads[0]


def test_the_consoles_faceplate_sets_forces_and_unforces_as_the_user_at_the_station_a_viewer_is_refused(
        qtbot, station: tuple[Station, list[float]], attach: Attach) -> None:  # noqa: F811
    st, _ = station
    engine = st.runtime.engine
    assert engine is not None
    viewer = attach(st, "viewer")
    plate = open_plate(qtbot, viewer, "Уставка температуры")
    assert plate.tag.name == "TEMP_SP" and not plate.set.isHidden()
    qtbot.waitUntil(lambda: not plate.set.isEnabled() and not plate.entry.isEnabled(), timeout=WAIT)
    assert "needs the operator role" in plate.set.toolTip()
    plate.entry.setText("50")  # were it sent, the station refuses it
    plate.set_value()
    qtbot.waitUntil(lambda: "needs the operator role; viewer is viewer" in plate.message.text(), timeout=WAIT)
    assert engine.snapshot.get_word(SETPOINT) != round(100 / 200 * 4095)

    operator = attach(st, "operator")
    plate = open_plate(qtbot, operator, "Уставка температуры")
    qtbot.waitUntil(lambda: plate.set.isEnabled(), timeout=WAIT)
    plate.entry.setText("50")
    plate.set_value()
    qtbot.waitUntil(lambda: engine.snapshot.get_word(SETPOINT) == round(100 / 200 * 4095), timeout=WAIT)
    written = [r for r in st.records if r.kind == "operator" and (r.text or "").startswith("запись ")
               and "TEMP_SP" in (r.text or "")]
    assert written and (written[-1].source or "").startswith("opcua:operator@")
    assert "-> 50.0 °C" in (written[-1].text or "")
    qtbot.waitUntil(lambda: plate.value.text() == "50.0 °C", timeout=WAIT)  # shown back from the station
    plate.entry.setText("900")  # outside PhyMin..PhyMax: the station refuses it
    plate.set_value()
    # Bad_OutOfRange carries no text: the console says it as the station's layer does, with the range
    qtbot.waitUntil(lambda: "900.0 вне диапазона -50.0 °C .. 150.0 °C" in plate.message.text(), timeout=WAIT)
    assert not plate.force.isEnabled()

    engineer = attach(st, "engineer")
    plate = open_plate(qtbot, engineer, "Уставка температуры")
    qtbot.waitUntil(lambda: plate.force.isEnabled(), timeout=WAIT)
    engineer.ask = asked = Answers(True)
    plate.force_entry.setText("20")
    plate.force_value()
    assert asked.asked[-1].startswith("Force: Force TEMP_SP to 20.0 °C?")
    qtbot.waitUntil(lambda: plate.forced.text().startswith("F forced by opcua:engineer@")
                    and plate.value.text() == "20.0 °C", timeout=WAIT)
    forced = [r for r in st.records if r.kind == "operator" and (r.text or "").startswith("фиксация TEMP_SP")]
    assert forced and (forced[-1].source or "").startswith("opcua:engineer@")
    plate.unforce_value()
    qtbot.waitUntil(lambda: plate.forced.text() == "", timeout=WAIT)
    assert engine.forces.count == 0
