"""A hot-standby pair on loopback (issue 26): the standby mirrors the primary every scan, refuses
writes naming it, takes over when the primary dies, and a restarted primary comes back as the
standby; IntoStandBy switches over and back with nothing lost."""

from __future__ import annotations

import pytest

from app.authority import Source, Who
from app.authority.layer import Reason
from app.cli import run_redundancy
from app.station.pair import HSB_NUM_PLC, HSB_STATUS_BYTE, HSB_SWITCH
from netplc.modbus import BUSY
from netplc.simulator import Simulator
from tests.app.pair.conftest import OPERATOR, Station, modbus_write, start_pair, wait_for, wait_paired

NODE_WORD = 0o4100  # where the primary's NWRITE puts the operator's word 04000 on the node
TIMER, COUNTER = 0o3000, 0o3010
ENGINEER = Who("", Source.STATION)  # the station's own authority: more than an engineer


def byte(station: Station, addr: int) -> int:
    assert station.rt.engine is not None
    return station.rt.engine.snapshot.get_byte(addr)


def node_word(node: Simulator) -> int:
    return node.engine.snapshot.get_word(NODE_WORD)


def test_the_standby_mirrors_and_refuses_writes_naming_the_primary(
        pair: tuple[Station, Station], node: Simulator) -> None:
    a, b = pair
    start_pair(a, b)
    assert (a.role, b.role) == ("primary", "standby")
    assert a.write(0o4000, 1234).ok
    wait_for(lambda: node_word(node) == 1234, what="the primary writes the node")
    wait_for(lambda: b.word(0o4000) == 1234, what="the standby mirrors the write")
    assert b.rt.modbus is not None
    assert modbus_write(b.rt.modbus.port, 1024, 99) == BUSY  # register 1024: the word 04000
    answer = b.write(0o4000, 7)
    assert answer.reason is Reason.STANDBY and "the primary is A" in answer.text
    assert any("refused" in t and "the primary is A" in t for t in b.texts())
    assert b.rt.exchange is not None and b.rt.exchange.stats[1].writes == 0  # only A writes
    assert "standby" in b.rt.status().pair


def test_kill_the_primary_the_standby_takes_over_and_the_old_one_comes_back_as_standby(
        pair: tuple[Station, Station], node: Simulator) -> None:
    a, b = pair
    start_pair(a, b)
    assert a.write(0o4000, 1111).ok
    assert a.rt.engine is not None and b.rt.engine is not None
    wait_for(lambda: b.word(0o4000) == 1111 and b.rt.engine.tim_ticks[TIMER] > 2, what="mirrored")
    # what the standby holds once the next write is answered: the state of a scan after this one
    # (read after the answer, the primary may have scanned on past what the standby was sent)
    elapsed, counted = a.rt.engine.tim_ticks[TIMER], a.rt.engine.ctr_values[COUNTER]
    assert a.write(0o4000, 1112).ok  # answered once the standby holds it: killed right after
    counted_at_kill = a.rt.engine.ctr_values[COUNTER]
    a.kill()
    wait_for(lambda: b.role == "primary", what="takeover")  # how fast: bench/failover.py
    # the role changes on the pair's thread, its record reaches the journal on the engine's
    wait_for(lambda: any("partner silent for" in t for t in b.texts()), what="the takeover journaled")
    wait_for(lambda: b.word(0o4000) == 1112, what="the acknowledged write is not lost")
    assert b.rt.engine.tim_ticks[TIMER] >= elapsed  # the timer kept its elapsed time
    assert b.rt.engine.ctr_values[COUNTER] >= counted  # and the counter its count, no edge twice
    assert b.rt.engine.ctr_values[COUNTER] <= counted_at_kill + 2
    assert b.write(0o4000, 2222).ok
    wait_for(lambda: node_word(node) == 2222, what="the new primary writes the node")
    a.start()  # the old primary comes back, finds a live primary and follows it
    assert a.role == "standby"
    wait_for(lambda: a.word(0o4000) == 2222, what="the old primary catches up")
    assert a.rt.exchange is not None and a.rt.exchange.stats[1].writes == 0


def test_into_standby_switches_over_and_back_with_nothing_lost(
        pair: tuple[Station, Station], node: Simulator) -> None:
    a, b = pair
    start_pair(a, b)
    wait_paired(a, b)
    assert a.write(0o4000, 1).ok
    assert a.rt.commands is not None
    assert a.rt.commands.into_standby(OPERATOR).result(3).reason is Reason.DENIED  # engineer's
    assert a.rt.commands.into_standby(ENGINEER).result(3).ok
    wait_for(lambda: b.role == "primary" and a.role == "standby", what="switchover")
    wait_for(lambda: b.word(0o4000) == 1, what="B leads from A's last scan")
    assert b.write(0o4000, 2).ok
    wait_for(lambda: a.word(0o4000) == 2 and node_word(node) == 2, what="B leads")
    assert a.rt.commands.into_standby(ENGINEER).result(3).reason is Reason.STANDBY
    assert b.rt.pair is not None and b.rt.pair.into_standby("IntoStandBy by test", wait=2)
    wait_for(lambda: a.role == "primary" and b.role == "standby", what="switch back")
    wait_for(lambda: a.word(0o4000) == 2, what="A leads from B's last scan")
    assert a.write(0o4000, 3).ok
    wait_for(lambda: node_word(node) == 3, what="A leads again")
    assert any("handed over by the partner: IntoStandBy by station" in t for t in b.texts())
    assert any("handed over by the partner: IntoStandBy by test" in t for t in a.texts())


def test_the_hsb_status_words_and_redundancy_status(pair: tuple[Station, Station], node: Simulator,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    a, b = pair
    start_pair(a, b)
    wait_for(lambda: (byte(a, HSB_NUM_PLC), byte(a, HSB_STATUS_BYTE)) == (1, 5)
             and (byte(b, HSB_NUM_PLC), byte(b, HSB_STATUS_BYTE)) == (0, 4), what="HSBNumPLC, HSBStatus")
    assert b.rt.pair is not None
    assert run_redundancy(f"127.0.0.1:{b.rt.pair.port}") == 0
    out = capsys.readouterr().out
    assert "letter: B" in out and "role: standby" in out and "link: up" in out, out
    a.kill()
    wait_for(lambda: byte(b, HSB_STATUS_BYTE) == 5 and b.rt.engine is not None
             and b.rt.engine.snapshot.get_word(HSB_SWITCH) == (1 << 8 | 50), what="B's words after takeover")
