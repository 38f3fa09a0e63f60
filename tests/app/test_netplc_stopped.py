"""NetPlc not running, stepped with a FakeClock: the operator's Stop, an emergency stop by bit
03770 and HLT each raise the one NETPLC.STOPPED alarm (with why), never a quality alarm per tag;
the tags' alarms stay frozen while it is stopped, and running again raises nothing spurious."""

from __future__ import annotations

from pathlib import Path

from app.scada.alarms import STOPPED_ID, STOPPED_PRIORITY, State
from app.scada.quality import Quality
from app.scada.station import StationAlarms, stop_reason
from netplc.address import EMERGENCY_STOP
from netplc.engine import Engine, FakeClock
from netplc.program import parse
from netplc.records import ListSink

T0 = 1_800_000_000.0
HALT_BIT = 0o2100  # the program halts while it is 1
PROGRAM = "TNA $02100\nJMN go\nHLT\ngo: NOP\n"
TAGS = ("name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description,h,off_delay\n"
        "LEVEL,04010,word,%,0,4095,0,100,1,Уровень,90,0.5\n")


class Station:
    """An engine on a FakeClock with the station's alarms attached, scanned by the test."""

    def __init__(self, folder: Path) -> None:
        (folder / "tags.csv").write_text(TAGS, encoding="utf-8")
        self.clock = FakeClock()
        self.sink = ListSink()
        program = parse(PROGRAM)
        self.engine = Engine(program, clock=self.clock, wallclock=lambda: T0 + self.clock.t,
                             sink=self.sink, tick=0.1)
        self.alarms = StationAlarms(folder / "tags.csv", program, [], self.sink, folder / "alarms.sqlite")
        self.alarms.attach(self.engine, None)

    def scan(self, n: int = 1) -> None:
        for _ in range(n):
            self.clock.advance(0.1)
            self.engine.scan()

    def level(self, percent: float) -> None:
        self.engine.write_word(0o4010, round(percent * 4095 / 100))

    def state(self, alarm_id: str) -> State:
        return self.alarms.system.get(alarm_id).state

    def alarm_records(self) -> list[tuple[str, int, int]]:
        return [(r.source or "", r.number or 0, r.type or 0) for r in self.sink.records if r.kind == "alarm"]

    def quality(self) -> Quality:
        readings = self.alarms.readings
        assert readings is not None
        return readings.tag("LEVEL").quality


def test_stop_emergency_stop_and_hlt_raise_one_station_alarm_and_no_quality_alarm(tmp_path: Path) -> None:
    st = Station(tmp_path)
    st.level(95)
    st.scan(2)
    assert st.state("LEVEL.H") is State.UNACK and st.quality() is Quality.GOOD
    st.alarms.system.acknowledge("LEVEL.H", "ivanov")

    st.engine.stop()  # the operator's Stop (runtime.stop_program)
    st.level(50)  # written while stopped: a frozen value says nothing, the alarm stays
    st.scan(10)
    assert st.quality() is Quality.NOT_RUNNING
    assert st.state("LEVEL.H") is State.ACKED and st.state("LEVEL.BAD") is State.NORMAL
    assert st.state(STOPPED_ID) is State.UNACK
    stopped = st.alarms.system.get(STOPPED_ID)
    assert stopped.defn.priority == STOPPED_PRIORITY == 2
    assert stopped.text == "NetPlc is not running: stopped by the operator or the watchdog (code 0)"
    row = next(r for r in st.alarms.summary if r.id == STOPPED_ID)
    assert "stopped by the operator" in row.text
    record = next(r for r in st.sink.records if r.kind == "alarm" and r.source == STOPPED_ID)
    assert record.grp == 2 and record.type == State.UNACK and "code 0" in (record.text or "")

    st.engine.start()  # runs again: the station alarm returns; the value is judged afresh
    st.scan(10)
    assert st.quality() is Quality.GOOD
    assert st.state(STOPPED_ID) is State.RTNUN and st.state("LEVEL.H") is State.NORMAL
    st.alarms.system.acknowledge(STOPPED_ID, "ivanov")

    st.engine.write_bit(EMERGENCY_STOP, 1)  # an emergency stop by bit 03770
    st.scan(3)
    assert st.state(STOPPED_ID) is State.UNACK
    assert st.alarms.system.get(STOPPED_ID).detail == "emergency stop by bit 03770 (code 11)"
    st.engine.start()
    st.scan(2)
    st.alarms.system.acknowledge(STOPPED_ID, "ivanov")

    st.engine.write_bit(HALT_BIT, 1)  # the program halts by HLT
    st.scan(3)
    assert st.state(STOPPED_ID) is State.UNACK
    assert st.alarms.system.get(STOPPED_ID).detail == "halted by HLT"

    assert not [r for r in st.alarm_records() if r[0] == "LEVEL.BAD"]  # never one per tag
    stops = [r for r in st.alarm_records() if r[0] == STOPPED_ID]
    assert [new for _, _, new in stops] == [State.UNACK, State.RTNUN, State.NORMAL, State.UNACK, State.RTNUN,
                                            State.NORMAL, State.UNACK]


def test_a_tag_whose_quality_alarm_was_active_keeps_it_frozen_while_netplc_is_stopped(tmp_path: Path) -> None:
    st = Station(tmp_path)
    st.scan()
    system = st.alarms.system
    system.evaluate(st.engine.snapshot, T0 + 1, [Quality.COMM_FAIL])  # the node went down
    assert st.state("LEVEL.BAD") is State.UNACK
    system.evaluate(st.engine.snapshot, T0 + 2, [Quality.NOT_RUNNING], stopped="halted by HLT")
    system.evaluate(st.engine.snapshot, T0 + 3, [Quality.INITIAL])  # runs again, no data yet
    assert st.state("LEVEL.BAD") is State.UNACK  # nothing known: it neither comes nor goes
    system.evaluate(st.engine.snapshot, T0 + 4, [Quality.GOOD])
    assert st.state("LEVEL.BAD") is State.RTNUN


def test_stop_reasons_name_the_stop_code() -> None:
    assert stop_reason("stopped") == "stopped by the operator or the watchdog (code 0)"
    assert stop_reason("stopped, code 11") == "emergency stop by bit 03770 (code 11)"
    assert stop_reason("halted") == "halted by HLT"
    assert stop_reason("stopped, code 7") == "stopped, code 7"


def test_netplc_stopped_names_who_stopped_it_through_the_command_layer(tmp_path: Path) -> None:
    from app.scada.station import STOPPED_BY_COMMAND
    from netplc.records import Record

    st = Station(tmp_path)
    st.engine.start()
    st.scan(2)
    st.alarms.observe(Record(T0, "operator", source="engineer", text=STOPPED_BY_COMMAND))  # Commands.stop
    st.engine.stop()
    st.scan(2)
    assert st.alarms.system.get(STOPPED_ID).text == "NetPlc is not running: stopped by engineer (code 0)"
    st.engine.start()
    st.scan(2)
    st.engine.stop()  # not through the layer (the watchdog): who is not known
    st.scan(2)
    assert "stopped by the operator or the watchdog" in st.alarms.system.get(STOPPED_ID).text
