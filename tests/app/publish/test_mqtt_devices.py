"""The nodes of the exchange as Sparkplug devices of the station's edge node: a node that stops
answering dies (DDEATH) and is born again when it answers; DCMD writes its points through the
command layer, as NCMD writes the edge node's."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from app.authority import Source
from app.publish import sparkplug as spb
from app.station.runtime import Runtime
from tests.app.publish.conftest import Host, Mosquitto, demo_with, metric, mqtt_section, props, session
from tests.netplc.test_exchange import wait_until


@pytest.fixture
def host(broker: Mosquitto) -> Iterator[Host]:
    h = Host(broker, group="Devices")
    yield h
    h.close()


def started(folder: Path, broker: Mosquitto, extra: str = "",
            writable: str = "TEMP_SP") -> tuple[Runtime, list]:
    records: list = []
    return demo_with(folder, mqtt_section(broker, extra, "Devices", writable), records, "en"), records


def test_a_node_that_stops_answering_dies_and_is_born_again(tmp_path: Path, broker: Mosquitto,
                                                           host: Host) -> None:
    runtime, _ = started(tmp_path / "station", broker)
    try:
        birth = host.wait("NBIRTH")
        first = host.wait("DBIRTH", device="Node0")
        level = metric(first, "LEVEL")
        runtime.simulator_answers(0, False)  # node 0's Modbus server on 127.0.0.1 stops: a pulled cable
        death = host.wait("DDEATH", device="Node0")
        assert not death.metrics and death.timestamp  # a timestamp and a seq, nothing else (spec 3.0)
        runtime.simulator_answers(0, True)
        again = host.wait("DBIRTH", device="Node0", after=1)
        between = [(k, d) for k, d, _ in session(host, birth)]
        dead = between[between.index(("DDEATH", "Node0")) + 1:between.index(("DBIRTH", "Node0"), 2)]
        assert ("DDATA", "Node0") not in dead  # its points are not published while it is dead
        assert metric(again, "Link/Up").boolean_value is True
        assert metric(again, "Link/Errors").long_value >= 1 and metric(again, "Link/LastError").string_value
        assert metric(again, "LEVEL").alias == level.alias  # the same alias, as the spec wants
        quality = props(metric(again, "LEVEL"))["Quality"].int_value
        assert quality in (spb.GOOD, spb.STALE, spb.BAD)  # read again already, or not yet
        seqs = [p.seq for _, _, p in session(host, birth)]
        assert seqs == [n % 256 for n in range(len(seqs))]  # one seq through births, data and deaths
    finally:
        runtime.stop()


def test_dcmd_writes_through_the_command_layer_and_a_viewer_role_is_refused(tmp_path: Path, broker: Mosquitto,
                                                                           host: Host) -> None:
    runtime, records = started(tmp_path / "station", broker, 'role = "viewer"\n', "LEVEL")
    try:
        host.wait("NBIRTH")
        level = metric(host.wait("DBIRTH", device="Node0"), "LEVEL")
        host.command("LEVEL", 40.0, device="Node0")  # [mqtt] role = "viewer": MQTT may only look
        host.command("Link/Up", False, device="Node0")  # a link metric is read-only
        host.command("LEVEL", 40.0, device="Node9")  # no such device
        host.command("LEVEL", "40", device="Node0")  # a String for a Double metric

        def operator(*words: str) -> list[str]:
            return [r.text for r in records if r.kind == "operator" and all(w in r.text for w in words)]

        publisher = next(p for p in runtime.publishers if hasattr(p, "layout"))
        wait_until(lambda: publisher.status.refused == 4, 10)
        assert operator("refused") == [  # the String's refusal is the first one's: the role first, counted
            "refused write LEVEL: needs the operator role; clients with no user act as viewer",
            "refused write Link/Up: a link metric, read-only",
            "refused write Node9: no such device of Devices/Demo"]
        runtime.commands.grant(Source.MQTT, "operator")
        host.command("LEVEL", "40", device="Node0")
        alias = spb.Payload(timestamp=1)  # by alias, as a host writes after the birth
        alias.metrics.add(alias=level.alias, datatype=spb.DOUBLE, double_value=40.0)
        host.client.publish("spBv1.0/Devices/DCMD/Demo/Node0", alias.SerializeToString(), qos=1)
        wait_until(lambda: operator("LEVEL", "40") and operator("String"), 10)
        assert operator("refused write LEVEL: a String for a Double metric")
        written = [r for r in records if r.kind == "operator" and "LEVEL" in r.text
                   and "refused" not in r.text]
        assert written and written[0].source.startswith("mqtt DCMD Devices/Demo/Node0 via 127.0.0.1:")
    finally:
        runtime.stop()
