"""The demo journals its alarms and its 'system' records in the station's `Language`: the same
words reach the journal, OPC UA, MQTT and every console (app/scada/words.py)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from app.scada.alarms import STOPPED_ID, State
from app.station.config import load_station
from app.station.runtime import Runtime
from registrar.query import Archive
from registrar.reading import Filter

WORDS = {  # language: the start record, NETPLC.STOPPED's text and the stop record
    "ru": ("станция запускается: ", "NetPlc не работает: остановлена: engineer (код 0)",
           "станция остановлена"),
    "en": ("station starting: ", "NetPlc is not running: stopped by engineer (code 0)", "station stopped"),
}


@pytest.mark.parametrize("language", sorted(WORDS))
def test_the_demo_journals_its_alarms_and_system_records_in_its_language(demo_copy: Path,
                                                                         language: str) -> None:
    toml = demo_copy / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8").replace('Language = "ru"', f'Language = "{language}"'),
                    encoding="utf-8")
    station = load_station(demo_copy)
    runtime = Runtime(station)
    runtime.start()
    try:
        assert runtime.alarms is not None
        runtime.stop_program("engineer")
        deadline = time.monotonic() + 30
        while runtime.alarms.system.get(STOPPED_ID).state is not State.UNACK and time.monotonic() < deadline:
            time.sleep(0.05)
        assert runtime.alarms.system.get(STOPPED_ID).text == WORDS[language][1]
    finally:
        runtime.stop()
    with Archive(station.Archive) as archive:
        day = archive.days()[0]
        system = [r.text for r in archive.records(day, Filter(kinds={"system"}, source="station"),
                                                  limit=1000, newest_first=False)]
        alarms = [r.text for r in archive.records(day, Filter(kinds={"alarm"}, source=STOPPED_ID), limit=100)]
    starting, stopped, end = WORDS[language]
    assert system[0].startswith(starting) and system[-1] == end
    assert any(t and stopped in t for t in alarms)
