"""The Sparkplug B publisher of a running headless station, against a real mosquitto broker."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from app.publish import sparkplug as spb
from app.station.runtime import Runtime
from tests.app.conftest import REPO, copy_demo
from tests.app.publish.conftest import Host, Mosquitto, demo_with, metric, mqtt_section, props, session
from tests.netplc.test_exchange import wait_until

TOPIC = "spBv1.0/Plant/{}/Demo"


@pytest.fixture
def host(broker: Mosquitto) -> Iterator[Host]:
    h = Host(broker)
    yield h
    h.close()


@pytest.fixture
def station(tmp_path: Path, broker: Mosquitto, host: Host) -> Iterator[Runtime]:
    runtime = demo_with(tmp_path / "station", mqtt_section(broker), language="en")
    yield runtime
    runtime.stop()


def test_nbirth_dbirth_then_ndata_on_change(station: Runtime, host: Host) -> None:
    """The NBIRTH has the station's own points, the DBIRTH of node 0 (Node0) the points its NREADs
    fill and its link; one seq counts every message of the session."""
    birth = host.wait("NBIRTH")
    assert birth.seq == 0
    assert metric(birth, "bdSeq").datatype == spb.INT64
    assert metric(birth, "Node Control/Rebirth").boolean_value is False
    assert not metric(birth, "Node Control/Rebirth").alias  # spec 3.0: never an alias
    assert {m.name for m in birth.metrics} == {"bdSeq", "Node Control/Rebirth", "TEMP_SP"}
    device = host.wait("DBIRTH", device="Node0")
    level = metric(device, "LEVEL")
    assert level.alias and level.datatype == spb.DOUBLE
    assert props(level)["engUnit"].string_value == "%"
    assert props(level)["Quality"].type == spb.INT32
    assert props(level)["Quality"].int_value in (spb.GOOD, spb.BAD)  # read already, or not yet
    assert {m.name for m in device.metrics} == {"Link/Up", "Link/Errors", "Link/LastError", "Link/Endpoint",
                                                "LEVEL", "TEMP", "TRIGGER"}
    assert metric(device, "Link/Up").boolean_value is True
    assert metric(device, "Link/Endpoint").string_value.startswith("tcp://127.0.0.1:")
    aliases = [m.alias for m in [*birth.metrics, *device.metrics] if m.alias]
    assert len(aliases) == len(set(aliases))  # unique across the edge node (spec 3.0)
    sp = metric(birth, "TEMP_SP")
    host.command("TEMP_SP", 55.0)
    data = host.wait("NDATA", lambda p: any(m.alias == sp.alias and abs(m.double_value - 55) < 0.1
                                            for m in p.metrics))
    changed = next(m for m in data.metrics if m.alias == sp.alias)
    assert not changed.name  # by alias after the birth
    assert props(changed)["Quality"].int_value == spb.GOOD
    host.wait("DDATA", lambda p: any(m.alias == level.alias for m in p.metrics), device="Node0")
    seqs = [p.seq for kind, _, p in session(host, birth)]
    assert seqs == [n % 256 for n in range(len(seqs))]


def test_rebirth_on_command_and_ncmd_writes(station: Runtime, host: Host) -> None:
    records: list = []
    station.subscribe(records.append)
    first = host.wait("NBIRTH")
    host.wait("DBIRTH", device="Node0")  # once node 0's link is known up
    host.command("Node Control/Rebirth", True)
    second = host.wait("NBIRTH", after=1)
    assert metric(second, "bdSeq").long_value == metric(first, "bdSeq").long_value  # same session
    host.wait("DBIRTH", after=1, device="Node0")  # the whole birth sequence again
    host.command("LEVEL", 12.0)  # a point of device Node0, not of the edge node: refused
    host.command("LEVEL", 12.0, device="Node0")  # not writable: refused and journaled
    host.command("TEMP_SP", 33.0)  # writable: written and journaled
    wait_until(lambda: any(r.kind == "operator" and "TEMP_SP" in r.text and "refused" not in r.text
                           for r in records), 10)
    wait_until(lambda: len([r for r in records if "LEVEL" in (r.text or "")]) == 2, 10)
    refused = [r for r in records if r.kind == "operator" and "LEVEL" in r.text]
    peer = station.station.mqtt.broker.split('//')[1]
    assert [(r.text, r.source) for r in refused] == [
        ("refused write LEVEL: no such metric of Plant/Demo", f"mqtt NCMD Plant/Demo via {peer}"),
        ("refused write LEVEL: not among the points [mqtt] writable names",
         f"mqtt DCMD Plant/Demo/Node0 via {peer}")]


def test_reconnect_after_broker_restart_with_new_nbirth_and_buffer(tmp_path: Path,
                                                                   mosquitto: Mosquitto) -> None:
    """The station waits for its primary host here: after the restart the births come once the
    host is back and subscribed, whoever of the two reconnects first."""
    host = Host(mosquitto, primary="SCADA")
    runtime = demo_with(tmp_path / "station", mqtt_section(mosquitto, 'buffer = 2\nprimary_host = "SCADA"\n'))
    try:
        first = host.wait("NBIRTH")
        publisher = next(p for p in runtime.publishers if hasattr(p, "topics"))
        mosquitto.stop(signal.SIGKILL)  # gone: not even the host's will (STATE offline) is published
        wait_until(lambda: not publisher.status.connected, 10)
        # the demo's level and temperature move every scan: NDATA pile up, the oldest dropped
        wait_until(lambda: publisher.status.dropped >= 3, 10)
        assert publisher.status.buffered == 2
        births = len(host.of("NBIRTH"))
        mosquitto.start()
        second = host.wait("NBIRTH", after=births, timeout=40)
        assert metric(second, "bdSeq").long_value != metric(first, "bdSeq").long_value

        def after() -> list[Any]:
            return [p for k, _, p in host.since(second) if k in ("NDATA", "DDATA")]

        wait_until(lambda: len(after()) >= 2, 10)
        historical = [p for p in after()[:2] if all(m.is_historical for m in p.metrics)]
        assert len(historical) == 2  # the buffer, after the new births, marked historical
        assert all(m.timestamp <= second.metrics[0].timestamp for p in historical for m in p.metrics)
    finally:
        runtime.stop()
        host.close()


def test_ndeath_when_the_station_is_killed(tmp_path: Path, broker: Mosquitto, host: Host) -> None:
    station = copy_demo(tmp_path / "station")
    toml = station / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8") + "\n" + mqtt_section(broker), encoding="utf-8")
    proc = subprocess.Popen([sys.executable, "main.py", "--no-gui", str(station), "--duration", "60"],
                            cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        birth = host.wait("NBIRTH", timeout=30)
        proc.kill()
        death = host.wait("NDEATH", timeout=10)
        assert metric(death, "bdSeq").long_value == metric(birth, "bdSeq").long_value
    finally:
        proc.kill()
        proc.wait(10)


def test_bdseq_goes_on_across_restarts_of_the_station(tmp_path: Path, broker: Mosquitto, host: Host) -> None:
    """Each connection's bdSeq is the previous one's plus one, also after the station restarts
    (kept in the station folder), so a host never takes an old session's NDEATH for the new one's;
    a file that holds no bdSeq is journaled and the count starts again."""
    from app.publish.station import BDSEQ_FILE
    from app.station.config import load_station

    station = copy_demo(tmp_path / "station", "en")
    toml = station / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8") + "\n" + mqtt_section(broker), encoding="utf-8")
    records: list = []

    def run() -> int:
        births, deaths = len(host.of("NBIRTH")), len(host.of("NDEATH"))
        runtime = Runtime(load_station(station))
        runtime.subscribe(records.append)
        runtime.start()
        try:
            bdseq = metric(host.wait("NBIRTH", after=births), "bdSeq").long_value
        finally:
            runtime.stop()
        assert metric(host.wait("NDEATH", after=deaths), "bdSeq").long_value == bdseq
        return bdseq

    assert (run(), run()) == (0, 1)
    (station / BDSEQ_FILE).write_text("many\n", encoding="utf-8")
    assert run() == 0
    assert any(BDSEQ_FILE in (r.text or "") and "not a bdSeq" in r.text for r in records)


def test_ncmd_writes_are_checked_and_their_refusals_journaled_throttled(station: Runtime, host: Host) -> None:
    """A String for a Double metric, a value outside PhyMin..PhyMax, a metric not named writable
    (in a DCMD) and an unknown one are refused; 400 bad commands leave a record per cause, not 400
    (the throttle counts per cause, per source, per minute: 100 of each prove it as 750 did)."""
    records: list = []
    station.subscribe(records.append)
    host.wait("NBIRTH")
    publisher = next(p for p in station.publishers if hasattr(p, "topics"))

    def send(name: str, kind: int, field: str, value: object, topic: str = TOPIC.format("NCMD")) -> None:
        payload = spb.Payload(timestamp=int(time.time() * 1000))
        metric = payload.metrics.add(name=name, datatype=kind)
        setattr(metric, field, value)
        host.client.publish(topic, payload.SerializeToString(), qos=1)

    for i in range(100):
        send("TEMP_SP", spb.STRING, "string_value", "42")
        send("TEMP_SP", spb.DOUBLE, "double_value", 1000.0 + i)
        send("LEVEL", spb.DOUBLE, "double_value", 12.0, TOPIC.format("DCMD") + "/Node0")
        send("NOPE", spb.DOUBLE, "double_value", 1.0)
    send("TEMP_SP", spb.INT32, "int_value", 42)  # an Int32 for a Double metric: refused too
    wait_until(lambda: publisher.status.refused == 401, 30)
    refused = [r for r in records if r.kind == "operator" and r.text.startswith("refused")]
    assert len(refused) == 4, [r.text for r in refused]  # the Int32's record is the String's, counted
    texts = " | ".join(r.text for r in refused)
    for words in ("a String for a Double metric", "outside -50.0 °C .. 150.0 °C", "[mqtt] writable",
                  "no such metric"):
        assert words in texts
    assert all(r.source.startswith(("mqtt NCMD Plant/Demo via 127.0.0.1:", "mqtt DCMD Plant/Demo/Node0 via "))
               for r in refused)
    host.command("TEMP_SP", 77.0)  # a right one still goes through
    wait_until(lambda: abs(station.readings().tag("TEMP_SP").value - 77.0) < 0.05, 10)
    assert any(r.kind == "operator" and "TEMP_SP" in r.text and "refused" not in r.text for r in records)
