"""The OPC UA server: the station's tags, nodes, NetPlc state and alarms for any OPC UA client.

asyncua runs on a thread and event loop of its own. Values come from the station's `Readings`
(`Runtime.watch`, through `LatestReadings`: at most one update per tick, none while the loop
lags); only the variables whose value or quality changed are written, each with the scan's wall
time as source timestamp, the time it is written as server timestamp and a StatusCode from the
tag's quality. A tag's variable is of Part 8's standard types with its ranges and units
(ua_types.py), and its history, where the program archives it, is read from the station's archive
(history.py, Part 11).

Client writes are the station's commands (app/authority/): every session's Write service is taken
before asyncua's own, and a write to a tag variable goes to the command layer with the session's
user and peer, which checks the role, the tag's physical range and journals it; the Write is
answered once the value is applied, committed to the journal and readable here (an immediate
Read returns it). The variable's DataType is the one a client must send (Boolean for a bit, Double
for a scaled tag...), anything else is Bad_TypeMismatch; a node that is never writable (the state,
the node diagnostics, a tag `[opcua] writable` does not name) is Bad_NotWritable, journaled like
every refusal. UserAccessLevel is answered per session from the same policy: read for a viewer or
an anonymous client, read and write for a role that may write. The station object's methods
(methods.py: run, stop, step, force and unforce an address or a tag) are commands the same way;
NetPlc's memory and forces are read-only variables for a remote Program view. No role is checked here.

Security off loopback: sessions only over Basic256Sha256 Sign&Encrypt. asyncua keeps a None channel
when a client asks for one, and would then create a session over it (a password in clear);
the station lets a None channel serve discovery only (GetEndpoints, FindServers: how standard
clients learn the endpoints and the server certificate, as OPC UA Part 4 section 5.4 provides)
and refuses CreateSession on it with Bad_SecurityPolicyRejected, whatever the client asks. A
client certificate that is not in the station's trust list (pki.py) is refused when it opens its
secure channel, by closing the connection (the way asyncua answers a refused OpenSecureChannel).
Logins are the station's users with a back-off per host (app/authority/logins.py). A loopback
endpoint (the demo) is for local clients only and has no security.

Alarms are OPC UA conditions (Part 9: conditions.py) in the station's Alarms folder, their
events at the Server object and the station object, their methods (Acknowledge, shelving, out of
service...) the station's commands like the station's own methods, ConditionRefresh answered.
"""

from __future__ import annotations

import asyncio
import contextlib
import contextvars
import ipaddress
import json
import logging
import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any
from urllib.parse import quote, urlsplit

import numpy as np
from asyncua import Node, Server, ua
from asyncua.common.callback import CallbackType, ServerItemCallback
from asyncua.common.utils import ServiceError
from asyncua.crypto.permission_rules import SimpleRoleRuleset, User, UserRole
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256, SecurityPolicyFactory

from app.authority import Action, Commands, Reason, Source, Ticket, Who
from app.authority.logins import Logins
from app.authority.users import UserError, Users
from app.publish import standard_nodes
from app.publish.aligned import ScanClock
from app.publish.conditions import Conditions
from app.publish.feed import LatestReadings, Watch
from app.publish.files import StationFiles
from app.publish.history import JOURNAL, AlarmSource, Archived, Series, StationHistory, install, series_of
from app.publish.index_range import index_ranges, ranged
from app.publish.methods import StationMethods, StepLock
from app.publish.pki import TrustList, host_names, station_certificate, subject, thumbprint
from app.publish.points import PointReader, PointWriter, Writable
from app.publish.seats import Seats
from app.publish.ua_types import (
    CODES,
    HISTORY_READ,
    READ,
    WRITE,
    TagNode,
    build_info,
    python,
    tag_items,
    variant_type,
)
from app.scada.alarms import Alarm
from app.scada.readings import Readings
from app.scada.tag import Tag
from app.scada.words import Journal
from app.station.config import OpcUaSettings
from netplc.address import DATA_SIZE, IO_BITS, fmt_octal
from netplc.forcing import Force
from netplc.memory import Snapshot
from netplc.records import Record

logger = logging.getLogger(__name__)

START_TIMEOUT = 60.0
_S = ua.StatusCodes
ANSWERS = {Reason.APPLIED: _S.Good, Reason.DENIED: _S.BadUserAccessDenied,  # by the layer's Reason
           Reason.NOT_WRITABLE: _S.BadNotWritable, Reason.UNKNOWN: _S.BadNodeIdUnknown,
           Reason.TYPE_MISMATCH: _S.BadTypeMismatch, Reason.OUT_OF_RANGE: _S.BadOutOfRange,
           Reason.INVALID: _S.BadInvalidArgument, Reason.BUSY: _S.BadTooManyOperations,
           Reason.JOURNAL_FULL: _S.BadResourceUnavailable, Reason.NOT_RUNNING: _S.BadServerHalted,
           Reason.FAILED: _S.BadInternalError, Reason.STANDBY: _S.BadInvalidState}
HEALTHY = 255  # ServiceLevel of a station alone (Part 4 6.6.2.4.2: 200-255 healthy)
YIELD_EVERY = 500  # variable writes between two turns of the event loop
_UNWRITTEN = object()  # no value written yet (see _write_changed)
READABLE_WITHIN = 2.0  # s at most an applied write waits for its value to be readable here
MEMORY_BITS = "NetPlc's I/O bits 00000-03777, one byte each (0 or 1): byte n is bit n"
MEMORY_DATA = ("NetPlc's data memory, its 8 banks of 2 KB in turn: byte k*2048 + i is address "
               "k*010000 + 04000 + i (04000..07777, 014000..017777, ... 074000..077777)")
FORCES = ('what is forced, as JSON: [{"kind": "bit", "address": "02120", "value": 1, "user": "..."}] '
          "(kind bit, byte or word; address in octal); force > program > live")


def application_uri(station: str, letter: str = "") -> str:
    """A station's ApplicationUri, and without `letter` its namespace's URI: `urn:netplc:station:` and
    its name, with its letter for one of a pair; its non-ASCII characters (a Russian name) are
    percent-encoded as UTF-8, as RFC 3987 section 3.1 maps an IRI to a URI, since the certificate
    holds the ApplicationUri as an IA5String and the server's is the certificate's (Part 4 7.2)."""
    uri = f"urn:netplc:station:{station}:{letter}" if letter else f"urn:netplc:station:{station}"
    return "".join(c if c.isascii() else quote(c, safe="") for c in uri)


def is_loopback(endpoint: str) -> bool:
    host = urlsplit(endpoint).hostname or ""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def forces_json(forces: Sequence[Force]) -> str:
    return json.dumps([{"kind": f.kind, "address": fmt_octal(f.addr), "value": f.value, "user": f.user}
                       for f in forces])


ENCODE: tuple[Callable[[Any], ua.Variant], ...] = (  # the memory variables' values from a snapshot's
    lambda bits: ua.Variant(bytes(bits), ua.VariantType.ByteString),  # bits, data and forces
    lambda data: ua.Variant(data, ua.VariantType.ByteString),
    lambda forces: ua.Variant(forces_json(forces)))


def _peer(name: object) -> str:
    """A session's peer (asyncua names it by the socket's peer address) as host:port."""
    if isinstance(name, tuple) and len(name) >= 2:
        return f"{name[0]}:{name[1]}"
    return str(name)


def _no_registrations(*_args: object) -> None:
    """The station is no discovery server: RegisterServer(2) is refused."""
    raise ServiceError(ua.StatusCodes.BadServiceUnsupported)


def _who(session: Any) -> Who:
    user = session.user.name if session.user is not None and session.user.name else ""
    return Who(user, Source.OPCUA, _peer(session.name))


@dataclass
class OpcUaStatus:
    updates: int = 0  # variable values written into the address space
    skipped: int = 0  # scans not published because the server lagged
    error: str = ""


class _Users:
    """asyncua's user manager: the station's users (`Logins`: back-off, failures journaled);
    anonymous clients where the station has no users or on a loopback endpoint (the layer lets
    them read only: anonymous has no role)."""

    def __init__(self, logins: Logins, folder: Path, loopback: bool) -> None:
        self.logins = logins
        self.folder = folder
        self.loopback = loopback
        self.peer = ""  # of the session being activated (set around asyncua's activate_session)

    def get_user(self, iserver: object, username: str | None = None, password: str | None = None,
                 certificate: object = None) -> User | None:
        if not username:
            anonymous = self.loopback or not self.any()
            return User(role=UserRole.User) if anonymous else None
        user = self.logins.login(username, password or "", self.peer)
        return None if user is None else User(role=UserRole.User, name=user.name)

    def any(self) -> bool:
        """Does the station have users? A users file that cannot be read counts as yes: nobody
        comes in anonymously because the file broke."""
        try:
            return bool(Users(self.folder).users)
        except UserError:
            logger.exception("users of %s not readable", self.folder)
            return True


# Whether the connection being served has a secure channel: set by `_Trusting` in the task asyncua
# runs each connection's messages in, so its later requests (CreateSession) see it and no other
# connection does.
_SECURE_CHANNEL: contextvars.ContextVar[bool] = contextvars.ContextVar("secure_channel", default=False)


class _Trusting(SecurityPolicyFactory):
    """Basic256Sha256 Sign&Encrypt for a client whose certificate the station trusts."""

    def __init__(self, certificate: Any, private_key: Any, check: Callable[[bytes | None], bool]) -> None:
        super().__init__(SecurityPolicyBasic256Sha256, ua.MessageSecurityMode.SignAndEncrypt, certificate,
                         private_key, permission_ruleset=SimpleRoleRuleset())
        self.check = check

    def create(self, peer_certificate: bytes | None) -> Any:
        if not self.check(peer_certificate):
            raise ua.uaerrors.BadUserAccessDenied()  # asyncua closes the connection
        _SECURE_CHANNEL.set(True)
        return super().create(peer_certificate)


async def _stop_clock(server: Server) -> None:
    """End asyncua's ServerStatus.CurrentTime clock now: its `stop()` waits for the clock's next tick
    (up to 1 s) before it closes anything."""
    task = server.iserver.time_task
    if task is not None:
        task.cancel()
        await asyncio.wait([task])
        server.iserver.time_task = None


class OpcUaServer:
    """`start()` (OSError or RuntimeError naming the problem), then `stop()`."""

    def __init__(self, *, settings: OpcUaSettings, station: str, folder: Path, tags: Sequence[Tag],
                 commands: Commands, watch: Watch, engine: Any, exchange: Any, alarms: Sequence[Alarm] = (),
                 journal: Journal = lambda _name, **_values: None,
                 step_lock: StepLock = lambda: None, archived: Archived | None = None,
                 language: str = "", pair_letter: str = "",
                 service_level: Callable[[], int] = lambda: HEALTHY,
                 files: StationFiles | None = None) -> None:
        """`journal` takes the system records of the server's security (a certificate made or
        made private, a client certificate refused); `step_lock` gives the scan thread's lock, which
        the Step method needs; `archived` what the station archives, for Historical Access;
        `language` the station's (a bit's TrueState and FalseState are in it); `pair_letter` this
        station's in a hot-standby pair ("" alone), `service_level` its ServiceLevel now; `files`
        what the station serves its consoles (files.py)."""
        self.endpoint = settings.endpoint
        self.settings = settings
        self.archived = archived
        self.language = language
        self.pair_letter = pair_letter
        self.service_level = service_level
        self._level = -1  # the ServiceLevel the address space holds
        self.station = station
        self.folder = folder
        self.tags = list(tags)
        self.commands = commands
        self.watch = watch
        self.engine = engine
        self.exchange = exchange
        self.alarms = list(alarms)
        self.journal = journal
        self.writable = Writable(settings.writable)
        self.writer = PointWriter(commands, self.writable, "[opcua]")
        self.methods = StationMethods(commands, step_lock, ANSWERS)
        self.conditions = Conditions(commands, ANSWERS, self.alarms)
        self.reader = PointReader(self.tags)
        self.status = OpcUaStatus()
        self.secure = not is_loopback(self.endpoint)
        self.trust = TrustList(folder)
        self.users = _Users(Logins(lambda: Users(folder), commands, Source.OPCUA), folder, not self.secure)
        self.files = files
        self.seats = Seats(settings.max_consoles, commands, journal)
        self.feed = LatestReadings(self._wake)
        self._unwatch: Callable[[], None] | None = None
        self._published = -1  # the scan whose values the address space holds
        self._events = 0  # the journal's events since the start (Station.JournalEvents)
        self._written: dict[ua.NodeId, object] = {}  # what _write_changed wrote last, by node
        self._waiting: list[tuple[int, asyncio.Future[None]]] = []  # writes waiting to be readable
        self._loop: asyncio.AbstractEventLoop | None = None
        self._ready = threading.Event()
        self._thread: threading.Thread | None = None
        self._stop: asyncio.Event | None = None
        self._tick: asyncio.Event | None = None
        self._scans = ScanClock(self.engine.tick)  # on the loop: its subscriptions' cycles end at the scans

    # --- life cycle (any thread) ---------------------------------------------------------------

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="opcua", daemon=True)
        self._thread.start()
        if not self._ready.wait(START_TIMEOUT):
            raise RuntimeError(f"OPC UA server at {self.endpoint} did not start within {START_TIMEOUT:g} s")
        if self.status.error:
            self._thread.join(5)
            raise RuntimeError(self.status.error)
        self._unwatch = self.watch(self.feed)

    def stop(self) -> None:
        if self._unwatch is not None:
            self._unwatch()
            self._unwatch = None
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
        """The runtime's record observer: an alarm's transition becomes its condition's state and
        event; every event of the journal counts in Station.JournalEvents."""
        if record.kind in JOURNAL:
            self._events += 1
        if record.kind == "alarm" and self._ready.is_set():
            self.conditions.post(record)

    def on_adopted(self, alarm_ids: list[str]) -> None:
        """StationAlarms' observer of the states a pair's standby adopted (no record): their
        conditions show them."""
        if self._ready.is_set():
            self.conditions.adopt(alarm_ids)

    # --- the server's own loop -----------------------------------------------------------------

    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except Exception as e:  # reported by start(), or to the runtime through status
            logger.exception("OPC UA server at %s failed", self.endpoint)
            self.status.error = f"OPC UA server at {self.endpoint}: {type(e).__name__}: {e}"
            self._ready.set()

    async def _main(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._stop, self._tick = asyncio.Event(), asyncio.Event()
        server = Server(user_manager=self.users)
        standard_nodes.install(server)  # from the cache: asyncua's own fill is 3 s of CPU
        await server.init()
        server.set_endpoint(self.endpoint)
        build = build_info()
        server.set_server_name(f"{build.product} {self.station}")  # the ApplicationName
        server.product_uri, server.manufacturer_name = build.product_uri, build.manufacturer
        server.application_type = ua.ApplicationType.Server
        await server.set_build_info(build.product_uri, build.manufacturer, build.product, build.version,
                                    build.build_number, build.build_date)
        uri = application_uri(self.station)  # the namespace's: one for both stations of a pair
        application = application_uri(self.station, self.pair_letter)
        await server.set_application_uri(application)
        if self.secure:
            await self._secure(server, application)
        else:
            server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        self.server = server
        await self._build(server, uri)
        if self.pair_letter:
            await self._redundancy(server, uri)
        await self._serve_level()
        self._intercept(server)
        await server.start()
        if self.secure:  # no await since the listener opened: no client is served before this
            assert server.bserver is not None
            server.bserver.set_policies([
                _Trusting(server.iserver.certificate, server.iserver.private_key, self._trusted)])
        files = asyncio.get_running_loop().create_task(self.files.run()) if self.files is not None else None
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
                    await self._publish(item)
                    self._readable(item.snapshot.scan)
                    self._scans.published()
                await self._serve_level()
                self.status.skipped = self.feed.skipped
        finally:
            if files is not None:
                files.cancel()
            await _stop_clock(server)
            await server.stop()

    async def _redundancy(self, server: Server, namespace: str) -> None:
        """One of a hot-standby pair (Part 4 6.6.2, non-transparent redundancy, Hot; Part 5
        NonTransparentRedundancyType): RedundancySupport Hot, ServerUriArray the partner's
        ApplicationUri; the ServiceLevel says which of the two is the primary."""
        node = server.get_node(ua.NodeId(ua.ObjectIds.Server_ServerRedundancy))
        await node.delete_reference(ua.NodeId(ua.ObjectIds.ServerRedundancyType),
                                    ua.ObjectIds.HasTypeDefinition, bidirectional=False)
        await node.add_reference(ua.NodeId(ua.ObjectIds.NonTransparentRedundancyType),
                                 ua.ObjectIds.HasTypeDefinition, bidirectional=False)
        support = server.get_node(ua.NodeId(ua.ObjectIds.Server_ServerRedundancy_RedundancySupport))
        await support.write_value(ua.Variant(ua.RedundancySupport.Hot.value, ua.VariantType.Int32))
        partner = "B" if self.pair_letter == "A" else "A"
        await node.add_property(ua.NodeId("ServerRedundancy.ServerUriArray", self.idx),
                                ua.QualifiedName("ServerUriArray", 0), [f"{namespace}:{partner}"],
                                ua.VariantType.String)

    async def _serve_level(self) -> None:
        """Server.ServiceLevel, written when it changed (Part 4 6.6.2.4.2: a client of a pair
        chooses the server with the highest)."""
        level = self.service_level()
        if level != self._level:
            self._level = level
            node = self.server.get_node(ua.NodeId(ua.ObjectIds.Server_ServiceLevel))
            await node.write_value(ua.Variant(level, ua.VariantType.Byte))

    async def _secure(self, server: Server, uri: str) -> None:
        """Basic256Sha256 Sign&Encrypt with the station's own certificate (pki.py)."""
        names = host_names(urlsplit(self.endpoint).hostname or "", self.settings.certificate_names)
        own = await asyncio.to_thread(station_certificate, self.folder, uri, names, self.station)
        for note in own.notes:
            self.journal("opcua note", note=note)
        await server.load_certificate(str(own.cert))
        server.iserver.private_key = own.private_key  # what `load_private_key` would load and check again
        server.set_security_policy([ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt])
        tokens: list[type] = [ua.UserNameIdentityToken]
        if not self.users.any():
            tokens.append(ua.AnonymousIdentityToken)
        server.set_identity_tokens(tokens)

    def _trusted(self, der: bytes | None) -> bool:
        """Is the client's certificate in the trust list? A refused one is kept in pki/rejected/
        and journaled the first time."""
        if der and self.trust.is_trusted(der):
            return True
        if not der:
            return False
        try:
            kept = self.trust.reject(der)
        except OSError:
            logger.exception("refused client certificate not kept")
            kept = None
        if kept is not None:
            thumb = thumbprint(der)
            self.journal("opcua untrusted", subject=subject(der), thumb=thumb, kept=kept.parent,
                         folder=self.folder)
        return False

    async def _build(self, server: Server, uri: str) -> None:
        idx = await server.register_namespace(uri)
        self.idx = idx

        def name(text: str) -> ua.QualifiedName:
            return ua.QualifiedName(text, idx)

        station = await server.nodes.objects.add_object(ua.NodeId(self.station, idx), name(self.station))
        self.station_node = station
        folder = await station.add_folder(ua.NodeId("Tags", idx), name("Tags"))
        self.kinds = [variant_type(t) for t in self.tags]
        self.convert = [python(k) for k in self.kinds]
        self.nodeids = [ua.NodeId(f"Tags.{t.name}", idx) for t in self.tags]
        self.position = {nodeid: i for i, nodeid in enumerate(self.nodeids)}  # a tag variable's index
        nstore = self.archived.nstore if self.archived is not None else {}
        self.series: dict[ua.NodeId, Series] = {
            nodeid: series for tag, kind, nodeid in zip(self.tags, self.kinds, self.nodeids)
            if (series := series_of(tag, kind, nstore)) is not None}
        await self._add_tags(server, folder.nodeid)
        self._last_values = np.full(len(self.tags), np.nan)
        self._last_quality = np.full(len(self.tags), -1, dtype=np.int8)
        plc = await station.add_object(ua.NodeId("NetPlc", idx), name("NetPlc"))
        self.plc_state = await plc.add_variable(ua.NodeId("NetPlc.State", idx), name("State"), "")
        self.plc_scan_ms = await plc.add_variable(ua.NodeId("NetPlc.ScanTimeMs", idx), name("ScanTimeMs"),
                                                  0.0)
        self.plc_tick = await plc.add_variable(ua.NodeId("NetPlc.Tick", idx), name("Tick"),
                                               ua.Variant(0, ua.VariantType.UInt64))
        await plc.add_variable(ua.NodeId("NetPlc.NetSyncTimeMs", idx), name("NetSyncTimeMs"),
                               ua.Variant(round(self.engine.tick * 1000), ua.VariantType.UInt32))
        await self._add_memory(plc, idx)
        nodes = await station.add_folder(ua.NodeId("Nodes", idx), name("Nodes"))
        self.node_vars: dict[int, dict[str, Any]] = {}
        for n, stats in (self.exchange.stats.items() if self.exchange is not None else ()):
            obj = await nodes.add_object(ua.NodeId(f"Nodes.{n}", idx), name(str(n)))
            await obj.add_variable(ua.NodeId(f"Nodes.{n}.Endpoint", idx), name("Endpoint"), stats.endpoint)
            self.node_vars[n] = {
                key: await obj.add_variable(ua.NodeId(f"Nodes.{n}.{key}", idx), name(key), value)
                for key, value in (("Up", False), ("Reads", ua.Variant(0, ua.VariantType.UInt64)),
                                   ("Writes", ua.Variant(0, ua.VariantType.UInt64)),
                                   ("Errors", ua.Variant(0, ua.VariantType.UInt64)), ("LastError", ""))}
        alarms = await station.add_folder(ua.NodeId("Alarms", idx), name("Alarms"))
        sources = {tag.name: nodeid for tag, nodeid in zip(self.tags, self.nodeids)}
        await self.conditions.build(server, idx, alarms, station, sources, plc, self.plc_state.nodeid)
        await self.methods.add(station, idx)
        if self.files is not None:
            await self.files.build(server, station, idx)
        events = ua.Variant(0, ua.VariantType.UInt64)
        self.journal_events = await station.add_variable(ua.NodeId("Station.JournalEvents", idx),
                                                         name("JournalEvents"), events)
        await self.journal_events.write_attribute(ua.AttributeIds.Description, ua.DataValue(ua.Variant(
            ua.LocalizedText("events journaled since the station started (messages, alarm transitions, "
                             "operator actions, system records): a console reads the journal's history "
                             "when it changes"))))
        role = await station.add_variable(ua.NodeId("Station.Role", idx), name("Role"), "")
        self.role_node = role.nodeid
        await role.write_attribute(ua.AttributeIds.Description, ua.DataValue(ua.Variant(ua.LocalizedText(
            "the role of the session's user at this station (a console names it in a refusal); empty: "
            "none"))))
        # after the conditions, which set the station's EventNotifier
        alarm_sources = {alarm_id: AlarmSource(c.nodeid, c.type_id, c.source, c.source_name)
                         for alarm_id, c in self.conditions.by_id.items()}
        await install(server, StationHistory(server.iserver, self.archived, self.series, station.nodeid,
                                             alarm_sources))

    async def _add_tags(self, server: Server, folder: ua.NodeId) -> None:
        """The tags' variables, of their standard types (ua_types.py), and then their properties in
        one batch. asyncua checks each new child against all of its parent's references (quadratic:
        a minute for 10,000 tags); tag names are unique, so each variable is added to a folder whose
        reference list is set aside meanwhile and put back with the new reference appended."""
        service = server.iserver.node_mgt_service
        folder_data = server.iserver.aspace.get(folder)
        references = folder_data.references
        properties: list[ua.AddNodesItem] = []
        for tag, nodeid, kind in zip(self.tags, self.nodeids, self.kinds):
            archived = nodeid in self.series
            # what a client may do at all; UserAccessLevel is answered per session
            access = READ | (WRITE if self.writable(tag.name) else 0) | (HISTORY_READ if archived else 0)
            node = TagNode(tag, nodeid, kind, access, archived)
            variable, children = tag_items(node, folder, self.language)
            folder_data.references = []
            try:
                added = service.add_nodes([variable])
            finally:
                references.extend(folder_data.references)
                folder_data.references = references
            added[0].StatusCode.check()
            properties += children
        for result in service.add_nodes(properties):
            result.StatusCode.check()
        write = server.iserver.aspace.write_attribute_value
        now = datetime.now(UTC)
        waiting = ua.StatusCode(ua.StatusCodes.BadWaitingForInitialData)
        for nodeid in self.nodeids:
            await write(nodeid, ua.AttributeIds.Value,
                        ua.DataValue(StatusCode=waiting, SourceTimestamp=now, ServerTimestamp=now))

    async def _add_memory(self, plc: Node, idx: int) -> None:
        """NetPlc's memory and forces, read-only, for a remote Program view (`main.py monitor
        opc.tcp://...`) and the consoles' forms, which need raw memory, not only tags. A Read's
        or a monitored item's IndexRange is answered that part (index_range.py); a client that
        gives none reads each whole (20 KB in all)."""
        memory = await plc.add_object(ua.NodeId("NetPlc.Memory", idx), ua.QualifiedName("Memory", idx))
        nodes = []
        for parent, name, initial, description in ((memory, "Bits", bytes(IO_BITS), MEMORY_BITS),
                                                   (memory, "Data", bytes(DATA_SIZE), MEMORY_DATA),
                                                   (plc, "Forces", "[]", FORCES)):
            path = "NetPlc." + ("" if parent is plc else "Memory.") + name
            var = await parent.add_variable(ua.NodeId(path, idx), ua.QualifiedName(name, idx), initial)
            await var.write_attribute(ua.AttributeIds.Description,
                                      ua.DataValue(ua.Variant(ua.LocalizedText(description))))
            nodes.append(var.nodeid)
        self.memory_nodes = nodes
        self._memory: tuple[object, ...] = (None, None, None)  # bits, data, forces as last written

    async def _publish_memory(self, snapshot: Snapshot, when: datetime, now: datetime) -> None:
        """The memory variables as of `snapshot`, each written only when it changed."""
        write = self.server.iserver.aspace.write_attribute_value
        memory = (snapshot.bits, snapshot.data, snapshot.forces)
        for node, new, old, encode in zip(self.memory_nodes, memory, self._memory, ENCODE):
            if new is not old and new != old:
                await write(node, ua.AttributeIds.Value,
                            ua.DataValue(encode(new), SourceTimestamp=when, ServerTimestamp=now))
        self._memory = memory

    async def _publish(self, readings: Readings) -> None:
        reading = self.reader.read(readings)
        quality = reading.quality
        values, last = reading.values, self._last_values
        changed = np.flatnonzero(~((values == last) | (np.isnan(values) & np.isnan(last)))
                                 | (quality != self._last_quality))
        self._last_values, self._last_quality = values, quality
        when = datetime.fromtimestamp(reading.wall, UTC)  # the scan's: the source timestamp
        now = datetime.now(UTC)  # when the server took it: the server timestamp
        write = self.server.iserver.aspace.write_attribute_value
        value_attr = ua.AttributeIds.Value
        for n, i in enumerate(changed.tolist()):
            if n % YIELD_EVERY == YIELD_EVERY - 1:
                await asyncio.sleep(0)  # let the server answer its clients' requests meanwhile
            v = values[i]
            code = CODES[quality[i]]
            if math.isnan(v):  # a BCD word that is not BCD
                dv = ua.DataValue(StatusCode=ua.StatusCode(ua.StatusCodes.BadOutOfRange),
                                  SourceTimestamp=when, ServerTimestamp=now)
            else:
                dv = ua.DataValue(ua.Variant(self.convert[i](v), self.kinds[i]), StatusCode=code,
                                  SourceTimestamp=when, ServerTimestamp=now)
            await write(self.nodeids[i], value_attr, dv)
        self.status.updates += len(changed)
        await self._publish_memory(readings.snapshot, when, now)  # before the tick that says which scan
        await self._write_changed(self.plc_state, reading.state)
        await self.plc_scan_ms.write_value(float(self.engine.stats.last_ms))
        await write(self.plc_tick.nodeid, value_attr,  # the scan's time: a console's latency counts from it
                    ua.DataValue(ua.Variant(reading.scan, ua.VariantType.UInt64), SourceTimestamp=when,
                                 ServerTimestamp=now))
        await self._write_changed(self.journal_events, ua.Variant(self._events, ua.VariantType.UInt64))
        for n, stats in (self.exchange.stats.items() if self.exchange is not None else ()):
            vars_ = self.node_vars.get(n)
            if vars_ is None:
                continue
            for key, value in (("Up", stats.up), ("Reads", ua.Variant(stats.reads, ua.VariantType.UInt64)),
                               ("Writes", ua.Variant(stats.writes, ua.VariantType.UInt64)),
                               ("Errors", ua.Variant(stats.errors, ua.VariantType.UInt64)),
                               ("LastError", stats.last_error)):
                await self._write_changed(vars_[key], value)

    async def _write_changed(self, node: Node, value: object) -> None:
        """`value` written to `node` only when it is not the one written last: a variable that
        rarely changes (the PLC's state, a node's link) written at every scan costs each
        console's monitored item a sampling and a comparison per scan, and moves its source
        timestamp though the value did not change."""
        if self._written.get(node.nodeid, _UNWRITTEN) != value:
            self._written[node.nodeid] = value
            await node.write_value(value)

    def _readable(self, scan: int) -> None:
        """The address space holds the values of `scan`: answer the writes that waited for them."""
        self._published = scan
        still = []
        for after, future in self._waiting:
            if scan > after:
                if not future.done():
                    future.set_result(None)
            else:
                still.append((after, future))
        self._waiting = still

    async def _until_readable(self, after: int) -> None:
        """Until a scan newer than `after` is in the address space (bounded: an applied write is
        answered even while the server lags)."""
        if self._published > after:
            return
        future: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self._waiting.append((after, future))
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(future, max(READABLE_WITHIN, 3 * self.engine.tick))

    # --- client sessions -----------------------------------------------------------------------

    def _intercept(self, server: Server) -> None:
        """Every client session's Write goes through `_write` instead of asyncua's attribute
        service (the session knows the user and the peer; that service knows neither), and the
        login sees its peer; a Read of UserAccessLevel is answered for the session's user; the
        monitored items of its subscriptions honour their IndexRange (index_range.py)."""
        iserver = server.iserver
        create = iserver.create_session
        users = self.users

        def create_session(name: str, user: User | None = None, external: bool = False) -> Any:
            if external and self.secure and not _SECURE_CHANNEL.get():
                self.commands.refuse(Who("", Source.OPCUA, _peer(name)), "open a session", "",
                                     Reason.DENIED, self.commands.say("session none", endpoint=self.endpoint))
                raise ServiceError(ua.StatusCodes.BadSecurityPolicyRejected)
            session = create(name, user=user or User(role=UserRole.Anonymous), external=external)
            if not external:
                return session
            activate = session.activate_session

            def activate_session(params: Any, peer_certificate: bytes | None) -> Any:
                users.peer = _peer(session.name)
                token = params.UserIdentityToken
                who = Who(getattr(token, "UserName", None) or "", Source.OPCUA, users.peer)
                try:
                    if session not in self.seats.sessions():
                        self.seats.check(who)
                    result = activate(params, peer_certificate)
                finally:
                    users.peer = ""
                self.seats.take(session, _who(session))
                return result

            async def close_session(delete_subs: bool = True) -> None:
                self.seats.leave(session)
                await close(delete_subs)

            async def write(params: ua.WriteParameters) -> list[ua.StatusCode]:
                return await self._write(_who(session), params)

            async def call(requests: list[ua.CallMethodRequest]) -> list[ua.CallMethodResult]:
                return await self._call(session, requests, service)

            async def create_subscription(params: ua.CreateSubscriptionParameters, callback: Any,
                                          request_callback: Any = None) -> ua.CreateSubscriptionResult:
                result = await subscribe(params, callback, request_callback)
                subscription = session.subscription_service.subscriptions[result.SubscriptionId]
                ranged(subscription)
                self._scans.align(subscription)
                return result

            service, close, subscribe = session.call, session.close_session, session.create_subscription
            session.activate_session = activate_session
            session.close_session = close_session
            session.write = write
            session.call = call
            session.create_subscription = create_subscription  # IndexRange honoured, cycles at the scans
            return session

        iserver.create_session = create_session
        iserver.register_server = _no_registrations  # no session is needed, over any channel
        server.subscribe_server_callback(CallbackType.PostRead, self._user_access_level)

    def _user_access_level(self, event: ServerItemCallback, _service: object) -> None:
        """A tag's UserAccessLevel and a station method's UserExecutable as the policy answers
        for the session's user (every user may read a tag and its history), and Station.Role;
        a Value read with an IndexRange its part (asyncua keeps one PostRead callback: this one)."""
        index_ranges(event, _service)
        if not event.is_external:
            return
        may: bool | None = None
        reads, results = event.request_params.NodesToRead, event.response_params
        user = event.user.name if event.user is not None and event.user.name else ""
        for n, rv in enumerate(reads):
            if rv.NodeId == self.role_node and rv.AttributeId == ua.AttributeIds.Value:
                role = self.commands.role(Who(user, Source.OPCUA)) or ""
                results[n] = ua.DataValue(ua.Variant(role, ua.VariantType.String))
                continue
            if rv.AttributeId == ua.AttributeIds.UserExecutable:
                who = Who(user, Source.OPCUA)
                executable = self.methods.executable(who, rv.NodeId)
                if executable is None:
                    executable = self.conditions.executable(who, rv.NodeId)
                if executable is not None:
                    results[n] = ua.DataValue(ua.Variant(executable, ua.VariantType.Boolean))
                continue
            if rv.AttributeId != ua.AttributeIds.UserAccessLevel:
                continue
            i = self.position.get(rv.NodeId)
            if i is None:
                continue
            level = READ | (HISTORY_READ if rv.NodeId in self.series else 0)  # history: every user
            if self.writable(self.tags[i].name):
                if may is None:
                    may = self.commands.may(Who(user, Source.OPCUA), Action.WRITE)
                if may:
                    level |= WRITE
            results[n] = ua.DataValue(ua.Variant(level, ua.VariantType.Byte))

    async def _call(self, session: Any, requests: list[ua.CallMethodRequest],
                    service: Callable[[list[ua.CallMethodRequest]], Any]) -> list[ua.CallMethodResult]:
        """The station's methods and its conditions' as its commands, with the session's user, and
        ConditionRefresh for the session's subscriptions (conditions.py); others to asyncua."""
        who = _who(session)
        station = [r.MethodId in self.methods.by_node for r in requests]
        condition = [not own and self.conditions.owns(r) for r, own in zip(requests, station)]
        theirs = [r for r, a, b in zip(requests, station, condition) if not (a or b)]
        others = iter(await service(theirs) if theirs else [])
        return [await self.methods.call(who, r) if a else
                await self.conditions.call(who, session.session_id, r) if b else next(others)
                for r, a, b in zip(requests, station, condition)]

    async def _write(self, who: Who, params: ua.WriteParameters) -> list[ua.StatusCode]:
        tickets = [self._command(who, wv) for wv in params.NodesToWrite]
        answers = [await asyncio.wrap_future(t) for t in tickets]
        if any(a.ok for a in answers):
            # applied in a scan after the one handed over last: readable once a newer one is
            await self._until_readable(self.feed.scan)
        return [ua.StatusCode(ANSWERS[a.reason]) for a in answers]

    def _command(self, who: Who, wv: ua.WriteValue) -> Ticket:
        """One client write as the station's command, or its refusal (journaled, throttled)."""
        commands = self.commands
        i = self.position.get(wv.NodeId)
        if i is None:
            target = wv.NodeId.to_string()
            if wv.NodeId in self.server.iserver.aspace:
                return commands.refuse(who, Action.WRITE, target, Reason.NOT_WRITABLE,
                                       commands.say("only tags"))
            return commands.refuse(who, Action.WRITE, target, Reason.UNKNOWN, commands.say("no node"))
        tag, kind = self.tags[i], self.kinds[i]
        if wv.AttributeId != ua.AttributeIds.Value:
            return commands.refuse(who, Action.WRITE, tag.name, Reason.NOT_WRITABLE,
                                   commands.say("only value", attribute=ua.AttributeIds(wv.AttributeId).name))
        variant = wv.Value.Value if wv.Value is not None else None
        value = variant.Value if variant is not None else None
        mismatch = ""
        if variant is None or variant.VariantType != kind or value is None or isinstance(value, list):
            sent = variant.VariantType.name if variant is not None and value is not None else "no value"
            mismatch = f"a {sent} for a {kind.name} variable"
        return self.writer.write(who, tag, value, mismatch)
