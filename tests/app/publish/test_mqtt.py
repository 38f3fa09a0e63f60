"""The Sparkplug B publisher of a running headless station, against a real mosquitto broker."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import paho.mqtt.client as mqtt
import pytest

from app.publish import sparkplug as spb
from app.station.runtime import Runtime
from tests.app.conftest import REPO, copy_demo
from tests.app.publish.conftest import Mosquitto, demo_with
from tests.netplc.test_exchange import wait_until

TOPIC = "spBv1.0/Plant/{}/Demo"


def mqtt_section(broker: Mosquitto, extra: str = "") -> str:
    return (f'[mqtt]\nenabled = true\nbroker = "{broker.url}"\ngroup_id = "Plant"\nedge_node_id = "Demo"\n'
            f'writable = ["TEMP_SP"]\ndeadband = {{ word = 0.0 }}\n{extra}')


class Host:
    """A Sparkplug host application: every message of the namespace, decoded, in arrival order."""

    def __init__(self, broker: Mosquitto) -> None:
        self.messages: list[tuple[str, Any]] = []
        self.lock = threading.Lock()
        client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=f"host-{id(self)}")
        client.on_connect = lambda c, *_: c.subscribe("spBv1.0/#", qos=1)
        client.on_message = self._message
        client.reconnect_delay_set(0.1, 0.5)
        client.connect("127.0.0.1", broker.port)
        client.loop_start()
        self.client = client
        wait_until(client.is_connected, 5)
        time.sleep(0.2)  # the subscription is in place

    def _message(self, client: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        parts = message.topic.split("/")  # spBv1.0/group/TYPE/edge
        if len(parts) == 4:
            with self.lock:
                self.messages.append((parts[2], spb.Payload.FromString(message.payload)))

    def of(self, kind: str) -> list[Any]:
        with self.lock:
            return [p for k, p in self.messages if k == kind]

    def wait(self, kind: str, cond: Callable[[Any], bool] = lambda p: True, timeout: float = 10,
             after: int = 0) -> Any:
        def found() -> list[Any]:
            return [p for p in self.of(kind)[after:] if cond(p)]

        wait_until(lambda: bool(found()), timeout)
        return found()[0]

    def command(self, name: str, value: float | bool) -> None:
        """An NCMD of one metric, by name."""
        payload = spb.Payload(timestamp=int(time.time() * 1000))
        metric = payload.metrics.add(name=name)
        if isinstance(value, bool):
            metric.datatype, metric.boolean_value = spb.BOOLEAN, value
        else:
            metric.datatype, metric.double_value = spb.DOUBLE, value
        self.client.publish(TOPIC.format("NCMD"), payload.SerializeToString(), qos=1).wait_for_publish(5)

    def close(self) -> None:
        self.client.disconnect()
        self.client.loop_stop()


@pytest.fixture
def host(mosquitto: Mosquitto) -> Iterator[Host]:
    h = Host(mosquitto)
    yield h
    h.close()


@pytest.fixture
def station(tmp_path: Path, mosquitto: Mosquitto, host: Host) -> Iterator[Runtime]:
    runtime = demo_with(tmp_path / "station", mqtt_section(mosquitto))
    yield runtime
    runtime.stop()


def metric(birth: Any, name: str) -> Any:
    return next(m for m in birth.metrics if m.name == name)


def props(m: Any) -> dict[str, Any]:
    return {k: v for k, v in zip(m.properties.keys, m.properties.values)}


def test_nbirth_then_ndata_on_change(station: Runtime, host: Host) -> None:
    birth = host.wait("NBIRTH")
    assert birth.seq == 0
    assert metric(birth, "bdSeq").datatype == spb.INT64
    assert metric(birth, "Node Control/Rebirth").boolean_value is False
    level = metric(birth, "LEVEL")
    assert level.alias and level.datatype == spb.DOUBLE
    assert props(level)["engUnit"].string_value == "%"
    assert props(level)["Quality"].int_value in spb.QUALITY_CODES.values()
    sp = metric(birth, "TEMP_SP")
    host.command("TEMP_SP", 55.0)
    data = host.wait("NDATA", lambda p: any(m.alias == sp.alias and abs(m.double_value - 55) < 0.1
                                            for m in p.metrics))
    changed = next(m for m in data.metrics if m.alias == sp.alias)
    assert not changed.name  # by alias after the birth
    assert "Quality" in props(changed)
    assert len(data.metrics) < len(birth.metrics)  # only what changed (report by exception)
    seqs = [p.seq for p in host.of("NBIRTH")[:1] + host.of("NDATA")]
    assert seqs == list(range(len(seqs)))


def test_rebirth_on_command_and_ncmd_writes(station: Runtime, host: Host) -> None:
    records: list = []
    station.subscribe(records.append)
    first = host.wait("NBIRTH")
    host.command("Node Control/Rebirth", True)
    second = host.wait("NBIRTH", after=1)
    assert metric(second, "bdSeq").long_value == metric(first, "bdSeq").long_value  # same session
    host.command("LEVEL", 12.0)  # not writable: refused and journaled
    host.command("TEMP_SP", 33.0)  # writable: written and journaled
    wait_until(lambda: any(r.kind == "operator" and "TEMP_SP" in r.text and "refused" not in r.text
                           for r in records), 10)
    refused = [r for r in records if r.kind == "operator" and "LEVEL" in r.text]
    assert refused and "refused" in refused[0].text
    assert refused[0].source == f"mqtt NCMD Plant/Demo via {station.station.mqtt.broker.split('//')[1]}"


def test_reconnect_after_broker_restart_with_new_nbirth_and_buffer(tmp_path: Path, host: Host,
                                                                   mosquitto: Mosquitto) -> None:
    runtime = demo_with(tmp_path / "station", mqtt_section(mosquitto, "buffer = 2\n"))
    try:
        first = host.wait("NBIRTH")
        publisher = next(p for p in runtime.publishers if hasattr(p, "topics"))
        mosquitto.stop()
        wait_until(lambda: not publisher.status.connected, 10)
        # the demo's level and temperature move every scan: NDATA pile up, the oldest dropped
        wait_until(lambda: publisher.status.dropped >= 3, 10)
        assert publisher.status.buffered == 2
        births = len(host.of("NBIRTH"))
        mosquitto.start()
        second = host.wait("NBIRTH", after=births, timeout=40)
        assert metric(second, "bdSeq").long_value != metric(first, "bdSeq").long_value
        def after() -> list[Any]:
            with host.lock:
                pos = next(i for i, (_, p) in enumerate(host.messages) if p is second)
                return [p for k, p in host.messages[pos + 1:] if k == "NDATA"]

        wait_until(lambda: len(after()) >= 2, 10)
        historical = [p for p in after()[:2] if all(m.is_historical for m in p.metrics)]
        assert len(historical) == 2  # the buffer, after the new NBIRTH, marked historical
        assert all(m.timestamp <= second.metrics[0].timestamp for p in historical for m in p.metrics)
    finally:
        runtime.stop()


def test_ndeath_when_the_station_is_killed(tmp_path: Path, mosquitto: Mosquitto, host: Host) -> None:
    station = copy_demo(tmp_path / "station")
    toml = station / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8") + "\n" + mqtt_section(mosquitto), encoding="utf-8")
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


def test_bdseq_goes_on_across_restarts_of_the_station(tmp_path: Path, mosquitto: Mosquitto,
                                                        host: Host) -> None:
    """Each connection's bdSeq is the previous one's plus one, also after the station restarts
    (kept in the station folder), so a host never takes an old session's NDEATH for the new one's;
    a file that holds no bdSeq is journaled and the count starts again."""
    from app.publish.station import BDSEQ_FILE
    from app.station.config import load_station

    station = copy_demo(tmp_path / "station")
    toml = station / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8") + "\n" + mqtt_section(mosquitto), encoding="utf-8")
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
    and an unknown one are refused; 3,000 bad commands leave a record per cause, not 3,000."""
    records: list = []
    station.subscribe(records.append)
    host.wait("NBIRTH")
    publisher = next(p for p in station.publishers if hasattr(p, "topics"))

    def send(name: str, kind: int, field: str, value: object) -> None:
        payload = spb.Payload(timestamp=int(time.time() * 1000))
        metric = payload.metrics.add(name=name, datatype=kind)
        setattr(metric, field, value)
        host.client.publish(TOPIC.format("NCMD"), payload.SerializeToString(), qos=1)

    for i in range(750):
        send("TEMP_SP", spb.STRING, "string_value", "42")
        send("TEMP_SP", spb.DOUBLE, "double_value", 1000.0 + i)
        send("LEVEL", spb.DOUBLE, "double_value", 12.0)
        send("NOPE", spb.DOUBLE, "double_value", 1.0)
    send("TEMP_SP", spb.INT32, "int_value", 42)  # an Int32 for a Double metric: refused too
    wait_until(lambda: publisher.status.refused == 3001, 30)
    refused = [r for r in records if r.kind == "operator" and r.text.startswith("refused")]
    assert len(refused) == 4, [r.text for r in refused]  # the Int32's record is the String's, counted
    texts = " | ".join(r.text for r in refused)
    for words in ("a String for a Double metric", "outside -50.0 °C .. 150.0 °C", "[mqtt] writable",
                  "no such metric"):
        assert words in texts
    assert all(r.source.startswith("mqtt NCMD Plant/Demo via 127.0.0.1:") for r in refused)
    host.command("TEMP_SP", 77.0)  # a right one still goes through
    wait_until(lambda: abs(station.readings().tag("TEMP_SP").value - 77.0) < 0.05, 10)
    assert any(r.kind == "operator" and "TEMP_SP" in r.text and "refused" not in r.text for r in records)
