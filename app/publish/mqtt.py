"""The MQTT publisher: the station as a Sparkplug B 3.0 edge node (paho-mqtt), each node of its
exchange a device of it (app/publish/devices.py).

One thread of its own takes the newest snapshot (`LatestReadings`: the scan never waits) and
publishes everything, so one `seq` counts every NBIRTH, DBIRTH, NDATA, DDATA and DDEATH of a
session; paho's network thread connects, reconnects with back-off (1 s doubling to 30 s) and hands
commands and STATE messages over. Per connection: NDEATH with the connection's bdSeq registered as
the last will, then the birth sequence: NBIRTH (the edge node's metrics with name, alias,
datatype, engUnit and Quality, the bdSeq and Node Control/Rebirth), then a DBIRTH for each device
whose node's link is up (its link metrics and the points its NREADs fill). Then by exception:
NDATA and DDATA with only the metrics whose value moved beyond the deadband of its tag type or
whose quality changed, by alias; a DDEATH when a node's link goes down (its points are then not
published until it is up again and born anew) and a DBIRTH when it comes back. While no session is
up the NDATA and DDATA are kept in a bounded buffer (oldest dropped first, counted) and sent after
the next births as historical metrics. NCMD Node Control/Rebirth republishes the whole sequence.

With `[mqtt] primary_host` the node waits for that Primary Host Application (spec 3.0, 5.x Edge
Node Session Establishment): it subscribes to the host's STATE (`spBv1.0/STATE/<id>`, retained
JSON) and births only while the host is online. When the host says it is offline (a STATE whose
timestamp is not older than the last one seen) the node publishes NDEATH, disconnects and connects
again at once, with the next bdSeq, and births when the host is online again. A STATE older than
the last one seen (an old session's death delivered late) is ignored.

A station of a hot-standby pair is one edge node with its partner (one group and edge node id,
one client id): only the primary connects and publishes (`leads()`), the standby keeps no session.
A station that stops leading publishes NDEATH and disconnects; one that starts leading connects
and births with the next bdSeq of the pair's: the primary's bdSeq is mirrored to the standby
(`follow`), so after a takeover a host application never takes the old primary's NDEATH (its will,
sent late) for the new session's.

Every other NCMD metric is a write of an edge node point, every DCMD metric a write of one of the
device's points, through the station's command layer (app/authority/) by the MQTT source (a
command names no user: it acts with `[mqtt] role`), checked for the metric's Sparkplug datatype
(a String for a Double metric is refused), the tag's physical range and `[mqtt] writable`. A
command has no answer: the journal is the answer, each refusal journaled by the layer, throttled
(one record per cause per minute with the count of the others).
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
from typing import TYPE_CHECKING, Any
from urllib.parse import urlsplit

import numpy as np
import paho.mqtt.client as mqtt

from app.authority import Action, Commands, Reason, Source, Ticket, Who
from app.publish import sparkplug as spb
from app.publish.devices import LINK, Device, Layout
from app.publish.feed import LatestReadings, Watch
from app.publish.points import PointReader, PointWriter, Reading, Writable
from app.scada.quality import QualityMap
from app.scada.readings import Readings
from app.scada.tag import Tag
from app.scada.words import Journal, phrase
from app.station.config import MqttSettings

if TYPE_CHECKING:
    from netplc.exchange import Exchange

logger = logging.getLogger(__name__)

BACKOFF = (1, 30)  # seconds: first reconnect delay, doubling up to the second
KEEPALIVE = 10  # s: the broker publishes NDEATH within 1.5 of these after the station vanishes
NODE = -1  # the edge node itself, where a device index is expected


@dataclass
class MqttStatus:
    connected: bool = False
    births: int = 0  # NBIRTH published
    device_births: int = 0  # DBIRTH published
    device_deaths: int = 0  # DDEATH published
    messages: int = 0  # NDATA and DDATA published
    metrics: int = 0  # metrics in them
    buffered: int = 0  # NDATA and DDATA waiting for a session
    dropped: int = 0  # NDATA and DDATA dropped from a full buffer (the oldest first) or of a dead device
    refused: int = 0  # NCMD and DCMD writes refused
    host_online: bool = False  # the primary host's last STATE (False too until one came)


class SparkplugPublisher:
    def __init__(self, settings: MqttSettings, station: str, *, tags: Sequence[Tag], commands: Commands,
                 watch: Watch, journal: Journal, bdseq_file: Path | None = None,
                 quality_map: QualityMap | None = None, exchange: Exchange | None = None,
                 leads: Callable[[], bool] = lambda: True) -> None:
        """`bdseq_file` keeps the bdSeq of the last connection across restarts (Sparkplug 3.0:
        each connection's bdSeq is the previous one's plus one), so a host application never
        takes the NDEATH of an old session for the new one's; None: it starts at 0. The exchange's
        nodes are the devices, their points those `quality_map` says their NREADs fill. `leads()`:
        does this station publish now (the primary of a pair, or a station alone)?"""
        self.settings = settings
        self.topics = spb.Topics(settings.group_id, settings.edge_node_id or station)
        self.tags = list(tags)
        self.layout = Layout(self.tags, quality_map, exchange.configs.values() if exchange else ())
        self.exchange = exchange
        self.reader = PointReader(self.tags)
        self.writer = PointWriter(commands, Writable(settings.writable), "[mqtt]")
        self.commands = commands
        self.watch = watch
        self.journal = journal
        self.status = MqttStatus()
        self.leads = leads
        self._online = False  # connecting or connected (a pair's standby: not)
        self.kinds = [spb.datatype(t) for t in self.tags]
        bands = dict(settings.deadband)
        self.deadband = np.array([bands.get(t.type.value, 0.0) for t in self.tags])
        url = urlsplit(settings.broker)
        self.host = url.hostname or "127.0.0.1"
        self.port = url.port or (8883 if url.scheme == "mqtts" else 1883)
        self.peer = f"{self.host}:{self.port}"
        self.who = Who("", Source.MQTT, f"NCMD {self.topics.node} via {self.peer}")
        self.primary = settings.primary_host
        self.feed = LatestReadings(self._wakeup)
        self._unwatch: Callable[[], None] | None = None
        self.bdseq_file = bdseq_file
        self.bdseq = (self._stored_bdseq() + 1) % 256  # the next connection's (stored once connected)
        # the publisher thread's: the session (births sent on this connection), seq, what was sent
        self._seq = 0
        self._session = False
        self._born: set[int] = set()  # devices born in this session
        self._readings: Readings | None = None
        self._latest: Reading | None = None
        self._sent_values = np.full(len(self.tags), np.nan)
        self._sent_quality = np.full(len(self.tags), -1, dtype=np.int8)
        self._sent_link: dict[int, tuple[Any, ...]] = {}
        self._buffer: deque[tuple[int, bytes]] = deque()  # (device index or NODE, NDATA/DDATA)
        # set by paho's thread, acted on by the publisher's
        self._birth_due = False
        self._host_online = False
        self._host_time: int | None = None  # the timestamp of the last STATE taken
        self._state_problem = ""  # the last bad STATE journaled, so that it is said once
        self._leave_due = False  # the primary host went offline: end the session
        self._leaving = False
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
        client.message_callback_add(self.topics.dcmd, self._on_dcmd)
        if self.primary:
            client.message_callback_add(spb.state_topic(self.primary), self._on_state)
        self.client = client
        self._set_will()

    # --- life cycle ----------------------------------------------------------------------------

    def start(self) -> None:
        """Never fails for a broker that is away: the client keeps trying, the station runs on.
        A pair's standby connects once it leads (the publisher's thread)."""
        if self.leads():
            self._go_online()
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
        if self._online:
            self._go_offline()

    def _go_online(self) -> None:
        self._online = True
        with self._lock:
            self._set_will()
        self.client.reconnect_delay_set(*BACKOFF)
        self.client.connect_async(self.host, self.port, KEEPALIVE)
        self.client.loop_start()

    def _go_offline(self) -> None:
        """NDEATH by the node itself (spec 3.0), then disconnect: a stop, or a pair's primary
        that became the standby."""
        self._online = False
        self._session = False
        self._leaving = True
        if self.status.connected:
            self._publish_death()
        self.client.disconnect()
        self.client.loop_stop()
        self._leaving = False

    def follow(self, bdseq: int) -> None:
        """A pair's standby: the primary's session has `bdseq`; this station's next is the one
        after it, kept as the last one made, so that it goes on from there after a restart too."""
        with self._lock:
            if self._online or not 0 <= bdseq <= 255:
                return
            self.bdseq = bdseq
            self._store_bdseq()
            self.bdseq = (bdseq + 1) % 256

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
            self.journal("mqtt bad bdseq", file=self.bdseq_file, error=e)
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
            self.journal("mqtt bdseq not kept", file=self.bdseq_file, error=e)

    def _death(self) -> bytes:
        payload = spb.Payload(timestamp=_ms(time.time()))
        metric = payload.metrics.add(name=spb.BDSEQ, datatype=spb.INT64)
        metric.long_value = self.bdseq
        return payload.SerializeToString()

    def _set_will(self) -> None:
        self.client.will_set(self.topics.ndeath, self._death(), qos=1, retain=False)

    def _publish_death(self) -> None:
        """NDEATH by the node itself, before a deliberate disconnect (which cancels the will)."""
        try:
            self.client.publish(self.topics.ndeath, self._death(), qos=1).wait_for_publish(2)
        except (RuntimeError, ValueError) as e:  # the connection went meanwhile: the will says it
            logger.warning("NDEATH not published: %s", e)

    def _on_connect(self, client: mqtt.Client, userdata: object, flags: Any, reason: Any, props: Any) -> None:
        if reason.is_failure:
            self.journal("mqtt refused", peer=self.peer, reason=reason)
            return
        topics = [(self.topics.ncmd, 1), (self.topics.dcmd, 1)]
        if self.primary:
            self._host_online = self.status.host_online = False  # until its STATE says so again
            topics.append((spb.state_topic(self.primary), 1))
        client.subscribe(topics)
        with self._lock:
            self._store_bdseq()  # registered with the broker: the one the next start goes on from
        self.status.connected = True
        self._birth_due = True
        self._wake.set()
        dropped = self.status.dropped
        self.journal("mqtt connected", peer=self.peer, node=self.topics.node, bdseq=self.bdseq,
                     lost=phrase("mqtt dropped", n=dropped) if dropped else "",
                     waiting=phrase("mqtt awaiting", host=self.primary) if self.primary else "")

    def _on_disconnect(self, client: mqtt.Client, userdata: object, flags: Any, reason: Any,
                       props: Any) -> None:
        was = self.status.connected
        self.status.connected = False
        self._session = False
        with self._lock:
            self.bdseq = (self.bdseq + 1) % 256  # the next session's NDEATH, before paho reconnects
            self._set_will()
        if was and not (self._stopping or self._leaving):
            self.journal("mqtt lost", peer=self.peer, reason=reason)

    def _on_state(self, client: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        """The primary host's STATE (spec 3.0): taken unless older than the last one seen."""
        try:
            state = spb.parse_state(message.payload)
        except ValueError as e:
            problem = f"{self.primary}: {e}"
            if problem != self._state_problem:  # a retained one comes again at every connection
                self._state_problem = problem
                self.journal("mqtt bad state", host=self.primary, error=e)
            return
        last = self._host_time
        if last is not None and state.timestamp < last:
            self.journal("mqtt old state", host=self.primary, stamp=state.timestamp, last=last)
            return
        self._host_time = state.timestamp
        was, self._host_online = self._host_online, state.online
        self.status.host_online = state.online
        if state.online and not was:
            self.journal("mqtt host online", host=self.primary)
        elif not state.online:
            self._leave_due = True
        self._wake.set()

    def _on_ncmd(self, client: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        self._command(message.payload, None, self.who)

    def _on_dcmd(self, client: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        name = message.topic.rsplit("/", 1)[1]
        who = Who("", Source.MQTT, f"DCMD {self.topics.node}/{name} via {self.peer}")
        device = self.layout.by_id.get(name)
        if device is None:
            self._refused(self.commands.refuse(who, Action.WRITE, name, Reason.UNKNOWN,
                                               self.commands.say("no device", node=self.topics.node)))
            return
        self._command(message.payload, device, who)

    def _command(self, data: bytes, device: Device | None, who: Who) -> None:
        """Each metric of an NCMD (`device` None) or a DCMD: a rebirth request (NCMD only), or a
        write of one of the node's or the device's points through the command layer."""
        try:
            payload = spb.Payload.FromString(data)
        except Exception as e:  # no log: bad input, answered by the journaled refusal below
            self._refused(self.commands.refuse(who, Action.WRITE, "", Reason.INVALID,
                                               self.commands.say("not sparkplug", error=type(e).__name__)))
            return
        layout = self.layout
        for metric in payload.metrics:
            name, alias = metric.name, int(metric.alias)
            if device is None and name == spb.REBIRTH:
                if spb.get_value(metric):
                    self._birth_due = True
                    self._wake.set()
                    self.journal("mqtt rebirth", peer=self.peer)
                continue
            i = layout.point(device, name, alias)
            label = name or (self.tags[alias - 1].name if 0 < alias <= len(self.tags) else f"alias {alias}")
            if i is not None:
                kind = self.kinds[i]
                ticket = self.writer.write(who, self.tags[i], spb.get_value(metric, kind),
                                           spb.mismatch(metric, kind))
            elif device is not None and (link := layout.link_name(device, name, alias)):
                ticket = self.commands.refuse(who, Action.WRITE, link, Reason.NOT_WRITABLE,
                                              self.commands.say("link metric"))
            else:
                of = f"device {device.id}" if device is not None else self.topics.node
                ticket = self.commands.refuse(who, Action.WRITE, label, Reason.UNKNOWN,
                                              self.commands.say("no metric", node=of))
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
            if not self._lead_or_follow():
                continue
            if item is not None:
                self._readings, self._latest = item, self.reader.read(item)
            reading = self._latest
            if reading is None:
                continue
            if self._leave_due:
                self._leave()
            elif self._birth_due and self.status.connected and (self._host_online or not self.primary):
                self._birth(reading)
            elif item is not None:
                self._data(reading)
            last = time.monotonic()

    def _lead_or_follow(self) -> bool:
        """Connect when this station has come to lead its pair, end the session when it has come to
        follow; True while it publishes."""
        leads = self.leads()
        if leads and not self._online:
            self.journal("mqtt leads", node=self.topics.node, bdseq=self.bdseq)
            self._buffer.clear()  # what a standby saw was the primary's to publish
            self._go_online()
        elif not leads and self._online:
            self.journal("mqtt follows", bdseq=self.bdseq)
            self._go_offline()
        return leads

    def _leave(self) -> None:
        """The primary host is offline: NDEATH, disconnect, and connect again at once (the next
        bdSeq), to birth when the host is back. Nothing to end while no session is up."""
        self._leave_due = False
        if not (self._session and self.status.connected):  # paho reconnects: STATE is awaited again
            return
        self._session = False
        self._leaving = True
        self.journal("mqtt host offline", host=self.primary)
        self._publish_death()
        self.client.disconnect()
        self.client.loop_stop()  # its thread ends with a deliberate disconnect: a new one connects
        self._leaving = False
        if not self._stopping:
            self.client.reconnect_delay_set(*BACKOFF)  # a deliberate reconnect: its back-off afresh
            self.client.connect_async(self.host, self.port, KEEPALIVE)
            self.client.loop_start()

    def _next_seq(self) -> int:
        seq, self._seq = self._seq, (self._seq + 1) % 256
        return seq

    def _alive(self) -> list[bool]:
        """Each device: is its node's link up as of the newest scan?"""
        links = self._readings.links.links if self._readings is not None else None
        return [links is None or links.get(d.node, False) for d in self.layout.devices]

    def _add_points(self, payload: Any, points: Sequence[int], reading: Reading, birth: bool) -> None:
        ts, values, quality, kinds = _ms(reading.wall), reading.values, reading.quality, self.kinds
        add = payload.metrics.add
        for i in points:
            if birth:
                metric = add(name=self.tags[i].name, alias=i + 1, datatype=kinds[i], timestamp=ts)
            else:
                metric = add(alias=i + 1, datatype=kinds[i], timestamp=ts)
            spb.set_reading(metric, kinds[i], float(values[i]), int(quality[i]))
            if birth and self.tags[i].unit:
                spb.add_units(metric, self.tags[i].unit)

    def _birth(self, reading: Reading) -> None:
        """NBIRTH, a DBIRTH for each device that lives, then what was buffered meanwhile."""
        self._birth_due = False
        self._seq = 0
        self._born.clear()
        payload = spb.Payload(timestamp=_ms(time.time()), seq=self._next_seq())
        ts = _ms(reading.wall)
        metric = payload.metrics.add(name=spb.BDSEQ, datatype=spb.INT64, timestamp=ts)
        metric.long_value = self.bdseq
        payload.metrics.add(name=spb.REBIRTH, datatype=spb.BOOLEAN, timestamp=ts, boolean_value=False)
        points = self.layout.node_points
        self._add_points(payload, points.tolist(), reading, birth=True)
        if not self._send(self.topics.nbirth, payload):
            self._birth_due = True
            return
        self.status.births += 1
        self._sent(points, reading)
        for device, alive in zip(self.layout.devices, self._alive(), strict=True):
            if alive:
                self._device_birth(device, reading)
        self._session = True
        while self._buffer and self.status.connected:  # what happened while no session was up
            k, data = self._buffer.popleft()
            if k != NODE and k not in self._born:  # a device that died meanwhile: no data without a birth
                self.status.dropped += 1
                continue
            buffered = spb.Payload.FromString(data)
            for metric in buffered.metrics:
                metric.is_historical = True
            self._send(self._data_topic(k), buffered)
        self.status.buffered = len(self._buffer)

    def _device_birth(self, device: Device, reading: Reading) -> None:
        payload = spb.Payload(timestamp=_ms(time.time()))
        ts = _ms(reading.wall)
        link = device.link(self._stats(device))
        for k, ((name, kind), value) in enumerate(zip(LINK, link, strict=True)):
            metric = payload.metrics.add(name=name, alias=device.first_alias + k, datatype=kind, timestamp=ts)
            _set_link(metric, kind, value)
        points = device.points
        self._add_points(payload, points.tolist(), reading, birth=True)
        if self._send(self.topics.of("DBIRTH", device.id), payload):
            self.status.device_births += 1
            self._born.add(device.index)
            self._sent_link[device.index] = link
            self._sent(points, reading)

    def _sent(self, points: np.ndarray, reading: Reading) -> None:
        """What a birth told of `points`: what their changes are reckoned from."""
        self._sent_values[points] = reading.values[points]
        self._sent_quality[points] = reading.quality[points]

    def _device_death(self, device: Device) -> None:
        self._born.discard(device.index)
        if self._send(self.topics.of("DDEATH", device.id), spb.Payload(timestamp=_ms(time.time()))):
            self.status.device_deaths += 1

    def _stats(self, device: Device) -> Any:
        return self.exchange.stats.get(device.node) if self.exchange is not None else None

    def _data_topic(self, k: int) -> str:
        return self.topics.ndata if k == NODE else self.topics.of("DDATA", self.layout.devices[k].id)

    def _data(self, reading: Reading) -> None:
        """Births and deaths of devices whose link changed, then NDATA and DDATA of what changed:
        sent within a session, kept for the next one otherwise."""
        if not self.status.births:  # nothing born yet: the first births will carry every value
            return
        session = self._session and self.status.connected and not self._birth_due
        alive = self._alive()
        if session:
            for device, up in zip(self.layout.devices, alive, strict=True):
                if device.index in self._born and not up:
                    self._device_death(device)
                elif device.index not in self._born and up:
                    self._device_birth(device, reading)
            live = self._born
        else:
            live = {d.index for d, up in zip(self.layout.devices, alive, strict=True) if up}
        values, sent = reading.values, self._sent_values
        moved = np.abs(values - sent) > self.deadband
        moved |= np.isnan(values) != np.isnan(sent)
        moved |= reading.quality != self._sent_quality
        owner = self.layout.owner
        moved &= (owner == NODE) | np.isin(owner, list(live))  # a dead device publishes nothing
        changed = np.flatnonzero(moved)
        sent[changed] = values[changed]
        self._sent_quality[changed] = reading.quality[changed]
        ts = _ms(reading.wall)
        payloads: dict[int, Any] = {}
        for k in sorted(live):  # link metrics that changed (Up changes by birth and death)
            device = self.layout.devices[k]
            link = device.link(self._stats(device))
            before = self._sent_link.get(k)
            if before is None or link == before:
                continue
            self._sent_link[k] = link
            payload = payloads[k] = spb.Payload(timestamp=_ms(time.time()))
            for j, ((_, kind), value) in enumerate(zip(LINK, link, strict=True)):
                if value != before[j]:
                    _set_link(payload.metrics.add(alias=device.first_alias + j, datatype=kind, timestamp=ts),
                              kind, value)
        if len(changed):
            for k in np.unique(owner[changed]).tolist():
                if k not in payloads:
                    payloads[k] = spb.Payload(timestamp=_ms(time.time()))
                self._add_points(payloads[k], changed[owner[changed] == k].tolist(), reading, birth=False)
        for k, payload in payloads.items():
            if session and self._send(self._data_topic(k), payload):
                self.status.messages += 1
                self.status.metrics += len(payload.metrics)
            else:
                payload.ClearField("seq")
                self._keep(k, payload.SerializeToString())

    def _keep(self, k: int, data: bytes) -> None:
        limit = self.settings.buffer
        if limit <= 0:
            self.status.dropped += 1
            return
        if len(self._buffer) >= limit:
            self._buffer.popleft()
            self.status.dropped += 1
        self._buffer.append((k, data))
        self.status.buffered = len(self._buffer)

    def _send(self, topic: str, payload: Any) -> bool:
        """Every message but the NDEATH takes the session's next seq (spec 3.0: one more than the
        edge node's previous message, NBIRTH's first, 255 wrapping to 0)."""
        if not payload.HasField("seq"):
            payload.seq = self._next_seq()
        info = self.client.publish(topic, payload.SerializeToString(), qos=0)
        if info.rc != mqtt.MQTT_ERR_SUCCESS:
            self._seq = (self._seq - 1) % 256  # not sent: the next message takes its number
            return False
        return True


def _set_link(metric: Any, kind: int, value: Any) -> None:
    if kind == spb.STRING:
        metric.string_value = value
    else:
        spb.set_value(metric, kind, float(value))


def _ms(seconds: float) -> int:
    return int(seconds * 1000)
