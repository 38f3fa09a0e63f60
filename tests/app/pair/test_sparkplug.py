"""The pair is one Sparkplug edge node (issue 26): only the primary connects and publishes NBIRTH
and data; after a takeover the new primary births with the next bdSeq (the primary's is mirrored
to the standby), a station that comes back as the standby births nothing, and IntoStandBy hands
the session over: NDEATH from the old primary, NBIRTH from the new with the next bdSeq."""

from __future__ import annotations

from pathlib import Path

from netplc.simulator import Simulator
from tests.app.pair.conftest import make_pair, start_pair, wait_for
from tests.app.publish.conftest import Host, Mosquitto, metric
from tests.app.publish.conftest import mosquitto as mosquitto  # the fixture, a broker of the test's

MQTT = '[mqtt]\nenabled = true\nbroker = "{url}"\ngroup_id = "Pair"\nedge_node_id = "Boiler"\n'


def bdseq(payload: object) -> int:
    return int(metric(payload, "bdSeq").long_value)


def test_one_edge_node_for_the_pair(tmp_path: Path, node: Simulator, mosquitto: Mosquitto) -> None:
    host = Host(mosquitto, group="Pair", edge="Boiler")
    a, b = make_pair(tmp_path, node, top=MQTT.format(url=mosquitto.url))
    try:
        start_pair(a, b)
        first = bdseq(host.wait("NBIRTH"))
        assert b.rt.pair is not None and b.role == "standby"
        wait_for(lambda: b.rt.pair is not None and b.rt.pair.mirror.complete, timeout=10,
                 what="B holds A's state")
        a.kill()
        wait_for(lambda: b.role == "primary", what="takeover")
        second = host.wait("NBIRTH", after=1)
        assert bdseq(second) == (first + 1) % 256
        assert [bdseq(d) for d in host.of("NDEATH")] == [first]  # A's session ended, B's lives
        a.start()  # back as the standby: no session of its own
        assert a.role == "standby"
        wait_for(lambda: a.rt.pair is not None and a.rt.pair.mirror.complete, what="A follows")
        assert b.rt.pair is not None and b.rt.pair.into_standby("IntoStandBy by test", wait=2)
        third = host.wait("NBIRTH", after=2)
        assert bdseq(third) == (first + 2) % 256  # A learned B's bdSeq as its standby
        wait_for(lambda: [bdseq(d) for d in host.of("NDEATH")] == [first, first + 1], timeout=10,
                 what="B's NDEATH")
        assert len(host.of("NBIRTH")) == 3  # no standby ever born
    finally:
        b.stop()
        a.stop()
        host.close()
