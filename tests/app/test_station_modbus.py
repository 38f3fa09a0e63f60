"""The station's Modbus server as an entry point of the command layer (app/authority/modbus.py):
every write a command, checked, journaled, answered after the commit or refused with the exception
its reason maps to. Real Modbus TCP on 127.0.0.1, the real layer and engine, the scans, the
archive's commits and the layer's minute stepped by hand."""

from __future__ import annotations

import socket
import struct
from collections.abc import Iterator
from dataclasses import dataclass

import pytest

from app.authority import Commands, Source
from app.authority.layer import Reason
from app.authority.modbus import EXCEPTION_OF, ModbusCommands
from app.station.config import DEFAULT_WRITABLE
from netplc.address import EMERGENCY_STOP
from netplc.engine import Engine, FakeClock, RunState
from netplc.modbus import ModbusServer
from netplc.program import parse
from tests.app.authority.test_layer import Durable
from tests.netplc.test_modbus_server_limits import Answers, connect_from, request, wait_until, write_register

BANK1 = 0o14000 // 2  # register of data byte 014000: memory, but not writable by default


@dataclass
class Rig:
    engine: Engine
    sink: Durable
    commands: Commands
    server: ModbusServer
    clock: FakeClock
    minute: list[float]

    def scan(self) -> None:
        self.clock.advance(self.engine.tick)
        self.engine.scan()

    def operator_records(self) -> list[str]:
        return [r.text or "" for r in self.sink.records if r.kind == "operator"]


@pytest.fixture
def rig() -> Iterator[Rig]:
    sink, clock, minute = Durable(), FakeClock(), [0.0]
    engine = Engine(parse("TNA $03760\nYON $02001\n"), clock=clock, sink=sink, write_queue=2)
    commands = Commands(engine, sink, role_of={}.get, monotonic=lambda: minute[0])
    server = ModbusServer(ModbusCommands(commands, DEFAULT_WRITABLE), sink=sink)
    server.start()
    yield Rig(engine, sink, commands, server, clock, minute)
    server.stop()


def write_coil(tid: int, bit: int, on: bool) -> bytes:
    return request(tid, struct.pack(">BHH", 5, bit, 0xFF00 if on else 0))


def exception(code: int, fc: int = 6) -> bytes:
    return bytes((fc | 0x80, code))


def test_every_reason_has_its_modbus_exception() -> None:
    assert set(EXCEPTION_OF) == set(Reason)
    assert (EXCEPTION_OF[Reason.DENIED], EXCEPTION_OF[Reason.NOT_WRITABLE], EXCEPTION_OF[Reason.BUSY],
            EXCEPTION_OF[Reason.JOURNAL_FULL], EXCEPTION_OF[Reason.FAILED]) == (1, 2, 6, 6, 4)


def test_a_write_is_answered_once_applied_and_committed_and_journaled_naming_the_peer(rig: Rig) -> None:
    with socket.create_connection(("127.0.0.1", rig.server.port)) as sock:
        answers = Answers(sock)
        sock.sendall(write_register(1, 1024, 0x55))
        wait_until(lambda: rig.engine.writes_waiting == 1)
        rig.scan()
        assert rig.engine.snapshot.get_word(0o4000) == 0x55
        assert answers.got == []  # applied, but its record is not committed yet
        rig.sink.commit()
        wait_until(lambda: len(answers.got) == 1)
        peer = f"modbus 127.0.0.1:{sock.getsockname()[1]}"
    assert answers.got == [(1, bytes.fromhex("06 0400 0055"))]
    assert [(r.source, r.text) for r in rig.sink.records if r.kind == "operator"] == [
        (peer, "write 04000: 0 -> 85")]


def test_writes_outside_writable_answer_2_with_one_record_per_minute_carrying_the_count(rig: Rig) -> None:
    with socket.create_connection(("127.0.0.1", rig.server.port)) as sock:
        answers = Answers(sock)
        sock.sendall(b"".join(write_register(i, BANK1, i) for i in range(100)))
        wait_until(lambda: len(answers.got) == 100)
        assert {pdu for _, pdu in answers.got} == {exception(2)}
        assert rig.operator_records() == [
            "refused write 014000: not writable over Modbus (station.toml [modbus_server] writable)"]
        rig.minute[0] = 61.0
        sock.sendall(write_register(100, BANK1, 1))
        wait_until(lambda: len(answers.got) == 101)
    assert rig.operator_records()[1].endswith("(99 more refused like it in the minute before)")
    assert rig.commands.refusals == 101
    rig.scan()
    assert rig.engine.snapshot.get_word(0o14000) == 0  # nothing was written


def test_the_stop_bit_not_named_writable_is_refused_and_journaled(rig: Rig) -> None:
    with socket.create_connection(("127.0.0.1", rig.server.port)) as sock:
        answers = Answers(sock)
        sock.sendall(write_coil(7, EMERGENCY_STOP, True))
        wait_until(lambda: len(answers.got) == 1)
    assert answers.got == [(7, exception(2, 5))]
    rig.scan()
    assert rig.engine.state is RunState.RUNNING
    assert rig.operator_records() == [
        "refused write 03770: not writable over Modbus (station.toml [modbus_server] writable)"]


def test_a_full_journal_answers_6_at_once(rig: Rig) -> None:
    rig.sink.space = 10  # the archive takes 10 more records: less than a scan's writes may need
    with socket.create_connection(("127.0.0.1", rig.server.port)) as sock:
        answers = Answers(sock)
        sock.sendall(write_register(1, 1024, 1))
        wait_until(lambda: len(answers.got) == 1)  # no scan, no commit: answered at once
    assert answers.got == [(1, exception(6))]
    assert rig.engine.writes_waiting == 0
    assert "the archive cannot take the record" in rig.operator_records()[0]


def test_a_full_queue_answers_6_at_once(rig: Rig) -> None:
    with socket.create_connection(("127.0.0.1", rig.server.port)) as first, \
            connect_from("127.0.0.2", rig.server.port) as second:
        held = Answers(first)
        first.sendall(write_register(1, 1024, 1) + write_register(2, 1025, 2))  # the queue holds 2
        wait_until(lambda: rig.engine.writes_waiting == 2)
        answers = Answers(second)
        second.sendall(write_register(3, 1026, 3))
        wait_until(lambda: len(answers.got) == 1)
        assert answers.got == [(3, exception(6))] and held.got == []
        rig.scan()
        rig.sink.commit()
        wait_until(lambda: len(held.got) == 2)
    assert [pdu[0] for _, pdu in held.got] == [6, 6]


def test_a_viewer_role_makes_the_server_read_only(rig: Rig) -> None:
    rig.commands.grant(Source.MODBUS, "viewer")
    with socket.create_connection(("127.0.0.1", rig.server.port)) as sock:
        answers = Answers(sock)
        sock.sendall(write_register(1, 1024, 1) + request(2, struct.pack(">BHH", 3, 1024, 1)))
        wait_until(lambda: len(answers.got) == 2)
    assert answers.got == [(1, exception(1)), (2, bytes.fromhex("03 02 0000"))]
    assert rig.operator_records() == [
        "refused write 04000: needs the operator role; clients with no user act as viewer"]
    with pytest.raises(ValueError, match="role 'root' is not one of"):
        rig.commands.grant(Source.MODBUS, "root")
