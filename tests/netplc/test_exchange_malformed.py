"""A node that answers, but not the request's answer (issue 18 items 2 and 9): a reply holding
only the function code, another function code or unit id, a wrong byte count, a write echo that
does not match. Each is a failed attempt: retries, then the link is down (link bit, presence byte,
status) and journaled with the reason, with our lean client and with pymodbus's alike, over TCP
and RTU."""

from __future__ import annotations

import os
import select
import socket
import struct
import threading
from collections.abc import Callable, Iterator

import pytest

from netplc.exchange import NodeConfig
from netplc.modbus.rtu import crc16, take_frames
from tests.netplc.test_exchange import Station, wait_until

MBAP = struct.Struct(">HHHB")
Reply = Callable[[int, bytes], tuple[int, bytes]]  # (unit, request PDU) -> (unit, answer PDU)


def registers(unit: int, pdu: bytes) -> tuple[int, bytes]:
    count = struct.unpack_from(">H", pdu, 3)[0]
    return unit, bytes((pdu[0], 2 * count)) + bytes(2 * count)


MALFORMED: dict[str, Reply] = {
    "only the function code": lambda unit, pdu: (unit, pdu[:1]),
    "another function code": lambda unit, pdu: (unit, bytes((4,)) + registers(unit, pdu)[1][1:]),
    "another unit id": lambda unit, pdu: (unit + 1, registers(unit, pdu)[1]),
    "a wrong byte count": lambda unit, pdu: (unit, bytes((pdu[0], 3, 0, 0, 0))),
    "one register too many": lambda unit, pdu: (unit, registers(unit, pdu)[1] + b"\x00\x00"),
}


class BadNode:
    """A Modbus TCP 'device' on 127.0.0.1 that answers every request with `reply(unit, pdu)`."""

    def __init__(self, reply: Reply) -> None:
        self.reply = reply
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.requests = 0
        threading.Thread(target=self.serve, daemon=True).start()

    def serve(self) -> None:
        while True:
            try:
                conn, _ = self.listener.accept()
            except OSError:
                return
            threading.Thread(target=self.answer, args=(conn,), daemon=True).start()

    def answer(self, conn: socket.socket) -> None:
        buf = b""
        with conn:
            while True:
                try:
                    data = conn.recv(4096)
                except OSError:
                    return
                if not data:
                    return
                buf += data
                while len(buf) >= 7 and len(buf) >= 6 + MBAP.unpack_from(buf)[2]:
                    tid, _, length, unit = MBAP.unpack_from(buf)
                    pdu, buf = buf[7 : 6 + length], buf[6 + length :]
                    self.requests += 1
                    self.respond(conn, tid, unit, pdu)

    def respond(self, conn: socket.socket, tid: int, unit: int, pdu: bytes) -> None:
        got_unit, answer = self.reply(unit, pdu)
        conn.sendall(MBAP.pack(tid, 0, len(answer) + 1, got_unit) + answer)

    def close(self) -> None:
        self.listener.close()


@pytest.fixture
def bad_node(request: pytest.FixtureRequest) -> Iterator[BadNode]:
    node = BadNode(request.param)
    yield node
    node.close()


READ = "TNA $03760\nFON C:$02100 N:NODE S:1\nTNA $03760\nFON C:$02104 N:NREAD S:4000 D:$04000 R:2\nJMP 0\n"
WRITE = "TNA $03760\nFON C:$02100 N:NODE S:1\nTNA $03760\nFON C:$02104 N:NWRITE S:$04000 D:4000 R:4\nJMP 0\n"


def link_goes_down(program: str, node: BadNode, lean: bool) -> str:
    """Run NetPlc against the node; the reason journaled with the link-down record."""
    st = Station(program, [NodeConfig(1, f"tcp://127.0.0.1:{node.port}", timeout=0.3, retries=1,
                                      backoff=0.1, backoff_max=0.2)], lean=lean)
    st.engine.mem.set_bit(0o2105, 1)  # as if the link had been up: it must be seen to go down
    st.start()
    try:
        wait_until(lambda: st.exchange.stats[1].errors >= 2, timeout=5)
        snap = st.engine.snapshot
        assert snap.get_bit(0o2105) == 0 and snap.get_byte(0o77741) == 0x00
        assert not st.exchange.link_up(1)
        assert node.requests >= 2  # the request was tried again before the link went down
        downs = [r for r in st.sink.records if r.kind == "system" and r.source == "node 1"]
        assert downs and all("link down" in (r.text or "") for r in downs)
        assert not any("link up" in (r.text or "") for r in st.sink.records)
        return downs[0].text or ""
    finally:
        st.stop()


@pytest.mark.parametrize("bad_node", MALFORMED.values(), ids=MALFORMED.keys(), indirect=True)
@pytest.mark.parametrize("lean", [True, False], ids=["lean", "pymodbus"])
def test_a_malformed_read_answer_is_a_failed_attempt(bad_node: BadNode, lean: bool) -> None:
    reason = link_goes_down(READ, bad_node, lean)
    assert "read holding 1024+1" in reason
    if lean:  # our client says what was wrong; pymodbus drops what it cannot decode (a timeout)
        assert "internal error" not in reason and "answer" in reason


def echo_elsewhere(unit: int, pdu: bytes) -> tuple[int, bytes]:
    if pdu[0] == 16:
        address, count = struct.unpack_from(">HH", pdu, 1)
        return unit, struct.pack(">BHH", 16, address + 1, count)
    return registers(unit, pdu)


@pytest.mark.parametrize("bad_node", [echo_elsewhere], indirect=True)
@pytest.mark.parametrize("lean", [True, False], ids=["lean", "pymodbus"])
def test_a_write_echo_that_does_not_match_is_a_failed_attempt(bad_node: BadNode, lean: bool) -> None:
    reason = link_goes_down(WRITE, bad_node, lean)
    assert "write holding 1024+2" in reason and "echo" in reason


class BadRtuDevice:
    """An RTU 'device' on a pty's master side answering every request with `reply(unit, pdu)`."""

    def __init__(self, reply: Reply) -> None:
        self.reply = reply
        self.master, self.slave = os.openpty()
        self.port = os.ttyname(self.slave)
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    def serve(self) -> None:
        buf = bytearray()
        while not self.stop.is_set():
            if not select.select([self.master], [], [], 0.05)[0]:
                continue
            buf += os.read(self.master, 256)
            requests, _ = take_frames(buf)
            for frame in requests:
                unit, answer = self.reply(frame[0], frame[1:-2])
                out = bytes([unit]) + answer
                os.write(self.master, out + crc16(out))

    def close(self) -> None:
        self.stop.set()
        self.thread.join()
        os.close(self.master)
        os.close(self.slave)


@pytest.mark.parametrize("reply", [MALFORMED["another function code"], MALFORMED["another unit id"]],
                         ids=["another function code", "another unit id"])
def test_a_malformed_rtu_answer_is_a_failed_attempt(reply: Reply) -> None:
    device = BadRtuDevice(reply)
    try:
        line = f"rtu://{device.port}?baudrate=115200&parity=N"  # a pty takes no parity setting
        st = Station(READ, [NodeConfig(1, line, timeout=0.3, retries=1, backoff=0.1, backoff_max=0.2)])
        st.start()
        try:
            wait_until(lambda: st.exchange.stats[1].errors >= 2, timeout=5)
            assert st.engine.snapshot.get_bit(0o2105) == 0 and not st.exchange.link_up(1)
            downs = [r.text or "" for r in st.sink.records if r.kind == "system" and r.source == "node 1"]
            assert downs and all("link down" in t and "read holding 1024+1" in t for t in downs)
        finally:
            st.stop()
    finally:
        device.close()
