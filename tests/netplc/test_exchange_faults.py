"""A node dies and comes back while another keeps exchanging (issue 4 acceptance, fault tests)."""

from __future__ import annotations

import socket
import time

from netplc.exchange import NodeConfig
from netplc.modbus import ModbusServer
from netplc.program import parse
from netplc.simulator import EngineMemory, Simulator
from tests.netplc.test_exchange import Station, wait_until

TIMEOUT = 0.3
BACKOFF_MAX = 0.4


PROGRAM = """\
TNA $03760
FON C:$02100 N:NODE S:1
TNA $03760
FON C:$02104 N:NREAD S:4000 D:$04000 R:2
TNA $03760
FON C:$02110 N:NODE S:2
TNA $03760
FON C:$02114 N:NREAD S:4000 D:$04010 R:64
JMP 0
"""


def config(node: int, port: int) -> NodeConfig:
    return NodeConfig(node, f"tcp://127.0.0.1:{port}", timeout=TIMEOUT, retries=1,
                      backoff=0.1, backoff_max=BACKOFF_MAX)


def rate(st: Station, node: int, seconds: float) -> float:
    stats = st.exchange.stats[node]
    n0, t0 = stats.reads, time.monotonic()
    time.sleep(seconds)
    return (stats.reads - n0) / (time.monotonic() - t0)


def test_dead_node_goes_down_and_comes_back_without_touching_the_other() -> None:
    program = parse("TNA $03760\nJMP 0\n")
    a, b = Simulator(program, tick=0.01), Simulator(program, tick=0.01)
    a.start()
    b.start()
    st = Station(PROGRAM, [config(1, a.port), config(2, b.port)])
    st.start()
    snap = lambda: st.engine.snapshot  # noqa: E731
    try:
        wait_until(lambda: snap().get_bit(0o2105) == 1 and snap().get_bit(0o2115) == 1)
        assert snap().read(0o77741, 2) == b"\xff\xff"
        normal = rate(st, 2, 0.3)
        assert normal > 20  # about one read per 10 ms scan

        a.server.stop()  # node 1 switched off mid-run
        t_down = wait_until(lambda: snap().get_bit(0o2105) == 0, timeout=5)
        assert t_down < 2 * TIMEOUT + 0.05
        assert snap().read(0o77741, 2) == b"\x00\xff"
        assert rate(st, 2, 0.3) > 0.5 * normal  # node 2 keeps its rate while node 1 is dead
        assert snap().get_bit(0o2115) == 1

        a.server = ModbusServer(EngineMemory(a.engine), port=a.port, sink=a.engine.sink)
        a.server.start()  # node 1 switched on again, same address
        t_up = wait_until(lambda: snap().get_bit(0o2105) == 1, timeout=5)
        assert t_up < BACKOFF_MAX + TIMEOUT + 0.1
        wait_until(lambda: snap().get_byte(0o77741) == 0xFF)

        # the scans never waited for the network: no scan came near a timeout, none overran
        assert st.engine.stats.max_ms < 1000 * TIMEOUT / 3
        texts = [r.text or "" for r in st.sink.records if r.kind == "system" and r.source == "node 1"]
        assert texts[0].endswith("link up")
        assert "link down" in texts[1] and texts[2].endswith("link up")
        assert st.exchange.stats[1].errors > 0 and st.exchange.stats[1].last_error
    finally:
        st.stop()
        a.stop()
        b.stop()


def test_silent_node_times_out_and_the_scan_does_not_wait() -> None:
    """A node that accepts connections but never answers: every request ends in timeouts."""
    with socket.create_server(("127.0.0.1", 0)) as listener:
        port = listener.getsockname()[1]
        b = Simulator(parse("TNA $03760\nJMP 0\n"), tick=0.01)
        b.start()
        st = Station(PROGRAM, [config(1, port), config(2, b.port)])
        st.start()
        try:
            snap = lambda: st.engine.snapshot  # noqa: E731
            wait_until(lambda: snap().get_bit(0o2115) == 1)
            wait_until(lambda: st.exchange.stats[1].errors >= 1, timeout=3)
            assert snap().get_bit(0o2105) == 0
            assert "read holding 1024+1" in st.exchange.stats[1].last_error
            # down from the start is reported too, not only a change after an up
            texts = [r.text for r in st.sink.records if r.kind == "system" and r.source == "node 1"]
            assert texts[0] == (f"node 1 (tcp://127.0.0.1:{port}): link down: "
                                f"read holding 1024+1: no answer within {TIMEOUT:g} s")
            wait_until(lambda: st.exchange.stats[2].reads > 50)  # node 2 polled on while 1 is silent
            assert st.engine.stats.max_ms < 1000 * TIMEOUT  # no scan waited out the silent node
        finally:
            st.stop()
            b.stop()
