"""Modbus RTU on pseudo-terminal pairs: the exchange (pymodbus serial framer, pyserial) against our
RTU slave, and the simulator's RTU slave (`main.py simulate --serial`) against raw frames.

For the exchange, NetPlc opens the pty's slave side as its serial port and the simulated CPU-165
node answers on the master side. For the simulator, it opens the slave side itself and the test
plays the RTU master on the master side, byte for byte.
"""

from __future__ import annotations

import contextlib
import os
import select
import subprocess
import sys
import time
import tty
from collections.abc import Iterator
from pathlib import Path

import pytest

from netplc.engine import Engine
from netplc.exchange import NodeConfig
from netplc.modbus.rtu import RtuServer, crc16, request_length, take_frames
from netplc.program import parse
from netplc.scheduler import ScanThread
from netplc.simulator import EngineMemory
from tests.commands import run_in_process
from tests.netplc.test_exchange import Station, wait_until

UNIT = 5
REPO = Path(__file__).resolve().parents[2]


class PtyLine:
    """The master side of a pty as a serial line: `read` returns at a 5 ms silence, or b"" after
    `idle` seconds of silence (a serial port's read timeout), each counted in `silences`."""

    def __init__(self, fd: int, idle: float = 0.1) -> None:
        self.fd = fd
        self.idle = idle
        self.silences = 0

    def read(self, size: int) -> bytes:
        if not select.select([self.fd], [], [], self.idle)[0]:
            self.silences += 1
            return b""
        data = os.read(self.fd, size)
        while len(data) < size and select.select([self.fd], [], [], 0.005)[0]:
            data += os.read(self.fd, size - len(data))
        return data

    def write(self, data: bytes) -> int:
        return os.write(self.fd, data)

    def close(self) -> None:
        pass  # the pty is the test's to close


class RtuNode:
    """A CPU-165 node (an engine on its scan thread) answering as RTU unit 5 on a pty's master side."""

    def __init__(self) -> None:
        self.engine = Engine(parse("JMP 0\n"), tick=0.01)
        self.scan = ScanThread(self.engine, 0.01)
        self.master, slave = os.openpty()
        self.port = os.ttyname(slave)
        self._slave = slave
        self.server = RtuServer(EngineMemory(self.engine), UNIT, PtyLine(self.master),
                                self.port)

    def start(self) -> None:
        self.scan.start()
        self.server.start()

    def stop(self) -> None:
        self.server.stop()
        self.scan.stop()
        os.close(self.master)
        os.close(self._slave)


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
    line = f"rtu://{rtu_node.port}?baudrate=19200&parity=N"  # a pty takes no parity setting
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


def test_a_port_that_refuses_its_settings_is_a_link_fault_with_the_reason(
        rtu_node: RtuNode, caplog: pytest.LogCaptureFixture) -> None:
    """A pty takes no parity: termios refuses the line's default even parity (EINVAL). The node
    is down with the system's reason, as for an absent port, and the exchange logs no error of
    its own."""
    program = "TNA $03760\nFON C:$02100 N:NODE S:0\nFON C:$02104 N:NREAD S:4000 D:$04000 R:2\nJMP 0\n"
    st = Station(program, [NodeConfig(0, f"rtu://{rtu_node.port}", unit=UNIT, timeout=0.2, retries=0)])
    st.start()
    try:
        wait_until(lambda: st.exchange.stats[0].errors >= 1)
        error = st.exchange.stats[0].last_error
        assert error.startswith(f"cannot open rtu://{rtu_node.port}?baudrate=19200&parity=E: [Errno 22] ")
        assert "internal error" not in error and st.engine.snapshot.get_bit(0o2105) == 0
        assert not [r for r in caplog.records if r.levelname == "ERROR"]
    finally:
        st.stop()


def test_nodes_on_one_port_need_the_same_line_settings() -> None:
    with pytest.raises(ValueError, match=r"node 2: .* share /dev/ttyS7 with different line settings"):
        Station("JMP 0\n", [NodeConfig(1, "rtu:///dev/ttyS7?baudrate=9600"),
                            NodeConfig(2, "rtu:///dev/ttyS7?baudrate=19200")])


# --- the simulator as an RTU slave (`main.py simulate --serial`) ----------------------------------

NODE = "TNA $03760\nFON C:$02000 N:MOV S:$04000 D:$04002\nJMP 0\n"  # copies 04000 to 04002 each scan


def frame(unit: int, pdu: bytes) -> bytes:
    return bytes([unit]) + pdu + crc16(bytes([unit]) + pdu)


class Master:
    """The RTU master on a pty's master side; the simulator process opens the slave side."""

    def __init__(self, fd: int) -> None:
        self.fd = fd

    def ask(self, request: bytes, wait: float = 2.0) -> bytes:
        """Send a frame; the reply frame, or b"" if none came within `wait` seconds."""
        os.write(self.fd, request)
        reply = b""
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline:
            if select.select([self.fd], [], [], 0.02)[0]:
                reply += os.read(self.fd, 256)
            elif reply:
                return reply
        return reply


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Master, subprocess.Popen[str]]]:
    """One `main.py simulate` process for the module's tests: each writes the words it then reads."""
    tmp_path = tmp_path_factory.mktemp("simulated")
    (tmp_path / "node.stl").write_text(NODE)
    master, slave = os.openpty()
    serial = f"rtu://{os.ttyname(slave)}?baudrate=19200&parity=E"
    proc = subprocess.Popen([sys.executable, "main.py", "simulate", str(tmp_path / "node.stl"),
                             "--tick", "10", "--unit", str(UNIT), "--serial", serial],
                            cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        banner = proc.stdout.readline()
        assert "Modbus RTU on /dev/pts/" in banner and "19200 baud, 8E1) unit 5" in banner, banner
        yield Master(master), proc
    finally:
        proc.terminate()
        proc.wait(10)
        os.close(master)
        os.close(slave)


def test_the_simulator_answers_as_an_rtu_slave(simulated: tuple[Master, subprocess.Popen[str]]) -> None:
    master, _ = simulated
    # FC16 writes 0x1234 to register 1024 (the word at 04000); the program copies it to 04002
    written = master.ask(frame(UNIT, bytes.fromhex("10 0400 0001 02 1234")))
    assert written == frame(UNIT, bytes.fromhex("10 0400 0001"))
    read = frame(UNIT, bytes.fromhex("03 0400 0002"))  # applied at the next scan, then copied by MOV
    wait_until(lambda: master.ask(read) == frame(UNIT, bytes.fromhex("03 04 1234 1234")))
    assert master.ask(frame(UNIT, bytes.fromhex("03 0000 0001"))) == frame(UNIT, bytes.fromhex("83 02"))


def test_the_rtu_slave_ignores_bad_frames_and_other_units_and_refuses_unknown_codes(
        simulated: tuple[Master, subprocess.Popen[str]]) -> None:
    master, _ = simulated
    read = frame(UNIT, bytes.fromhex("03 0400 0001"))
    assert master.ask(read[:-1] + bytes([read[-1] ^ 1]), wait=0.5) == b""  # CRC wrong: silence
    assert master.ask(frame(UNIT + 1, bytes.fromhex("03 0400 0001")), wait=0.5) == b""  # another unit's
    assert master.ask(frame(UNIT, bytes.fromhex("2b 0e 01 00"))) == frame(UNIT, bytes.fromhex("ab 01"))
    assert master.ask(frame(0, bytes.fromhex("06 0400 00ff")), wait=0.5) == b""  # broadcast: done, no reply
    wait_until(lambda: master.ask(read) == frame(UNIT, bytes.fromhex("03 02 00ff")))


def test_rtu_request_lengths() -> None:
    assert request_length(b"\x05") == 0 and request_length(b"\x05\x03") == 8
    assert request_length(bytes.fromhex("05 10 0000 0002 04")) == 13 and request_length(b"\x05\x10\x00") == 0
    assert request_length(bytes.fromhex("05 2b 0e 01 00")) == 7  # pymodbus knows every code's length
    assert request_length(b"\x05\x63") is None  # a code nobody knows: its CRC or the silence ends it


ASK2 = frame(2, bytes.fromhex("03 0400 0040"))  # the master polls unit 2 for 64 registers
ANSWER2 = frame(2, bytes([3, 128]) + bytes(range(128)))  # unit 2 answers
ASK5 = frame(UNIT, bytes.fromhex("03 0400 0001"))  # then polls us


def test_frames_are_found_by_length_and_crc_on_a_shared_bus() -> None:
    buf = bytearray((ASK2 + ANSWER2 + ASK5) * 5)
    requests, skipped = take_frames(buf)
    assert requests == [ASK2, ASK5] * 5 and skipped == 0 and not buf
    # noise before a frame is skipped byte by byte; a split frame waits for the rest
    buf = bytearray(b"\xff\x00" + ASK5 + ASK5[:3])
    assert take_frames(buf) == ([ASK5], 2) and buf == ASK5[:3]
    buf += ASK5[3:]
    assert take_frames(buf) == ([ASK5], 0)
    unknown = frame(UNIT, bytes.fromhex("63 01 02 03"))  # found by its CRC
    buf = bytearray(unknown + ASK5)
    assert take_frames(buf)[0] == [unknown, ASK5]
    buf = bytearray(b"\x07\x03\x99\x00")  # looks like the start of a long answer: the silence ends it
    assert take_frames(buf) == ([], 0) and take_frames(buf, silent=True) == ([], 4) and not buf


def raw_slave_side(port: str) -> int:
    fd = os.open(port, os.O_RDWR | os.O_NOCTTY)
    tty.setraw(fd)
    return fd


def replies(fd: int, size: int, wait: float = 3.0) -> bytes:
    data = b""
    deadline = time.monotonic() + wait
    while len(data) < size and time.monotonic() < deadline:
        if select.select([fd], [], [], 0.05)[0]:
            data += os.read(fd, 1024)
    return data


def test_the_slave_answers_every_poll_on_a_shared_bus_with_no_idle_gap(rtu_node: RtuNode) -> None:
    fd = raw_slave_side(rtu_node.port)
    try:
        os.write(fd, (ASK2 + ANSWER2 + ASK5) * 5)
        answer = frame(UNIT, bytes.fromhex("03 02 5aa5"))
        assert replies(fd, 5 * len(answer)) == answer * 5
        deadline = time.monotonic() + 3.0  # the count follows the write of the answer
        while rtu_node.server.answered < 5 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert rtu_node.server.answered == 5
    finally:
        os.close(fd)


def test_a_broadcast_write_is_done_and_a_broadcast_read_is_not(rtu_node: RtuNode) -> None:
    fd = raw_slave_side(rtu_node.port)
    try:
        os.write(fd, frame(0, bytes.fromhex("03 0400 0001")) + frame(0, bytes.fromhex("06 0402 0077")))
        wait_until(lambda: rtu_node.engine.snapshot.get_word(0o4004) == 0x0077)
        assert replies(fd, 1, wait=0.3) == b""
        assert rtu_node.server.answered == 0
    finally:
        os.close(fd)


def test_a_serial_port_failure_is_journaled_and_retried() -> None:
    engine = Engine(parse("JMP 0\n"), tick=0.01)
    notes: list[str] = []
    ptys: list[tuple[int, int]] = [os.openpty()]

    def reopen() -> PtyLine:
        ptys.append(os.openpty())
        return PtyLine(ptys[-1][0])

    server = RtuServer(EngineMemory(engine), UNIT, PtyLine(ptys[0][0]), "pty",
                       reopen=reopen, note=notes.append)
    server.start()
    try:
        os.close(ptys[0][1])  # the adapter is unplugged: reading the line fails (EIO)
        wait_until(lambda: len(notes) >= 1)
        assert notes[0].startswith("Modbus RTU on pty failed: ") and "retrying every 1 s" in notes[0]
        wait_until(lambda: notes[-1] == "Modbus RTU on pty works again", timeout=5)
        assert server.fault == ""
        fd = ptys[-1][1]
        tty.setraw(fd)
        os.write(fd, ASK5)
        assert replies(fd, 7) == frame(UNIT, bytes.fromhex("03 02 0000"))
    finally:
        server.stop()
        for master, slave in ptys:
            for f in (master, slave):
                with contextlib.suppress(OSError):
                    os.close(f)


def test_simulate_with_a_serial_port_that_cannot_be_opened(tmp_path: Path,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    """In this process (tests/commands.py): `simulate` as a process of its own is the `simulated`
    fixture's."""
    from app.cli import main

    (tmp_path / "node.stl").write_text(NODE)
    node = tmp_path / "node.stl"
    r = run_in_process(main, ["simulate", node, "--serial", "rtu:///dev/no-such-tty"], capsys)
    assert r.returncode == 1 and "Traceback" not in r.stderr
    assert r.stderr.startswith("simulate: cannot open /dev/no-such-tty: ")
    r = run_in_process(main, ["simulate", node, "--serial", "tcp://h:502"], capsys)
    assert r.returncode == 2 and "expected an rtu:// endpoint" in r.stderr
