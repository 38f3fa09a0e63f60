"""The edge node and its Primary Host Application (Sparkplug 3.0): births only while the host's
STATE is online, a session ended and a new one begun when it goes offline and comes back."""

from __future__ import annotations

import time
from pathlib import Path

from app.publish.mqtt import SparkplugPublisher
from app.station.runtime import Runtime
from tests.app.publish.conftest import Host, Mosquitto, demo_with, metric, mqtt_section
from tests.netplc.test_exchange import wait_until


def waiting(folder: Path, broker: Mosquitto, host_id: str,
            group: str) -> tuple[Runtime, SparkplugPublisher, list]:
    """A demo station with `primary_host = host_id`, connected to the broker; its records."""
    records: list = []
    runtime = demo_with(folder, mqtt_section(broker, f'primary_host = "{host_id}"\n', group), records, "en")
    publisher = next(p for p in runtime.publishers if isinstance(p, SparkplugPublisher))
    wait_until(lambda: publisher.status.connected, 5)
    return runtime, publisher, records


def scans(publisher: SparkplugPublisher, n: int) -> None:
    """Wait until the publisher has been handed `n` more scans (it births, if it may, at the first)."""
    scan = publisher.feed.scan
    wait_until(lambda: publisher.feed.scan >= scan + n, 5)


def test_births_wait_for_the_primary_host_and_a_new_session_follows_its_offline_state(
        tmp_path: Path, broker: Mosquitto) -> None:
    host = Host(broker, group="Primary")  # the test publishes the host's STATE itself
    runtime, publisher, records = waiting(tmp_path / "station", broker, "SCADA-1", "Primary")
    try:
        scans(publisher, 3)
        assert publisher.status.births == 0 and not host.of("NBIRTH")  # no STATE yet: no birth

        t0 = int(time.time() * 1000)
        host.state("SCADA-1", True, t0)
        birth = host.wait("NBIRTH")
        bdseq = metric(birth, "bdSeq").long_value
        host.wait("DBIRTH", device="Node0")

        # a death older than the online STATE (an earlier session of the host's, delivered late)
        # is ignored: the rebirth asked after it comes in the same session, with no NDEATH between
        host.state("SCADA-1", False, t0 - 1)
        host.command("Node Control/Rebirth", True)
        again = host.wait("NBIRTH", after=1)
        assert metric(again, "bdSeq").long_value == bdseq
        assert "NDEATH" not in [kind for kind, _, _ in host.since(birth)]

        # offline: NDEATH of this session, then a new connection that waits for the host
        host.state("SCADA-1", False, t0 + 1)
        death = host.wait("NDEATH")
        assert metric(death, "bdSeq").long_value == bdseq
        wait_until(lambda: publisher.status.connected and publisher.bdseq == (bdseq + 1) % 256, 5)
        scans(publisher, 3)
        assert publisher.status.births == 2 and len(host.of("NBIRTH")) == 2

        host.state("SCADA-1", True, t0 + 2)
        third = host.wait("NBIRTH", after=2)
        assert metric(third, "bdSeq").long_value == (bdseq + 1) % 256  # a new session
        host.wait("DBIRTH", device="Node0", after=2)
        texts = [r.text for r in records if r.kind == "system"]
        assert any("STATE of primary host SCADA-1 ignored: its timestamp" in t for t in texts)
        assert any("primary host SCADA-1 is offline: NDEATH" in t for t in texts)
    finally:
        runtime.stop()
        host.close()


def test_a_state_that_is_no_sparkplug_3_state_is_journaled_and_no_birth_comes_of_it(
        tmp_path: Path, broker: Mosquitto) -> None:
    """A Sparkplug 2.2 host's plain ONLINE is not a 3.0 STATE: journaled, and no birth comes of it."""
    host = Host(broker, group="Old")
    host.client.publish("spBv1.0/STATE/OLD-HOST", b"ONLINE", qos=1, retain=True).wait_for_publish(5)
    runtime, publisher, records = waiting(tmp_path / "station", broker, "OLD-HOST", "Old")
    try:
        wait_until(lambda: any("STATE of primary host OLD-HOST ignored: not UTF-8 JSON" in (r.text or "")
                               for r in records), 5)
        scans(publisher, 3)
        assert publisher.status.births == 0
        host.state("OLD-HOST", True, int(time.time() * 1000))
        host.wait("NBIRTH")
    finally:
        runtime.stop()
        host.client.publish("spBv1.0/STATE/OLD-HOST", b"", qos=1, retain=True).wait_for_publish(5)
        host.close()
