"""Link state while NetPlc asks a node nothing: probes keep it truthful (never a stale "link up")."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from netplc.exchange import PROBE_IDLE, NodeConfig
from netplc.modbus import ModbusServer
from netplc.program import parse
from netplc.simulator import EngineMemory, Simulator
from tests.netplc.test_exchange import NETPLC_PROGRAM, NODE_PROGRAM, Station, wait_until

TIMEOUT = 0.2
BACKOFF_MAX = 0.4


@pytest.fixture
def node0() -> Iterator[Simulator]:
    sim = Simulator(parse(NODE_PROGRAM, "node.stl"), tick=0.01)
    sim.start()
    yield sim
    sim.stop()


def node_records(st: Station) -> list[str]:
    return [r.text or "" for r in st.sink.records if r.kind == "system" and r.source == "node 0"]


def test_a_node_that_dies_while_the_program_is_stopped_shows_down_and_comes_back(node0: Simulator) -> None:
    st = Station(NETPLC_PROGRAM, [NodeConfig(0, f"tcp://127.0.0.1:{node0.port}", timeout=TIMEOUT,
                                             retries=0, backoff=0.1, backoff_max=BACKOFF_MAX)])
    st.start()
    snap = lambda: st.engine.snapshot  # noqa: E731
    stats = st.exchange.stats[0]
    try:
        wait_until(lambda: snap().get_byte(0o77740) == 0xFF)
        assert stats.probes == 0  # requests every scan: nothing to probe

        st.engine.post(lambda _m: st.engine.stop())
        wait_until(lambda: snap().state == "stopped")
        wait_until(lambda: st.exchange.in_flight == 0)  # the last scan's requests are answered
        reads = stats.reads
        node0.server.stop()  # node 0 switched off while NetPlc asks it nothing
        took = wait_until(lambda: snap().get_byte(0o77740) == 0, timeout=PROBE_IDLE + 3)
        assert took < PROBE_IDLE + 2 * TIMEOUT + 0.5
        assert not st.exchange.link_up(0) and not stats.up
        assert "link down" in node_records(st)[-1]
        assert stats.probes >= 1 and stats.reads == reads  # the probes are not NREADs

        node0.server = ModbusServer(EngineMemory(node0.engine), port=node0.port, sink=node0.engine.sink)
        node0.server.start()  # switched on again, the program still stopped
        wait_until(lambda: snap().get_byte(0o77740) == 0xFF, timeout=PROBE_IDLE + BACKOFF_MAX + 3)
        assert st.exchange.link_up(0)
        assert node_records(st)[-1].endswith("link up")
        assert [t.rsplit(": link ", 1)[1][:2] for t in node_records(st)] == ["up", "do", "up"]
        assert stats.errors == 0  # no request of the program failed
    finally:
        st.stop()


def test_a_node_the_program_never_addresses_is_reported_down_from_the_start() -> None:
    """A dead node that no instruction talks to still gets its presence byte and its record."""
    st = Station("TNA $03760\nJMP 0\n", [NodeConfig(0, "tcp://127.0.0.1:1", timeout=TIMEOUT, retries=0)])
    st.start()
    try:
        wait_until(lambda: node_records(st) != [], timeout=PROBE_IDLE + 3)
        assert node_records(st)[0].startswith("node 0 (tcp://127.0.0.1:1): link down: cannot connect")
        assert st.engine.snapshot.get_byte(0o77740) == 0 and not st.exchange.link_up(0)
    finally:
        st.stop()
