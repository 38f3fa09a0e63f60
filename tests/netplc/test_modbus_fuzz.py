"""Fuzzing that stays (issue 18): arbitrary byte streams and request sequences into the Modbus
server, over TCP and with RTU framing. Whatever came before, a valid read is then answered
correctly, and the server's file descriptors and threads are back to where they were."""

from __future__ import annotations

import os
import select
import socket
import struct
import threading
import time
from collections.abc import Iterator

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from netplc.engine import Engine
from netplc.modbus.rtu import RtuServer, crc16
from netplc.modbus.server import ModbusServer
from netplc.modbus.tcp_server import ServerLimits
from netplc.program import parse
from netplc.scheduler import ScanThread
from netplc.simulator import EngineMemory
from tests.netplc.test_rtu import PtyLine, raw_slave_side, replies

WRITABLE = [(0o2000, 0o2777), (0o4000, 0o4777)]  # not the word checked after each example
CHECK = 0o14000 // 2  # register of word 014000


def open_fds() -> int:
    return len(os.listdir("/proc/self/fd"))


@pytest.fixture(scope="module")
def station() -> Iterator[tuple[Engine, ModbusServer]]:
    engine = Engine(parse("TNA $03760\nJMP 0\n"), tick=0.005)
    engine.mem.set_word(0o14000, 0xA55A)
    scan = ScanThread(engine, 0.005)
    scan.start()
    # every client here is 127.0.0.1, and a test's connections may still wait to be accepted when
    # the next one comes: the per-peer limit is not what is fuzzed
    limits = ServerLimits(idle_timeout=2.0, max_per_peer=16)
    server = ModbusServer(EngineMemory(engine, WRITABLE), limits=limits, sink=engine.sink)
    server.start()
    BASELINE[:] = [open_fds(), threading.active_count()]
    yield engine, server
    server.stop()
    scan.stop()


BASELINE = [0, 0]  # open fds and threads once the server is up and idle


mbap_requests = st.builds(
    lambda tid, unit, pdu: struct.pack(">HHHB", tid, 0, len(pdu) + 1, unit) + pdu,
    st.integers(0, 0xFFFF), st.integers(0, 255),
    st.one_of(st.binary(min_size=1, max_size=20),
              st.tuples(st.sampled_from([1, 2, 3, 4, 5, 6, 15, 16]), st.integers(0, 0xFFFF),
                        st.integers(0, 0xFFFF), st.binary(max_size=12))
              .map(lambda t: struct.pack(">BHH", *t[:3]) + t[3])))
streams = st.lists(st.one_of(st.binary(max_size=64), mbap_requests), max_size=12)


def read_check_over_tcp(port: int) -> bytes:
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        sock.sendall(struct.pack(">HHHBBHH", 77, 0, 6, 1, 3, CHECK, 1))
        data = b""
        while len(data) < 11:
            chunk = sock.recv(64)
            if not chunk:
                break
            data += chunk
        return data


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(chunks=streams)
def test_tcp_server_survives_any_byte_stream(station: tuple[Engine, ModbusServer],
                                             chunks: list[bytes]) -> None:
    _, server = station
    with socket.create_connection(("127.0.0.1", server.port), timeout=5) as sock:
        for chunk in chunks:
            try:
                sock.sendall(chunk)
            except OSError:  # the server closed a connection that was not Modbus TCP
                break
    assert read_check_over_tcp(server.port) == struct.pack(">HHHBBB", 77, 0, 5, 1, 3, 2) + b"\xa5\x5a"
    back_to_baseline(server)


def back_to_baseline(server: ModbusServer) -> None:
    """Every connection of the example gone on the server's side too: the fds and threads of the
    process are those it had with the server idle."""
    deadline = time.monotonic() + 10
    while (server._server.connections or open_fds() > BASELINE[0]) and time.monotonic() < deadline:
        time.sleep(0.002)
    assert not server._server.connections
    assert open_fds() <= BASELINE[0] and threading.active_count() == BASELINE[1]


def test_tcp_server_resources_are_back_to_baseline(station: tuple[Engine, ModbusServer]) -> None:
    _, server = station
    socks = [socket.create_connection(("127.0.0.1", server.port)) for _ in range(10)]
    for i, sock in enumerate(socks):
        sock.sendall(bytes(range(i * 7 % 13)))  # half frames, garbage, nothing
    for sock in socks:
        sock.close()
    back_to_baseline(server)
    assert read_check_over_tcp(server.port)[-2:] == b"\xa5\x5a"


def rtu_frame(unit: int, pdu: bytes) -> bytes:
    return bytes([unit]) + pdu + crc16(bytes([unit]) + pdu)


rtu_requests = st.builds(rtu_frame, st.integers(0, 255),
                         st.one_of(st.binary(min_size=1, max_size=20),
                                   st.tuples(st.sampled_from([1, 2, 3, 4, 5, 6, 15, 16, 43, 99]),
                                             st.binary(min_size=4, max_size=12))
                                   .map(lambda t: bytes([t[0]]) + t[1])))
rtu_streams = st.lists(st.one_of(st.binary(max_size=64), rtu_requests), max_size=8)


@pytest.fixture(scope="module")
def rtu_station(station: tuple[Engine, ModbusServer]) -> Iterator[tuple[RtuServer, PtyLine, int]]:
    """The slave on a pty whose silence (the read timeout that ends what is left as noise) is 20 ms:
    an example waits for the slave to have read one, not for a fixed time."""
    engine, _ = station
    master, slave = os.openpty()
    line = PtyLine(master, idle=0.02)
    server = RtuServer(EngineMemory(engine, WRITABLE), 5, line, "pty")
    server.start()
    fd = raw_slave_side(os.ttyname(slave))
    yield server, line, fd
    server.stop()
    for f in (fd, master, slave):
        os.close(f)


def silence_read(line: PtyLine) -> None:
    """The slave has read a whole silence since now: everything written before was read, answered
    or dropped as noise (the first silence counted may have begun before the last write)."""
    after = line.silences + 2
    deadline = time.monotonic() + 10
    while line.silences < after and time.monotonic() < deadline:
        time.sleep(0.002)
    assert line.silences >= after


def drain(fd: int) -> None:
    while select.select([fd], [], [], 0)[0]:
        os.read(fd, 1024)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(chunks=rtu_streams)
def test_rtu_slave_survives_any_byte_stream(rtu_station: tuple[RtuServer, PtyLine, int],
                                            chunks: list[bytes]) -> None:
    server, line, fd = rtu_station
    for chunk in chunks:
        os.write(fd, chunk)
    silence_read(line)  # the silence ends what is left
    drain(fd)  # whatever it answered
    assert server.thread_alive
    os.write(fd, rtu_frame(5, struct.pack(">BHH", 3, CHECK, 1)))
    expected = rtu_frame(5, bytes([3, 2, 0xA5, 0x5A]))
    assert replies(fd, len(expected)).endswith(expected)
