"""The publishers of a running station, started and stopped by the runtime (with or without a
window). A publisher that cannot start is a problem the operator sees; the station runs on."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from app.authority.users import Users
from app.publish.points import PasswordCheck, PointReader, Writable, Writer, published_tags, runtime_quality

BDSEQ_FILE = "sparkplug_bdseq.txt"  # in the station folder: the last MQTT connection's bdSeq


class Publisher(Protocol):
    def stop(self) -> None: ...


def password_check(station: Any) -> PasswordCheck | None:
    """The one place that checks a client's user name and password against the station's users
    (app/authority/users.py, read at each login, so a user added or removed counts at once); None while the
    station has no users (clients are then anonymous)."""
    if not Users(station.folder).users:
        return None
    return lambda name, password: Users(station.folder).verify(name, password) is not None


def role_of(station: Any) -> Callable[[str], str | None] | None:
    """A user's role, read at each client write (a role changed or a user removed counts at
    once); None while the station has no users (then the `writable` tags are all that limits)."""
    if not Users(station.folder).users:
        return None

    def role(name: str) -> str | None:
        user = Users(station.folder).get(name)
        return None if user is None else user.role

    return role


def start_publishers(runtime: Any) -> list[Publisher]:
    st = runtime.station
    if not (st.opcua.enabled or st.mqtt.enabled):
        return []
    table_tags = runtime.alarms.table.tags if runtime.alarms is not None else []
    tags = published_tags(table_tags, runtime.symbols)
    reader = PointReader(tags, runtime_quality(runtime))
    started: list[Publisher] = []
    if st.opcua.enabled:
        from app.publish.opcua import OpcUaServer  # asyncua loads only for a station that serves OPC UA

        writer = Writer(runtime.engine, tags, Writable(st.opcua.writable), runtime, runtime.wallclock)
        alarms = runtime.alarms.system.alarms if runtime.alarms is not None else []
        server = OpcUaServer(endpoint=st.opcua.endpoint, station=st.name, folder=st.folder, tags=tags,
                             reader=reader, writer=writer, engine=runtime.engine, exchange=runtime.exchange,
                             alarms=alarms, password_check=password_check(st), role_of=role_of(st))
        try:
            server.start()
        except (OSError, RuntimeError) as e:
            runtime.problem(f"OPC UA server not started: {st.path}: opcua.endpoint: {e}")
        else:
            runtime.subscribe(server.on_record)
            started.append(_Unsubscribing(server, runtime))
            security = "Basic256Sha256 Sign&Encrypt" if server.secure else "no security, loopback"
            runtime.system(f"OPC UA server at {st.opcua.endpoint} ({security}), {len(tags)} tags")
    if st.mqtt.enabled:
        from app.publish.mqtt import SparkplugPublisher

        writer = Writer(runtime.engine, tags, Writable(st.mqtt.writable), runtime, runtime.wallclock)
        publisher = SparkplugPublisher(st.mqtt, st.name, tags=tags, reader=reader, writer=writer,
                                       engine=runtime.engine, journal=runtime.system,
                                       bdseq_file=st.folder / BDSEQ_FILE)
        publisher.start()
        started.append(publisher)
        runtime.system(f"MQTT Sparkplug B publisher to {st.mqtt.broker} as {publisher.topics.node}, "
                       f"{len(tags)} metrics")
    return started


class _Unsubscribing:
    """The OPC UA server with its record observer (alarm events), removed when it stops."""

    def __init__(self, server: Any, runtime: Any) -> None:
        self.server, self.runtime = server, runtime

    def stop(self) -> None:
        self.runtime.unsubscribe(self.server.on_record)
        self.server.stop()
