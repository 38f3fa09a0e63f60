"""The OPC UA server: the station's tags, nodes, NetPlc state and alarms for any OPC UA client.

asyncua runs on a thread and event loop of its own. Values come from the engine's snapshots
through `LatestSnapshot` (at most one update per tick, none while the loop lags); only the
variables whose value or quality changed are written, each with the snapshot's wall time as
source timestamp and a StatusCode from the tag's quality. Client writes to tag variables are
taken before asyncua's own write service: a writable tag goes into the engine's queue (journaled
with the OPC UA user and peer), any other gets Bad_NotWritable (journaled as refused).

Alarms: each alarm is a String variable holding its ISA-18.2 state word, and each transition
fires an event (BaseEventType: SourceName the alarm id, Message its text, Severity from its
priority) on the station object. asyncua's Alarms & Conditions have no acknowledge/shelve state
machine behind them, so acknowledging stays with the station's operators (docs/architecture.md
section 1: every acknowledgement journaled with its user).
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import numpy as np
from asyncua import Server, ua
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.permission_rules import User, UserRole
from cryptography.x509.oid import ExtendedKeyUsageOID

from app.authority.users import rank
from app.publish.feed import LatestSnapshot
from app.publish.points import PasswordCheck, PointReader, Writer, WriteRefused
from netplc.records import Record
from netplc.tags.alarms import PRIORITIES, Alarm, State
from netplc.tags.quality import Quality
from netplc.tags.tag import Tag, TagType

CERT_FILE, KEY_FILE = "opcua-cert.der", "opcua-key.pem"  # generated in the station folder
START_TIMEOUT = 60.0
UNECE_UNITS = "http://www.opcfoundation.org/UA/units/un/cefact"
STATUS = {Quality.GOOD: ua.StatusCodes.Good, Quality.INITIAL: ua.StatusCodes.BadWaitingForInitialData,
          Quality.STALE: ua.StatusCodes.UncertainLastUsableValue,
          Quality.COMM_FAIL: ua.StatusCodes.BadCommunicationError,
          Quality.NOT_RUNNING: ua.StatusCodes.BadOutOfService,
          Quality.FORCED: ua.StatusCodes.GoodLocalOverride}
CODES = [ua.StatusCode(STATUS[q]) for q in Quality]  # by quality code
YIELD_EVERY = 500  # variable writes between two turns of the event loop
SEVERITY = {1: 900, 2: 700, 3: 500, 4: 300}  # alarm priority -> OPC UA severity 1-1000


def is_loopback(endpoint: str) -> bool:
    host = urlsplit(endpoint).hostname or ""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def variant_type(tag: Tag) -> ua.VariantType:
    if tag.scaling is not None:
        return ua.VariantType.Double
    return {TagType.BIT: ua.VariantType.Boolean, TagType.WORD: ua.VariantType.UInt16,
            TagType.INT16: ua.VariantType.Int16, TagType.BCD: ua.VariantType.UInt16,
            TagType.INT32: ua.VariantType.Int32, TagType.FLOAT32: ua.VariantType.Float}[tag.type]


def _python(kind: ua.VariantType) -> Callable[[float], Any]:
    if kind is ua.VariantType.Boolean:
        return bool
    if kind in (ua.VariantType.Double, ua.VariantType.Float):
        return float
    return int


async def station_certificate(folder: Path, uri: str, host: str, station: str) -> tuple[Path, Path]:
    """The station's certificate and key in its folder: made on first start (and again when
    missing or expired), kept afterwards so clients that trusted it once go on trusting it."""
    key, cert = folder / KEY_FILE, folder / CERT_FILE
    await setup_self_signed_certificate(key, cert, uri, host, [ExtendedKeyUsageOID.SERVER_AUTH],
                                        {"commonName": f"NetPlc Station {station}"})
    return cert, key


@dataclass
class OpcUaStatus:
    updates: int = 0  # variable values written into the address space
    skipped: int = 0  # snapshots not published because the server lagged
    error: str = ""


class _Users:
    """asyncua's user manager: anonymous users where no users exist or on a loopback endpoint
    (local clients, as security None is for them only), else name and password; a name given is
    always checked."""

    def __init__(self, check: PasswordCheck | None, anonymous: bool) -> None:
        self.check = check
        self.anonymous = anonymous

    def get_user(self, iserver: object, username: str | None = None, password: str | None = None,
                 certificate: object = None) -> User | None:
        if self.check is None or (self.anonymous and not username):
            return User(role=UserRole.User, name=username or None)  # no name: anonymous
        if username and password is not None and self.check(username, password):
            return User(role=UserRole.User, name=username)
        return None


class OpcUaServer:
    """`start()` (OSError or RuntimeError naming the problem), then `stop()`."""

    def __init__(self, *, endpoint: str, station: str, folder: Path, tags: Sequence[Tag], reader: PointReader,
                 writer: Writer, engine: Any, exchange: Any, alarms: Sequence[Alarm] = (),
                 password_check: PasswordCheck | None = None,
                 role_of: Callable[[str], str | None] | None = None) -> None:
        """`role_of` gives a user's role at each write (so a changed role counts at once); None
        while the station has no users, when any client may write what `writable` names."""
        self.endpoint = endpoint
        self.station = station
        self.folder = folder
        self.tags = list(tags)
        self.reader = reader
        self.writer = writer
        self.engine = engine
        self.exchange = exchange
        self.alarms = list(alarms)
        self.password_check = password_check
        self.role_of = role_of
        self.status = OpcUaStatus()
        self.secure = not is_loopback(endpoint)
        self.feed = LatestSnapshot(reader, self._wake)
        self._loop: asyncio.AbstractEventLoop | None = None
        self._ready = threading.Event()
        self._thread: threading.Thread | None = None
        self._stop: asyncio.Event | None = None
        self._tick: asyncio.Event | None = None

    # --- life cycle (any thread) ---------------------------------------------------------------

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="opcua", daemon=True)
        self._thread.start()
        if not self._ready.wait(START_TIMEOUT):
            raise RuntimeError(f"OPC UA server at {self.endpoint} did not start within {START_TIMEOUT:g} s")
        if self.status.error:
            self._thread.join(5)
            raise RuntimeError(self.status.error)
        self.engine.subscribe(self.feed)

    def stop(self) -> None:
        self.engine.unsubscribe(self.feed)
        loop, stop = self._loop, self._stop
        if loop is not None and stop is not None and not loop.is_closed():
            loop.call_soon_threadsafe(stop.set)
        if self._thread is not None:
            self._thread.join(10)
            self._thread = None

    def _wake(self) -> None:
        loop, tick = self._loop, self._tick
        if loop is not None and tick is not None:
            with contextlib.suppress(RuntimeError):  # the loop closed while the scan ran
                loop.call_soon_threadsafe(tick.set)

    def on_record(self, record: Record) -> None:
        """The runtime's record observer: alarm transitions become variable states and events."""
        loop = self._loop
        if record.kind == "alarm" and loop is not None and self._ready.is_set():
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(lambda: loop.create_task(self._alarm_event(record)))

    # --- the server's own loop -----------------------------------------------------------------

    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except Exception as e:  # reported by start(), or to the runtime through status
            self.status.error = f"OPC UA server at {self.endpoint}: {type(e).__name__}: {e}"
            self._ready.set()

    async def _main(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._stop, self._tick = asyncio.Event(), asyncio.Event()
        server = Server(user_manager=_Users(self.password_check, anonymous=not self.secure))
        await server.init()
        server.set_endpoint(self.endpoint)
        server.set_server_name(f"NetPlc Station {self.station}")
        uri = f"urn:netplc:station:{self.station}"
        await server.set_application_uri(uri)
        if self.secure:
            await self._secure(server, uri)
        else:
            server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        self.server = server
        await self._build(server, uri)
        self._intercept_writes(server)
        await server.start()
        try:
            self._ready.set()
            while not self._stop.is_set():
                waiter = asyncio.ensure_future(self._tick.wait())
                stopper = asyncio.ensure_future(self._stop.wait())
                await asyncio.wait((waiter, stopper), return_when=asyncio.FIRST_COMPLETED)
                waiter.cancel()
                stopper.cancel()
                self._tick.clear()
                item = self.feed.take()
                if item is not None:
                    await self._publish(*item)
                self.status.skipped = self.feed.skipped
        finally:
            await server.stop()

    async def _secure(self, server: Server, uri: str) -> None:
        """Basic256Sha256 Sign&Encrypt with the station's own certificate, made on first start."""
        host = urlsplit(self.endpoint).hostname or "localhost"
        cert, key = await station_certificate(self.folder, uri, host, self.station)
        await server.load_certificate(str(cert))
        await server.load_private_key(str(key))
        server.set_security_policy([ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt])
        server.set_security_IDs(["Anonymous" if self.password_check is None else "Username"])

    async def _build(self, server: Server, uri: str) -> None:
        idx = await server.register_namespace(uri)
        self.idx = idx
        station = await server.nodes.objects.add_object(ua.NodeId(self.station, idx), f"{idx}:{self.station}")
        self.station_node = station
        folder = await station.add_folder(ua.NodeId("Tags", idx), f"{idx}:Tags")
        self.kinds = [variant_type(t) for t in self.tags]
        self.convert = [_python(k) for k in self.kinds]
        self.nodeids: list[ua.NodeId] = []
        self.by_nodeid: dict[ua.NodeId, str] = {}
        # asyncua checks each new child against all of its parent's references (quadratic: a
        # minute for 10,000 tags); tag names are unique, so each tag is added to a folder whose
        # reference list is set aside meanwhile and put back with the new reference appended.
        folder_data = server.iserver.aspace.get(folder.nodeid)
        references = folder_data.references
        for i, (tag, kind) in enumerate(zip(self.tags, self.kinds)):
            nodeid = ua.NodeId(f"Tags.{tag.name}", idx)
            initial = ua.DataValue(ua.Variant(self.convert[i](0), kind),
                                   StatusCode=ua.StatusCode(ua.StatusCodes.BadWaitingForInitialData))
            folder_data.references = []
            try:
                var = await folder.add_variable(nodeid, f"{idx}:{tag.name}", initial, kind)
            finally:
                references.extend(folder_data.references)
                folder_data.references = references
            if tag.description:
                await var.write_attribute(ua.AttributeIds.Description,
                                          ua.DataValue(ua.Variant(ua.LocalizedText(tag.description))))
            if self.writer.can_write(tag.name):
                await var.set_writable()
            if tag.type is not TagType.BIT:
                unit = ua.LocalizedText(tag.unit)
                eu = ua.EUInformation(NamespaceUri=UNECE_UNITS, UnitId=-1, DisplayName=unit, Description=unit)
                await var.add_property(ua.NodeId(f"Tags.{tag.name}.EngineeringUnits", idx),
                                       ua.QualifiedName("EngineeringUnits", 0), eu,
                                       datatype=ua.NodeId(ua.ObjectIds.EUInformation))
                lo, hi = tag.phy_limits
                await var.add_property(ua.NodeId(f"Tags.{tag.name}.EURange", idx),
                                       ua.QualifiedName("EURange", 0), ua.Range(Low=lo, High=hi),
                                       datatype=ua.NodeId(ua.ObjectIds.Range))
            self.nodeids.append(nodeid)
            self.by_nodeid[nodeid] = tag.name
        self._last_values = np.full(len(self.tags), np.nan)
        self._last_quality = np.full(len(self.tags), -1, dtype=np.int8)
        plc = await station.add_object(ua.NodeId("NetPlc", idx), f"{idx}:NetPlc")
        self.plc_state = await plc.add_variable(ua.NodeId("NetPlc.State", idx), f"{idx}:State", "")
        self.plc_scan_ms = await plc.add_variable(ua.NodeId("NetPlc.ScanTimeMs", idx), f"{idx}:ScanTimeMs",
                                                  0.0)
        self.plc_tick = await plc.add_variable(ua.NodeId("NetPlc.Tick", idx), f"{idx}:Tick",
                                               ua.Variant(0, ua.VariantType.UInt64))
        await plc.add_variable(ua.NodeId("NetPlc.NetSyncTimeMs", idx), f"{idx}:NetSyncTimeMs",
                               ua.Variant(round(self.engine.tick * 1000), ua.VariantType.UInt32))
        nodes = await station.add_folder(ua.NodeId("Nodes", idx), f"{idx}:Nodes")
        self.node_vars: dict[int, dict[str, Any]] = {}
        for n, stats in (self.exchange.stats.items() if self.exchange is not None else ()):
            obj = await nodes.add_object(ua.NodeId(f"Nodes.{n}", idx), f"{idx}:{n}")
            await obj.add_variable(ua.NodeId(f"Nodes.{n}.Endpoint", idx), f"{idx}:Endpoint", stats.endpoint)
            self.node_vars[n] = {
                key: await obj.add_variable(ua.NodeId(f"Nodes.{n}.{key}", idx), f"{idx}:{key}", value)
                for key, value in (("Up", False), ("Reads", ua.Variant(0, ua.VariantType.UInt64)),
                                   ("Writes", ua.Variant(0, ua.VariantType.UInt64)),
                                   ("Errors", ua.Variant(0, ua.VariantType.UInt64)), ("LastError", ""))}
        alarms = await station.add_folder(ua.NodeId("Alarms", idx), f"{idx}:Alarms")
        self.alarm_vars = {}
        for alarm in self.alarms:
            var = await alarms.add_variable(ua.NodeId(f"Alarms.{alarm.id}", idx), f"{idx}:{alarm.id}",
                                            alarm.state.word)
            await var.add_property(idx, f"{idx}:Priority", PRIORITIES.get(alarm.defn.priority, ""))
            await var.add_property(idx, f"{idx}:Text", alarm.defn.text)
            self.alarm_vars[alarm.id] = var
        self.events = await server.get_event_generator(ua.ObjectIds.BaseEventType, station)

    async def _publish(self, snapshot: Any, quality: np.ndarray) -> None:
        reading = self.reader.read(snapshot, quality)
        values, last = reading.values, self._last_values
        changed = np.flatnonzero(~((values == last) | (np.isnan(values) & np.isnan(last)))
                                 | (quality != self._last_quality))
        self._last_values, self._last_quality = values, quality.copy()
        when = datetime.fromtimestamp(reading.wall, UTC)
        write = self.server.iserver.aspace.write_attribute_value
        value_attr = ua.AttributeIds.Value
        for n, i in enumerate(changed.tolist()):
            if n % YIELD_EVERY == YIELD_EVERY - 1:
                await asyncio.sleep(0)  # let the server answer its clients' requests meanwhile
            v = values[i]
            code = CODES[quality[i]]
            if math.isnan(v):  # a BCD word that is not BCD
                dv = ua.DataValue(StatusCode=ua.StatusCode(ua.StatusCodes.BadOutOfRange),
                                  SourceTimestamp=when)
            else:
                dv = ua.DataValue(ua.Variant(self.convert[i](v), self.kinds[i]), StatusCode=code,
                                  SourceTimestamp=when)
            await write(self.nodeids[i], value_attr, dv)
        self.status.updates += len(changed)
        await self.plc_state.write_value(reading.state)
        await self.plc_scan_ms.write_value(float(self.engine.stats.last_ms))
        await self.plc_tick.write_value(ua.Variant(reading.scan, ua.VariantType.UInt64))
        for n, stats in (self.exchange.stats.items() if self.exchange is not None else ()):
            vars_ = self.node_vars.get(n)
            if vars_ is None:
                continue
            for key, value in (("Up", stats.up), ("Reads", ua.Variant(stats.reads, ua.VariantType.UInt64)),
                               ("Writes", ua.Variant(stats.writes, ua.VariantType.UInt64)),
                               ("Errors", ua.Variant(stats.errors, ua.VariantType.UInt64)),
                               ("LastError", stats.last_error)):
                await vars_[key].write_value(value)

    async def _alarm_event(self, record: Record) -> None:
        var = self.alarm_vars.get(record.source)
        if var is None:
            return
        state = State(record.type or 0)
        await var.write_value(state.word)
        self.events.event.SourceName = record.source
        self.events.event.Severity = SEVERITY.get(record.grp or 3, 500)
        await self.events.trigger(message=f"{record.source}: {State(record.number or 0).word} -> {state.word}"
                                          + (f": {record.text}" if record.text else ""))

    # --- client writes -------------------------------------------------------------------------

    def _intercept_writes(self, server: Server) -> None:
        """Every session's Write service passes through `_write` first (the session knows the user
        and the peer; asyncua's attribute service knows neither)."""
        iserver = server.iserver
        create = iserver.create_session

        def create_session(name: str, user: User | None = None, external: bool = False) -> Any:
            session = create(name, user=user or User(role=UserRole.Anonymous), external=external)
            service = session.write

            async def write(params: ua.WriteParameters) -> list[ua.StatusCode]:
                return await self._write(session, params, service)

            session.write = write
            return session

        iserver.create_session = create_session

    async def _write(self, session: Any, params: ua.WriteParameters, service: Any) -> list[ua.StatusCode]:
        results: list[ua.StatusCode | None] = []
        others = []
        named = session.user.name if session.user is not None and session.user.name else None
        peer = session.name
        peer_text = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) and len(peer) >= 2 else str(peer)
        refusal = self._refusal(named)
        for wv in params.NodesToWrite:
            name = self.by_nodeid.get(wv.NodeId)
            if name is None:
                others.append(wv)
                results.append(None)
                continue
            results.append(self._write_tag(name, wv, f"opcua:{named or 'anonymous'}@{peer_text}", refusal))
        if others:
            done = iter(await service(ua.WriteParameters(NodesToWrite=others)))
            results = [r if r is not None else next(done) for r in results]
        return [r for r in results if r is not None]

    def _refusal(self, user: str | None) -> str | None:
        """Why `user` (None: anonymous) may not write at all, as in the workstation: the operator
        role or above, where the station has users."""
        if self.role_of is None:
            return None
        if user is None:
            return "anonymous clients may only read where the station has users"
        role = self.role_of(user)
        if role is None or rank(role) < rank("operator"):
            return f"{user} is {role or 'no longer a user'}: writing needs the operator role"
        return None

    def _write_tag(self, name: str, wv: ua.WriteValue, user: str, refusal: str | None) -> ua.StatusCode:
        if wv.AttributeId != ua.AttributeIds.Value:
            return ua.StatusCode(ua.StatusCodes.BadNotWritable)
        value = wv.Value.Value.Value if wv.Value is not None and wv.Value.Value is not None else None
        try:
            if refusal is not None:
                self.writer.refuse(name, value, user, refusal)  # journaled, then refused
            self.writer.write(name, value, user)
        except WriteRefused as e:
            why = str(e)
            if refusal is not None:
                return ua.StatusCode(ua.StatusCodes.BadUserAccessDenied)
            if why.startswith("write queue full"):
                return ua.StatusCode(ua.StatusCodes.BadTooManyOperations)
            if why == "not a number":
                return ua.StatusCode(ua.StatusCodes.BadTypeMismatch)
            return ua.StatusCode(ua.StatusCodes.BadNotWritable)
        return ua.StatusCode(ua.StatusCodes.Good)
