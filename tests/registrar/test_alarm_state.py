"""Alarm states on disk across a real restart: new objects, the file read back, nothing re-raised."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import numpy as np

from app.scada.alarms import AlarmSystem, State
from app.scada.table import load_tags
from netplc.memory import Memory
from netplc.records import ListSink
from registrar.alarm_state import AlarmStateFile

T0 = 1_800_000_000.0
TAGS = """name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description,h,l,alarm_when,priority
LEVEL,04010,word,%,0,4095,0,100,1,Уровень,90,10,,2
TEMP,04012,word,°C,0,1000,-50,150,1,Температура,120,,,3
TRIG,02005,bit,,,,,,,Триггер,,,1,1
"""


class Station:
    """What a runtime holds of alarms: the tags, the system and its state file (started)."""

    def __init__(self, folder: Path, mem: Memory) -> None:
        (folder / "tags.csv").write_text(TAGS, encoding="utf-8")
        self.sink = ListSink()
        self.file = AlarmStateFile(folder / "archive" / "alarms.sqlite", self.sink)
        saved = self.file.load()
        self.system = AlarmSystem(load_tags(folder / "tags.csv"), sink=self.sink, saved=saved,
                                  on_change=self.file.update)
        self.file.start()
        self.mem = mem

    def scan(self, at: float) -> list[tuple[str, State, State]]:
        out = self.system.evaluate(self.mem.snapshot(), T0 + at, np.zeros(3, dtype=np.int8))
        return [(t.alarm, t.old, t.new) for t in out]

    def stop(self) -> None:
        self.file.close()


def stored(path: Path) -> dict[str, dict]:
    con = sqlite3.connect(path)
    try:
        rows = con.execute("SELECT alarm, state FROM alarm_state").fetchall()
        return {alarm: json.loads(state) for alarm, state in rows}
    finally:
        con.close()


def plant() -> Memory:
    mem = Memory()
    mem.set_word(0o4010, 3900)  # 95 %: LEVEL.H
    mem.set_word(0o4012, 900)  # 130 °C: TEMP.H
    mem.set_bit(0o2005, 1)  # TRIG.ALARM
    return mem


def test_a_restart_keeps_every_state_and_raises_nothing_twice(tmp_path: Path) -> None:
    mem = plant()
    first = Station(tmp_path, mem)
    assert len(first.scan(0)) == 3
    first.system.acknowledge("TEMP.H", "ivanov", T0 + 1)
    first.system.shelve("TRIG.ALARM", "petrov", "sensor check", 600, T0 + 2)
    first.stop()
    saved = stored(tmp_path / "archive" / "alarms.sqlite")
    assert saved["LEVEL.H"]["acked"] is False and saved["LEVEL.H"]["state"] == "active-unacknowledged"

    again = Station(tmp_path, mem)  # conditions still active at the restart
    assert "alarm states restored from alarms.sqlite: 3 alarm(s)" in again.sink.records[0].text
    assert again.scan(10) == []
    assert again.system.get("LEVEL.H").state is State.UNACK
    assert again.system.get("TEMP.H").state is State.ACKED
    assert again.system.get("TRIG.ALARM").shelved_until == T0 + 602
    mem.set_word(0o4010, 2000)  # the level went back meanwhile: it returns, still to be acknowledged
    assert again.scan(11) == [("LEVEL.H", State.UNACK, State.RTNUN)]
    assert again.scan(602) == [("TRIG.ALARM", State.SHELVED, State.UNACK)]
    again.stop()

    third = Station(tmp_path, mem)
    assert third.system.get("LEVEL.H").state is State.RTNUN
    assert third.system.get("TRIG.ALARM").state is State.UNACK
    third.stop()


def test_a_damaged_file_starts_every_alarm_normal_and_says_so(tmp_path: Path) -> None:
    (tmp_path / "archive").mkdir()
    (tmp_path / "archive" / "alarms.sqlite").write_bytes(b"not a database, a damaged file" * 100)
    station = Station(tmp_path, plant())
    assert station.sink.records[0].kind == "system"
    assert "alarm states not restored from alarms.sqlite" in station.sink.records[0].text
    assert "kept as alarms.sqlite.damaged" in station.sink.records[0].text
    assert len(station.scan(0)) == 3
    station.stop()
    assert set(stored(tmp_path / "archive" / "alarms.sqlite")) == {"LEVEL.H", "TEMP.H", "TRIG.ALARM"}


def test_a_save_that_fails_is_journaled_once_and_retried(tmp_path: Path) -> None:
    blocker = tmp_path / "archive"
    blocker.write_text("a file where the folder should be")
    sink = ListSink()
    file = AlarmStateFile(blocker / "alarms.sqlite", sink)
    file.update({"A": {"active": True}})
    file.update({"A": {"active": False}})
    assert [r.text for r in sink.records if "could not be saved" in (r.text or "")] != []
    assert len(sink.records) == 1
    blocker.unlink()
    file.flush()
    assert "being saved again" in sink.records[-1].text
    assert stored(blocker / "alarms.sqlite") == {"A": {"active": False}}
    file.close()
