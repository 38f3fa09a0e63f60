"""Alarm-system health from a real archive written by the real writer: floods, top 10,
chattering and stale alarms of one day, and `main.py alarms-report`."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import pytest

from app.cli import main
from app.scada.alarms import State
from netplc.records import Record
from registrar.health import alarm_health
from registrar.query import Archive
from registrar.store import Store

DAY = dt.date(2026, 3, 5)


def at(day: dt.date, hh: int, mm: int = 0, ss: float = 0.0) -> float:
    return dt.datetime(day.year, day.month, day.day, hh, mm).timestamp() + ss


def transition(ts: float, alarm: str, old: State, new: State, text: str = "Уровень: high") -> Record:
    return Record(ts, "alarm", grp=2, type=int(new), source=alarm, number=int(old),
                  text=f"{alarm} {old.word} -> {new.word}: {text}; by nobody")


def journal(db: Path) -> None:
    prev = DAY - dt.timedelta(days=1)
    records = [
        # day before: TEMP.H comes and stays (stale by the end of DAY); PUMP.L comes and goes
        transition(at(prev, 8), "TEMP.H", State.NORMAL, State.UNACK, "Температура: high"),
        transition(at(prev, 9), "TEMP.H", State.UNACK, State.ACKED, "Температура: high"),
        transition(at(prev, 1), "PUMP.L", State.NORMAL, State.UNACK, "Насос: low"),
        transition(at(prev, 3), "PUMP.L", State.UNACK, State.RTNUN, "Насос: low"),
        # DAY: TRIG comes in the evening (active, not stale)
        transition(at(DAY, 20), "TRIG.ALARM", State.NORMAL, State.UNACK, "Триггер = 1"),
    ]
    # LEVEL.H chatters: 12 times between 10:00 and 10:04, every 20 s (a flood, and chattering)
    for k in range(12):
        t = at(DAY, 10, 0, 20 * k)
        records.append(transition(t, "LEVEL.H", State.RTNUN if k else State.NORMAL, State.UNACK))
        records.append(transition(t + 5, "LEVEL.H", State.UNACK, State.RTNUN))
    # 11 other alarms, once each in the afternoon, to see the top 10 cut off
    for k in range(11):
        records.append(transition(at(DAY, 14, 5 * k), f"X{k:02d}.H", State.NORMAL, State.UNACK, f"x {k}"))
    store = Store(db)
    store.start()
    for r in sorted(records, key=lambda r: r.ts):
        store.put(r)
    store.close()


def test_health_of_a_day(db: Path) -> None:
    journal(db)
    with Archive(db) as archive:
        report = alarm_health(archive, DAY)
    assert report.activations == 12 + 1 + 11
    assert report.floods == [(at(DAY, 10), 12)]
    assert len(report.slots) == 144
    assert report.top[0] == ("LEVEL.H", 12, "Уровень: high")
    assert len(report.top) == 10
    assert report.chattering == [("LEVEL.H", 4, at(DAY, 10))]  # 0, 20, 40, 60 s
    assert [(a, since) for a, since, _ in report.stale] == [("TEMP.H", at(DAY - dt.timedelta(days=1), 8))]
    assert report.stale[0][2] == pytest.approx(40.0)


def test_the_report_on_the_command_line(db: Path, capsys: pytest.CaptureFixture[str]) -> None:
    journal(db)
    assert main(["alarms-report", str(db), "--day", "05_03_2026"]) == 0
    out = capsys.readouterr().out
    assert "alarm-system health for 05.03.2026" in out
    assert "alarms: 24; per 10 minutes" in out
    assert "floods (>= 10 alarms in 10 minutes): 1" in out and "10:00:00-10:10:00  12 alarms" in out
    assert "    12  LEVEL.H  Уровень: high" in out
    assert "LEVEL.H: 4 activations in 60 s from 10:00:00" in out
    assert "TEMP.H: active since 04.03.2026 08:00:00 (40.0 h)" in out


def test_the_report_names_a_bad_day_or_archive(db: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["alarms-report", str(db), "--day", "2026-03-05"]) == 2
    assert "--day: '2026-03-05' is not a day written DD_MM_YYYY" in capsys.readouterr().err
    assert main(["alarms-report", str(db), "--day", "05_03_2026"]) == 2
    assert "no such archive" in capsys.readouterr().err
