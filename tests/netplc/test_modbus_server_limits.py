"""What no Modbus client may do to the station (issue 18): freeze the scan with a flood of writes,
be told a write succeeded before it is journaled, hold connections or memory without end, or
flood the journal. Real sockets on 127.0.0.1, a real archive file, the scans stepped by hand."""

from __future__ import annotations

import socket
import sqlite3
import struct
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from netplc.address import EMERGENCY_STOP
from netplc.engine import Engine, FakeClock, RunState
from netplc.modbus import Done, Table
from netplc.modbus.map import MapError
from netplc.modbus.pdu import ILLEGAL_FUNCTION
from netplc.modbus.server import ModbusServer
from netplc.modbus.tcp_server import ServerLimits, Throttle
from netplc.program import parse
from netplc.records import ListSink
from netplc.simulator import EngineMemory
from registrar.schema import DAY_GLOB
from registrar.store import Store

MBAP = struct.Struct(">HHHB")


def request(tid: int, pdu: bytes, unit: int = 1) -> bytes:
    return MBAP.pack(tid, 0, len(pdu) + 1, unit) + pdu


def write_register(tid: int, register: int, value: int) -> bytes:
    return request(tid, struct.pack(">BHH", 6, register, value))


def read_registers(tid: int, register: int, count: int) -> bytes:
    return request(tid, struct.pack(">BHH", 3, register, count))


class Answers:
    """Reads Modbus TCP answers off a socket on a thread of its own: (tid, PDU) in arrival order."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self.got: list[tuple[int, bytes]] = []
        self.closed = False
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self) -> None:
        buf = b""
        while True:
            try:
                data = self.sock.recv(65536)
            except OSError:
                data = b""
            if not data:
                self.closed = True
                return
            buf += data
            while len(buf) >= 7:
                tid, _, length, _ = MBAP.unpack_from(buf)
                if len(buf) < 6 + length:
                    break
                self.got.append((tid, buf[7 : 6 + length]))
                buf = buf[6 + length :]


def wait_until(cond, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError("condition not met in time")
        time.sleep(0.002)


def journaled_values(path: Path) -> set[float]:
    """The values of every 'operator' record in the archive file."""
    con = sqlite3.connect(path)
    try:
        days = [n for (n,) in con.execute("SELECT name FROM sqlite_master WHERE name GLOB ?", (DAY_GLOB,))]
        return {v for day in days for (v,) in con.execute(f'SELECT value FROM "{day}" WHERE kind = ?',
                                                           ("operator",))}
    finally:
        con.close()


@pytest.fixture
def archive(tmp_path: Path) -> Iterator[Store]:
    store = Store(tmp_path / "journal.sqlite")
    store.start()
    yield store
    store.close()


def test_a_write_flood_is_bounded_per_scan_answered_busy_when_full_and_loses_no_record(
        archive: Store) -> None:
    clock = FakeClock()
    engine = Engine(parse("TNA $03760\nJMP 0\n"), clock=clock, sink=archive, write_budget=8, write_queue=64)
    server = ModbusServer(EngineMemory(engine), sink=engine.sink)  # the default limits
    server.start()
    n = 3000
    try:
        with socket.create_connection(("127.0.0.1", server.port)) as sock:
            answers = Answers(sock)
            sock.sendall(b"".join(write_register(i, 1024 + i % 1000, i + 1) for i in range(n)))
            per_scan = []
            deadline = time.monotonic() + 60
            while len(answers.got) < n and time.monotonic() < deadline:
                before = engine.writes_applied
                clock.advance(0.1)
                engine.scan()
                per_scan.append(engine.writes_applied - before)
                time.sleep(0.001)
            assert len(answers.got) == n
    finally:
        server.stop()
    assert max(per_scan) <= 8  # no scan applied more than its budget, however many came
    assert [tid for tid, _ in answers.got] == list(range(n))  # answered in the order asked
    acked = {tid + 1 for tid, pdu in answers.got if pdu[0] == 6}
    busy = [pdu for _, pdu in answers.got if pdu[0] != 6]
    assert busy and all(pdu == bytes([0x86, 6]) for pdu in busy)  # exception 6: server busy
    assert len(acked) >= 64
    archive.close()
    assert archive.stats.dropped == 0
    assert journaled_values(archive.path) == acked  # every write answered done is journaled, no other


def test_a_write_is_answered_only_once_its_record_is_committed(archive: Store) -> None:
    clock = FakeClock()
    engine = Engine(parse("JMP 0\n"), clock=clock, sink=archive)
    server = ModbusServer(EngineMemory(engine), sink=engine.sink)
    server.start()
    try:
        with socket.create_connection(("127.0.0.1", server.port)) as sock:
            answers = Answers(sock)
            sock.sendall(write_register(1, 1024, 0x55) + read_registers(2, 1024, 1))
            time.sleep(0.2)
            assert answers.got == []  # the read waits behind the write: answers keep their order
            committed = archive.committed
            engine.scan()
            wait_until(lambda: len(answers.got) == 2)
            assert archive.committed > committed  # the record was on disk before the answer left
            assert answers.got[0] == (1, bytes.fromhex("06 0400 0055"))
    finally:
        server.stop()


def test_a_stop_by_bit_03770_from_a_client_is_a_system_record_naming_it() -> None:
    sink = ListSink()
    engine = Engine(parse("TNA $03760\nYON $02000\n"), clock=FakeClock(), sink=sink)
    server = ModbusServer(EngineMemory(engine), sink=engine.sink)
    server.start()
    try:
        with socket.create_connection(("127.0.0.1", server.port)) as sock:
            answers = Answers(sock)
            sock.sendall(request(9, struct.pack(">BHH", 5, EMERGENCY_STOP, 0xFF00)))
            wait_until(lambda: engine.writes_waiting == 1)
            engine.scan()
            wait_until(lambda: len(answers.got) == 1)
            peer = f"modbus 127.0.0.1:{sock.getsockname()[1]}"
    finally:
        server.stop()
    assert engine.state is RunState.STOPPED and engine.state_text == "stopped, code 11"
    stops = [r for r in sink.records if r.kind == "system" and "code 11" in (r.text or "")]
    assert len(stops) == 1 and stops[0].source == peer and peer in (stops[0].text or "")


@pytest.fixture
def limited() -> Iterator[tuple[Engine, ModbusServer, ListSink]]:
    sink = ListSink()
    engine = Engine(parse("JMP 0\n"), clock=FakeClock(), sink=sink)
    engine.mem.set_word(0o4000, 0x1234)
    engine.scan()
    limits = ServerLimits(max_connections=2, idle_timeout=0.3, max_inflight=4)
    server = ModbusServer(EngineMemory(engine, ()), limits=limits, sink=sink)
    server.start()
    yield engine, server, sink
    server.stop()


def closed_by_server(sock: socket.socket, timeout: float = 5.0) -> bool:
    sock.settimeout(timeout)
    try:
        while sock.recv(4096):
            pass
    except ConnectionResetError:
        return True
    except TimeoutError:
        return False
    return True


def test_connections_beyond_the_maximum_are_closed_with_one_journal_line(
        limited: tuple[Engine, ModbusServer, ListSink]) -> None:
    _, server, sink = limited
    kept = [socket.create_connection(("127.0.0.1", server.port)) for _ in range(2)]
    try:
        for s in kept:
            s.sendall(read_registers(1, 1024, 1))
            assert s.recv(64)[7:] == bytes.fromhex("03 02 1234")
        for _ in range(5):
            with socket.create_connection(("127.0.0.1", server.port)) as extra:
                assert closed_by_server(extra)
        kept[0].sendall(read_registers(2, 1024, 1))  # the open ones are still served
        assert kept[0].recv(64)[7:] == bytes.fromhex("03 02 1234")
    finally:
        for s in kept:
            s.close()
    refused = [r for r in sink.records if "refused a connection" in (r.text or "")]
    assert len(refused) == 1 and "max_connections" in (refused[0].text or "")
    assert refused[0].kind == "system"


def test_silent_connections_and_half_frames_are_closed_after_the_idle_timeout(
        limited: tuple[Engine, ModbusServer, ListSink]) -> None:
    _, server, sink = limited
    with socket.create_connection(("127.0.0.1", server.port)) as silent, \
            socket.create_connection(("127.0.0.1", server.port)) as half:
        half.sendall(read_registers(1, 1024, 1)[:5])
        assert closed_by_server(silent) and closed_by_server(half)
    wait_until(lambda: not server._server.connections)
    idle = [r for r in sink.records if "idle_timeout" in (r.text or "")]
    assert len(idle) == 1  # one line per cause per minute, not one per connection


def test_a_client_that_does_not_read_its_answers_is_no_longer_read(
        limited: tuple[Engine, ModbusServer, ListSink]) -> None:
    engine = limited[0]
    server = ModbusServer(EngineMemory(engine, ()), limits=ServerLimits(max_connections=2, max_inflight=4))
    server.start()
    try:
        a_client_that_does_not_read(server)
    finally:
        server.stop()


ANSWER = 259  # bytes of an answer to a read of 125 registers


def answers_past_the_buffers(sock: socket.socket) -> int:
    """Twice as many answers as the kernel can hold between the server and `sock`: its receive buffer
    (set small before it connects, so it stays so) and the server's send buffer at its largest
    (tcp_wmem's maximum, 4 MB by default). The server's CPU is in the answers: 26 MB of them, as
    there once were for a receive buffer left to grow, cost three times as much."""
    try:
        send_max = int(Path("/proc/sys/net/ipv4/tcp_wmem").read_text().split()[2])
    except (OSError, ValueError, IndexError):  # not Linux: what the test sent before
        return 100_000
    return 2 * (sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF) + send_max) // ANSWER


def a_client_that_does_not_read(server: ModbusServer) -> None:
    with socket.socket() as greedy:
        greedy.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 65536)
        greedy.connect(("127.0.0.1", server.port))
        n = answers_past_the_buffers(greedy)
        sender = threading.Thread(
            target=greedy.sendall, args=(b"".join(read_registers(i % 65536, 1024, 125) for i in range(n)),),
            daemon=True)
        sender.start()
        conns = server._server.connections
        wait_until(lambda: conns and not next(iter(conns)).reading)
        conn = next(iter(conns))
        time.sleep(0.2)
        buffered = len(conn.out)  # answers the socket did not take
        assert buffered <= 8 * 260 * 4  # bounded by max_inflight, not by what the client sent
        with socket.create_connection(("127.0.0.1", server.port)) as other:  # others are served
            other.sendall(read_registers(1, 1024, 1))
            assert other.recv(64)[7:] == bytes.fromhex("03 02 1234")
        answers = Answers(greedy)  # reading again: every answer comes, the server resumes reading
        wait_until(lambda: len(answers.got) == n, timeout=30)
        assert all(pdu[:2] == b"\x03\xfa" for _, pdu in answers.got)
        sender.join()


def test_the_throttle_writes_one_line_per_cause_per_minute() -> None:
    lines: list[str] = []
    now = [0.0]
    throttle = Throttle(lines.append, clock=lambda: now[0])
    for _ in range(100):
        throttle("a", "refused")
    throttle("b", "idle")
    now[0] = 61.0
    throttle("a", "refused")
    assert lines == ["refused", "idle", "refused (and 99 more like it in the last minute)"]


def connect_from(source: str, port: int) -> socket.socket:
    """A client from `source`: Linux routes all of 127/8 to lo, so 127.0.0.2 is a second peer."""
    sock = socket.socket()
    sock.bind((source, 0))
    sock.connect(("127.0.0.1", port))
    return sock


def answered(sock: socket.socket, tid: int) -> bool:
    """A register read on `sock` is answered (False: the server closed the connection)."""
    try:
        sock.sendall(read_registers(tid, 1024, 1))
        sock.settimeout(5)
        return len(sock.recv(64)) == 11
    except OSError:  # reset: the server closed it before or after the request came
        return False


def test_one_peer_cannot_take_every_connection() -> None:
    """Issue 23 item 10: 16 connections from one address each sending a request now and then
    used to lock every other client out; now one address holds max_per_peer of them (4 by
    default) and the next are closed at once, one journal line a minute."""
    sink = ListSink()
    engine = Engine(parse("JMP 0\n"), clock=FakeClock(), sink=sink)
    engine.mem.set_word(0o4000, 0x1234)
    engine.scan()
    server = ModbusServer(EngineMemory(engine, ()), sink=sink)  # the default limits: 16, 4 per peer
    server.start()
    hog = [connect_from("127.0.0.1", server.port) for _ in range(16)]
    try:
        served = [answered(s, i) for i, s in enumerate(hog)]
        assert served == [True] * 4 + [False] * 12
        other = connect_from("127.0.0.2", server.port)
        with other:
            assert answered(other, 99)
        assert answered(hog[0], 100)  # those it holds are still served
    finally:
        for s in hog:
            s.close()
        server.stop()
    refused = [r for r in sink.records if "max_per_peer" in (r.text or "")]
    assert len(refused) == 1 and refused[0].kind == "system"
    assert "4 connections from 127.0.0.1 are open" in (refused[0].text or "")


class Gated:
    """A handler that holds the server's loop inside the first read until let go, and notes the
    register each read asks (so which client's request was answered when)."""

    def __init__(self) -> None:
        self.order: list[int] = []
        self.holding = threading.Event()
        self.gate = threading.Event()

    def registers(self, address: int, count: int) -> bytes:
        if not self.order:
            self.holding.set()
            self.gate.wait(10)
        self.order.append(address)
        return bytes(2 * count)

    def bits(self, address: int, count: int) -> bytes:
        raise MapError("no coils here")

    def write(self, table: Table, address: int, values: list[int], peer: str, done: Done) -> int:
        return ILLEGAL_FUNCTION


def test_a_pipelining_client_does_not_make_another_wait_for_its_backlog() -> None:
    handler = Gated()
    server = ModbusServer(handler)
    server.start()
    try:
        with connect_from("127.0.0.1", server.port) as greedy, \
                connect_from("127.0.0.2", server.port) as polite:
            greedy.sendall(read_registers(0, 1024, 1))
            assert handler.holding.wait(5)  # the loop is held: what comes next waits in the kernel
            backlog = 3000
            greedy.sendall(b"".join(read_registers(i, 1024, 1) for i in range(1, backlog + 1)))
            polite.sendall(read_registers(1, 2000, 1))
            handler.gate.set()
            answers = Answers(greedy)
            polite.settimeout(5)
            assert polite.recv(64)[7:] == bytes.fromhex("03 02 0000")
            wait_until(lambda: len(answers.got) == backlog + 1)
    finally:
        server.stop()
    # after a few turns of the greedy one (TURN each; on a loaded machine the polite request may
    # be seen a select or two later), never after its backlog
    assert handler.order.index(2000) < backlog // 4
