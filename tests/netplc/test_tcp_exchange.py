"""The exchange's Modbus TCP hot path (netplc/tcp_exchange.py, netplc/modbus/frames.py): its frame
parser under fuzzing, and NREAD/NWRITE over real TCP on 127.0.0.1 against our Modbus server and
pymodbus's, a node that sends garbage, answers split and merged by TCP, and a standby's engine."""

from __future__ import annotations

import logging
import socket
import struct
from collections.abc import Iterator

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from netplc.exchange import NodeConfig
from netplc.modbus import TABLES, DeviceError, Frame, FrameError, LoopThread, answer_data, frame_size
from netplc.program import parse
from netplc.simulator import Simulator
from tests.netplc.test_exchange import Station, wait_until
from tests.netplc.test_exchange_malformed import BadNode

MBAP = struct.Struct(">HHHB")


def answer_of(request: bytes, unit: int | None = None) -> bytes:
    """The right answer to a read-registers request (zeros), or to a write (its echo)."""
    tid, _, _, req_unit = MBAP.unpack_from(request)
    pdu = request[7:]
    if pdu[0] in (3, 4):
        count = struct.unpack_from(">H", pdu, 3)[0]
        body = bytes((pdu[0], 2 * count)) + bytes(range(2 * count))
    else:
        body = pdu[:5]
    return MBAP.pack(tid, 0, len(body) + 1, req_unit if unit is None else unit) + body


# --- the parser ----------------------------------------------------------------------------------


@settings(max_examples=150, deadline=None)
@given(st.binary(max_size=300), st.integers(1, 125), st.integers(0, 255))
@example(b"HTTP/1.1 400 Bad Request\r\n\r\n", 1, 1)
@example(bytes.fromhex("0001 0000 0003 01 83 02"), 1, 1)  # an exception answer
@example(bytes.fromhex("0001 0000 0002 01 03"), 1, 1)  # only the function code
def test_any_bytes_give_a_frame_a_named_error_or_a_wait(data: bytes, count: int, unit: int) -> None:
    frame = Frame.read(unit, "holding", 1024, count)
    buf = bytearray(data)
    at = 0
    while at < len(buf):
        try:
            size = frame_size(buf, at)
        except FrameError as e:
            assert "not a Modbus TCP answer" in str(e)
            return
        if not size:
            return  # incomplete: wait for more
        assert 8 <= size <= 260 and at + size <= len(buf)
        try:
            data_ = answer_data(frame, buf, at, size)
        except (FrameError, DeviceError) as e:
            assert str(e).startswith(frame.what)
        else:
            assert len(data_) == 2 * count and data_ == bytes(buf[at + 9 : at + size])
        at += size


@settings(max_examples=80, deadline=None)
@given(st.integers(1, 0xFFFF), st.integers(0, 255), st.sampled_from(TABLES),
       st.integers(0, 0xFFFF - 2000), st.integers(1, 125), st.data())
def test_a_right_answer_gives_its_data(tid: int, unit: int, table: str, address: int, count: int,
                                       draw: st.DataObject) -> None:
    frame = Frame.read(unit, table, address, count)  # type: ignore[arg-type]
    request = bytes(frame.stamped(tid))
    assert request[0] << 8 | request[1] == tid and request[6] == unit
    data = draw.draw(st.binary(min_size=frame.nbytes, max_size=frame.nbytes))
    answer = MBAP.pack(tid, 0, len(data) + 3, unit) + bytes((frame.fc, len(data))) + data
    buf = bytearray(b"\x00" * 3 + answer + answer[:5])  # a frame in the middle of a stream
    assert frame_size(buf, 3) == len(answer)
    assert answer_data(frame, buf, 3, len(answer)) == data
    assert frame_size(buf, 3 + len(answer)) == 0  # the front of the next one: wait


def test_a_write_answer_must_echo_the_request() -> None:
    frame = Frame.write(1, "holding", 1024, [1, 2])
    good = answer_of(bytes(frame.stamped(7)))
    assert answer_data(frame, bytearray(good), 0, len(good)) == b""
    bad = bytearray(good)
    bad[9] ^= 1  # another address
    with pytest.raises(FrameError, match=r"write holding 1024\+2: the answer .* does not echo"):
        answer_data(frame, bad, 0, len(bad))
    refused = bytearray(MBAP.pack(7, 0, 3, 1) + bytes((0x90, 2)))
    with pytest.raises(DeviceError, match="exception 2"):
        answer_data(frame, refused, 0, len(refused))


# --- over real TCP -------------------------------------------------------------------------------


class ScriptedNode(BadNode):
    """A Modbus TCP 'device' on 127.0.0.1 answering right, or with the bytes `garbage` (once per
    connection, then silence, as a confused device would), or by `split` TCP segments."""

    def __init__(self) -> None:
        self.garbage: bytes | None = None
        self.split = False
        self.spoke: set[socket.socket] = set()  # connections that had their garbage
        super().__init__(lambda unit, pdu: (unit, pdu))

    def respond(self, conn: socket.socket, tid: int, unit: int, pdu: bytes) -> None:
        garbage = self.garbage
        if garbage is not None:
            if conn not in self.spoke:
                self.spoke.add(conn)
                conn.sendall(garbage)
            return
        out = answer_of(MBAP.pack(tid, 0, len(pdu) + 1, unit) + pdu)
        if self.split:  # a stale answer first, then the right one in two segments
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            stale = bytearray(out)
            stale[1] ^= 0x80
            conn.sendall(bytes(stale) + out[:5])
            conn.sendall(out[5:])
        else:
            conn.sendall(out)


READ = "TNA $03760\nFON C:$02100 N:NODE S:1\nTNA $03760\nFON C:$02104 N:NREAD S:4000 D:$04000 R:4\nJMP 0\n"


@pytest.fixture(scope="module")
def scripted() -> Iterator[tuple[ScriptedNode, Station]]:
    node = ScriptedNode()
    station = Station(READ, [NodeConfig(1, f"tcp://127.0.0.1:{node.port}", timeout=0.1, retries=0,
                                        backoff=0.01, backoff_max=0.02)])
    station.start()
    try:
        yield node, station
    finally:
        station.stop()
        node.close()


def reads_again(station: Station) -> None:
    stats = station.exchange.stats[1]
    n = stats.reads
    wait_until(lambda: stats.up and stats.reads > n + 2, timeout=10)


@settings(max_examples=8, deadline=None, suppress_health_check=list(HealthCheck))
@given(garbage=st.binary(min_size=1, max_size=40))
@example(garbage=b"HTTP/1.1 400 Bad Request\r\n\r\n")
@example(garbage=bytes.fromhex("0001 0000 0007 01 03 04 00 01 00 02"))  # no such transaction id: late
def test_garbage_fails_the_attempt_by_name_and_the_link_comes_back(
        scripted: tuple[ScriptedNode, Station], garbage: bytes) -> None:
    node, station = scripted
    stats = station.exchange.stats[1]
    reads_again(station)
    errors = stats.errors
    node.garbage = garbage
    try:
        wait_until(lambda: stats.errors > errors, timeout=10)
        assert stats.last_error.startswith(("read holding 1024+2: ", f"cannot connect to tcp://127.0.0.1:{node.port}"))
        assert "internal error" not in stats.last_error
    finally:
        node.garbage = None
    reads_again(station)  # the exchange thread lives on and the node reconnects


def test_answers_split_and_merged_by_tcp_and_stale_ones_are_dropped(
        scripted: tuple[ScriptedNode, Station]) -> None:
    node, station = scripted
    reads_again(station)
    node.split = True
    try:
        errors = station.exchange.stats[1].errors
        reads_again(station)
        assert station.exchange.stats[1].errors == errors
        assert station.engine.snapshot.read(0o4000, 4) == bytes((1, 0, 3, 2))  # registers byte-swapped
    finally:
        node.split = False


def test_our_server_multi_frame_reads_odd_edged_writes_and_a_host_name() -> None:
    """Our simulator by name (resolved off the exchange thread): a 300-byte read takes two frames,
    a write starting and ending at odd bytes reads its edge registers first."""
    sim = Simulator(parse("TNA $03760\nJMP 0\n", "node.stl"), tick=0.01)
    for i in range(300):
        sim.engine.mem.set_byte(0o4000 + i, i & 0xFF)
    sim.engine.mem.write(0o5000, b"\x11\x22\x33\x44\x55")  # before its scans start: one writer
    sim.start()
    program = ("TNA $03760\nFON C:$02100 N:NREAD S:4000 D:$04000 R:300\n"
               "FON C:$02104 N:NWRITE S:$05000 D:5001 R:3\nJMP 0\n")
    st = Station(program, [NodeConfig(0, f"tcp://localhost:{sim.port}", timeout=0.5)])
    st.engine.mem.write(0o5000, b"\xaa\xbb\xcc")
    st.start()
    try:
        block = bytes(i & 0xFF for i in range(300))
        wait_until(lambda: st.engine.snapshot.read(0o4000, 300) == block, timeout=10)
        wait_until(lambda: sim.engine.snapshot.read(0o5000, 5) == b"\x11\xaa\xbb\xcc\x55", timeout=10)
        assert st.exchange.stats[0].errors == 0
    finally:
        st.stop()
        sim.stop()


@pytest.fixture(scope="module")
def pymodbus_server() -> Iterator[tuple[int, object]]:
    from pymodbus.datastore import ModbusDeviceContext, ModbusSequentialDataBlock, ModbusServerContext
    from pymodbus.server import ModbusTcpServer

    logging.getLogger("pymodbus").setLevel(logging.ERROR)  # its deprecation notice on every start
    loop = LoopThread("pymodbus-server")
    loop.start()

    async def make() -> ModbusTcpServer:
        device = ModbusDeviceContext(hr=ModbusSequentialDataBlock(1, [0] * 200),
                                     co=ModbusSequentialDataBlock(1, [False] * 200))
        server = ModbusTcpServer(ModbusServerContext(devices=device, single=True), address=("127.0.0.1", 0))
        await server.serve_forever(background=True)
        return server

    server = loop.run(make())
    try:
        yield server.transport.sockets[0].getsockname()[1], server  # type: ignore[union-attr]
    finally:
        loop.run(server.shutdown())
        loop.stop()


@pytest.mark.parametrize("table", ["holding", "coils"])
def test_pymodbus_server_round_trip(pymodbus_server: tuple[int, object], table: str) -> None:
    """NWRITE then NREAD of the same registers or coils of pymodbus's server (profile modbus)."""
    port, _ = pymodbus_server
    program = ("TNA $03760\nFON C:$02100 N:NWRITE S:$04100 D:20 R:4\n"
               "TNA $03760\nFON C:$02104 N:NREAD S:20 D:$04000 R:4\n"
               "TNA $03760\nFON C:$02110 N:NREAD S:7777 D:$04010 R:2\nJMP 0\n")
    st = Station(program, [NodeConfig(0, f"tcp://127.0.0.1:{port}", profile="modbus", table=table,
                                      timeout=0.5)])
    payload = b"\x34\x12\x01\x00" if table == "holding" else b"\xa5\x3c\x0f\xf0"
    st.engine.mem.write(0o4100, payload)
    st.start()
    try:
        wait_until(lambda: st.engine.snapshot.read(0o4000, 4) == payload, timeout=10)
        wait_until(lambda: "exception" in st.exchange.stats[0].last_error, timeout=10)  # 07777: none there
        assert st.exchange.link_up(0) and st.engine.snapshot.get_bit(0o2105) == 1
    finally:
        st.stop()


def test_a_standby_engine_sends_no_writes() -> None:
    """The standby's engine follows the primary and runs no program: its exchange sends no NWRITE."""
    sim = Simulator(parse("TNA $03760\nJMP 0\n", "node.stl"), tick=0.01)
    sim.start()
    program = "TNA $03760\nFON C:$02100 N:NWRITE S:$04000 D:4000 R:2\nJMP 0\n"
    st = Station(program, [NodeConfig(0, f"tcp://127.0.0.1:{sim.port}", timeout=0.5)])
    st.engine.mem.write(0o4000, b"\x5a\xa5")
    st.engine.follower = True
    st.exchange.start()
    try:
        for _ in range(50):
            st.engine.scan()
        assert st.exchange.stats[0].writes == 0 and sim.engine.snapshot.read(0o4000, 2) == b"\x00\x00"
        st.engine.follower = False
        st.scan.start()
        wait_until(lambda: sim.engine.snapshot.read(0o4000, 2) == b"\x5a\xa5", timeout=10)
    finally:
        st.stop()
        sim.stop()


def test_a_stop_the_thread_saw_before_its_wake_up_was_sent_ends_cleanly() -> None:
    """The thread may see the stop flag and end before `stop` sends its wake-up (a busy thread, a
    loaded PC): the wake-up must still find its socket, and a late call from a helper thread is
    dropped (CI once failed with EBADF here)."""
    from netplc.tcp_exchange import TcpHub

    hub = TcpHub()
    hub.start()
    hub._stopping = True  # as `stop` does first, and the thread sees it before the wake-up
    hub._wake()
    hub._thread.join(5)
    assert not hub._thread.is_alive()
    hub.stop()
    hub.call(lambda: None)
