"""Quality and alarms through the whole runtime on the demo station: what readers get from
`runtime.readings()` while the node answers, after it is killed and with NetPlc stopped; the
alarm states across a restart of the runtime; NetPlc stopped and run again; and the archived
series (NSTORE, RegData) breaking over a node that is down and over NetPlc stopped."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from app.scada.alarms import STOPPED_ID, State
from app.scada.quality import Quality
from app.station.config import load_station
from app.station.runtime import Runtime
from registrar.query import Archive
from tests.netplc.test_exchange import wait_until

LEVEL = 0o4010


@pytest.fixture
def demo_copy(demo_copy: Path) -> Path:
    """The demo reconnecting to its node every 0.2 s at most, not every 2 s: the tests plug the
    cable back and wait for the link (the time the node may take to answer stays the demo's)."""
    toml = demo_copy / "station.toml"
    text = toml.read_text(encoding="utf-8")
    assert "\nbackoff_max = 2 " in text
    toml.write_text(text.replace("\nbackoff_max = 2 ", "\nbackoff_max = 0.2 "), encoding="utf-8")
    return demo_copy


def quality(runtime: Runtime, tag: str) -> Quality | None:
    readings = runtime.readings()
    return readings.tag(tag).quality if readings is not None else None


def test_readings_from_a_killed_node_and_from_netplc_stopped(demo_copy: Path) -> None:
    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    try:
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.GOOD, timeout=10)
        readings = runtime.readings()
        assert readings is not None
        level = readings.tag("LEVEL")
        assert level.unit == "%" and level.name == "LEVEL" and level.raw is not None
        assert abs(level.value - level.raw * 100 / 4095) < 1e-9 and level.time > 0
        assert readings.address(LEVEL, 2) is Quality.GOOD
        runtime.simulators[0].stop()
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.COMM_FAIL, timeout=10)
        assert quality(runtime, "TEMP") is Quality.COMM_FAIL
        assert quality(runtime, "TEMP_SP") is Quality.GOOD  # NetPlc's own word: nothing fills it
        wait_until(lambda: runtime.alarms is not None and
                   runtime.alarms.system.get("LEVEL.BAD").state is State.UNACK, timeout=5)
        runtime.stop_program("engineer")
        wait_until(lambda: quality(runtime, "TEMP_SP") is Quality.NOT_RUNNING, timeout=5)
        assert quality(runtime, "LEVEL") is Quality.NOT_RUNNING
    finally:
        runtime.stop()
    assert runtime.readings() is None  # a stopped station gives no values to trust


def activations(archive: Path, alarm: str) -> int:
    con = sqlite3.connect(f"file:{archive}?mode=ro", uri=True)
    try:
        tables = [t for (t,) in con.execute("SELECT name FROM sqlite_master WHERE type='table'")
                  if t[:2].isdigit()]
        return sum(con.execute(f'SELECT count(*) FROM "{t}" WHERE kind = ? AND source = ? AND type = ?',
                               ("alarm", alarm, int(State.UNACK))).fetchone()[0] for t in tables)
    finally:
        con.close()


def test_an_unacknowledged_alarm_stays_unacknowledged_across_a_restart(demo_copy: Path) -> None:
    tags = demo_copy / "tags.csv"  # LEVEL.H without its 2 s on-delay: the restart is the point here
    text = tags.read_text(encoding="utf-8")
    assert ",Уровень,95,90,,,2,2,1," in text
    tags.write_text(text.replace(",Уровень,95,90,,,2,2,1,", ",Уровень,95,90,,,2,0,1,"), encoding="utf-8")
    station = load_station(demo_copy)
    runtime = Runtime(station)
    runtime.start()
    try:
        wait_until(lambda: runtime.status().nodes_up == 1, timeout=10)
        runtime.simulators[0].engine.write_word(LEVEL, 3900)  # 95 %: LEVEL.H and LEVEL.HH
        wait_until(lambda: runtime.alarms is not None and
                   runtime.alarms.system.get("LEVEL.H").state is State.UNACK, timeout=10)
    finally:
        runtime.stop()
    assert activations(station.Archive, "LEVEL.H") == 1

    again = Runtime(station)
    again.start()
    try:
        assert again.alarms is not None
        assert again.alarms.system.get("LEVEL.H").state in (State.UNACK, State.RTNUN)  # not forgotten
        assert any(r.id == "LEVEL.H" and not r.acked for r in again.alarms.summary)
        wait_until(lambda: quality(again, "LEVEL") is Quality.GOOD, timeout=10)
        wait_until(lambda: again.status().scans > 10, timeout=5)  # no on-delay: a re-raise would be here
        assert not again.alarms.system.get("LEVEL.H").acked
    finally:
        again.stop()
    assert activations(station.Archive, "LEVEL.H") == 1  # raised once, remembered, not raised again


def test_the_operator_pulls_and_plugs_a_simulated_nodes_cable(demo_copy: Path) -> None:
    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    try:
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.GOOD, timeout=10)
        runtime.simulator_answers(0, False)
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.COMM_FAIL, timeout=10)
        wait_until(lambda: runtime.alarms is not None and
                   runtime.alarms.system.get("LEVEL.BAD").state is State.UNACK, timeout=5)
        runtime.simulator_answers(0, True)
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.GOOD, timeout=15)
        wait_until(lambda: runtime.alarms is not None and
                   runtime.alarms.system.get("LEVEL.BAD").state is State.RTNUN, timeout=5)
    finally:
        runtime.stop()


def test_stopping_netplc_raises_one_station_alarm_and_running_again_nothing_spurious(demo_copy: Path) -> None:
    runtime = Runtime(load_station(demo_copy))
    seen: list = []
    runtime.subscribe(lambda r: seen.append(r) if r.kind == "alarm" else None)
    runtime.start()
    try:
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.GOOD, timeout=10)
        assert runtime.alarms is not None
        runtime.stop_program("engineer")
        wait_until(lambda: runtime.alarms is not None and
                   runtime.alarms.system.get(STOPPED_ID).state is State.UNACK, timeout=5)
        assert quality(runtime, "LEVEL") is Quality.NOT_RUNNING
        runtime.run_program("engineer")
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.GOOD, timeout=10)
        wait_until(lambda: runtime.alarms is not None and
                   runtime.alarms.system.get(STOPPED_ID).state is State.RTNUN, timeout=5)
    finally:
        runtime.stop()
    assert not [r for r in seen if r.source.endswith(".BAD")]  # not one quality alarm per tag
    stops = [(r.number, r.type) for r in seen if r.source == STOPPED_ID]
    assert stops == [(State.NORMAL, State.UNACK), (State.UNACK, State.RTNUN)]


def test_the_archived_series_breaks_while_a_node_is_down_and_while_netplc_is_stopped(demo_copy: Path) -> None:
    station = load_station(demo_copy)
    runtime = Runtime(station)
    stored: list = []
    runtime.subscribe(lambda r: stored.append(r) if r.kind == "data" and r.source == "04010" else None)

    def stores(n: int) -> int:
        return sum(1 for r in list(stored) if r.value is not None and r.text is None) + n

    runtime.start()
    try:
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.GOOD, timeout=10)
        target = stores(2)
        wait_until(lambda: stores(0) >= target, timeout=10)  # NSTORE once a second
        runtime.simulator_answers(0, False)  # the node's cable pulled
        wait_until(lambda: any(r.value is None for r in list(stored)), timeout=10)  # the demo stores
        # only while the node answers: the mark is what breaks the line
        runtime.simulator_answers(0, True)
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.GOOD, timeout=15)
        target = stores(1)
        wait_until(lambda: stores(0) >= target, timeout=10)
        runtime.stop_program("engineer")
        wait_until(lambda: any(r.text == "not running" for r in list(stored)), timeout=5)
        runtime.run_program("engineer")
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.GOOD, timeout=10)
        target = stores(1)
        wait_until(lambda: stores(0) >= target, timeout=10)
    finally:
        runtime.stop()
    marks = [r.text for r in stored if r.value is None]
    assert marks in (["comm-fail", "not running"], ["stale", "not running"])  # one as each outage began

    with Archive(station.Archive) as archive:
        day = archive.days()[0]
        _, values = archive.series(day, grp=1, type=1, source="04010")
    gaps = np.flatnonzero(np.isnan(values))
    assert len(gaps) == 2 and 0 < gaps[0] < gaps[1] < len(values) - 1  # good points around each gap
    assert not np.isnan(values[gaps[0] - 1]) and not np.isnan(values[gaps[1] + 1])


def test_a_forms_regdata_series_is_marked_when_its_node_goes_down(demo_copy: Path) -> None:
    form = demo_copy / "forms" / "02_analog.hmi"
    doc = json.loads(form.read_text(encoding="utf-8"))
    level = next(e for e in doc["elements"] if e["Name"] == "Уровень")
    level["RegData"] = True
    form.write_text(json.dumps(doc, ensure_ascii=False), encoding="utf-8")
    runtime = Runtime(load_station(demo_copy))
    stored: list = []
    runtime.subscribe(lambda r: stored.append(r) if r.kind == "data" and r.source == "Уровень" else None)
    runtime.start()
    try:
        wait_until(lambda: quality(runtime, "LEVEL") is Quality.GOOD, timeout=10)
        wait_until(lambda: any(r.value is not None for r in list(stored)), timeout=10)
        runtime.simulator_answers(0, False)
        wait_until(lambda: any(r.value is None for r in list(stored)), timeout=10)
    finally:
        runtime.stop()
    mark = next(r for r in stored if r.value is None)
    assert mark.text in ("comm-fail", "stale") and mark.grp is None and mark.type is None
