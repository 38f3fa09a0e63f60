"""A remote console's session with its station (`main.py console opc.tcp://...`): the Program
view's `StationClient` (login, trust on first use, memory, back-off, commands as the user) and what
a console adds, all of it standard OPC UA that any client could do the same way:

- the station's files (files.py): the manifest watched (pushed when it changes); a file whose
  SHA-256 is not in the console's cache is read through its FileType object, and the station's
  folder as of that manifest is put together under the console's config directory
  (`stations/<host:port>/<hash>/`), which the console then loads like a station's own: a form
  saved at the station reaches the console within a second or two;
- the alarms: the conditions of the station's Alarms folder (browsed once per session), their
  ISA-18.2 state word, severity, text and time watched as monitored items of the memory's
  subscription (with the manifest, the nodes' links and the journal's count), so the station
  pushes what changed, when it changed, in the notification that carries the scan; each new
  session reads them all first, so a console that reconnects shows the station's alarms as they
  are now (the refresh a ConditionRefresh gives an event client);
- NetPlc's memory, only the parts its views want (`want`: the open form's operands; the whole of it
  while a Program view is open, or until a view said what it wants), watched as monitored items
  with an IndexRange (memory_items.py): the station pushes a part when it changed;
- the nodes' links (Nodes.<n>.Up), so the console judges its elements' quality as the station does;
- the user's role at the station (Station.Role, read with the user's rights every few seconds),
  so a refusal names the role it needed;
- writes of a form's raw address through the station's WriteBit and WriteWord methods;
- the journal: the station object's event history (HistoryReadEvents, Part 11), newest first;
- a trend's history: its tag's raw history (HistoryReadRawModified, Part 11), page after page
  with the station's continuation points;
- the viewer's queries: the journal's events of a time range under a where clause the station
  evaluates (a message's severity, its source, its text by Like), and which tags are historized.
"""

from __future__ import annotations

import asyncio
import datetime as dt
import hashlib
import json
import logging
import os
import shutil
import struct
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from datetime import UTC
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from asyncua import ua
from asyncua.client.ua_client import UaClientState
from asyncua.client.ua_file import UaFile
from asyncua.common.events import Event

from app.authority import Action, Answer, Reason, Refusal, Ticket, Who
from app.authority.policy import ROLES, needs, rank
from app.publish.client import LEADS, StationClient, _why, config_dir
from app.publish.history import journal_where
from app.publish.memory_items import WHOLE, MemoryItems, Ranges
from app.publish.ua_types import SEVERITY
from app.scada.alarms import AlarmRow, State
from app.scada.horn import AlarmSource
from netplc.address import fmt_octal
from netplc.memory import Snapshot
from registrar.reading import Filter, Row

logger = logging.getLogger(__name__)

STATES = {state.word: state for state in State}
PRIORITY_OF = {severity: priority for priority, severity in SEVERITY.items()}
FIELDS = ("State", "Severity", "Text", "Time")  # read of each condition
EVENT_FIELDS = ("EventId", "EventType", "SourceName", "Time", "Message", "Severity")  # what `_record` reads


@dataclass(frozen=True)
class Files:
    """The station's files as of one manifest, put together in `folder`."""

    folder: Path
    manifest: dict[str, object]

    def part(self, name: str) -> Path | None:
        rel = dict(self.manifest.get("parts", {})).get(name)  # type: ignore[call-overload]
        return self.folder / rel if rel else None


class ConsoleClient(StationClient):
    def __init__(self, url: str, *, partner: str = "", folder: Path | None = None,
                 period: float = 0.1) -> None:
        """`partner`: the other station of a hot-standby pair; the console follows the one that leads
        (StationClient), and reads the forms, alarms and journal there again (a new session)."""
        super().__init__(url, partner=partner, folder=folder, period=period)
        self.files: Files | None = None  # as last put together
        self.alarms: tuple[AlarmRow, ...] = ()
        self.links: dict[int, bool] = {}
        self.role = ""
        self.journal_events: object = None  # Station.JournalEvents as last read: it changes, the journal did
        self._manifest = ""  # the manifest whose files are put together in `files`
        self._alarm_ids: list[str] = []
        self._nodes: list[int] = []
        self._pushed_values: dict[str, object] = {}  # by variable, as the station pushed them
        self._fresh = False  # one of them changed since they were taken
        base = (folder or config_dir()) / "console"
        self._cache = base / "cache"
        self._stations = base / "stations" / urlsplit(url).netloc.replace(":", "_")
        self._own = f"{os.getpid()}-{id(self):x}"  # this client's partial files, apart from other consoles'
        self.memory = MemoryItems(self._node)
        self.memory.on_batch = self._pushed
        # the memory as last pushed and the parts of it that hold the station's values, together
        self.shown: tuple[Snapshot, Ranges] | None = None
        self._wants: dict[str, Ranges] = {}  # by the view that wants them
        self._wants_lock = threading.Lock()
        self._following: asyncio.Lock | None = None  # one change of the watched parts at a time
        self._forces_text = ""
        self._forces_parsed: tuple = ()

    @property
    def keep(self) -> Path:
        """This console's own folder for its station: the station's files as served, and what the
        console keeps of its own (its users' named trends)."""
        return self._stations

    # --- from any thread ----------------------------------------------------------------------

    def write_bit(self, addr: int, value: int, label: str | None, at_least: str | None) -> Ticket:
        return self.said(self.call("WriteBit", fmt_octal(addr), value, label or "", at_least or ""),
                          Action.WRITE, label or fmt_octal(addr), at_least)

    def write_word(self, addr: int, value: int, label: str | None, at_least: str | None) -> Ticket:
        return self.said(self.call("WriteWord", fmt_octal(addr), value, label or "", at_least or ""),
                          Action.WRITE, label or fmt_octal(addr), at_least)

    def want(self, key: str, ranges: Ranges | None) -> None:
        """The view `key` reads `ranges` of the memory from now on (None: it reads none any more).
        The console watches what all its views want together; the whole memory while nobody said."""
        with self._wants_lock:
            if ranges is None:
                self._wants.pop(key, None)
            else:
                self._wants[key] = ranges
        if self._loop.loop is not None and self._client is not None:
            self._submit(self._watch_wanted()).add_done_callback(self._watch_done)  # at once: a form shown

    def _watch_done(self, done: Future[None]) -> None:
        error = None if done.cancelled() else done.exception()
        if error is not None:  # the link's: the next poll finds it lost, and watches them once back
            logger.warning("%s: watching the parts of the memory the views want: %s", self.url, _why(error))

    @property
    def wanted(self) -> Ranges:
        with self._wants_lock:
            wants = list(self._wants.values())
        if not wants:
            return WHOLE
        out = Ranges()
        for ranges in wants:
            out = out | ranges
        return out

    def denial(self, action: Action, at_least: str | None = None, what: str | None = None) -> Refusal | None:
        """Why the user may not do `action` (needing at least `at_least`): the station's answers
        (UserExecutable of its method for the action, and the user's role for a form element's
        higher Role); None when it may, or until the station answered."""
        need = needs(action, at_least)
        role = self.role
        allowed = self.may(action) is not False
        if allowed and at_least is not None and role in ROLES:  # a form element asking more than the policy
            allowed = rank(role) >= rank(need)
        return None if allowed else Refusal(what or action.value, need, self.user, role)

    def journal(self, day: dt.date, limit: int, since: float | None = None) -> Future[list[Row]]:
        """The newest `limit` records of `day` (this machine's day) in the station's journal, newest
        first; with `since` (a record's time) only those from then on, oldest first (the station
        reads the few rows after it, not the day's newest page again)."""
        return self._submit(self._journal(day, limit, since))

    def history(self, tag: str, start: dt.datetime, end: dt.datetime) -> Future[list[ua.DataValue]]:
        """The archived values of the station's tag `tag` from `start` (included) to `end` (not),
        oldest first, in physical units with the StatusCode of their quality."""
        return self._submit(self._history(tag, start, end))

    def events(self, start: dt.datetime, end: dt.datetime, flt: Filter, limit: int) -> Future[list[Row]]:
        """The station's journal events from `start` (included) to `end` (not) that pass what the
        station evaluates of `flt` (history.py `journal_where`), oldest first, `limit` at most, as
        the records they were."""
        return self._submit(self._events(start, end, journal_where(flt), limit))

    def historizing(self, tags: list[str]) -> Future[set[str]]:
        """Which of the station's tags `tags` it keeps the history of (their Historizing)."""
        return self._submit(self._historizing(tags))

    def said(self, sent: Ticket, action: Action, what: str, at_least: str | None = None,
             out_of_range: Callable[[], str] | None = None) -> Ticket:
        """The station's answer, a refusal for the role in its parts (the role it needs, the user's);
        a refusal for the range in `out_of_range()`'s words, where the caller knows the range (the
        StatusCode carries no text)."""
        ticket: Ticket = Ticket()

        def done(answer: Ticket) -> None:
            a: Answer = answer.result()
            if a.reason is Reason.DENIED:
                a = Answer(a.reason, a.text, Refusal(what, needs(action, at_least), self.user, self.role))
            elif a.reason is Reason.OUT_OF_RANGE and out_of_range is not None:
                a = Answer(a.reason, out_of_range())
            ticket.set_result(a)

        sent.add_done_callback(done)
        return ticket

    # --- on the client's loop -------------------------------------------------------------------

    async def _read(self) -> None:
        """Each period: the link (the station pushes the rest: nothing to read), a new session's
        subscription, the files of a manifest pushed, the parts of the memory the views want."""
        client = self._client
        assert client is not None
        if client.uaclient.state is not UaClientState.CONNECTED:  # asyncua found the link lost
            raise ConnectionError(f"the link is lost ({client.uaclient.state.value})")
        if self.memory.client is not client:  # a new session: a subscription of its own
            tick = await client.get_node(self._node("NetPlc.NetSyncTimeMs")).read_value()
            await self.memory.open(client, float(tick or 100))
            await self._browse()
            self._pushed_values = {}
            await self.memory.values([(self._node(n), self._setter(n)) for n in self._watched_names()])
            self._take()
            self.service_level = self.memory.service_level if self.memory.service_level is not None else LEADS
        manifest = str(self._pushed_values.get("Files.Manifest") or "{}")
        if manifest != self._manifest:
            self.files = await self._fetch(manifest)
            self._manifest = manifest
            self.changed()
        await self._watch_wanted()

    def _watched_names(self) -> list[str]:
        """The station's variables a console watches besides the memory."""
        return ["Files.Manifest", "Station.JournalEvents", *(f"Nodes.{n}.Up" for n in self._nodes),
                *(f"Alarms.{a}.{f}" for a in self._alarm_ids for f in FIELDS)]

    def _setter(self, name: str) -> Callable[[ua.DataValue], None]:
        def apply(dv: ua.DataValue) -> None:
            self._pushed_values[name] = dv.Value.Value if dv.Value is not None else None
            self._fresh = True
        return apply

    def _take(self) -> None:
        """The links, the alarms and the journal's count as the station pushed them last."""
        self._fresh = False
        values = self._pushed_values
        self.journal_events = values.get("Station.JournalEvents")
        self.links = {n: bool(values.get(f"Nodes.{n}.Up")) for n in self._nodes}
        self.alarms = tuple(self._row(a, [values.get(f"Alarms.{a}.{f}") for f in FIELDS])
                            for a in self._alarm_ids)

    async def _ask_rights(self) -> None:
        """The user's rights, and the user's role with them (a role changed at the station)."""
        await super()._ask_rights()
        client = self._client
        if client is not None:
            (dv,) = await client.uaclient.read_attributes([self._node("Station.Role")], ua.AttributeIds.Value)
            self.role = str(dv.Value.Value or "") if dv.Value is not None else ""

    async def _watch_wanted(self) -> None:
        """Watch what the views want now (reading the parts newly wanted first)."""
        if self._following is None:
            self._following = asyncio.Lock()
        async with self._following:
            if self.memory.client is self._client and self._client is not None:
                await self.memory.follow(self.wanted)

    def _pushed(self) -> None:
        """The station pushed a change (or a part newly watched was read): the memory shown anew."""
        m = self.memory
        if self._fresh:
            self._take()
        if m.forces != self._forces_text:
            self._forces_text, self._forces_parsed = m.forces, self._forces(m.forces)
        snapshot = Snapshot(tuple(m.bits), bytes(m.data), m.tick, time.monotonic(), m.wall, m.state,
                            self._forces_parsed)
        self.shown = (snapshot, m.covered)
        self.snapshot = snapshot
        if m.service_level is not None:
            self.service_level = m.service_level
        self.reads = m.batches
        self.changed()

    async def _journal(self, day: dt.date, limit: int, since: float | None) -> list[Row]:
        """The day's events with no where clause: the select clauses are the few fields a record
        needs, not those asyncua's read_event_history builds by browsing the event types at each
        read (some fifty Browse requests a page, each a console's cost at the station)."""
        first = dt.datetime.combine(day, dt.time.min).astimezone(UTC)
        end = first + dt.timedelta(days=1)
        if since is None:  # an end before the start reads newest first
            return await self._events(end, first, ua.ContentFilter(), limit)
        return await self._events(dt.datetime.fromtimestamp(since, UTC), end, ua.ContentFilter(), limit)

    async def _history(self, tag: str, start: dt.datetime, end: dt.datetime) -> list[ua.DataValue]:
        client = self._client
        if client is None:
            raise ConnectionError(f"not connected: {self.error or 'logging in'}")
        try:  # asyncua reads on while the station answers a continuation point
            return await client.get_node(self._node(f"Tags.{tag}")).read_raw_history(start, end, 0, False)
        except ua.UaError as e:
            raise ConnectionError(f"{self.url}: {tag}: {_why(e)}") from None

    async def _events(self, start: dt.datetime, end: dt.datetime, where: ua.ContentFilter,
                      limit: int) -> list[Row]:
        """Answer after answer, with the station's continuation points, `limit` at most (the station
        is asked no more; a continuation point left is released)."""
        client = self._client
        if client is None:
            raise ConnectionError(f"not connected: {self.error or 'logging in'}")
        select = [ua.SimpleAttributeOperand(TypeDefinitionId=ua.NodeId(ua.ObjectIds.BaseEventType),
                                            BrowsePath=[ua.QualifiedName(name, 0)],
                                            AttributeId=ua.AttributeIds.Value) for name in EVENT_FIELDS]
        details = ua.ReadEventDetails(StartTime=start, EndTime=end, NumValuesPerNode=limit,
                                      Filter=ua.EventFilter(SelectClauses=select, WhereClause=where))
        value = ua.HistoryReadValueId(NodeId=self._node(self.station))
        rows: list[Row] = []
        try:
            while True:
                params = ua.HistoryReadParameters(HistoryReadDetails=details,  # (asyncua's default: release)
                                                  TimestampsToReturn=ua.TimestampsToReturn.Both,
                                                  ReleaseContinuationPoints=False, NodesToRead=[value])
                result = (await client.uaclient.history_read(params))[0]
                result.StatusCode.check()
                rows += [_record(Event.from_event_fields(select, e.EventFields))
                         for e in result.HistoryData.Events]
                value.ContinuationPoint = result.ContinuationPoint
                if not value.ContinuationPoint:
                    return rows
                if len(rows) >= limit:
                    params.ReleaseContinuationPoints = True
                    await client.uaclient.history_read(params)
                    return rows[:limit]
        except ua.UaError as e:
            raise ConnectionError(f"{self.url}: {_why(e)}") from None

    async def _historizing(self, tags: list[str]) -> set[str]:
        client = self._client
        if client is None:
            raise ConnectionError(f"not connected: {self.error or 'logging in'}")
        try:
            values = await client.uaclient.read_attributes([self._node(f"Tags.{t}") for t in tags],
                                                          ua.AttributeIds.Historizing)
        except ua.UaError as e:
            raise ConnectionError(f"{self.url}: {_why(e)}") from None
        return {t for t, dv in zip(tags, values, strict=True)
                if dv.StatusCode.is_good() and dv.Value is not None and dv.Value.Value is True}

    async def _browse(self) -> None:
        client = self._client
        assert client is not None
        alarms = await client.get_node(self._node("Alarms")).get_children()
        self._alarm_ids = [str(n.nodeid.Identifier).removeprefix("Alarms.") for n in alarms]
        nodes = await client.get_node(self._node("Nodes")).get_children()
        self._nodes = sorted(int(str(n.nodeid.Identifier).removeprefix("Nodes.")) for n in nodes)

    @staticmethod
    def _row(alarm_id: str, values: list[object]) -> AlarmRow:
        state, severity, text, when = values
        changed = when.timestamp() if isinstance(when, dt.datetime) else 0.0
        priority = PRIORITY_OF.get(int(severity or 0), 4)
        return AlarmRow(alarm_id, priority, STATES.get(str(state), State.NORMAL), changed, changed, None,
                        str(text or ""))

    async def _fetch(self, text: str) -> Files:
        """The files of `text` (a manifest), each read from the station unless cached by its hash."""
        client = self._client
        assert client is not None
        manifest = json.loads(text)
        files: dict[str, str] = manifest.get("files", {})
        self._cache.mkdir(parents=True, exist_ok=True)
        for rel, sha in files.items():
            cached = self._cache / sha
            if cached.exists():
                continue
            async with UaFile(client.get_node(self._node(f"Files.{rel}")), "r") as f:
                content: bytes = await f.read()
            if hashlib.sha256(content).hexdigest() != sha:
                raise ua.UaError(f"{rel}: the station sent other content than its manifest's hash "
                                 "(changed while read): read again at the next poll")
            partial = self._cache / f"{sha}.{self._own}.part"  # consoles may share the cache
            partial.write_bytes(content)
            partial.replace(cached)
        folder = self._stations / hashlib.sha256(text.encode()).hexdigest()[:16]
        if not folder.exists():
            made = self._stations / f"{folder.name}.{self._own}.part"
            shutil.rmtree(made, ignore_errors=True)
            for rel, sha in files.items():
                target = made / rel
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(self._cache / sha, target)
            made.mkdir(parents=True, exist_ok=True)
            if folder.is_dir():  # another console put the same files together meanwhile: theirs is ours
                shutil.rmtree(made, ignore_errors=True)
            else:
                made.replace(folder)
        logger.info("%s: station files as of manifest %s in %s", self.url, folder.name, folder)
        return Files(folder, manifest)


class StationCommands:
    """The station's command layer as a console's views call it (the alarm summary, the banner,
    the rights of their buttons): the layer's methods and answers, each sent as the station's
    method with the console's user; `who` is the console's and not sent (the session is who)."""

    def __init__(self, client: ConsoleClient, alarms: AlarmSource) -> None:
        """`alarms`: the console's copy of the station's alarms, whose horn a Silence the station
        took stops at once (as the layer does the station's own)."""
        self.client = client
        self.alarms = alarms

    def denial(self, who: Who, action: Action, at_least: str | None = None,
               what: str | None = None) -> Refusal | None:
        return self.client.denial(action, at_least, what)

    def may(self, who: Who, action: Action, at_least: str | None = None) -> bool:
        return self.denial(who, action, at_least) is None

    def acknowledge(self, who: Who, alarm_id: str, comment: str = "") -> Ticket:
        return self._sent(Action.ACKNOWLEDGE, alarm_id, "Acknowledge", alarm_id)

    def acknowledge_all(self, who: Who) -> Ticket:
        return self._sent(Action.ACKNOWLEDGE, Action.ACKNOWLEDGE.value, "AcknowledgeAll")

    def shelve(self, who: Who, alarm_id: str, reason: str, duration: float, once: bool = False) -> Ticket:
        return self._sent(Action.SHELVE, alarm_id, "Shelve", alarm_id, reason, float(duration))

    def unshelve(self, who: Who, alarm_id: str) -> Ticket:
        return self._sent(Action.UNSHELVE, alarm_id, "Unshelve", alarm_id)

    def silence(self, who: Who) -> Ticket:
        ticket = self._sent(Action.SILENCE, Action.SILENCE.value, "Silence")
        ticket.add_done_callback(self._silenced)
        return ticket

    def _silenced(self, ticket: Ticket) -> None:
        """On the client's thread, before the view hears the answer."""
        if ticket.result().ok:
            self.alarms.silence(time.time())

    def _sent(self, action: Action, what: str, method: str, *args: object) -> Ticket:
        return self.client.said(self.client.call(method, *args), action, what)


def _record(event: Any) -> Row:
    """A journal event as the record it was: its id from its EventId (history.py: day and id), its
    kind from its type and source (a system record is a SystemEventType, an alarm's transition its
    condition's type, a message's source MSGn, the rest operator actions)."""
    _day, rid = struct.unpack(">Iq", event.EventId) if len(event.EventId or b"") == 12 else (0, 0)
    when = event.Time if event.Time.tzinfo is not None else event.Time.replace(tzinfo=UTC)
    source = str(event.SourceName or "")
    kind = event.EventType.Identifier
    if kind == ua.ObjectIds.SystemEventType:
        kind = "system"
    elif kind != ua.ObjectIds.BaseEventType:
        kind = "alarm"
    else:
        kind = "message" if source.startswith("MSG") and source[3:].isdigit() else "operator"
    message = event.Message.Text if isinstance(event.Message, ua.LocalizedText) else str(event.Message or "")
    return Row(rid, when.timestamp(), kind, PRIORITY_OF.get(int(event.Severity or 0)), None, source,
               int(source[3:]) if kind == "message" else None, None, message)
