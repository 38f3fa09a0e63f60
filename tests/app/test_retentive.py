"""Retentive memory through the runtime: counting in data memory continues after a clean stop and
after SIGKILL (at most the last second of what the program counted lost); an answered write is in
the save already (tests/app/test_kill_writes.py kills the station under writes)."""

from __future__ import annotations

import re
import signal
import threading
import time
from pathlib import Path

from app.station.config import load_station
from app.station.runtime import Runtime
from netplc.memory import Memory
from registrar.retain import read_save
from tests.app.conftest import write_station
from tests.app.station_fork import Forks
from tests.app.test_runtime_errors import wait_for

COUNTER = 0o4000
# INCW every scan: the word at 04000 counts scans (04002 is the unused setpoint)
PROGRAM = "TNA $03760\nFON C:$02000 N:INCW S:$04002 D:$04000\nJMP 0\n"
TOML = 'NetPlcProgram = "count.stl"\nNetSyncTime = 20\n[modbus_server]\nenabled = false\n'


def counting_station(folder: Path) -> Path:
    return write_station(folder, TOML, {"count.stl": PROGRAM})


def counter(runtime: Runtime) -> int:
    assert runtime.engine is not None
    return runtime.engine.snapshot.get_word(COUNTER)


def test_counting_continues_after_a_clean_stop(tmp_path: Path) -> None:
    station = load_station(counting_station(tmp_path))
    first = Runtime(station)
    first.start()
    try:
        assert wait_for(lambda: counter(first) > 5)
    finally:
        first.stop()
    saved = counter(first)
    assert saved > 5
    second = Runtime(station)
    second.start()
    try:
        assert second.restored == "current"
        assert saved <= counter(second) <= saved + 10
        assert wait_for(lambda: counter(second) > saved)
    finally:
        second.stop()


def test_counting_continues_after_sigkill(tmp_path: Path, station_forks: Forks) -> None:
    folder = counting_station(tmp_path)
    # `main.py --no-gui` as a process of its own (a fork of the worker's, tests/app/station_fork.py)
    proc = station_forks.start(["--no-gui", str(folder), "--status-every", "0.3"], tmp_path / "stderr.txt",
                               tmp_path / "stdout.txt")

    def scanned(out: str) -> int:
        return max(map(int, re.findall(r"(\d+) scans\)", out)), default=0)

    try:
        scans = scanned(proc.until(lambda out: scanned(out) >= 100, timeout=20))
        proc.send_signal(signal.SIGKILL)
        proc.wait(10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert scans >= 100
    runtime = Runtime(load_station(folder))
    runtime.start()
    try:
        restored = counter(runtime)
        # the save is at most a second old (50 scans of 20 ms) plus the time one save takes to reach
        # the disk (its fsync: up to a few hundred ms on a disk busy with the fresh .venv's pages)
        assert scans - 75 <= restored <= scans + 50
    finally:
        runtime.stop()


def test_an_answered_write_is_in_the_retentive_save_already(tmp_path: Path) -> None:
    station = load_station(counting_station(tmp_path))
    runtime = Runtime(station)
    runtime.start()
    saved = Memory()
    answered = threading.Semaphore(0)
    engine = runtime.engine
    try:
        assert engine is not None
        for value in range(1, 31):
            assert engine.write_word(0o4100, value, user="modbus test", done=lambda ok: answered.release())
            assert answered.acquire(timeout=10)
            saved.data[:] = read_save(station.Retain).data
            assert saved.get_word(0o4100) == value
    finally:
        runtime.stop()


def saved_or_refused(runtime: Runtime) -> None:
    """One more save of the retentive memory, done or failed."""
    assert runtime.retainer is not None
    tried = threading.Event()
    runtime.retainer.after_save(tried.set)
    assert tried.wait(10)


def test_a_failing_save_is_journaled_once_shown_and_cleared(tmp_path: Path, qtbot) -> None:
    from app.gui.main_window import MainWindow

    folder = write_station(tmp_path, 'Retain = "blocked/retain.bin"\n' + TOML, {"count.stl": PROGRAM})
    (folder / "blocked").write_text("a file, not a folder", encoding="utf-8")  # fails as a read-only mount
    runtime = Runtime(load_station(folder))
    texts: list[str] = []
    runtime.subscribe(lambda record: texts.append(record.text or ""))
    runtime.start()
    window = MainWindow(runtime)
    qtbot.addWidget(window)
    try:
        assert wait_for(lambda: any("retentive memory not saved" in p for p in runtime.status().problems))
        for _ in range(2):  # two more saves fail: still journaled once
            saved_or_refused(runtime)
        assert len([t for t in texts if "could not be saved" in t]) == 1, texts
        assert "retentive memory not saved: " in runtime.status().line()
        window.refresh_status()
        assert not window.health.isHidden() and "retentive memory not saved" in window.health.label.text()

        (folder / "blocked").unlink()  # the disk works again
        (folder / "blocked").mkdir()
        saved_or_refused(runtime)  # the next save, asked for now rather than waited for
        assert wait_for(lambda: not any("retentive" in p for p in runtime.status().problems))
        assert any("being saved again" in t for t in texts)
        window.refresh_status()
        assert "retentive" not in window.health.label.text()
    finally:
        window.close()
        runtime.stop()
    assert (folder / "blocked" / "retain.bin").exists()


def test_a_start_left_pressed_is_no_new_press_after_a_restart(tmp_path: Path) -> None:
    """Пуск is retained (data memory) and so is its edge memory: the journal records one press,
    not one more at every restart."""
    from tests.app.conftest import copy_demo

    folder = copy_demo(tmp_path / "station")
    toml = folder / "station.toml"  # a scan every 20 ms, not 100: the 15 scans of each run sooner
    toml.write_text(toml.read_text(encoding="utf-8").replace("\nNetSyncTime = 100 ", "\nNetSyncTime = 20 "),
                    encoding="utf-8")
    station = load_station(folder)
    assert station.NetSyncTime == 20
    start_bit = 0o40042
    for run in range(2):
        runtime = Runtime(station)
        runtime.start()
        try:
            assert runtime.engine is not None
            if run == 0:
                runtime.engine.write_bit(start_bit, 1, user="operator", label="Пуск")
            deadline = time.monotonic() + 5
            while runtime.engine.snapshot.scan < 15 and time.monotonic() < deadline:
                time.sleep(0.05)
            assert runtime.engine.snapshot.get_hmi_bit(start_bit) == 1
        finally:
            runtime.stop()
    import sqlite3

    con = sqlite3.connect(f"file:{station.Archive}?mode=ro", uri=True)
    try:
        texts = [t for (name,) in con.execute("SELECT name FROM sqlite_master WHERE type = 'table' "
                                             "AND name GLOB '[0-9][0-9]_[0-9][0-9]_*'")
                 for (t,) in con.execute(f'SELECT text FROM "{name}" WHERE kind = ?', ("message",))]
    finally:
        con.close()
    assert texts.count("Пуск нажат") == 1
    assert texts.count("NetPlc запущен") == 2
