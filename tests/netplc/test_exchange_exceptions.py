"""A node that answers, but only with Modbus exceptions, is down (issue 23): it serves no data, so
NREAD/NWRITE show the link down, the presence list says 00, and the journal says why, once; its
first normal answer brings it up again. Real Modbus TCP on 127.0.0.1: our own server with a
handler that fails every request while the device is unwell."""

from __future__ import annotations

from netplc.exchange import NodeConfig
from netplc.modbus import DEVICE_FAILURE, Done, ModbusServer, Table
from netplc.modbus.pdu import Refuse
from tests.netplc.test_exchange import Station, wait_until

PROGRAM = """\
TNA $03760
FON C:$02100 N:NODE S:3
TNA $03760
FON C:$02104 N:NREAD S:4000 D:$04000 R:2
JMP 0
"""


class Unwell:
    """A device answering exception 4 (server device failure) to everything until it is well."""

    def __init__(self) -> None:
        self.well = False

    def registers(self, address: int, count: int) -> bytes:
        if not self.well:
            raise Refuse(DEVICE_FAILURE)
        return b"\x12\x34" * count

    def bits(self, address: int, count: int) -> bytes:
        raise Refuse(DEVICE_FAILURE)

    def write(self, table: Table, address: int, values: list[int], peer: str, done: Done) -> int:
        return DEVICE_FAILURE


def test_a_node_answering_only_exceptions_is_down_and_comes_back_with_its_first_answer() -> None:
    device = Unwell()
    server = ModbusServer(device)
    server.start()
    endpoint = f"tcp://127.0.0.1:{server.port}"
    st = Station(PROGRAM, [NodeConfig(3, endpoint, timeout=0.3, retries=1, backoff=0.05, backoff_max=0.1)])
    snap = lambda: st.engine.snapshot  # noqa: E731
    links = lambda: [r.text for r in st.sink.records if r.source == "node 3"]  # noqa: E731
    st.start()
    try:
        wait_until(lambda: any("link down" in (t or "") for t in links()))
        wait_until(lambda: snap().get_byte(0o77743) == 0x00 and snap().get_bit(0o2105) == 0)
        assert not st.exchange.link_up(3)
        wait_until(lambda: st.exchange.stats[3].errors >= 10)  # it keeps failing: down, journaled once
        assert snap().get_bit(0o2105) == 0
        device.well = True
        wait_until(lambda: snap().get_bit(0o2105) == 1 and snap().get_word(0o4000) == 0x1234)
        assert snap().get_byte(0o77743) == 0xFF
    finally:
        st.stop()
        server.stop()
    down = f"node 3 ({endpoint}): link down: answers only exception 4 (server device failure)"
    assert [t for t in links() if "down" in (t or "")] == [down]
    assert links()[-1] == f"node 3 ({endpoint}): link up"
