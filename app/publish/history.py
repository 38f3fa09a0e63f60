"""Historical Access (OPC UA Part 11) from the station's own archive (registrar/): the raw values of
the tags it archives, and its journal as events.

Archived is a tag whose word an NSTORE of the program stores (its records' `source` is the octal
address, registrar/schema.py). Its variable has Historizing true and HistoryRead in its AccessLevel;
its history is the NSTORE series converted to physical units as the live tag is, each value with the
StatusCode of the quality the archive kept of it (app/scada/series.py: a value not good carries its
quality word, and a series turning bad has a record without a value). The journal (messages, alarm
transitions, operator actions, system records) is the event history of the station object and of
the Server object. Every other node answers Bad_HistoryOperationUnsupported, an unknown one
Bad_NodeIdUnknown; Read Modified, Processed and AtTime are unsupported (the archive never rewrites
a record and keeps no aggregates).

asyncua's HistoryManager stays the server's (its HistoryRead and HistoryUpdate services call it; it
refuses every update) with its read side replaced here: its storage interface resumes a read at the
timestamp of the first value not returned, which repeats the values sharing that timestamp; its
NumValuesPerNode truncates without a continuation point; and it checks no node and knows no
bounds, TimestampsToReturn or ReleaseContinuationPoints. From asyncua come the
result structures, `Event.to_event_fields` for an EventFilter's select clauses and its
WhereClauseEvaluator for the where clause (with the Like operator it lacks: `Where`).

The time domain is Part 11's (4.4, 6.5.3): the start is included and the end is not, so contiguous
reads see every value once; an end before the start, or an end with a count alone, reads backward;
ReturnBounds adds the value at or before the start and at or after the end (Bad_BoundNotFound with
the requested time where there is none). Continuation points are stateless: the position (day,
record id) after which a read resumes, checked against the request they came from, so the server
keeps nothing per session, nothing leaks when a client never comes back, and a value is delivered
exactly once (ids are unique and in time order). ReleaseContinuationPoints has nothing to free.

Reads run on a thread of their own, each on a fresh read-only connection, with at most MAX_VALUES
values or MAX_EVENTS events per answer and at most SCAN_ROWS journal rows examined for one: the
server's event loop never waits for SQLite, and since it encodes each answer (a few tens of
milliseconds for MAX_VALUES), a long range is read in pages that keep it responsive.
"""

from __future__ import annotations

import asyncio
import datetime as dt
import logging
import re
import sqlite3
import struct
import zlib
from collections.abc import Callable, Collection, Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from datetime import UTC, datetime
from functools import lru_cache
from pathlib import Path
from typing import Any

from asyncua import ua
from asyncua.common.events import Event
from asyncua.common.utils import ServiceError
from asyncua.server.history import HistoryManager
from asyncua.server.monitored_item_service import WhereClauseEvaluator

from app.publish.conditions import TWO_STATES
from app.publish.ua_types import SEVERITY, STATUS, python
from app.scada.alarms import State
from app.scada.quality import Quality
from app.scada.tag import Tag, TagType
from netplc.address import fmt_octal
from registrar.query import Archive
from registrar.reading import Filter, Row, SeriesKey, alarm_priority, spellings
from registrar.schema import day_bounds_in

logger = logging.getLogger(__name__)

MAX_VALUES = 2_000  # values of one node in one answer (HistoryServerCapabilities.MaxReturnDataValues)
MAX_EVENTS = 1_000  # events of one node in one answer (MaxReturnEventValues)
MAX_NODES = 100  # nodes in one HistoryRead (OperationLimits.MaxNodesPerHistoryReadData, ...Events)
SCAN_ROWS = 200_000  # archive records one answer of events examines at most (the journal among data)
JOURNAL = ("message", "alarm", "operator", "system")  # the record kinds that are events
_BASE_EVENT = ua.NodeId(ua.ObjectIds.BaseEventType)
_V = ua.VariantType
UNSPECIFIED = datetime(1601, 1, 2, tzinfo=UTC)  # DateTime.MinValue (and anything before): no time given
ARCHIVED_TYPES = (TagType.WORD, TagType.INT16, TagType.BCD)  # what NSTORE stores: one word
_POINT = struct.Struct(">BIqBII")  # version, day ordinal, id, tail, taken, check
_VERSION = 1
_FAR = 1 << 62  # beyond any time in ms
_S = ua.StatusCodes
_UINT32 = ua.VariantType.UInt32
EVENT_TYPES = {"system": ua.ObjectIds.SystemEventType}  # the rest are BaseEventType, as the live events
QUALITY_BY_WORD = {q.word: q for q in Quality}

Nstore = Mapping[str, Collection[tuple[int | None, int | None]]]  # source -> (grp, type) of its NSTOREs


@dataclass(frozen=True)
class Archived:
    """What the station archives: its local archive and the series the program's NSTOREs write
    (app.scada.series.nstore_keys). The plant archive on PostgreSQL is not read here."""

    path: Path
    nstore: Nstore


@dataclass(frozen=True)
class Series:
    """A tag's archived series: its records' key, and how a raw word becomes its variable's value."""

    tag: Tag
    key: SeriesKey
    kind: ua.VariantType


def series_of(tag: Tag, kind: ua.VariantType, nstore: Nstore) -> Series | None:
    """The series NSTORE writes of `tag`'s word (the lowest group and type where several do)."""
    if tag.type not in ARCHIVED_TYPES:
        return None
    source = fmt_octal(tag.address)
    keys = sorted((g, t) for g, t in nstore.get(source, ()) if g is not None and t is not None)
    return Series(tag, SeriesKey("data", keys[0][0], keys[0][1], source), kind) if keys else None


# --- the time domain and where a read resumes -------------------------------------------------

@dataclass(frozen=True)
class Domain:
    """The records a request asks for: first <= ts <= last (ms; None: open), read forward or
    backward; `start`/`end` the times given (ms; None: not given); `count` values at most in all
    (0: no limit)."""

    first: int | None
    last: int | None
    forward: bool
    start: int | None
    end: int | None
    count: int

    @property
    def in_all(self) -> bool:
        """Whether `count` is the number of values asked in all: with one time only (Part 11
        6.5.3.2); with both times it is the size of each answer."""
        return self.count > 0 and (self.start is None or self.end is None)


def domain(start: datetime | None, end: datetime | None, count: int) -> Domain | None:
    """The domain of a request, None when fewer than two of start, end and count are given."""
    s, e = _ms(start), _ms(end)
    if (s is None and e is None) or (count == 0 and (s is None or e is None)):
        return None
    if s is not None and e is not None:
        if s <= e:  # equal: the values at that time, time flowing forward
            return Domain(s, s if s == e else e - 1, True, s, e, count)
        return Domain(e + 1, s, False, s, e, count)
    if s is not None:
        return Domain(s, None, True, s, None, count)
    return Domain(None, e, False, None, e, count)


def _ms(t: datetime | None) -> int | None:
    if t is None:
        return None
    if t.tzinfo is None:
        t = t.replace(tzinfo=UTC)
    return None if t < UNSPECIFIED else round(t.timestamp() * 1000)


@dataclass(frozen=True)
class Position:
    """Where a read resumes: after record `id` of the day `day` (an ordinal; 0: before any record
    of the domain), or with only the far bound left (`tail`); `taken` values delivered so far."""

    day: int = 0
    id: int = 0
    tail: bool = False
    taken: int = 0

    def pack(self, check: int) -> bytes:
        return _POINT.pack(_VERSION, self.day, self.id, self.tail, self.taken, check)

    @staticmethod
    def unpack(data: bytes, check: int) -> Position | None:
        """None for a point that is not ours or belongs to another request."""
        if len(data) != _POINT.size:
            return None
        version, day, id_, tail, taken, was = _POINT.unpack(data)
        if version != _VERSION or was != check or tail > 1:
            return None
        return Position(day, id_, bool(tail), taken)


def _check(node: ua.NodeId, d: Domain, *more: object) -> int:
    """What ties a continuation point to its request: the node and the domain."""
    return zlib.crc32(repr((node.to_string(), d.first, d.last, d.forward, *more)).encode())


# --- reading the archive (on the history thread) ----------------------------------------------

Fetch = Callable[[dt.date, tuple[int, int], int], list[Row]]  # day, ids [lo, hi), limit -> rows
Located = tuple[int, Row]  # a record and its day's ordinal (an id is unique within its day)


def walk(archive: Archive, d: Domain, fetch: Fetch, after: Position | None, limit: int,
         scan: int | None = None) -> tuple[list[Located], Position | None]:
    """Up to `limit` records of the domain after `after`, in its order, with the position to
    resume after (None: nothing is left). `scan` bounds the ids examined (a window of the journal
    among data records); a read that reaches it resumes after the last id examined."""
    out: list[Located] = []
    forward = d.forward
    after_day = after.day if after is not None and after.day else None
    for day in sorted(archive.days(), reverse=not forward):
        o = day.toordinal()
        if after_day is not None and (o < after_day if forward else o > after_day):
            continue
        t0, t1 = (round(t * 1000) for t in day_bounds_in(day, archive.tz))  # [t0, t1)
        if (d.last is not None and t0 > d.last) or (d.first is not None and t1 <= d.first):
            continue
        lo = archive.first_at(day, max(d.first, t0) if d.first is not None else t0)
        hi = archive.first_at(day, min(d.last + 1, t1) if d.last is not None else t1)
        if after_day == o:
            assert after is not None
            lo, hi = (max(lo, after.id + 1), hi) if forward else (lo, min(hi, after.id))
        if lo >= hi:
            continue
        cut: Position | None = None
        if scan is not None:
            if scan <= 0:
                return out, Position(o, lo - 1 if forward else hi)
            if hi - lo > scan:
                lo, hi = (lo, lo + scan) if forward else (hi - scan, hi)
                cut = Position(o, hi - 1 if forward else lo)
            scan -= hi - lo
        out += [(o, row) for row in fetch(day, (lo, hi), limit + 1 - len(out))]
        if len(out) > limit:
            del out[limit:]
            return out, _after(out) or after or Position()
        if cut is not None:
            return out, cut
    return out, None


def _after(rows: list[Located]) -> Position | None:
    """The position after the last of `rows` (None: there is none)."""
    return Position(rows[-1][0], rows[-1][1].id) if rows else None


def _times(d: Domain) -> tuple[int, int]:
    return (d.first if d.first is not None else -_FAR, d.last if d.last is not None else _FAR)


Sample = tuple[int, Row | None]  # time (ms), and the record (None: no bound there, Bad_BoundNotFound)


def read_raw(archive: Archive, key: SeriesKey, d: Domain, bounds: bool, after: Position | None,
             limit: int) -> tuple[list[Sample], Position | None]:
    """The series' records of the domain after `after`, with its bounds when asked (both times
    given): the starting one first in the first answer, the far one last."""
    def fetch(times: tuple[int, int] | None, forward: bool) -> Fetch:
        return lambda day, ids, n: archive.window(day, ids, key=key, times=times, newest_first=not forward,
                                                  limit=n)

    def neighbour(first: int | None, last: int | None, forward: bool) -> Row | None:
        """The series' first record of [first, last] in that direction (a bound)."""
        near = Domain(first, last, forward, None, None, 1)
        rows, _ = walk(archive, near, fetch(None, forward), None, 1)
        return rows[0][1] if rows else None

    both = bounds and d.start is not None and d.end is not None and d.start != d.end
    out: list[Sample] = []
    if after is None or not after.tail:
        rows, resume = walk(archive, d, fetch(_times(d), d.forward), after, limit)
        if both and after is None and not (rows and round(rows[0][1].ts * 1000) == d.start):
            assert d.start is not None  # a record at the start is its own bound; else the one beyond
            bound = neighbour(None, d.start - 1, False) if d.forward else neighbour(d.start + 1, None, True)
            out.append(_sample(bound, d.start))
            if len(rows) == limit:  # the bound counts: the page's last record waits for the next
                rows.pop()
                resume = _after(rows) or Position()
        out += [_sample(r) for _, r in rows]
        if resume is not None or not both:
            return out, resume
        if len(out) >= limit:  # the far bound in an answer of its own
            return out, Position(tail=True)
    assert d.end is not None
    far = neighbour(d.end, None, True) if d.forward else neighbour(None, d.end, False)
    out.append(_sample(far, d.end))
    return out, None


def _sample(row: Row | None, missing: int = 0) -> Sample:
    """A record as a sample at its time; none at all (no bound found) at the time `missing`."""
    return (missing, None) if row is None else (round(row.ts * 1000), row)


def read_journal(archive: Archive, d: Domain, after: Position | None,
                 limit: int) -> tuple[list[Located], Position | None]:
    """The journal's records of the domain after `after`: at most `limit`, of at most SCAN_ROWS
    records examined."""
    times = _times(d)

    def fetch(day: dt.date, ids: tuple[int, int], n: int) -> list[Row]:
        return archive.window(day, ids, kinds=JOURNAL, times=times, newest_first=not d.forward, limit=n)

    return walk(archive, d, fetch, after, limit, SCAN_ROWS)


# --- values and events as a client receives them ----------------------------------------------

def data_value(series: Series, sample: Sample, stamps: ua.TimestampsToReturn) -> ua.DataValue:
    ms, row = sample
    when = datetime.fromtimestamp(ms / 1000, UTC)
    source = when if stamps in (ua.TimestampsToReturn.Source, ua.TimestampsToReturn.Both) else None
    server = when if stamps in (ua.TimestampsToReturn.Server, ua.TimestampsToReturn.Both) else None
    if row is None:
        return ua.DataValue(StatusCode=ua.StatusCode(_S.BadBoundNotFound), SourceTimestamp=source,
                            ServerTimestamp=server)
    quality = QUALITY_BY_WORD.get(row.text or "", Quality.GOOD)
    code = ua.StatusCode(STATUS[quality] if row.text is None or row.text in QUALITY_BY_WORD
                         else _S.UncertainNoCommunicationLastUsableValue)
    if row.value is None or code.is_bad():  # the series turned bad here; a bad value is no value
        return ua.DataValue(StatusCode=code, SourceTimestamp=source, ServerTimestamp=server)
    phy = series.tag.word_value(int(row.value))
    if phy != phy:  # a BCD word that is not BCD, as the live tag says it
        return ua.DataValue(StatusCode=ua.StatusCode(_S.BadOutOfRange), SourceTimestamp=source,
                            ServerTimestamp=server)
    return ua.DataValue(ua.Variant(python(series.kind)(phy), series.kind), StatusCode=code,
                        SourceTimestamp=source, ServerTimestamp=server)


@dataclass(frozen=True)
class AlarmSource:
    """An alarm's condition as its live events name it (conditions.py), so that its history says
    the same: the condition (ConditionId), its type, its source."""

    condition: ua.NodeId
    type_id: ua.NodeId
    source: ua.NodeId
    source_name: str


# what an alarm's new state says of ActiveState and AckedState (the others say neither)
ACTIVE_ACKED = {State.NORMAL: (False, True), State.UNACK: (True, False), State.ACKED: (True, True),
                State.RTNUN: (False, False)}


def event_of(located: Located, station: ua.NodeId, alarms: Mapping[str, AlarmSource]) -> Event:
    """A journal record as the event it was: BaseEventType's fields (a system record a
    SystemEventType), its EventId the record's day and id. An alarm's transition is its
    condition's event: the condition's type, source, ConditionName and ConditionId, and the
    ActiveState and AckedState the new state says."""
    day, row = located
    event = Event(station)
    when = datetime.fromtimestamp(row.ts, UTC)
    name, text, severity = _describe(row)
    kind = ua.NodeId(EVENT_TYPES.get(row.kind, ua.ObjectIds.BaseEventType))
    fields: dict[str, tuple[Any, ua.VariantType]] = {
        "EventId": (struct.pack(">Iq", day, row.id), _V.ByteString), "EventType": (kind, _V.NodeId),
        "SourceNode": (station, _V.NodeId), "SourceName": (name, _V.String), "Time": (when, _V.DateTime),
        "ReceiveTime": (when, _V.DateTime), "Message": (ua.LocalizedText(text), _V.LocalizedText),
        "Severity": (severity, _V.UInt16)}
    alarm = alarms.get(row.source or "") if row.kind == "alarm" else None
    if alarm is not None:
        fields.update({"EventType": (alarm.type_id, _V.NodeId), "SourceNode": (alarm.source, _V.NodeId),
                       "SourceName": (alarm.source_name, _V.String), "ConditionName": (row.source, _V.String),
                       "NodeId": (alarm.condition, _V.NodeId)})  # NodeId: the ConditionId's field
        for state, on in zip(("ActiveState", "AckedState"), ACTIVE_ACKED.get(State(row.type or 0), ())):
            fields[state] = (ua.LocalizedText(TWO_STATES[state][0 if on else 1]), _V.LocalizedText)
            fields[f"{state}/Id"] = (on, _V.Boolean)
    for field, (value, variant) in fields.items():
        event.add_property(field, value, variant)
    return event


def _describe(row: Row) -> tuple[str, str, int]:
    """SourceName, Message and Severity of a journal record."""
    text = row.text or ""
    if row.kind == "message":
        return f"MSG{row.number}", text or f"message {row.number}", SEVERITY[alarm_priority(row.type or 0)]
    if row.kind == "alarm":  # its text names the change, as the condition's event says it
        change = f"{row.source} {State(row.number or 0).word} -> {State(row.type or 0).word}"
        return row.source or "", text or change, SEVERITY.get(row.grp or 3, 500)
    return row.source or "", text, 100


# --- the where clause ----------------------------------------------------------------------------

@lru_cache(maxsize=64)
def like_pattern(pattern: str) -> re.Pattern[str]:
    """Part 4's Like pattern (7.7.3, its table of special characters) as a regular expression:
    `%` any text, `_` one character, `[...]` one of, `[^...]` none of, `\\` the next literally."""
    out, i = [], 0
    while i < len(pattern):
        c = pattern[i]
        if c == "\\" and i + 1 < len(pattern):
            out.append(re.escape(pattern[i + 1]))
            i += 2
            continue
        if c == "[" and (end := pattern.find("]", i + 2 if pattern[i + 1:i + 2] == "^" else i + 1)) > 0:
            inner = pattern[i + 1:end]
            negate = inner.startswith("^")
            body = "".join("\\" + ch if ch in "\\]^[" else ch for ch in inner[negate:])
            out.append(f"[{'^' if negate else ''}{body}]")
            i = end + 1
            continue
        out.append(".*" if c == "%" else "." if c == "_" else re.escape(c))
        i += 1
    return re.compile("".join(out), re.DOTALL)


class Where(WhereClauseEvaluator):
    """asyncua's where-clause evaluator with the Like operator it leaves unimplemented, so that a
    client filters the journal's events by their Message (a console's viewer: "text contains")."""

    def _like_operator(self, string: object, pattern: object) -> bool:
        text = string.Text if isinstance(string, ua.LocalizedText) else string
        if not isinstance(text, str) or not isinstance(pattern, str):
            return False
        return like_pattern(pattern).fullmatch(text) is not None


def _field(name: str) -> ua.SimpleAttributeOperand:
    return ua.SimpleAttributeOperand(TypeDefinitionId=_BASE_EVENT, BrowsePath=[ua.QualifiedName(name, 0)],
                                     AttributeId=ua.AttributeIds.Value)


def _literal(value: object, kind: ua.VariantType) -> ua.LiteralOperand:
    return ua.LiteralOperand(Value=ua.Variant(value, kind))


Spec = tuple[ua.FilterOperator, list]  # an element: its operator and operands (a Spec: a sub-element)


def _all(op: ua.FilterOperator, specs: list[Spec]) -> Spec:
    """`specs` joined pairwise by `op` (And, Or), as the binary operators of Part 4 take them."""
    return specs[0] if len(specs) == 1 else (op, [specs[0], _all(op, specs[1:])])


def _elements(spec: Spec, out: list[ua.ContentFilterElement]) -> int:
    """`spec` and what it refers to into `out`, each element before its operands (the first the root)."""
    op, operands = spec
    at, element = len(out), ua.ContentFilterElement(FilterOperator=op)
    out.append(element)
    element.FilterOperands = [ua.ElementOperand(Index=_elements(o, out)) if isinstance(o, tuple) else o
                              for o in operands]
    return at


def like(text: str) -> str:
    """"Contains `text`" as a Like pattern (Part 4 7.7.3: its special characters escaped)."""
    return "%" + "".join("\\" + c if c in "%_[]\\" else c for c in text) + "%"


def _severity(op: ua.FilterOperator, message_type: int) -> Spec:
    """The events' Severity against a message type's (`_describe`: an alarm's by its priority)."""
    return op, [_field("Severity"), _literal(SEVERITY[alarm_priority(message_type)], _V.UInt16)]


def journal_where(flt: Filter) -> ua.ContentFilter:
    """The part of a journal's `Filter` a station evaluates on its events (a console's viewer,
    app/gui/console/archive.py): a type as a Severity (`_describe`), a source as the SourceName,
    a text as Like on the Message. Its From/To is the read's time range; a kind is told from the
    events' types by the client, and a group is in no event."""
    specs: list[Spec] = []
    if flt.min_type is not None:  # a message's type and worse, an alarm's priority and higher
        specs.append(_severity(ua.FilterOperator.GreaterThanOrEqual, flt.min_type))
    if flt.type is not None:
        specs.append(_severity(ua.FilterOperator.Equals, flt.type))
    if flt.source is not None:
        specs.append((ua.FilterOperator.Equals, [_field("SourceName"), _literal(flt.source, _V.String)]))
    if flt.text:  # in the spellings the local archive tries
        specs.append(_all(ua.FilterOperator.Or, [
            (ua.FilterOperator.Like, [_field("Message"), _literal(like(s), _V.String)])
            for s in spellings(flt.text)]))
    out: list[ua.ContentFilterElement] = []
    if specs:
        _elements(_all(ua.FilterOperator.And, specs), out)
    return ua.ContentFilter(Elements=out)


# --- the service --------------------------------------------------------------------------------

class StationHistory(HistoryManager):
    """The server's history manager, reading the station's archive."""

    def __init__(self, iserver: Any, archived: Archived | None, series: Mapping[ua.NodeId, Series],
                 station: ua.NodeId, alarms: Mapping[str, AlarmSource]) -> None:
        """`series`: the archived tags' variables; `station`: the station object, whose event
        history is the journal, as the Server object's is; `alarms`: the alarms' conditions."""
        super().__init__(iserver)
        self.archived = archived
        self.series = dict(series)
        self.station = station
        self.alarms = dict(alarms)
        self.notifiers = [ua.NodeId(ua.ObjectIds.Server), station] if archived is not None else []
        self._executor = ThreadPoolExecutor(1, thread_name_prefix="opcua-history")

    async def stop(self) -> None:
        self._executor.shutdown(wait=True, cancel_futures=True)
        await super().stop()

    async def read_history(self, params: ua.HistoryReadParameters) -> list[ua.HistoryReadResult]:
        if params.TimestampsToReturn not in (ua.TimestampsToReturn.Source, ua.TimestampsToReturn.Server,
                                             ua.TimestampsToReturn.Both):
            raise ServiceError(_S.BadTimestampsToReturnInvalid)
        if not params.NodesToRead:
            raise ServiceError(_S.BadNothingToDo)
        if len(params.NodesToRead) > MAX_NODES:
            raise ServiceError(_S.BadTooManyOperations)
        return [await self._read(params, rv) for rv in params.NodesToRead]

    async def _read(self, params: ua.HistoryReadParameters,
                    rv: ua.HistoryReadValueId) -> ua.HistoryReadResult:
        details = params.HistoryReadDetails
        raw = isinstance(details, ua.ReadRawModifiedDetails)
        events = isinstance(details, ua.ReadEventDetails)
        series = self.series.get(rv.NodeId) if raw else None
        ours = series is not None or (events and rv.NodeId in self.notifiers)
        if not ours:
            known = rv.NodeId in self.iserver.aspace
            return _failed(_S.BadHistoryOperationUnsupported if known else _S.BadNodeIdUnknown)
        if raw and details.IsReadModified:
            return _failed(_S.BadHistoryOperationUnsupported)  # the archive never rewrites a record
        if params.ReleaseContinuationPoints:
            return ua.HistoryReadResult(StatusCode=ua.StatusCode(_S.Good))  # stateless: nothing to free
        if events and not isinstance(details.Filter, ua.EventFilter):
            return _failed(_S.BadEventFilterInvalid)
        d = domain(details.StartTime, details.EndTime, details.NumValuesPerNode)
        if d is None:
            return _failed(_S.BadHistoryOperationInvalid)
        check = _check(rv.NodeId, d, details.ReturnBounds) if raw else _check(rv.NodeId, d)
        after = None
        if rv.ContinuationPoint:
            after = Position.unpack(rv.ContinuationPoint, check)
            if after is None:
                return _failed(_S.BadContinuationPointInvalid)
        cap = MAX_VALUES if raw else MAX_EVENTS
        taken = after.taken if after is not None else 0
        limit = min(cap, d.count - taken) if d.in_all else min(cap, d.count or cap)
        try:
            if series is not None:
                result, resume, n = await self._run(self._raw, series, d, details.ReturnBounds, after, limit,
                                                    params.TimestampsToReturn)
            else:
                result, resume, n = await self._run(self._events, details.Filter, d, after, limit)
        except (sqlite3.Error, OSError) as e:
            logger.exception("history of %s not read from %s", rv.NodeId.to_string(),
                             self.archived.path if self.archived else "no archive")
            return _failed(_S.BadNoData if isinstance(e, FileNotFoundError) else _S.BadInternalError)
        if resume is not None and d.in_all and taken + n >= d.count:
            resume = None  # the count asked for is reached
        point = None if resume is None else \
            Position(resume.day, resume.id, resume.tail, taken + n).pack(check)
        empty = n == 0 and point is None
        return ua.HistoryReadResult(StatusCode=ua.StatusCode(_S.GoodNoData if empty else _S.Good),
                                    ContinuationPoint=point, HistoryData=result)

    async def _run(self, fn: Callable[..., Any], *args: Any) -> Any:
        return await asyncio.get_running_loop().run_in_executor(self._executor, fn, *args)

    def _open(self) -> Archive:
        if self.archived is None:
            raise FileNotFoundError("the station has no archive")
        return Archive(self.archived.path)

    def _raw(self, series: Series, d: Domain, bounds: bool, after: Position | None, limit: int,
             stamps: ua.TimestampsToReturn) -> tuple[ua.HistoryData, Position | None, int]:
        with self._open() as archive:
            samples, resume = read_raw(archive, series.key, d, bounds, after, limit)
        values = [data_value(series, s, stamps) for s in samples]
        return ua.HistoryData(DataValues=values), resume, len(values)

    def _events(self, flt: ua.EventFilter, d: Domain, after: Position | None,
                limit: int) -> tuple[ua.HistoryEvent, Position | None, int]:
        with self._open() as archive:
            rows, resume = read_journal(archive, d, after, limit)
        where = Where(logger, self.iserver.aspace, flt.WhereClause)
        events = [event for event in (event_of(row, self.station, self.alarms) for row in rows)
                  if where.eval(event)]
        fields = [ua.HistoryEventFieldList(EventFields=e.to_event_fields(flt.SelectClauses)) for e in events]
        return ua.HistoryEvent(Events=fields), resume, len(fields)


def _failed(code: int) -> ua.HistoryReadResult:
    return ua.HistoryReadResult(StatusCode=ua.StatusCode(code))


async def install(server: Any, history: StationHistory) -> None:
    """Put the station's history manager in asyncua's place, let its notifiers say they keep event
    history, and fill in HistoryServerCapabilities (Part 11 5.4.2)."""
    server.iserver.history_manager = history
    for node in history.notifiers:
        await server.get_node(node).set_attr_bit(ua.AttributeIds.EventNotifier, ua.EventNotifier.HistoryRead)
    capabilities = {
        ua.ObjectIds.HistoryServerCapabilities_AccessHistoryDataCapability: bool(history.series),
        ua.ObjectIds.HistoryServerCapabilities_AccessHistoryEventsCapability: bool(history.notifiers),
        ua.ObjectIds.HistoryServerCapabilities_MaxReturnDataValues: ua.Variant(MAX_VALUES, _UINT32),
        ua.ObjectIds.HistoryServerCapabilities_MaxReturnEventValues: ua.Variant(MAX_EVENTS, _UINT32),
        ua.ObjectIds.HistoryServerCapabilities_ServerTimestampSupported: True,
        **{getattr(ua.ObjectIds, f"HistoryServerCapabilities_{name}Capability"): False for name in (
            "InsertData", "ReplaceData", "UpdateData", "DeleteRaw", "DeleteAtTime", "InsertAnnotation",
            "InsertEvent", "ReplaceEvent", "UpdateEvent", "DeleteEvent")},
    }
    for nodeid, value in capabilities.items():
        await server.get_node(nodeid).write_value(value)
    await server.get_node(ua.ObjectIds.Server_ServerCapabilities_MaxHistoryContinuationPoints).write_value(
        ua.Variant(0, ua.VariantType.UInt16))  # none kept: no limit
    for limit in (ua.ObjectIds.Server_ServerCapabilities_OperationLimits_MaxNodesPerHistoryReadData,
                  ua.ObjectIds.Server_ServerCapabilities_OperationLimits_MaxNodesPerHistoryReadEvents):
        await server.get_node(limit).write_value(ua.Variant(MAX_NODES, _UINT32))

