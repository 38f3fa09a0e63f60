"""`main.py archive backup` while the station runs and writes ~1,000 records a second, and
`archive restore`: into a stopped station it restores, into a running one it is refused."""

from __future__ import annotations

import datetime as dt
import json
import os
import shutil
import sqlite3
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from app.cli import run_backup, run_restore
from app.station.backup import MANIFEST, BackupError, backup, restore
from app.station.config import DEMO_STATION, load_station
from app.station.lock import StationRunning
from app.station.runtime import Runtime
from netplc.records import Record
from registrar.retain import parse_save
from registrar.schema import table_name
from tests.app.conftest import write_station

PROGRAM = "TNA $03760\nCTR C:$03000 N:255\nJMP 0\n"
RATE = 1000  # records a second while the backup runs
PREFILL = 10_000  # records in the journal before it: pages for many steps (of 2 pages)


def station_folder(folder: Path) -> Path:
    write_station(folder, 'NetPlcProgram = "count.stl"\nNetSyncTime = 20\n[modbus_server]\nenabled = false\n',
                  {"count.stl": PROGRAM, "notes.txt": "the engineer's notes\n"})
    shutil.copy(DEMO_STATION / "users.json", folder / "users.json")
    (folder / "pki").mkdir()
    key = folder / "pki" / "own.key"
    key.write_text("not really a key\n")
    key.chmod(0o600)
    (folder / "log").mkdir()
    (folder / "log" / "station.log").write_text("a log line\n")
    return folder


def committed(runtime: Runtime) -> None:
    """Wait until every record put so far is committed and a retentive save is on disk."""
    done = threading.Event()
    runtime.after_commit(done.set)
    assert done.wait(30)


class Writer(threading.Thread):
    """Puts RATE records a second into the running station's journal (its registrar store), and
    wants them committed 20 times a second, as outside writers do (each is answered once its
    record is committed)."""

    def __init__(self, runtime: Runtime, first: int) -> None:
        super().__init__(daemon=True)
        self.runtime, self.number = runtime, first
        self.stop = threading.Event()

    def run(self) -> None:
        ticks = 0
        while not self.stop.wait(0.01):
            for _ in range(RATE // 100):
                self.number += 1
                self.runtime.put(Record(time.time(), "data", grp=7, type=1, source="04000",
                                        number=self.number, value=float(self.number)))
            ticks += 1
            if ticks % 5 == 0 and self.runtime.store is not None:
                self.runtime.store.after_commit(lambda: None)


def rows(path: Path, up_to: int | None = None) -> list[tuple]:
    con = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    try:
        where = "" if up_to is None else f" WHERE id <= {up_to}"
        return con.execute(f'SELECT * FROM "{table_name(dt.date.today())}"{where} ORDER BY id').fetchall()
    finally:
        con.close()


@pytest.fixture
def running(tmp_path: Path) -> Iterator[Runtime]:
    runtime = Runtime(load_station(station_folder(tmp_path / "station")))
    runtime.start()
    try:
        yield runtime
    finally:
        runtime.stop()


def test_a_backup_while_the_journal_is_written_holds_every_record_committed_before(
        running: Runtime, tmp_path: Path) -> None:
    st = running.station
    for i in range(PREFILL):
        running.put(Record(time.time(), "data", grp=7, type=1, source="04000", number=i, value=float(i)))
    committed(running)
    writer = Writer(running, PREFILL)
    writer.start()
    try:
        deadline = time.monotonic() + 10
        while writer.number < PREFILL + RATE // 4 and time.monotonic() < deadline:  # well under way
            writer.stop.wait(0.01)
        committed(running)
        before = rows(st.Archive)
        assert running.store is not None
        batches = running.store.stats.batches
        report = backup(st.folder, tmp_path / "backup", pages=2, pause=0.002)
        during = running.store.stats.batches - batches
    finally:
        writer.stop.set()
        writer.join()
    copy = tmp_path / "backup" / "archive" / "journal.sqlite"
    assert report.journal is not None and report.journal.steps > 20  # a copy in many steps ...
    assert during >= 3  # ... while the station went on committing
    con = sqlite3.connect(copy)
    try:
        assert con.execute("PRAGMA integrity_check").fetchall() == [("ok",)]
    finally:
        con.close()
    assert rows(copy, up_to=before[-1][0]) == before  # every record committed before the backup began

    dest = tmp_path / "backup"
    assert sorted(report.files) == ["count.stl", "notes.txt", "pki/own.key", "station.toml", "users.json"]
    assert (dest / "users.json").read_bytes() == (st.folder / "users.json").read_bytes()
    assert (dest / "pki" / "own.key").stat().st_mode & 0o777 == 0o600
    assert not (dest / "log").exists() and not (dest / "station.lock").exists()
    assert report.state == {"retain": "archive/retain.bin", "alarms": "archive/alarms.sqlite",
                            "journal": "archive/journal.sqlite"}
    parse_save((dest / "archive" / "retain.bin").read_bytes())  # a whole save, as a restart takes it
    manifest = json.loads((dest / MANIFEST).read_text())
    assert manifest["files"] == report.files and manifest["state"] == report.state
    assert dest.stat().st_mode & 0o777 == 0o700  # it holds the users' hashes and the OPC UA key


def test_restore_into_a_stopped_station_and_never_into_a_running_one(
        running: Runtime, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    committed(running)
    backup(running.station.folder, tmp_path / "backup")

    with pytest.raises(StationRunning):
        restore(tmp_path / "backup", running.station.folder)
    assert run_restore(str(tmp_path / "backup"), str(running.station.folder)) == 1
    assert "a station is running in this folder" in capsys.readouterr().err

    stopped = tmp_path / "stopped"
    station_folder(stopped)
    (stopped / "count.stl").write_text("JMP 0\n")  # changed since: the backup's comes back
    (stopped / "archive").mkdir()
    (stopped / "archive" / "retain.bin.prev").write_bytes(b"an older save")  # of another moment: removed
    (stopped / "extra.txt").write_text("")
    report = restore(tmp_path / "backup", stopped)
    assert (stopped / "count.stl").read_text() == PROGRAM
    assert not (stopped / "archive" / "retain.bin.prev").exists()
    assert report.notes == [f"{stopped / 'extra.txt'}: kept (not in the backup)"]
    again = Runtime(load_station(stopped))
    again.start()
    try:
        assert again.restored == "current"
    finally:
        again.stop()


def test_a_backup_goes_into_a_new_folder_and_a_restore_needs_a_backup(tmp_path: Path) -> None:
    folder = station_folder(tmp_path / "station")
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x").write_text("")
    with pytest.raises(BackupError, match="not an empty folder"):
        backup(folder, tmp_path / "full")
    assert run_backup(str(folder), str(tmp_path / "full")) == 1
    with pytest.raises(BackupError, match="inside the station folder"):
        backup(folder, folder / "backup")
    with pytest.raises(BackupError, match="not a backup"):
        restore(tmp_path / "full", tmp_path / "target")
    report = backup(folder, tmp_path / "never-run")  # a station that never ran: its files alone
    assert report.state == {} and report.journal is None
    assert os.listdir(tmp_path / "never-run")
