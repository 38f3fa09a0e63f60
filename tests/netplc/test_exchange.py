"""NetPlc <-> simulated CPU-165 node over real Modbus TCP on 127.0.0.1 (issue 4 acceptance, part 1).

Real time is involved (sockets, threads), so every wait polls a condition against a deadline.
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Iterator

import pytest

from netplc.engine import Engine
from netplc.exchange import Exchange, NodeConfig, check_program_nodes
from netplc.program import parse
from netplc.records import ListSink
from netplc.scheduler import ScanThread
from netplc.simulator import Simulator

TICK = 0.01

# Appendix 1 section 5: the T trigger of section 4 between the two MOV exchange chains.
NODE_PROGRAM = """\
; exchange area 04004 -> input bits 02040.. (Пуск = 02042)
TNA $03760
FON C:$03000 N:MOV S:$04004 D:$02040
; T trigger: TTC = 02042, TA = 02003 (output TA[2] = 02005), TB = 02010
TNA $02042
CTR C:$02003 N:1
TNA $02012
YON $02004
TNA $02042
CTR C:$02010 N:2
TNA $02012
YON $02011
; bits 02000.. -> exchange area 04000 (02003 -> bit 3, 02005 -> bit 5)
TNA $03760
FON C:$03004 N:MOV S:$02000 D:$04000
JMP 0
"""

NETPLC_PROGRAM = """\
TNA $03760
FON C:$02100 N:NODE S:0
TNA $03760
FON C:$02104 N:NWRITE S:$04004 D:4004 R:2
TNA $03760
FON C:$02110 N:NREAD S:4000 D:$04000 R:2
JMP 0
"""


def wait_until(cond: Callable[[], bool], timeout: float = 3.0) -> float:
    """Poll `cond` until it holds; return the seconds it took (fail the test at the deadline)."""
    t0 = time.monotonic()
    while not cond():
        if time.monotonic() - t0 > timeout:
            pytest.fail(f"condition not met within {timeout} s")
        time.sleep(0.002)
    return time.monotonic() - t0


class Station:
    """A NetPlc engine on its scan thread with an exchange to the given nodes."""

    def __init__(self, program: str, nodes: list[NodeConfig], tick: float = TICK, lean: bool = True) -> None:
        self.sink = ListSink()
        self.exchange = Exchange(nodes, self.sink, lean=lean)
        self.engine = Engine(parse(program, "netplc.stl"), tick=tick, sink=self.sink)
        self.exchange.attach(self.engine)
        self.scan = ScanThread(self.engine, tick)

    def start(self) -> None:
        self.exchange.start()
        self.scan.start()

    def stop(self) -> None:
        self.scan.stop()
        self.exchange.stop()


@pytest.fixture
def node0() -> Iterator[Simulator]:
    sim = Simulator(parse(NODE_PROGRAM, "node.stl"), tick=TICK)
    sim.start()
    yield sim
    sim.stop()


def test_t_trigger_end_to_end(node0: Simulator) -> None:
    st = Station(NETPLC_PROGRAM, [NodeConfig(0, f"tcp://127.0.0.1:{node0.port}", timeout=0.5)])
    st.start()
    try:
        snap = lambda: st.engine.snapshot  # noqa: E731
        wait_until(lambda: snap().get_bit(0o2111) == 1 and snap().get_bit(0o2105) == 1)
        assert snap().get_byte(0o77740) == 0xFF  # presence list: node 0 present
        expected = []
        seen = []
        for press in range(1, 7):
            for value in (1, 0):  # Пуск on, then off
                st.engine.write_bit(0o40042, value)
                wait_until(lambda v=value: node0.engine.snapshot.get_bit(0o2042) == v)
            out = 1 if press % 2 else 0
            expected.append(out)
            wait_until(lambda o=out: snap().get_hmi_bit(0o40005) == o and
                       node0.engine.snapshot.get_bit(0o2005) == o)
            seen.append(snap().get_hmi_bit(0o40005))
        assert seen == expected == [1, 0, 1, 0, 1, 0]
        stats = st.exchange.stats[0]
        assert stats.up and stats.reads > 0 and stats.writes > 0 and stats.errors == 0
        assert [r.text for r in st.sink.records if r.kind == "system"] == [
            f"node 0 (tcp://127.0.0.1:{node0.port}): link up"]
    finally:
        st.stop()


def test_an_instruction_never_has_two_requests_in_flight() -> None:
    """A node that accepts the connection but never answers: 200 scans send exactly one request."""
    with socket.create_server(("127.0.0.1", 0)) as listener:
        port = listener.getsockname()[1]
        st = Station(NETPLC_PROGRAM.replace("FON C:$02104 N:NWRITE S:$04004 D:4004 R:2\n", ""),
                     [NodeConfig(0, f"tcp://127.0.0.1:{port}", timeout=5.0, retries=0)])
        st.exchange.start()
        try:
            for _ in range(200):
                st.engine.scan()
            conn, _ = listener.accept()
            conn.settimeout(2.0)
            frame = conn.recv(1024)
            conn.settimeout(0.3)
            with pytest.raises(TimeoutError):
                frame += conn.recv(1024)
            # one read-holding-registers request: MBAP(7) + fc 3, register 1024, count 1
            assert len(frame) == 12 and frame[7:] == bytes([3, 0x04, 0x00, 0x00, 0x01])
            conn.close()
        finally:
            st.exchange.stop()


def test_node_config_reports_bad_endpoints() -> None:
    with pytest.raises(ValueError, match=r"node 3: endpoint 'udp://x:1': unknown scheme"):
        NodeConfig(3, "udp://x:1")
    with pytest.raises(ValueError, match=r"node 3: endpoint 'tcp://:502': no host"):
        NodeConfig(3, "tcp://:502")
    with pytest.raises(ValueError, match=r"node 3: endpoint 'tcp://h:99999'.*out of range"):
        NodeConfig(3, "tcp://h:99999")
    with pytest.raises(ValueError, match=r"parity 'X' is not N, E or O"):
        NodeConfig(3, "rtu:///dev/ttyS0?parity=X")
    with pytest.raises(ValueError, match=r"unknown option 'speed'"):
        NodeConfig(3, "rtu:///dev/ttyS0?speed=9600")
    with pytest.raises(ValueError, match=r"node 300: node 300 is outside 0-255"):
        NodeConfig(300, "tcp://h:502")
    with pytest.raises(ValueError, match=r"profile 'plc' is not one of cpu165, modbus"):
        NodeConfig(1, "tcp://h:502", profile="plc")
    cfg = NodeConfig(1, "rtu:///dev/ttyUSB0?baudrate=9600&parity=e")
    assert (cfg.parsed.device, cfg.parsed.baudrate, cfg.parsed.parity) == ("/dev/ttyUSB0", 9600, "E")
    assert NodeConfig(2, "tcp://10.0.0.5").parsed.port == 502
    assert NodeConfig(4, "rtu://COM3?baudrate=9600").parsed.device == "COM3"  # a Windows port
    with pytest.raises(ValueError, match=r"the serial device must follow rtu://"):
        NodeConfig(3, "rtu://?baudrate=9600")


def test_node_unit_ids_follow_the_modbus_spec_per_scheme() -> None:
    # TCP: 0-255 (a device reached directly often wants 0 or 255, the spec's recommended 0xFF);
    # RTU: 1-247 (0 is broadcast and never answers a read, 248-255 are reserved)
    assert NodeConfig(1, "tcp://h:502", unit=255).unit == 255
    assert NodeConfig(1, "tcp://h:502", unit=0).unit == 0
    assert NodeConfig(1, "rtu:///dev/ttyS0", unit=247).unit == 247
    with pytest.raises(ValueError, match=r"node 1: unit 256 is not 0-255 on tcp"):
        NodeConfig(1, "tcp://h:502", unit=256)
    for unit in (0, 248):
        with pytest.raises(ValueError, match=rf"node 1: unit {unit} is not 1-247 on rtu"):
            NodeConfig(1, "rtu:///dev/ttyS0", unit=unit)


def test_check_program_nodes_names_the_program_line() -> None:
    program = parse(
        "TNA $03760\n"
        "FON C:$02100 N:NODE S:7\n"
        "TNA $03760\n"
        "FON C:$02104 N:NREAD S:4000 D:$04000 R:2\n"
        "FON C:$02110 N:NODE S:1\n"
        "FON C:$02114 N:NREAD S:10000 D:$04010 R:2\n"
        "FON C:$02120 N:NWRITE S:$07776 D:4000 R:4\n",
        "station.stl",
    )
    nodes = [NodeConfig(1, "tcp://127.0.0.1:1502")]
    errors = [str(d) for d in check_program_nodes(program, nodes)]
    assert errors == [
        "station.stl:2:1: NODE S:7: node 7 is not configured (configured nodes: 1)",
        "station.stl:6:1: NREAD: node 1: remote 010000 is not a valid address",
        "station.stl:7:1: NWRITE: local block of 4 bytes: "
        "07776: 4-byte operand runs past the end of its bank",
    ]
    no_node = parse("TNA $03760\nFON C:$02104 N:NREAD S:4000 D:$04000 R:2\n", "p.stl")
    assert [str(d) for d in check_program_nodes(no_node, nodes)] == [
        "p.stl:2:1: NREAD with no NODE in the program talks to node 0, which is not configured "
        "(configured nodes: 1)"]
    assert check_program_nodes(parse(NETPLC_PROGRAM), [NodeConfig(0, "tcp://h:1")]) == []


def test_modbus_profile_and_device_exceptions(node0: Simulator) -> None:
    """A `modbus` node addresses registers by number; a Modbus exception leaves the link up."""
    node0.engine.write_word(0o4010, 0xCAFE)
    program = (
        "TNA $03760\n"
        "FON C:$02100 N:NREAD S:2004 D:$04020 R:2\n"  # register 02004 (1028) = the node's word 04010
        "FON C:$02104 N:NREAD S:0 D:$04030 R:2\n"  # register 0: exception 2 from a CPU-165
        "JMP 0\n"
    )
    st = Station(program, [NodeConfig(0, f"tcp://127.0.0.1:{node0.port}", profile="modbus",
                                      table="input", timeout=0.5)])
    st.start()
    try:
        snap = lambda: st.engine.snapshot  # noqa: E731
        wait_until(lambda: snap().get_word(0o4020) == 0xCAFE and st.exchange.stats[0].errors >= 1)
        assert snap().get_bit(0o2105) == 1 and snap().get_bit(0o2101) == 1  # the device answered
        assert st.exchange.stats[0].last_error == ("0: read input 0+1: Modbus exception 2 "
                                                   "(illegal data address)")
    finally:
        st.stop()


def test_a_serial_node_left_at_its_defaults_talks_to_the_stations_rtu_server_at_its_defaults() -> None:
    """The Modbus serial line's defaults on both ends: even parity, 1 stop bit; no parity, 2."""
    from app.station.config import KEYS

    server = {name: key.default for name, key in KEYS["modbus_server"].items()}
    node = NodeConfig(1, "rtu:///dev/ttyUSB0").parsed
    assert (node.baudrate, node.parity, node.bytesize, node.stopbits) == \
        (server["baudrate"], server["parity"], 8, 1)
    assert NodeConfig(1, "rtu:///dev/ttyUSB0?parity=N").parsed.stopbits == 2
    assert NodeConfig(1, "rtu:///dev/ttyUSB0?parity=N&stopbits=1").parsed.stopbits == 1
