"""The station's Modbus server over RTU (`[modbus_server] transport = "rtu"`): a running station
answers on one end of a pty pair made by socat, the test is the RTU master on the other end, frame
by frame as mbpoll sends them, and mbpoll itself where it is installed. Every write goes through
the station's command layer (app/authority/modbus.py), as over TCP."""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import tty
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from app.authority import Source
from app.authority.layer import Who
from app.authority.users import Users
from app.station.check import check_station
from app.station.config import load_station
from app.station.runtime import Runtime
from netplc.records import Record
from tests.app.conftest import write_station
from tests.netplc.test_exchange import wait_until
from tests.netplc.test_rtu import Master, frame

UNIT = 7
BANK1 = 0o14000 // 2  # register of data byte 014000: memory, but not writable here
STATION = """
NetPlcProgram = "main.stl"
Tags = "tags.csv"
NetSyncTime = 10
[modbus_server]
transport = "rtu"
port = "{port}"
unit = {unit}
writable = [["02000", "02177"], ["04000", "04777"]]
"""
# 32-bit tags as two devices place them: big-endian (1234, ABCD) and NetPlc's own (3412, CDAB)
TAGS = """name,address,type,byte_order
BIG,04100,int32,1234
BIGF,04104,float32,ABCD
OURS,04110,int32,
OURSF,04114,float32,3412
"""
FILES = {"main.stl": "JMP 0\n", "tags.csv": TAGS}


class PtyPair:
    """Two linked ptys made by socat, named by the links `a` and `b`; stopped by its PID."""

    def __init__(self, folder: Path) -> None:
        self.a, self.b = folder / "a", folder / "b"
        self.proc = subprocess.Popen(
            ["socat", "-d", "-d", f"pty,raw,echo=0,link={self.a}", f"pty,raw,echo=0,link={self.b}"],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        wait_until(lambda: self.a.exists() and self.b.exists())

    def open_b(self) -> int:
        fd = os.open(self.b, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(fd)
        return fd

    def stop(self) -> None:
        os.kill(self.proc.pid, signal.SIGTERM)
        self.proc.wait(5)
        assert self.proc.stderr is not None
        self.proc.stderr.close()


def need_socat() -> None:
    if shutil.which("socat") is None:
        pytest.skip("socat is not installed: no pty pair to run Modbus RTU over (apt-get install socat)")


def socat_pair(folder: Path) -> PtyPair:
    need_socat()
    folder.mkdir(parents=True, exist_ok=True)
    return PtyPair(folder)


@dataclass
class Rtu:
    runtime: Runtime
    master: Master
    pair: PtyPair
    records: list[Record]

    def ask(self, pdu: bytes, unit: int = UNIT, wait: float = 3.0) -> bytes:
        """The reply's PDU to a request PDU for `unit` (b"": no reply within `wait`)."""
        reply = self.master.ask(frame(unit, pdu), wait)
        if not reply:
            return b""
        assert reply == frame(unit, reply[1:-2]), f"a reply with a bad CRC or unit: {reply.hex(' ')}"
        return reply[1:-2]

    def operator(self, since: int = 0) -> list[tuple[str, str]]:
        return [(r.source or "", r.text or "") for r in self.records[since:] if r.kind == "operator"]


@pytest.fixture(scope="module")
def rtu(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Rtu]:
    folder = tmp_path_factory.mktemp("rtu")
    pair = socat_pair(folder / "pty")
    write_station(folder / "station", STATION.format(port=pair.a, unit=UNIT), FILES)
    Users(folder / "station").add("olga", "operator", "olga")
    runtime = Runtime(load_station(folder / "station"))
    records: list[Record] = []
    runtime.subscribe(records.append)
    runtime.start()
    fd = pair.open_b()
    try:
        yield Rtu(runtime, Master(fd), pair, records)
    finally:
        runtime.stop()
        os.close(fd)
        pair.stop()


def test_reads_and_writes_of_every_function_an_rtu_master_uses(rtu: Rtu) -> None:
    assert rtu.runtime.status().modbus_serial == str(rtu.pair.a)
    assert rtu.ask(bytes.fromhex("06 0400 1234")) == bytes.fromhex("06 0400 1234")  # word 04000
    assert rtu.ask(bytes.fromhex("10 0401 0002 04 0001 fffe")) == bytes.fromhex("10 0401 0002")
    assert rtu.ask(bytes.fromhex("03 0400 0003")) == bytes.fromhex("03 06 1234 0001 fffe")
    assert rtu.ask(bytes.fromhex("05 0400 ff00")) == bytes.fromhex("05 0400 ff00")  # coil 1024 = bit 02000
    assert rtu.ask(bytes.fromhex("01 0400 0010")) == bytes.fromhex("01 02 0100")
    assert rtu.ask(bytes.fromhex("01 07f0 0001")) == bytes.fromhex("01 01 01")  # 03760 is always 1
    snap = rtu.runtime.engine.snapshot
    assert (snap.get_word(0o4000), snap.get_word(0o4004), snap.get_bit(0o2000)) == (0x1234, 0xFFFE, 1)
    assert (f"modbus rtu {rtu.pair.a}", "write 04000: 0 -> 4660") in rtu.operator()


def test_frames_for_another_unit_or_with_a_bad_crc_are_ignored_and_broadcast_writes_done_unanswered(
        rtu: Rtu) -> None:
    assert rtu.ask(bytes.fromhex("06 0410 0001"), unit=UNIT + 1, wait=0.15) == b""
    bad = frame(UNIT, bytes.fromhex("06 0410 0002"))
    assert rtu.master.ask(bad[:-1] + bytes([bad[-1] ^ 0xFF]), 0.15) == b""
    assert rtu.ask(bytes.fromhex("06 0410 0003"), unit=0, wait=0.15) == b""  # broadcast
    wait_until(lambda: rtu.runtime.engine.snapshot.get_word(0o4040) == 3)
    assert rtu.ask(bytes.fromhex("03 0410 0001")) == bytes.fromhex("03 02 0003")  # in step after all that


def test_refused_writes_answer_the_exceptions_of_the_tcp_server(rtu: Rtu) -> None:
    since = len(rtu.records)
    assert rtu.ask(bytes([6]) + BANK1.to_bytes(2, "big") + b"\x00\x01") == bytes.fromhex("86 02")
    assert rtu.ask(bytes.fromhex("05 07f8 ff00")) == bytes.fromhex("85 02")  # the stop bit 03770
    rtu.runtime.commands.grant(Source.MODBUS, "viewer")
    try:
        assert rtu.ask(bytes.fromhex("06 0400 0001")) == bytes.fromhex("86 01")
        word = rtu.runtime.engine.snapshot.get_word(0o4000)
        assert rtu.ask(bytes.fromhex("03 0400 0001")) == b"\x03\x02" + word.to_bytes(2, "big")  # reads do
    finally:
        rtu.runtime.commands.grant(Source.MODBUS, "operator")
    peer = f"modbus rtu {rtu.pair.a}"
    assert rtu.operator(since) == [  # one record per cause per peer a minute, as over TCP
        (peer, "refused write 014000: not writable over Modbus (station.toml [modbus_server] writable)"),
        (peer, "refused write 04000: needs the operator role; clients with no user act as viewer")]


def mbpoll(rtu: Rtu, options: str, *writes: int) -> str:
    """mbpoll as an operator runs it against the station's port: 19200 baud 8E1 (its defaults
    spelled out), PDU addresses (-0), once."""
    if shutil.which("mbpoll") is None:
        pytest.skip("mbpoll is not installed (apt-get install mbpoll)")
    command = ["mbpoll", "-m", "rtu", "-a", str(UNIT), "-b", "19200", "-P", "even", "-0", "-1",
               *options.split(), str(rtu.pair.b), *(["--", *map(str, writes)] if writes else [])]
    r = subprocess.run(command, capture_output=True, text=True, timeout=20)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def values(output: str) -> dict[int, str]:
    return {int(a): v for a, v in re.findall(r"^\[(\d+)\]:\s+(\S+)", output, re.M)}


def test_mbpoll_reads_and_writes_the_station(rtu: Rtu) -> None:
    assert "Written 1 references" in mbpoll(rtu, "-t 4 -r 1030", 4321)
    assert rtu.runtime.engine.snapshot.get_word(0o4014) == 4321
    assert "Written 1 references" in mbpoll(rtu, "-t 0 -r 1025", 1)
    assert values(mbpoll(rtu, "-t 0 -r 1025 -c 2")) == {1025: "1", 1026: "0"}  # bits 02001, 02002
    # a 32-bit value in NetPlc's order, low word first, is what mbpoll reads without -B
    assert rtu.ask(bytes.fromhex("10 0408 0002 04 cd15 075b")) == bytes.fromhex("10 0408 0002")
    assert values(mbpoll(rtu, "-t 4:int -r 1032")) == {1032: "123456789"}
    assert values(mbpoll(rtu, "-t 4:hex -r 1032 -c 2")) == {1032: "0xCD15", 1033: "0x075B"}


def test_a_port_that_cannot_be_opened_is_named_and_the_station_runs_on_and_retries(tmp_path: Path) -> None:
    need_socat()
    port = tmp_path / "pty" / "a"  # the adapter is not plugged in yet
    write_station(tmp_path / "station", STATION.format(port=port, unit=UNIT), FILES)
    assert check_station(tmp_path / "station").problems == []  # a port may come later: no check problem
    runtime = Runtime(load_station(tmp_path / "station"))
    texts: list[str] = []
    runtime.subscribe(lambda r: texts.append(r.text or "") if r.kind == "system" else None)
    runtime.start()
    pair = None
    try:
        fault = f"Modbus RTU on {port} cannot be opened: No such file or directory"
        assert runtime.started and runtime.engine is not None and runtime.status().problems == (fault,)
        station = tmp_path / "station" / "station.toml"
        assert (f"Modbus server not started yet: {station}: modbus_server.port: {fault}; "
                "retrying every 1 s") in texts
        pair = socat_pair(port.parent)
        wait_until(lambda: runtime.status().problems == (), timeout=5)
        assert f"Modbus RTU on {port} works again" in texts
        fd = pair.open_b()
        try:
            answer = Master(fd).ask(frame(UNIT, bytes.fromhex("01 07f0 0001")))
            assert answer == frame(UNIT, bytes.fromhex("01 01 01"))
        finally:
            os.close(fd)
    finally:
        runtime.stop()
        if pair is not None:
            pair.stop()


def test_mbpoll_and_the_station_agree_on_32_bit_values_in_the_tags_byte_order(rtu: Rtu) -> None:
    runtime = rtu.runtime

    def value(name: str) -> float | None:
        readings = runtime.readings()
        return None if readings is None else readings.tag(name).value

    # mbpoll as the device: it places each value in its order (-B: big-endian words), the tag reads it
    for options, tag, written in ((f"-B -t 4:int -r {0o4100 // 2}", "BIG", -123456789),
                                  (f"-B -t 4:float -r {0o4104 // 2}", "BIGF", -1234.5),
                                  (f"-t 4:int -r {0o4110 // 2}", "OURS", 123456789),
                                  (f"-t 4:float -r {0o4114 // 2}", "OURSF", 3.25)):
        assert "Written 1 references" in mbpoll(rtu, options, written)
        wait_until(lambda tag=tag, written=written: value(tag) == written)
    # the station writes each tag (its one conversion, encode), mbpoll reads what a device would get
    olga = Who("olga", Source.CONSOLE)
    for options, tag, written, shown in ((f"-B -t 4:int -r {0o4100 // 2}", "BIG", 987654321, "987654321"),
                                         (f"-B -t 4:float -r {0o4104 // 2}", "BIGF", 0.5, "0.5"),
                                         (f"-t 4:int -r {0o4110 // 2}", "OURS", -42, "-42")):
        assert runtime.commands.write_tag(olga, tag, written).result(5).ok
        assert values(mbpoll(rtu, options))[int(options.rsplit(" ", 1)[1])] == shown
