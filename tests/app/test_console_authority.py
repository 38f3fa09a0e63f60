"""One authority at the workstation and its Program view, on the demo station with its real
archive: every action is a command of the station's command layer as the user on duty. A viewer
is refused acknowledge, shelve, write, force and stop, each journaled once per cause per minute
however often it is tried; an operator acknowledges and writes but does not force; an engineer
forces and stops. A control the user may not use is greyed, its tooltip naming the role. And the
window shows each scan's values with the quality of that same scan."""

from __future__ import annotations

from collections import Counter

from PySide6.QtCore import Qt

from app.gui.main_window import MainWindow
from app.gui.monitor.view import ProgramMonitor
from app.scada.alarms import STOPPED_ID, State
from app.station.runtime import Runtime
from tests.app import test_console
from tests.app.test_console import Answers, committed, element, operator_rows, scans_later

# the fixtures: the demo station's console, started, viewer on duty: the module's, reset after each
# test; each test reads the journal's records from its own start (`journaled`)
console, shared_console = test_console.console, test_console.shared_console

START_BIT = 0o40042
FORCED_BIT = 0o2120


def program_view(window: MainWindow) -> ProgramMonitor:
    window.open_program()
    return window.viewers[-1].monitor  # type: ignore[attr-defined]


def journaled(qtbot, runtime: Runtime) -> int:
    """How many operator records the archive holds once all journaled so far is committed: where
    a test's own records begin."""
    committed(qtbot, runtime)
    return len(operator_rows(runtime))


def refusals(runtime: Runtime, since: int) -> Counter[tuple[str, str]]:
    """The refusal records of the journal from its `since`th operator record, by who and what was
    refused."""
    return Counter((source, text.split(":")[0]) for source, text in operator_rows(runtime)[since:]
                   if text.startswith("refused "))


def greyed(control, role: str) -> bool:
    return not control.isEnabled() and f"needs the {role} role" in control.toolTip()


def test_a_viewer_is_refused_everything_once_per_cause_and_sees_it_greyed(qtbot, console: MainWindow) -> None:
    """First of the module: no refusal of the minute before it."""
    runtime, summary = console.runtime, console.summary
    since = journaled(qtbot, runtime)
    assert console.user == "viewer"
    for control in (summary.ack, summary.ack_all, summary.shelve, summary.unshelve, console.alarms.ack,
                    console.alarms.ack_all):
        assert greyed(control, "operator"), control.text()
    for action in (console.act_run, console.act_stop, console.act_quit):
        assert greyed(action, "engineer"), action.text()
    assert greyed(console.act_users, "admin")
    start, button = element(console, "Пуск")
    setpoint, _ = element(console, "Уставка температуры")
    assert "Пуск: needs the operator role; viewer is viewer" in button.toolTip()
    monitor = program_view(console)
    assert greyed(monitor.unforce_button, "engineer") and greyed(monitor.step_button, "engineer")
    qtbot.waitUntil(lambda: start.value is not None, timeout=5000)

    console.ask = Answers(True)
    for _ in range(3):  # the layer refuses what is asked all the same, and journals it once
        summary.acknowledge_all()
        summary.shelve_alarm(STOPPED_ID, 10, "на поверке")
        qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
        assert setpoint.submit("50")[0] is False
        console.stop_program()
        monitor.force("bit", FORCED_BIT, 1)
    assert console.status.currentMessage() == ("Refused: Stop NetPlc: needs the engineer role; "
                                               "viewer is viewer")
    assert monitor.message.text() == "Refused: force 02120: needs the engineer role; viewer is viewer"
    assert console.ask.asked == []  # nothing refused is asked first
    scans_later(qtbot, runtime)
    assert runtime.engine is not None and runtime.engine.snapshot.get_hmi_bit(START_BIT) == 0
    assert runtime.status().forced == 0 and runtime.status().state == "running"
    committed(qtbot, runtime)
    assert refusals(runtime, since) == {
        ("viewer", "refused acknowledge all"): 1, ("viewer", "refused shelve NETPLC.STOPPED"): 1,
        ("viewer", "refused write Пуск"): 1,  # and the setpoint: the same cause, counted into it
        ("viewer", "refused stop NetPlc"): 1, ("program view:viewer", "refused force bit 02120"): 1}


def test_an_operator_acknowledges_and_writes_but_does_not_force(qtbot, console: MainWindow) -> None:
    runtime, summary = console.runtime, console.summary
    since = journaled(qtbot, runtime)
    console.login("operator", "operator")
    runtime.stop_program("engineer")  # the station's own alarm: NetPlc is not running
    qtbot.waitUntil(lambda: any(r.id == STOPPED_ID for r in summary.unacknowledged()), timeout=5000)
    runtime.run_program("engineer")
    assert summary.ack_all.isEnabled() and console.alarms.ack.isEnabled()
    qtbot.mouseClick(summary.ack_all, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: not summary.unacknowledged(), timeout=5000)
    assert runtime.alarms is not None and runtime.alarms.system.get(STOPPED_ID).state is not State.UNACK
    start, button = element(console, "Пуск")
    qtbot.waitUntil(lambda: start.value == 0 and not start.stale, timeout=10_000)
    assert "needs" not in button.toolTip()
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    engine = runtime.engine
    assert engine is not None
    qtbot.waitUntil(lambda: engine.snapshot.get_hmi_bit(START_BIT) == 1, timeout=3000)
    setpoint, _ = element(console, "Уставка температуры")
    assert setpoint.submit("50") == (True, "Set to 50.0 °C")
    assert greyed(console.act_stop, "engineer")
    monitor = program_view(console)
    assert greyed(monitor.unforce_button, "engineer")
    monitor.force("bit", FORCED_BIT, 1)
    assert monitor.message.text() == "Refused: force 02120: needs the engineer role; operator is operator"
    scans_later(qtbot, runtime)
    assert runtime.status().forced == 0
    committed(qtbot, runtime)
    rows = operator_rows(runtime)[since:]
    assert ("operator", "write Пуск (040042): 0 -> 1") in rows
    assert any(s == "operator" and t.startswith("write Уставка температуры TEMP_SP:") for s, t in rows)
    assert refusals(runtime, since) == {("program view:operator", "refused force bit 02120"): 1}


def test_an_engineer_forces_and_stops(qtbot, console: MainWindow) -> None:
    runtime = console.runtime
    since = journaled(qtbot, runtime)
    console.login("engineer", "engineer")
    monitor = program_view(console)
    assert monitor.unforce_button.isEnabled() and monitor.unforce_button.toolTip() == ""
    monitor.force("bit", FORCED_BIT, 1)
    qtbot.waitUntil(lambda: runtime.status().forced == 1, timeout=3000)
    assert console.act_stop.isEnabled() and "needs" not in console.act_stop.toolTip()
    console.ask = Answers(True)
    console.stop_program()
    qtbot.waitUntil(lambda: runtime.status().state != "running", timeout=3000)
    monitor.unforce_all()
    qtbot.waitUntil(lambda: runtime.status().forced == 0, timeout=3000)
    committed(qtbot, runtime)
    rows = operator_rows(runtime)[since:]
    assert ("program view:engineer", "force 02120: 0 -> 1") in rows
    assert ("engineer", "NetPlc stopped") in rows
    assert not refusals(runtime, since)
    assert runtime.run_program("engineer").result(5).ok  # running again, as the module's others find it


def test_the_tooltips_follow_a_logout_and_an_idle_logout(qtbot, console: MainWindow) -> None:
    now = [0.0]
    console.session.clock = lambda: now[0]
    console.session.idle = 900
    console.login("engineer", "engineer")
    monitor = program_view(console)
    assert console.summary.shelve.isEnabled() and monitor.unforce_button.isEnabled()
    now[0] += 901
    console.refresh_status()  # idle: back to the default viewer
    assert greyed(console.summary.shelve, "operator") and greyed(monitor.unforce_button, "engineer")
    console.login("operator", "operator")
    assert console.summary.shelve.isEnabled() and greyed(monitor.unforce_button, "engineer")
    console.log_out()
    assert greyed(console.summary.shelve, "operator")


def test_the_window_shows_each_scans_values_with_that_scans_quality(qtbot, console: MainWindow) -> None:
    paired: list[bool] = []
    # connected after the window's own slot: it runs once the views have taken the readings
    views = console.views
    console.bridge.readings.connect(lambda r: paired.append(all(v._last is r.snapshot for v in views)))
    qtbot.waitUntil(lambda: len(paired) > 10, timeout=10_000)
    assert all(paired)
