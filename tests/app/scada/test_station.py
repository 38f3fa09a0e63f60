"""Tags, quality and alarms attached to a real engine: quality from a node that is killed, NMSG
alarms, operator actions through the engine thread, and a restart that raises nothing twice.

Real time is involved (sockets, threads), so every wait polls a condition against a deadline."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.scada.alarms import AlarmError, State
from app.scada.quality import Quality
from app.scada.station import StationAlarms
from netplc.engine import Engine, FakeClock
from netplc.exchange import Exchange, NodeConfig
from netplc.program import parse
from netplc.records import ListSink, Record
from netplc.scheduler import ScanThread
from netplc.simulator import Simulator
from registrar.catalog import Message
from tests.netplc.test_exchange import wait_until

TICK = 0.01
PROGRAM = "TNA $03760\nFON C:$02110 N:NREAD S:4010 D:$04010 R:2\nJMP 0\n"
TAGS = ("name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description,h\n"
        "LEVEL,LEVEL_SYM,word,%,0,4095,0,100,1,Уровень,90\n")


class Tap(ListSink):
    """The runtime's sink: keeps the records and shows each to the alarms (its record observer)."""

    alarms: StationAlarms | None = None

    def put(self, record: Record) -> None:
        super().put(record)
        if self.alarms is not None:
            self.alarms.observe(record)


class Plant:
    """A simulated CPU-165 node whose word 04010 is the level."""

    def __init__(self, level: int) -> None:
        self.node = Simulator(parse("JMP 0\n"), port=0, tick=TICK)
        self.node.engine.mem.set_word(0o4010, level)
        self.node.start()


class Run:
    """What a runtime holds: engine, exchange, alarms, scan thread."""

    def __init__(self, folder: Path, port: int) -> None:
        (folder / "tags.csv").write_text(TAGS, encoding="utf-8")
        self.sink = Tap()
        program = parse(PROGRAM)
        self.engine = Engine(program, tick=TICK, sink=self.sink)
        self.exchange = Exchange([NodeConfig(0, f"tcp://127.0.0.1:{port}", timeout=0.2, retries=0,
                                             backoff=0.05, backoff_max=0.1)], self.sink)
        self.exchange.attach(self.engine)
        self.alarms = StationAlarms(folder / "tags.csv", program, [], self.sink, folder / "alarms.sqlite",
                                    {"LEVEL_SYM": 0o4010})
        self.sink.alarms = self.alarms
        self.alarms.attach(self.engine, self.exchange)
        self.scan = ScanThread(self.engine, TICK)
        self.exchange.start()
        self.scan.start()

    def state(self, alarm_id: str) -> State:
        return self.alarms.system.get(alarm_id).state

    def transitions(self, alarm_id: str) -> list[tuple[int, int]]:
        return [(r.number, r.type) for r in list(self.sink.records)
                if r.kind == "alarm" and r.source == alarm_id]

    def stop(self) -> None:
        self.scan.stop()
        self.exchange.stop()
        self.alarms.close()


def test_quality_alarms_and_a_restart_with_a_real_node(tmp_path: Path) -> None:
    plant = Plant(3900)  # 95 %
    run = Run(tmp_path, plant.node.port)
    try:
        wait_until(lambda: run.state("LEVEL.H") is State.UNACK)
        assert run.alarms.quality[0] == Quality.GOOD
        run.alarms.acknowledge("LEVEL.H", "ivanov")
        wait_until(lambda: run.state("LEVEL.H") is State.ACKED)
        plant.node.stop()  # the node dies: its tag is comm-fail, its own alarm comes
        wait_until(lambda: run.state("LEVEL.BAD") is State.UNACK)
        assert run.alarms.quality[0] == Quality.COMM_FAIL
        assert run.state("LEVEL.H") is State.ACKED  # frozen, neither raised again nor gone
    finally:
        run.stop()
    first = run.transitions("LEVEL.H")
    assert first == [(State.NORMAL, State.UNACK), (State.UNACK, State.ACKED)]

    plant = Plant(3900)  # the plant is back, still high
    again = Run(tmp_path, plant.node.port)
    try:
        wait_until(lambda: again.state("LEVEL.BAD") is State.RTNUN)  # quality good again
        assert again.state("LEVEL.H") is State.ACKED
        assert again.transitions("LEVEL.H") == []  # no second alarm
        with pytest.raises(AlarmError):
            again.alarms.shelve("LEVEL.H", "petrov", "", 60)
        again.alarms.shelve("LEVEL.H", "petrov", "calibration", 60)
        wait_until(lambda: again.state("LEVEL.H") is State.SHELVED)
    finally:
        again.stop()
        plant.node.stop()


def test_nmsg_alarm_messages_reach_the_alarms_through_the_record_observer(tmp_path: Path) -> None:
    sink = Tap()
    program = parse("TNA $02000\nFON C:$02010 N:NMSG S:3 D:1 R:2\nJMP 0\n")
    clock = FakeClock(100.0)
    engine = Engine(program, clock=clock, wallclock=clock, sink=sink)
    alarms = StationAlarms(None, program, [Message(3, 1, 2, "Уровень выше 90 %")], sink,
                           tmp_path / "alarms.sqlite")
    sink.alarms = alarms
    alarms.attach(engine, None)
    try:
        engine.scan()
        assert alarms.system.get("MSG3").state is State.NORMAL
        engine.write_bit(0o2000, 1)
        engine.scan()
        assert alarms.system.get("MSG3").state is State.UNACK
        engine.write_bit(0o2000, 0)
        engine.scan()
        assert alarms.system.get("MSG3").state is State.RTNUN
        alarms.acknowledge_all("operator")
        engine.scan()
        assert alarms.system.get("MSG3").state is State.NORMAL
    finally:
        alarms.close()


def test_a_forced_tag_has_the_forced_quality_and_unforced_its_own_again(tmp_path: Path) -> None:
    (tmp_path / "tags.csv").write_text(TAGS + "SP,04020,word,,,,,,0,Уставка,\nRUN,040042,bit,,,,,,,Пуск,\n",
                                       encoding="utf-8")
    program = parse("JMP 0\n")
    clock = FakeClock(100.0)
    engine = Engine(program, clock=clock, wallclock=clock, sink=ListSink())
    alarms = StationAlarms(tmp_path / "tags.csv", program, [], ListSink(), tmp_path / "alarms.sqlite",
                           {"LEVEL_SYM": 0o4010})
    alarms.attach(engine, None)
    names = [t.name for t in alarms.table.tags]
    try:
        engine.scan()
        assert {alarms.readings.quality(n) for n in ("SP", "RUN")} == {Quality.GOOD}
        engine.forces.force("word", 0o4021, 7, user="engineer")  # covers the high byte of SP only
        engine.forces.force("bit", 0o40042, 1, user="engineer")  # an HMI bit: byte 04004 bit 2
        engine.scan()
        assert alarms.quality[names.index("SP")] == Quality.FORCED
        assert alarms.quality[names.index("RUN")] == Quality.FORCED
        assert alarms.quality[names.index("LEVEL")] == Quality.GOOD
        engine.forces.unforce_all(user="engineer")
        engine.scan()
        assert {alarms.readings.quality(n) for n in ("SP", "RUN")} == {Quality.GOOD}
    finally:
        alarms.close()
