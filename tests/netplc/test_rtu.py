"""The exchange over Modbus RTU (pymodbus serial framer, pyserial) on a pseudo-terminal pair.

NetPlc opens the pty's slave side as its serial port; the test plays the CPU-165 node on the master
side: it deframes RTU requests (unit, PDU, CRC-16), answers them from a node engine's memory through
the same cpu165 map the TCP server uses, and frames the answers back.
"""

from __future__ import annotations

import os
import select
import threading
from collections.abc import Iterator

import pytest

from netplc.engine import Engine, FakeClock
from netplc.exchange import NodeConfig
from netplc.modbus_driver import answer
from netplc.modbus_server import ALL_MEMORY, ModbusServer
from netplc.program import parse
from tests.netplc.test_exchange import Station, wait_until

UNIT = 5


def crc16(data: bytes) -> bytes:
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc.to_bytes(2, "little")


def frame_length(buf: bytes) -> int:
    """Length of the RTU request at the start of `buf` (0: not enough bytes yet)."""
    if len(buf) < 7:
        return 0
    if buf[1] in (15, 16):
        return 9 + buf[6]
    return 8


class RtuNode:
    """A CPU-165 node on the master side of a pty: its memory served with the cpu165 profile."""

    def __init__(self) -> None:
        self.engine = Engine(parse("JMP 0\n"), clock=FakeClock())
        self.handler = ModbusServer(self.engine, writable=ALL_MEMORY)  # used as the map, not started
        self.master, slave = os.openpty()
        self.port = os.ttyname(slave)
        self._slave = slave
        self.frames = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2)
        os.close(self.master)
        os.close(self._slave)

    def _serve(self) -> None:
        buf = b""
        while not self._stop.is_set():
            ready, _, _ = select.select([self.master], [], [], 0.05)
            if not ready:
                continue
            buf += os.read(self.master, 512)
            while (n := frame_length(buf)) and len(buf) >= n:
                frame, buf = buf[:n], buf[n:]
                assert crc16(frame[:-2]) == frame[-2:], f"bad CRC in {frame.hex(' ')}"
                self.frames += 1
                if frame[0] != UNIT:
                    continue  # another device on the line: stay silent
                self.engine.scan()  # the node's scan applies queued writes and publishes memory
                pdu = answer(self.handler, frame[1:-2], "rtu")
                reply = bytes([UNIT]) + pdu
                os.write(self.master, reply + crc16(reply))
                self.engine.scan()


@pytest.fixture
def rtu_node() -> Iterator[RtuNode]:
    node = RtuNode()
    node.engine.mem.set_word(0o4000, 0x5AA5)
    node.engine.mem.write(0o4004, bytes([0x11, 0x22, 0x33, 0x44]))
    node.engine.scan()
    node.start()
    yield node
    node.stop()


def test_nread_and_odd_edged_nwrite_over_rtu(rtu_node: RtuNode) -> None:
    program = (
        "TNA $03760\n"
        "FON C:$02100 N:NODE S:0\n"
        "TNA $03760\n"
        "FON C:$02104 N:NREAD S:4000 D:$04000 R:2\n"
        "TNA $03760\n"
        "FON C:$02110 N:NWRITE S:$04020 D:4005 R:2\n"
        "JMP 0\n"
    )
    endpoint = f"rtu://{rtu_node.port}?baudrate=115200&parity=N"
    st = Station(program, [NodeConfig(0, endpoint, unit=UNIT, timeout=0.5)])
    st.engine.mem.write(0o4020, bytes([0xAB, 0xCD]))
    st.start()
    try:
        snap = lambda: st.engine.snapshot  # noqa: E731
        wait_until(lambda: snap().get_word(0o4000) == 0x5AA5 and snap().get_bit(0o2105) == 1)
        # remote 04005..04006 written; 04004 and 04007 kept by read-modify-write
        wait_until(lambda: rtu_node.engine.snapshot.read(0o4004, 4) == bytes([0x11, 0xAB, 0xCD, 0x44]))
        assert snap().get_bit(0o2111) == 1
        assert st.exchange.stats[0].errors == 0
    finally:
        st.stop()


def test_two_nodes_share_the_line_and_a_silent_one_only_fails_itself(rtu_node: RtuNode) -> None:
    program = (
        "TNA $03760\n"
        "FON C:$02100 N:NODE S:1\n"
        "FON C:$02104 N:NREAD S:4000 D:$04000 R:2\n"
        "FON C:$02110 N:NODE S:2\n"
        "FON C:$02114 N:NREAD S:4000 D:$04010 R:2\n"
        "JMP 0\n"
    )
    line = f"rtu://{rtu_node.port}?baudrate=19200"
    nodes = [NodeConfig(1, line, unit=UNIT, timeout=0.2, retries=0),
             NodeConfig(2, line, unit=UNIT + 1, timeout=0.2, retries=0)]  # nobody answers unit 6
    st = Station(program, nodes)
    st.start()
    try:
        snap = lambda: st.engine.snapshot  # noqa: E731
        wait_until(lambda: st.exchange.stats[2].errors >= 2)
        wait_until(lambda: snap().get_word(0o4000) == 0x5AA5 and snap().get_bit(0o2105) == 1)
        assert snap().get_bit(0o2115) == 0 and snap().get_word(0o4010) == 0
        assert snap().read(0o77741, 2) == b"\xff\x00"
        assert st.exchange.stats[1].errors == 0 and st.exchange.stats[1].reads >= 1
        assert "no answer" in st.exchange.stats[2].last_error or "retries" in st.exchange.stats[2].last_error
    finally:
        st.stop()


def test_nodes_on_one_port_need_the_same_line_settings() -> None:
    with pytest.raises(ValueError, match=r"node 2: .* share /dev/ttyS7 with different line settings"):
        Station("JMP 0\n", [NodeConfig(1, "rtu:///dev/ttyS7?baudrate=9600"),
                            NodeConfig(2, "rtu:///dev/ttyS7?baudrate=19200")])
