"""The MQTT publisher: the station as a Sparkplug B 3.0 edge node (paho-mqtt).

One thread of its own takes the newest snapshot (`LatestSnapshot`: the scan never waits) and
publishes; paho's network thread connects, reconnects with back-off (1 s doubling to 30 s) and
hands NCMD commands over. Per connection: NDEATH with the connection's bdSeq registered as the
last will, then NBIRTH (every metric with name, alias, datatype, engUnit and Quality properties,
the bdSeq and Node Control/Rebirth) and then NDATA with only the metrics whose value moved beyond
the deadband of its tag type or whose quality changed (report by exception), by alias. While the
broker is away the NDATA are kept in a bounded buffer (oldest dropped first, counted) and sent
after the next NBIRTH as historical metrics. NCMD Node Control/Rebirth republishes the NBIRTH.

Every other NCMD metric is a write through the station's command layer (app/authority/), by the
MQTT source (a command names no user: it acts with the role station.toml grants MQTT), checked
for the metric's Sparkplug datatype (a String for a Double metric is refused), the tag's physical
range and `[mqtt] writable`. An NCMD has no answer: the journal is the answer, each refusal
journaled by the layer, throttled (one record per cause per minute with the count of the others).
"""

from __future__ import annotations

import logging
import os
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import numpy as np
import paho.mqtt.client as mqtt

from app.authority import Action, Commands, Reason, Source, Ticket, Who
from app.publish import sparkplug as spb
from app.publish.feed import LatestReadings, Watch
from app.publish.points import PointReader, PointWriter, Reading, Writable
from app.scada.tag import Tag
from app.station.config import MqttSettings

logger = logging.getLogger(__name__)

BACKOFF = (1, 30)  # seconds: first reconnect delay, doubling up to the second
KEEPALIVE = 10  # s: the broker publishes NDEATH within 1.5 of these after the station vanishes


@dataclass
class MqttStatus:
    connected: bool = False
    births: int = 0
    messages: int = 0  # NDATA published
    metrics: int = 0  # metrics in them
    buffered: int = 0  # NDATA waiting for the broker
    dropped: int = 0  # NDATA dropped from a full buffer (the oldest first)
    refused: int = 0  # NCMD writes refused


class SparkplugPublisher:
    def __init__(self, settings: MqttSettings, station: str, *, tags: Sequence[Tag], commands: Commands,
                 watch: Watch, journal: Callable[[str], None], bdseq_file: Path | None = None) -> None:
        """`bdseq_file` keeps the bdSeq of the last connection across restarts (Sparkplug 3.0:
        each connection's bdSeq is the previous one's plus one), so a host application never
        takes the NDEATH of an old session for the new one's; None: it starts at 0."""
        self.settings = settings
        self.topics = spb.Topics(settings.group_id, settings.edge_node_id or station)
        self.tags = list(tags)
        self.index = {t.name: i for i, t in enumerate(self.tags)}
        self.reader = PointReader(self.tags)
        self.writer = PointWriter(commands, Writable(settings.writable), "[mqtt]")
        self.commands = commands
        self.watch = watch
        self.journal = journal
        self.status = MqttStatus()
        self.kinds = [spb.datatype(t) for t in self.tags]
        bands = dict(settings.deadband)
        self.deadband = np.array([bands.get(t.type.value, 0.0) for t in self.tags])
        url = urlsplit(settings.broker)
        self.host = url.hostname or "127.0.0.1"
        self.port = url.port or (8883 if url.scheme == "mqtts" else 1883)
        self.peer = f"{self.host}:{self.port}"
        self.who = Who("", Source.MQTT, f"NCMD {self.topics.node} via {self.peer}")
        self.feed = LatestReadings(self._wakeup)
        self._unwatch: Callable[[], None] | None = None
        self.bdseq_file = bdseq_file
        self.bdseq = (self._stored_bdseq() + 1) % 256  # the next connection's (stored once connected)
        self._seq = 0
        self._birth_due = False
        self._latest: Reading | None = None
        self._sent_values = np.full(len(self.tags), np.nan)
        self._sent_quality = np.full(len(self.tags), -1, dtype=np.int8)
        self._buffer: deque[bytes] = deque()
        self._wake = threading.Event()
        self._stopping = False
        self._lock = threading.Lock()  # bdSeq and the will, between paho's thread and stop()
        self._thread: threading.Thread | None = None
        client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=f"netplc-{self.topics.group}-"
                             f"{self.topics.edge}", clean_session=True)
        if settings.username:
            client.username_pw_set(settings.username, settings.password or None)
        if url.scheme == "mqtts":
            client.tls_set(ca_certs=str(settings.ca_file) if settings.ca_file else None)
        client.reconnect_delay_set(*BACKOFF)
        client.on_connect = self._on_connect
        client.on_disconnect = self._on_disconnect
        client.message_callback_add(self.topics.ncmd, self._on_ncmd)
        self.client = client
        self._set_will()

    # --- life cycle ----------------------------------------------------------------------------

    def start(self) -> None:
        """Never fails for a broker that is away: the client keeps trying, the station runs on."""
        self.client.connect_async(self.host, self.port, KEEPALIVE)
        self.client.loop_start()
        self._thread = threading.Thread(target=self._run, name="mqtt-publish", daemon=True)
        self._thread.start()
        self._unwatch = self.watch(self.feed)

    def stop(self) -> None:
        """A deliberate stop: NDEATH published by the node itself (spec 3.0), then disconnect."""
        if self._unwatch is not None:
            self._unwatch()
            self._unwatch = None
        self._stopping = True
        self._wake.set()
        if self._thread is not None:
            self._thread.join(10)
        if self.status.connected:
            info = self.client.publish(self.topics.ndeath, self._death(), qos=1)
            info.wait_for_publish(2)
        self.client.disconnect()
        self.client.loop_stop()

    def _wakeup(self) -> None:
        self._wake.set()

    # --- paho's thread -------------------------------------------------------------------------

    def _stored_bdseq(self) -> int:
        """The bdSeq of the last connection made (-1: none, the first is then 0)."""
        if self.bdseq_file is None or not self.bdseq_file.exists():
            return -1
        try:
            value = int(self.bdseq_file.read_text(encoding="utf-8").strip())
            if not 0 <= value <= 255:
                raise ValueError(f"{value} is not 0..255")
        except (OSError, ValueError) as e:
            self.journal(f"MQTT: {self.bdseq_file}: not a bdSeq ({e}); starting again at 0")
            return -1
        return value

    def _store_bdseq(self) -> None:
        if self.bdseq_file is None:
            return
        tmp = self.bdseq_file.with_suffix(".tmp")
        try:
            tmp.write_text(f"{self.bdseq}\n", encoding="utf-8")
            os.replace(tmp, self.bdseq_file)
        except OSError as e:  # the station runs on; a host may then see a bdSeq again after a restart
            self.journal(f"MQTT: {self.bdseq_file}: bdSeq not kept ({e})")

    def _death(self) -> bytes:
        payload = spb.Payload(timestamp=_ms(time.time()))
        metric = payload.metrics.add(name=spb.BDSEQ, datatype=spb.INT64)
        metric.long_value = self.bdseq
        return payload.SerializeToString()

    def _set_will(self) -> None:
        self.client.will_set(self.topics.ndeath, self._death(), qos=1, retain=False)

    def _on_connect(self, client: mqtt.Client, userdata: object, flags: Any, reason: Any, props: Any) -> None:
        if reason.is_failure:
            self.journal(f"MQTT broker {self.peer} refused the connection: {reason}")
            return
        client.subscribe(self.topics.ncmd, qos=1)
        with self._lock:
            self._store_bdseq()  # registered with the broker: the one the next start goes on from
        self.status.connected = True
        self._birth_due = True
        self._wake.set()
        dropped = self.status.dropped
        lost = f", {dropped} NDATA dropped so far from a full buffer" if dropped else ""
        self.journal(f"MQTT connected to {self.peer} as {self.topics.node} (bdSeq {self.bdseq}){lost}")

    def _on_disconnect(self, client: mqtt.Client, userdata: object, flags: Any, reason: Any,
                       props: Any) -> None:
        was = self.status.connected
        self.status.connected = False
        with self._lock:
            self.bdseq = (self.bdseq + 1) % 256  # the next session's NDEATH, before paho reconnects
            self._set_will()
        if was and not self._stopping:
            self.journal(f"MQTT connection to {self.peer} lost ({reason}); reconnecting with back-off, "
                         "NDATA buffered meanwhile")

    def _on_ncmd(self, client: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        who = self.who
        try:
            payload = spb.Payload.FromString(message.payload)
        except Exception as e:  # no log: bad input, answered by the journaled refusal below
            self._refused(self.commands.refuse(who, Action.WRITE, "", Reason.INVALID,
                                               f"not a Sparkplug B payload ({type(e).__name__})"))
            return
        for metric in payload.metrics:
            name = metric.name
            if not name and metric.alias:
                i = int(metric.alias) - 1
                name = self.tags[i].name if 0 <= i < len(self.tags) else f"alias {metric.alias}"
            if name == spb.REBIRTH:
                if spb.get_value(metric):
                    self._birth_due = True
                    self._wake.set()
                    self.journal(f"MQTT rebirth requested by NCMD via {self.peer}")
                continue
            i = self.index.get(name)
            if i is None:
                ticket = self.commands.refuse(who, Action.WRITE, name, Reason.UNKNOWN, "no such metric")
            else:
                kind = self.kinds[i]
                ticket = self.writer.write(who, self.tags[i], spb.get_value(metric, kind),
                                           spb.mismatch(metric, kind))
            self._refused(ticket)

    def _refused(self, ticket: Ticket) -> None:
        """Count the command's refusal (the layer journals it) once it is answered."""
        def answered(done: Ticket) -> None:
            if not done.result().ok:
                with self._lock:
                    self.status.refused += 1

        ticket.add_done_callback(answered)

    # --- the publisher's thread ----------------------------------------------------------------

    def _run(self) -> None:
        period = self.settings.publish_period / 1000
        last = 0.0
        while not self._stopping:
            self._wake.wait()
            if self._stopping:
                break
            if period and (wait := last + period - time.monotonic()) > 0:
                time.sleep(wait)
            self._wake.clear()
            item = self.feed.take()
            if item is not None:
                self._latest = self.reader.read(item)
            reading = self._latest
            if reading is None:
                continue
            if self._birth_due and self.status.connected:
                self._birth(reading)
            elif item is not None:
                self._data(reading)
            last = time.monotonic()

    def _next_seq(self) -> int:
        seq, self._seq = self._seq, (self._seq + 1) % 256
        return seq

    def _birth(self, reading: Reading) -> None:
        self._birth_due = False
        self._seq = 0
        payload = spb.Payload(timestamp=_ms(time.time()), seq=self._next_seq())
        ts = _ms(reading.wall)
        metric = payload.metrics.add(name=spb.BDSEQ, datatype=spb.INT64, timestamp=ts)
        metric.long_value = self.bdseq
        payload.metrics.add(name=spb.REBIRTH, datatype=spb.BOOLEAN, timestamp=ts, boolean_value=False)
        for i, tag in enumerate(self.tags):
            metric = payload.metrics.add(name=tag.name, alias=i + 1, datatype=self.kinds[i], timestamp=ts)
            spb.set_value(metric, self.kinds[i], float(reading.values[i]))
            if tag.unit:
                spb.add_units(metric, tag.unit)
            spb.add_quality(metric, int(reading.quality[i]))
        if not self._send(self.topics.nbirth, payload.SerializeToString()):
            self._birth_due = True
            return
        self.status.births += 1
        self._sent_values, self._sent_quality = reading.values.copy(), reading.quality.copy()
        while self._buffer and self.status.connected:  # what happened while the broker was away
            buffered = spb.Payload.FromString(self._buffer.popleft())
            buffered.seq = self._next_seq()
            for metric in buffered.metrics:
                metric.is_historical = True
            self._send(self.topics.ndata, buffered.SerializeToString())
        self.status.buffered = len(self._buffer)

    def _data(self, reading: Reading) -> None:
        if not self.status.births:  # nothing born yet: the first NBIRTH will carry every value
            return
        values, sent = reading.values, self._sent_values
        moved = np.abs(values - sent) > self.deadband
        moved |= np.isnan(values) != np.isnan(sent)
        moved |= reading.quality != self._sent_quality
        changed = np.flatnonzero(moved)
        if not len(changed):
            return
        sent[changed] = values[changed]
        self._sent_quality[changed] = reading.quality[changed]
        payload = spb.Payload(timestamp=_ms(time.time()))
        ts = _ms(reading.wall)
        kinds, quality = self.kinds, reading.quality
        add = payload.metrics.add
        for i in changed.tolist():
            metric = add(alias=i + 1, datatype=kinds[i], timestamp=ts)
            spb.set_value(metric, kinds[i], float(values[i]))
            spb.add_quality(metric, int(quality[i]))
        if self.status.connected and not self._birth_due:
            payload.seq = self._next_seq()
            if self._send(self.topics.ndata, payload.SerializeToString()):
                self.status.messages += 1
                self.status.metrics += len(changed)
                return
        self._keep(payload.SerializeToString())

    def _keep(self, data: bytes) -> None:
        limit = self.settings.buffer
        if limit <= 0:
            self.status.dropped += 1
            return
        if len(self._buffer) >= limit:
            self._buffer.popleft()
            self.status.dropped += 1
        self._buffer.append(data)
        self.status.buffered = len(self._buffer)

    def _send(self, topic: str, data: bytes) -> bool:
        info = self.client.publish(topic, data, qos=0)
        return info.rc == mqtt.MQTT_ERR_SUCCESS


def _ms(seconds: float) -> int:
    return int(seconds * 1000)
