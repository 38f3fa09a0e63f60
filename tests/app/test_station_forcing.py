"""Forcing in a running station: the exchange's NREAD results and a Modbus client's writes lose to
the force, the status carries the forced count, a restart unforces unless RetainForces = true,
and "step one scan" runs one scan of the stopped program."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from app.authority import Reason, Source, Who
from app.station.config import load_station
from app.station.runtime import Runtime
from netplc.engine import RunState
from netplc.forcing import Force, load_forces
from netplc.modbus import LeanTcpClient, LoopThread, parse_endpoint
from netplc.records import Record
from tests.app.conftest import copy_demo

LEVEL, SETPOINT, LEVEL_OK = 0o4010, 0o4030, 0o2131


def wait_for(runtime: Runtime, what, scans: int = 1500) -> None:
    """Let the station scan until `what(snapshot)` holds (at most `scans` scans)."""
    engine = runtime.engine
    assert engine is not None
    end = engine.snapshot.scan + scans
    while engine.snapshot.scan < end:
        if what(engine.snapshot):
            return
        time.sleep(0.02)
    raise AssertionError("the station never got there")


def after_scans(runtime: Runtime, n: int = 3) -> None:
    assert runtime.engine is not None
    target = runtime.engine.snapshot.scan + n
    wait_for(runtime, lambda s: s.scan >= target)


def scanning_every_20_ms(folder: Path) -> Path:
    """The demo scanning every 20 ms, not 100: the tests wait for scans, the exchange and the node
    keep their own times."""
    toml = folder / "station.toml"
    text = toml.read_text(encoding="utf-8")
    assert "\nNetSyncTime = 100 " in text
    toml.write_text(text.replace("\nNetSyncTime = 100 ", "\nNetSyncTime = 20 "), encoding="utf-8")
    return folder


@pytest.fixture
def english(tmp_path: Path) -> Path:
    """The demo in English: these tests read the forces' records word for word."""
    return scanning_every_20_ms(copy_demo(tmp_path / "station", "en"))


@pytest.fixture
def demo_copy(demo_copy: Path) -> Path:
    return scanning_every_20_ms(demo_copy)


def test_exchange_and_modbus_writes_lose_to_forces_and_the_status_counts_them(english: Path) -> None:
    runtime = Runtime(load_station(english))
    records: list[Record] = []
    runtime.subscribe(records.append)
    runtime.start()
    loop = LoopThread("test-client")
    try:
        engine = runtime.engine
        assert engine is not None and runtime.modbus is not None
        wait_for(runtime, lambda s: s.get_bit(LEVEL_OK) == 1)  # node 0's level arrives by NREAD
        engine.forces.force("word", LEVEL, 4321, user="engineer")
        engine.forces.force("word", SETPOINT, 100, user="engineer")
        after_scans(runtime)
        assert runtime.status().forced == 2
        loop.start()
        client = LeanTcpClient(parse_endpoint(f"tcp://127.0.0.1:{runtime.modbus.port}"), 2.0)
        loop.run(client.connect())
        loop.run(client.write(1, "holding", SETPOINT // 2, [777]))  # writable in the demo station
        after_scans(runtime, 5)
        snap = engine.snapshot
        assert snap.get_word(LEVEL) == 4321 and snap.get_word(SETPOINT) == 100
        assert loop.run(client.read(1, "holding", SETPOINT // 2, 1)) == [100]  # what Modbus sees too
        client.close()
        engine.forces.unforce_all(user="engineer")
        wait_for(runtime, lambda s: s.get_word(LEVEL) != 4321)  # the exchange writes it again
        assert runtime.status().forced == 0
    finally:
        loop.stop()
        runtime.stop()
    texts = [(r.source or "", r.text or "") for r in records if r.kind == "operator"]
    assert any(s == "engineer" and t.startswith("force 04010:word: ") and t.endswith("-> 4321")
               for s, t in texts)
    assert ("engineer", "unforce 04030:word (was forced 100; unforce all)") in texts
    assert any(s.startswith("modbus 127.0.0.1") and t.startswith("write 04030") for s, t in texts)


def test_forces_are_not_retained_by_default_and_are_with_retain_forces(demo_copy: Path) -> None:
    for retain, expected in ((False, 0), (True, 1)):
        if retain:
            toml = demo_copy / "station.toml"
            toml.write_text("RetainForces = true\n" + toml.read_text(encoding="utf-8"), encoding="utf-8")
        station = load_station(demo_copy)
        assert station.RetainForces is retain
        runtime = Runtime(station)
        runtime.start()
        try:
            assert runtime.engine is not None
            runtime.engine.forces.force("bit", 0o2120, 1, user="engineer")
            after_scans(runtime)
            # with RetainForces the file is written as the forces change, not only at a clean stop
            expected_file = [Force("bit", 0o2120, 1, "engineer")] if retain else []
            assert load_forces(station.forces_file)[0] == expected_file
        finally:
            runtime.stop()
        runtime = Runtime(station)
        runtime.start()
        try:
            assert runtime.engine is not None
            after_scans(runtime)
            assert runtime.engine.forces.count == expected
            if expected:
                assert runtime.engine.snapshot.get_bit(0o2120) == 1
        finally:
            runtime.stop()
    assert (demo_copy / "archive" / "retain.forces.json").is_file()


def test_step_one_scan_runs_the_stopped_program_once(english: Path) -> None:
    runtime = Runtime(load_station(english))
    records: list[Record] = []
    runtime.subscribe(records.append)
    runtime.start()
    try:
        engine, commands, thread = runtime.engine, runtime.commands, runtime.scan_thread
        assert engine is not None and commands is not None and thread is not None
        engineer = Who("engineer", Source.CONSOLE)
        answer = commands.step(engineer, thread.lock).result(0)
        assert answer.reason is Reason.INVALID and "NetPlc is running" in answer.text  # nothing to step
        assert commands.step(Who("operator", Source.CONSOLE), thread.lock).result(0).reason is Reason.DENIED
        runtime.stop_program("engineer")
        wait_for(runtime, lambda s: s.state.startswith("stopped"))
        after_scans(runtime)
        before = engine.scan_counter
        assert commands.step(engineer, thread.lock).result(0).ok
        assert engine.state is RunState.STOPPED and engine.scan_counter >= before + 1
        seconds = engine.snapshot.get_word(0o4100)
        after_scans(runtime, 60)  # 1.2 s of stopped scans that follow do not run the program
        assert engine.snapshot.get_word(0o4100) == seconds
    finally:
        runtime.stop()
    assert any(r.source == "engineer" and (r.text or "").startswith("step one scan") for r in records)
