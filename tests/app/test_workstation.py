"""The operator workstation on the demo station: real runtime, real TCP, real archive, offscreen Qt."""

from __future__ import annotations

import datetime as dt
import itertools
import math
import sqlite3
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import pytest
from PySide6.QtCore import Qt

from app.gui.main_window import MainWindow
from app.gui.status import StationStatusBar, station_problems
from app.station.config import load_station
from app.station.runtime import NodeStatus, Runtime, RuntimeStatus
from hmi_forms.elements import Element
from hmi_forms.widgets.base import ElementWidget

START_BIT = 0o40042
LEVEL = 0o4010


@pytest.fixture
def workstation(qtbot, demo_copy: Path) -> Iterator[MainWindow]:
    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    window = MainWindow(runtime)
    qtbot.addWidget(window)
    window.show()
    window.login("operator", "operator")  # the demo opens as its viewer, who may not act
    try:
        yield window
    finally:
        window.close()
        runtime.stop()


def element(window: MainWindow, name: str) -> tuple[Element, ElementWidget]:
    for view in window.views:
        for model, widget in view.pairs:
            if model.Name == name:
                return model, widget
    raise AssertionError(f"no element {name!r} in the demo forms")


def transitions(values: list[float]) -> int:
    live = [v for v in values if not math.isnan(v)]
    return sum(a != b for a, b in itertools.pairwise(live))


def archive_rows(runtime: Runtime, kind: str) -> list[tuple]:
    con = sqlite3.connect(f"file:{runtime.station.Archive}?mode=ro", uri=True)
    try:
        return con.execute(f'SELECT source, number, text FROM "{dt.date.today():%d_%m_%Y}" WHERE kind = ?',
                           (kind,)).fetchall()
    finally:
        con.close()


def test_start_twice_changes_the_trigger_output_once(qtbot, workstation: MainWindow) -> None:
    runtime = workstation.runtime
    engine = runtime.engine
    assert engine is not None
    graph, _ = element(workstation, "TA[2]: выход триггера")
    _, button = element(workstation, "Пуск")
    qtbot.waitUntil(lambda: runtime.status().nodes_up == 1 and graph.trend.count > 3, timeout=10_000)
    qtbot.waitUntil(lambda: not math.isnan(graph.trend.last), timeout=5000)
    assert graph.trend.last == 0.0
    before = graph.trend.count

    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: engine.snapshot.get_hmi_bit(START_BIT) == 1, timeout=3000)
    qtbot.wait(400)
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: engine.snapshot.get_hmi_bit(START_BIT) == 0, timeout=3000)
    qtbot.waitUntil(lambda: graph.trend.last == 1.0, timeout=5000)
    qtbot.wait(600)  # the output must stay: the second click (a falling edge) does not count

    shown = list(graph.trend.values())[-(graph.trend.count - before):]
    assert transitions(shown) == 1
    assert graph.trend.last == 1.0
    workstation.refresh_status()
    assert workstation.status.state.text() == "NetPlc: running"


def test_an_alarm_is_shown_and_its_acknowledgement_journaled(qtbot, workstation: MainWindow) -> None:
    runtime = workstation.runtime
    qtbot.waitUntil(lambda: runtime.status().nodes_up == 1, timeout=10_000)
    workstation.login("engineer", "engineer")
    # the plant: node 0's level jumps close to the top; its program keeps it rising past 90 %
    runtime.simulators[0].engine.write_word(LEVEL, 3700)
    high = "Уровень выше 90 %"
    qtbot.waitUntil(lambda: any(a.text == high for a in workstation.alarms.alarms), timeout=5000)
    assert workstation.alarms.isVisible()
    assert high in workstation.alarms.text.text()  # the newest alarm is in front
    assert workstation.alarms.grab().toImage().pixelColor(4, 4).red() > 150  # a red banner

    banner = workstation.alarms
    button = banner.ack_all if len(banner.alarms) > 1 else banner.ack
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    assert not banner.alarms and not banner.isVisible()
    qtbot.waitUntil(lambda: not workstation.summary.unacknowledged(), timeout=3000)
    runtime.stop()  # flushes the archive
    acks = [r for r in archive_rows(runtime, "alarm") if r[0] == "MSG3" and "оператор engineer" in r[2]]
    assert len(acks) == 1 and "квитирована" in acks[0][2] and high in acks[0][2]  # one, naming it
    messages = archive_rows(runtime, "message")
    assert (None, 3, "Уровень выше 90 %") in messages


def test_a_dead_node_and_a_stopped_program_show_in_the_window(qtbot, workstation: MainWindow) -> None:
    runtime = workstation.runtime
    qtbot.waitUntil(lambda: runtime.status().nodes_up == 1, timeout=10_000)
    qtbot.waitUntil(lambda: runtime.status().scans > 35, timeout=10_000)  # past the start-up grace
    runtime.simulators[0].stop()
    qtbot.waitUntil(lambda: runtime.status().nodes_up == 0, timeout=10_000)
    runtime.stop_program("engineer")  # after the link is seen down: a stopped program sends no more requests
    text = workstation.health.label.text
    qtbot.waitUntil(lambda: "NetPlc program stopped" in text() and "no link to node 0" in text(),
                    timeout=3000)
    assert workstation.health.isVisible()
    assert workstation.status.state.property("level") == "bad"
    assert workstation.status.nodes.property("level") == "bad"


def test_a_form_element_that_fails_is_named_in_the_health_strip(qtbot, workstation: MainWindow) -> None:
    graph, _ = element(workstation, "TA[2]: выход триггера")

    def broken(*args: object) -> bool:
        raise RuntimeError("display bug")

    graph.update = broken  # type: ignore[method-assign]  # read at every refresh of its form
    text = workstation.health.label.text
    qtbot.waitUntil(lambda: 'element "TA[2]: выход триггера": update failed' in text(), timeout=5000)
    assert "display bug" in text() and workstation.health.isVisible()
    assert len(workstation.view_faults) == 1  # once, though it fails at every refresh


def test_a_failing_archive_shows_in_the_status_bar(qtbot) -> None:
    status = RuntimeStatus(
        running=True, state="running", scans=100, scan_last_ms=0.3, scan_max_ms=1.0, scan_mean_ms=0.4,
        overruns=0, tick_ms=100, nodes=(NodeStatus(0, "tcp://127.0.0.1:1", True),), records_written=10,
        records_pending=5, records_lost=7, modbus_port=None,
        problems=("archive: database or disk is full", "archive: 7 records lost (disk too slow or full)"))
    bar = StationStatusBar()
    qtbot.addWidget(bar)
    bar.show_status(status)
    assert bar.records.property("level") == "bad"
    assert bar.state.property("level") == "ok"
    assert station_problems(status) == list(status.problems)
    fault = "Modbus RTU on /dev/ttyUSB0 failed: device disconnected"
    bar.show_status(replace(status, modbus_serial="/dev/ttyUSB0", problems=(fault,)))
    assert bar.server.text() == "Modbus RTU /dev/ttyUSB0" and bar.server.property("level") == "bad"
    assert bar.server.toolTip() == fault


def test_elements_mark_a_dead_node_and_a_stopped_netplc_and_link_labels_follow_the_link(
        qtbot, workstation: MainWindow) -> None:
    runtime = workstation.runtime
    level, gauge = element(workstation, "Уровень")
    trend, _ = element(workstation, "Уровень, тренд")
    link, _ = element(workstation, "Связь")  # bound to LEVEL_OK, the NREAD's link output
    qtbot.waitUntil(lambda: runtime.status().nodes_up == 1 and not level.stale and link.value == 1,
                    timeout=10_000)
    assert level.quality == "" and "comm-fail" not in gauge.toolTip()
    form = gauge.parentWidget()  # painted elements are drawn by their form
    live = form.grab(gauge.geometry()).toImage()

    runtime.simulator_answers(0, False)  # the node that fills the level stops answering
    qtbot.waitUntil(lambda: level.quality == "comm-fail", timeout=10_000)
    assert gauge.toolTip().startswith("? comm-fail")
    qtbot.waitUntil(lambda: math.isnan(trend.trend.last), timeout=3000)  # the trend breaks its line
    assert form.grab(gauge.geometry()).toImage() != live  # greyed and hatched
    qtbot.waitUntil(lambda: link.value == 0, timeout=3000)
    runtime.simulator_answers(0, True)
    qtbot.waitUntil(lambda: level.quality == "" and link.value == 1, timeout=15_000)

    runtime.stop_program("engineer")
    qtbot.waitUntil(lambda: level.quality == "not running", timeout=5000)
    assert math.isnan(trend.trend.last) and gauge.toolTip().startswith("? not running")
    assert link.value == 1 and link.quality == ""  # the link is up: said, and not marked
    runtime.simulator_answers(0, False)  # NetPlc is stopped, its copy of the link frozen at 1...
    qtbot.waitUntil(lambda: link.value == 0, timeout=10_000)  # ...the label follows the link itself
    assert "нет связи" in link.text and not link.stale


def test_a_key_click_or_wheel_in_any_window_of_the_workstation_keeps_the_user_logged_in(
        qtbot, workstation: MainWindow) -> None:
    """Input as the window system gives it (to a window, then to its widget), in the main window and
    in a window opened from it; with none, the idle user is logged out."""
    from PySide6.QtCore import QPoint, QPointF
    from PySide6.QtGui import QWheelEvent
    from PySide6.QtTest import QTest
    from PySide6.QtWidgets import QApplication

    now = [0.0]
    session = workstation.session
    session.clock = lambda: now[0]
    session.idle = 900
    workstation.login("operator", "operator")
    qtbot.waitExposed(workstation)
    trends = workstation.open_trends()
    qtbot.waitExposed(trends)

    def idle_then(act) -> str:
        now[0] += 800
        act()
        now[0] += 200  # 1000 s after the login, 200 s after the input
        workstation.refresh_status()
        return workstation.user

    main = workstation.windowHandle()
    assert idle_then(lambda: QTest.keyClick(main, Qt.Key.Key_Shift)) == "operator"
    assert idle_then(lambda: QTest.mouseClick(trends.windowHandle(), Qt.MouseButton.LeftButton,
                                              Qt.KeyboardModifier.NoModifier, QPoint(5, 5))) == "operator"
    wheel = QWheelEvent(QPointF(5, 5), QPointF(main.mapToGlobal(QPoint(5, 5))), QPoint(), QPoint(0, -120),
                        Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier, Qt.ScrollPhase.NoScrollPhase,
                        False)
    assert idle_then(lambda: QApplication.sendEvent(main, wheel)) == "operator"
    assert idle_then(lambda: None) == "viewer"  # 1000 s without input
