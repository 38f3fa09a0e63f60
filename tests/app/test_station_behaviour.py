"""The forms' station behaviour runs in the runtime: `--no-gui` and the workstation produce the same
sync pulses, scan for scan, and the same element records, once each, even when the window lags."""

from __future__ import annotations

import datetime as dt
import itertools
import signal
import sqlite3
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from app.station.config import load_station
from app.station.runtime import Runtime
from netplc.memory import Snapshot
from tests.app.station_fork import Forks
from tests.ports import free_port

SELECT, OUT, ENABLE, TIMER_OUT = 0o2000, 0o2001, 0o2002, 0o2003  # 03_sync.hmi
PUMP, TEMP = 0o2120, 0o4012
PUMP_ON = ("Насос, состояние", "Насос работает")
TEMP_HIGH = ("Температура", "Температура выше 120 °C")


class Scans:
    """Every snapshot the engine publishes, as the engine thread hands it out."""

    def __init__(self) -> None:
        self.snapshots: list[Snapshot] = []
        self.lock = threading.Lock()

    def __call__(self, snapshot: Snapshot) -> None:
        with self.lock:
            self.snapshots.append(snapshot)

    def count(self) -> int:
        with self.lock:
            return len(self.snapshots)


def expected_pulses(before: Snapshot) -> tuple[int, int]:
    """What the demo's generator and timer write for scan S = before.scan (Fig. 2.4.3)."""
    s = before.scan
    gen = s % 10 == 1 if before.get_bit(SELECT) else s % 5 == 0
    timer = before.get_bit(ENABLE) and s % 4 == 2
    return int(gen), int(timer)


def check_every_scan(scans: Scans) -> int:
    """Each snapshot holds the pulses written for the scan that made it; returns the pulses seen."""
    with scans.lock:
        snaps = list(scans.snapshots)
    pulses = 0
    for before, after in itertools.pairwise(snaps):
        assert after.scan == before.scan + 1  # the listener saw every scan
        assert (after.get_bit(OUT), after.get_bit(TIMER_OUT)) == expected_pulses(before), before.scan
        pulses += after.get_bit(OUT) + after.get_bit(TIMER_OUT)
    return pulses


def messages(runtime: Runtime) -> list[tuple[str, str]]:
    con = sqlite3.connect(f"file:{runtime.station.Archive}?mode=ro", uri=True)
    try:
        return con.execute(f'SELECT source, text FROM "{dt.date.today():%d_%m_%Y}" WHERE kind = ?'
                           " AND source IS NOT NULL", ("message",)).fetchall()
    finally:
        con.close()


def scanning_every(folder: Path, ms: int) -> Path:
    """The demo copy scanning every `ms`, not 100 ms: the pulses are counted in scans, and the
    node (its own tick, 100 ms) still holds the temperature over 120 °C for about a second."""
    toml = folder / "station.toml"
    text = toml.read_text(encoding="utf-8")
    assert "\nNetSyncTime = 100 " in text
    toml.write_text(text.replace("\nNetSyncTime = 100 ", f"\nNetSyncTime = {ms} "), encoding="utf-8")
    return folder


@pytest.fixture
def runtime(request: pytest.FixtureRequest, demo_copy: Path) -> Iterator[Runtime]:
    """The demo running, scanning every `request.param` ms (indirect parametrization) or 20 ms."""
    rt = Runtime(load_station(scanning_every(demo_copy, getattr(request, "param", 20))))
    rt.start()
    try:
        yield rt
    finally:
        rt.stop()


def drive(runtime: Runtime, scans: Scans, wait) -> None:
    """The operator switches the pump and the timer on; the plant's temperature jumps over 120 °C;
    returns once both messages were journaled and 30 scans ran."""
    engine = runtime.engine
    assert engine is not None
    said: list[tuple[str | None, str | None]] = []
    runtime.subscribe(lambda r: said.append((r.source, r.text)) if r.kind == "message" else None)
    wait(lambda: runtime.status().nodes_up == 1)
    engine.write_bit(ENABLE, 1, user="test")
    engine.write_bit(PUMP, 1, user="test")
    # raw 1000 = 150 °C: the node pulls it back 1/32 a scan, so it stays over 120 °C for ~1 s
    runtime.simulators[0].engine.write_word(TEMP, 1000)
    start = scans.count()
    wait(lambda: scans.count() > start + 30 and PUMP_ON in said and TEMP_HIGH in said)


def poll(condition, timeout: float = 15.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.02)


def test_headless_runtime_pulses_every_scan_and_journals_the_forms_records(runtime: Runtime) -> None:
    scans = Scans()
    assert runtime.engine is not None
    runtime.engine.subscribe(scans)
    drive(runtime, scans, poll)
    assert check_every_scan(scans) > 10
    runtime.stop()  # flushes the archive
    found = messages(runtime)
    assert found.count(PUMP_ON) == 1 and found.count(TEMP_HIGH) == 1
    con = sqlite3.connect(f"file:{runtime.station.Archive}?mode=ro", uri=True)
    try:
        system = [t for (t,) in con.execute(f'SELECT text FROM "{dt.date.today():%d_%m_%Y}" WHERE kind = ?',
                                            ("system",))]
    finally:
        con.close()
    loaded = "мнемосхемы загружены: 3, из их элементов 4 действуют на станции"  # the demo speaks Russian
    assert any(t.startswith(loaded) for t in system)


@pytest.mark.parametrize("runtime", [50], indirect=True)  # the window draws every scan it keeps up with
def test_the_workstation_changes_nothing_even_when_its_window_lags(qtbot, runtime: Runtime) -> None:
    from app.gui.main_window import MainWindow

    scans = Scans()
    assert runtime.engine is not None
    runtime.engine.subscribe(scans)
    window = MainWindow(runtime)
    qtbot.addWidget(window)
    window.show()

    def wait(condition) -> None:
        qtbot.waitUntil(condition, timeout=15_000)

    drive(runtime, scans, wait)
    before = scans.count()
    time.sleep(0.75)  # the GUI thread is busy: the bridge drops every snapshot meanwhile (15 scans)
    assert scans.count() >= before + 10
    wait(lambda: scans.count() > before + 25)
    assert check_every_scan(scans) > 10
    window.close()
    runtime.stop()
    found = messages(runtime)
    assert found.count(PUMP_ON) == 1 and found.count(TEMP_HIGH) == 1  # the views journal nothing


def test_no_gui_process_pulses_and_journals_what_a_modbus_client_switches(
        demo_copy: Path, station_forks: Forks) -> None:
    from pymodbus.client import ModbusTcpClient

    port = free_port()
    toml = demo_copy / "station.toml"
    server = '[modbus_server]\nhost = "127.0.0.1"\nport = '
    text = toml.read_text(encoding="utf-8").replace(server + "0", server + str(port))
    toml.write_text(text, encoding="utf-8")
    assert f"port = {port}" in toml.read_text(encoding="utf-8")
    # `main.py --no-gui` as a process of its own (a fork of the worker's, tests/app/station_fork.py)
    proc = station_forks.start(["--no-gui", str(demo_copy)], demo_copy / "stderr.txt")
    try:
        client = ModbusTcpClient("127.0.0.1", port=port)
        poll(client.connect)
        outputs = set()
        poll(lambda: not client.write_coil(PUMP, True).isError())
        deadline = time.monotonic() + 2
        while outputs != {False, True} and time.monotonic() < deadline:
            outputs.add(client.read_coils(OUT, count=1).bits[0])
            time.sleep(0.01)
        client.close()
        proc.send_signal(signal.SIGTERM)  # a stop as the service manager's: everything is flushed
        assert proc.wait(30) == 0, proc.errors()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert outputs == {False, True}  # the generator pulses without a window
    con = sqlite3.connect(f"file:{demo_copy / 'archive' / 'journal.sqlite'}?mode=ro", uri=True)
    try:
        rows = con.execute(f'SELECT source, text FROM "{dt.date.today():%d_%m_%Y}" WHERE kind = ?',
                           ("message",)).fetchall()
    finally:
        con.close()
    assert rows.count(PUMP_ON) == 1


def test_a_form_that_does_not_load_is_a_problem_the_station_runs_with(tmp_path: Path) -> None:
    from tests.app.conftest import write_station

    forms = tmp_path / "forms"
    forms.mkdir(parents=True)
    (forms / "bad.hmi").write_text("{", encoding="utf-8")
    (forms / "good.hmi").write_text(
        '{"form": {"width": 200, "height": 100}, "elements": [{"type": "SyncGenerator", "Name": "G", '
        '"x": 0, "y": 0, "w": 100, "h": 50, "OutAddr": "02001", "Period0": 2}]}', encoding="utf-8")
    write_station(tmp_path, 'NetPlcProgram = "p.stl"\nHMIload = "forms"\n[modbus_server]\nenabled = false\n',
                  {"p.stl": "TNA $02001\nYON $02002\n"})
    rt = Runtime(load_station(tmp_path))
    scans = Scans()
    rt.start()
    try:
        assert rt.engine is not None
        rt.engine.subscribe(scans)
        poll(lambda: scans.count() > 6)
        status = rt.status()
    finally:
        rt.stop()
    assert status.problems == (f"form problem: {forms / 'bad.hmi'}:1:2: bad JSON: Expecting property name "
                               "enclosed in double quotes",)
    assert "NetPlc running" in status.line() and "form problem" in status.line()
    with scans.lock:
        snaps = list(scans.snapshots)
    for before, after in itertools.pairwise(snaps):  # the good form's generator, seen by the program
        assert after.get_bit(0o2002) == after.get_bit(OUT) == int(before.scan % 2 == 0)
