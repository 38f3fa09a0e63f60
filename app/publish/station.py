"""The publishers of a running station, started and stopped by the runtime (with or without a
window). They read the station's `Readings` (`Runtime.watch`) and act through its command layer
(`Runtime.commands`); a publisher that cannot start is a problem the operator sees (`Runtime.problem`)
and the station runs on."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

from app.authority import Source
from app.publish.points import published_tags
from app.scada.series import nstore_keys
from app.scada.words import phrase

if TYPE_CHECKING:
    from app.station.runtime import Runtime

BDSEQ_FILE = "sparkplug_bdseq.txt"  # in the station folder: the last MQTT connection's bdSeq


class Publisher(Protocol):
    def stop(self) -> None: ...


def start_publishers(runtime: Runtime) -> list[Publisher]:
    st = runtime.station
    if not (st.opcua.enabled or st.mqtt.enabled):
        return []
    tags = published_tags(runtime.tags.tags, runtime.symbols)
    started: list[Publisher] = []
    if st.opcua.enabled:
        from app.publish.files import StationFiles
        from app.publish.history import Archived
        from app.publish.opcua import OpcUaServer  # asyncua loads only for a station that serves OPC UA

        # the alarms' identities and states as the station starts; their transitions follow as records
        alarms = runtime.alarm_definitions()
        # the history is the local archive's (where `Archive` names a plant archive the station still
        # writes its own first: that is the one read here)
        archived = Archived(st.Archive, nstore_keys(runtime.program))
        server = OpcUaServer(settings=st.opcua, station=st.name, folder=st.folder, tags=tags,
                             commands=runtime.commands, watch=runtime.watch, engine=runtime.engine,
                             exchange=runtime.exchange, alarms=alarms, journal=runtime.say,
                             step_lock=lambda: runtime.scan_thread.lock if runtime.scan_thread else None,
                             archived=archived, language=st.Language,
                             pair_letter=st.redundancy.letter if st.redundancy is not None else "",
                             service_level=runtime.service_level, files=StationFiles(st))
        try:
            server.start()
        except (OSError, RuntimeError) as e:
            runtime.problem("opcua not started", path=st.path, error=e)
        else:
            runtime.subscribe(server.on_record)
            runtime.alarms.adopted.append(server.on_adopted)
            started.append(_Unsubscribing(server, runtime))
            runtime.say("opcua started", endpoint=st.opcua.endpoint, tags=len(tags),
                        security=phrase("opcua secure" if server.secure else "opcua open"))
    if st.mqtt.enabled:
        from app.publish.mqtt import SparkplugPublisher

        runtime.commands.grant(Source.MQTT, st.mqtt.role)
        publisher = SparkplugPublisher(st.mqtt, st.name, tags=tags, commands=runtime.commands,
                                       watch=runtime.watch, journal=runtime.say,
                                       bdseq_file=st.folder / BDSEQ_FILE, exchange=runtime.exchange,
                                       quality_map=runtime.alarms.quality_map, leads=runtime.leads)
        publisher.start()
        started.append(publisher)
        devices = ", ".join(d.id for d in publisher.layout.devices) or phrase("no devices")
        runtime.say("mqtt primary" if st.mqtt.primary_host else "mqtt started", broker=st.mqtt.broker,
                    node=publisher.topics.node, tags=len(tags), devices=devices, host=st.mqtt.primary_host)
    return started


class _Unsubscribing:
    """The OPC UA server with its record observer (alarm events) and its observer of adopted alarm
    states, removed when it stops."""

    def __init__(self, server: Any, runtime: Runtime) -> None:
        self.server, self.runtime = server, runtime
        self.seats = server.seats  # the sessions logged in (seats.py): the station's status lists them

    def stop(self) -> None:
        self.runtime.unsubscribe(self.server.on_record)
        alarms = self.runtime.alarms
        if alarms is not None and self.server.on_adopted in alarms.adopted:
            alarms.adopted.remove(self.server.on_adopted)
        self.server.stop()
