"""NetPlc's own Modbus TCP server, seen by clients that are not ours: pymodbus's sync client and a
raw socket (issue 4 acceptance: the documented map, writes refused outside the allowed ranges)."""

from __future__ import annotations

import socket
import struct
import threading
from collections.abc import Iterator

import pytest
from pymodbus.client import ModbusTcpClient

from netplc.engine import Engine, FakeClock
from netplc.modbus.server import ModbusServer
from netplc.program import parse
from netplc.records import ListSink
from netplc.simulator import EngineMemory

WRITABLE = [(0o2040, 0o2077), (0o4000, 0o4017)]


@pytest.fixture
def served() -> Iterator[tuple[Engine, ModbusServer, ListSink]]:
    sink = ListSink()
    engine = Engine(parse("TNA $03760\nJMP 0\n"), clock=FakeClock(), sink=sink)
    engine.mem.set_word(0o4000, 0x1234)
    engine.mem.set_word(0o14000, 0x00AB)
    engine.mem.set_bit(0o2042, 1)
    engine.scan()
    server = ModbusServer(EngineMemory(engine, WRITABLE), unit=1, sink=sink)
    server.start()
    yield engine, server, sink
    server.stop()


@pytest.fixture
def client(served: tuple[Engine, ModbusServer, ListSink]) -> Iterator[ModbusTcpClient]:
    c = ModbusTcpClient("127.0.0.1", port=served[1].port, timeout=2)
    assert c.connect()
    yield c
    c.close()


def test_documented_map(client: ModbusTcpClient) -> None:
    assert client.read_holding_registers(1024, count=1, device_id=1).registers == [0x1234]
    assert client.read_input_registers(1024, count=1, device_id=1).registers == [0x1234]
    assert client.read_holding_registers(0o14000 // 2, count=1, device_id=1).registers == [0x00AB]
    assert client.read_coils(0o2040, count=4, device_id=1).bits[:4] == [False, False, True, False]
    assert client.read_discrete_inputs(0o2042, count=1, device_id=1).bits[0] is True


def test_reads_outside_memory_answer_exception_2(client: ModbusTcpClient) -> None:
    for rr in (client.read_holding_registers(0, count=1, device_id=1),
               client.read_holding_registers(1023, count=2, device_id=1),  # 03776..04001
               client.read_holding_registers(0o10000 // 2, count=1, device_id=1),  # bank gap
               client.read_coils(0o3777, count=2, device_id=1)):
        assert rr.isError() and rr.exception_code == 2


class Scanning:
    """Scans the engine on a thread of its own while the test's client waits for its answers (a
    write is answered once a scan has applied and journaled it), the clock stepped by hand."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)

    def run(self) -> None:
        clock = self.engine.clock
        assert isinstance(clock, FakeClock)
        while not self.stop.wait(0.005):
            clock.advance(0.1)
            self.engine.scan()

    def __enter__(self) -> Scanning:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join()


def test_writes_are_queued_into_the_scan_and_journaled_with_the_peer(
    served: tuple[Engine, ModbusServer, ListSink], client: ModbusTcpClient
) -> None:
    engine, _, sink = served
    with Scanning(engine):
        assert not client.write_register(1026, 0xBEEF, device_id=1).isError()  # word 04004
        assert engine.writes_applied == 1  # answered only once a scan applied it
        assert not client.write_registers(1028, [1, 2], device_id=1).isError()  # 04010..04013
        assert not client.write_coil(0o2043, True, device_id=1).isError()
        assert not client.write_coils(0o2050, [True] + [False] * 6 + [True], device_id=1).isError()
        assert not client.write_coils(0o2060, [True, False, True], device_id=1).isError()
    snap = engine.snapshot
    assert snap.get_word(0o4004) == 0xBEEF
    assert snap.read(0o4010, 4) == bytes([1, 0, 2, 0])
    assert snap.get_bit(0o2043) == 1
    assert [snap.get_bit(0o2050 + i) for i in range(8)] == [1, 0, 0, 0, 0, 0, 0, 1]
    assert [snap.get_bit(0o2060 + i) for i in range(4)] == [1, 0, 1, 0]
    ops = [r for r in sink.records if r.kind == "operator"]
    assert len(ops) == 5  # one record per request, also for coils that are not whole bytes
    assert ops[4].text == "write 02060:3 bits: 000 -> 101"
    local_port = client.socket.getsockname()[1]
    assert {r.source for r in ops} == {f"modbus 127.0.0.1:{local_port}"}
    assert ops[0].text == "write 04004: 0 -> 48879"


def test_writes_outside_the_allowed_ranges_answer_exception_2(
    served: tuple[Engine, ModbusServer, ListSink], client: ModbusTcpClient
) -> None:
    engine, _, sink = served
    for rr in (client.write_register(1032, 1, device_id=1),  # byte 04020: past 04017
               client.write_registers(1031, [1, 2], device_id=1),  # 04016..04021 straddles the end
               client.write_coil(0o2000, True, device_id=1),
               client.write_coils(0o2076, [True] * 4, device_id=1),  # 02076..02101
               client.write_register(0, 1, device_id=1)):
        assert rr.isError() and rr.exception_code == 2
    engine.scan()
    assert not [r for r in sink.records if r.kind == "operator"]


def _raw(port: int, unit: int, pdu: bytes) -> bytes:
    with socket.create_connection(("127.0.0.1", port), timeout=2) as s:
        s.sendall(struct.pack(">HHHB", 7, 0, len(pdu) + 1, unit) + pdu)
        head = s.recv(7)
        tid, proto, length, got_unit = struct.unpack(">HHHB", head)
        assert (tid, proto, got_unit) == (7, 0, unit)
        body = b""
        while len(body) < length - 1:
            body += s.recv(256)
        return body


def test_raw_client_exceptions(served: tuple[Engine, ModbusServer, ListSink]) -> None:
    port = served[1].port
    assert _raw(port, 1, bytes([3, 0x04, 0x00, 0x00, 0x01])) == bytes([3, 2, 0x12, 0x34])
    assert _raw(port, 1, bytes([0x2B, 0x0E, 0x01, 0x00])) == bytes([0xAB, 1])  # unsupported function
    assert _raw(port, 1, bytes([3, 0x04, 0x00, 0x00, 0x00])) == bytes([0x83, 3])  # count 0
    assert _raw(port, 1, bytes([5, 0x04, 0x22, 0x12, 0x34])) == bytes([0x85, 3])  # coil value not FF00/0000
    assert _raw(port, 9, bytes([3, 0x04, 0x00, 0x00, 0x01])) == bytes([0x83, 0x0B])  # another unit id


def test_read_only_by_default_and_ranges_are_checked() -> None:
    engine = Engine(parse("JMP 0\n"), clock=FakeClock())
    server = ModbusServer(EngineMemory(engine, ()))
    with pytest.raises(ValueError, match="not within 00000-077777"):
        EngineMemory(engine, [(0o4000, 0o100000)])
    server.start()
    try:
        c = ModbusTcpClient("127.0.0.1", port=server.port, timeout=2)
        assert c.connect()
        rr = c.write_register(1024, 1)
        assert rr.isError() and rr.exception_code == 2
        c.close()
    finally:
        server.stop()
