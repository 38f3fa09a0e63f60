"""The station's ISA-18.2 alarms as OPC UA Alarms & Conditions (Part 9), for any A&C client.

Each configured alarm is one condition instance (one per alarm identity, as the station has one),
an Object in the station's Alarms folder with the stable NodeId `Alarms.<id>` and its children
`Alarms.<id>.<BrowseName>...`, of the standard type that fits its source:

    H, HH, L, LL limits      ExclusiveLevelAlarmType, its one limit (HighLimit...) and LimitState
    a bit's value            OffNormalAlarmType (NormalState: a NormalValue variable for a bit)
    a tag's bad quality      SystemOffNormalAlarmType
    NetPlc not running       SystemOffNormalAlarmType (InputNode NetPlc.State, normal "running")
    a pair with no standby   SystemOffNormalAlarmType (PAIR.NO_STANDBY: no input variable)
    NMSG alarm messages      AlarmConditionType (raised by the program: no input variable)

with the optional ShelvingState, SuppressedState, OutOfServiceState and the RemoveFromService and
PlaceInService methods, and three properties of the station's own: State (the ISA-18.2 state
word), Priority and Text. The source (SourceNode, SourceName) is the alarm's tag variable, or the
NetPlc object; it has a HasCondition reference to the condition, and the Server object notifies
the station object (HasNotifier), which has the sources as event sources (HasEventSource).

The station's alarm model stays the one truth (app/scada/alarms.py): a condition is what the last
transition of its alarm left, copied on the engine thread as the transition is journaled (`post`),
so its fields and its event agree with the journal record, whichever seat acted; on a hot-standby
pair's standby, what the primary's states it adopted left (`adopt`: no transition of its own), so
the new primary's conditions are its alarms' states from its first scan on. Its fields:
ActiveState = active (a latched alarm stays active until acknowledged), AckedState = acknowledged,
EnabledState = in service (out of service is disabled and OutOfServiceState), SuppressedState =
suppressed by design, ShelvingState Unshelved / TimedShelved / OneShotShelved with UnshelveTime
(ms left, as of the last event), SuppressedOrShelved, Retain = enabled and (active or
unacknowledged), Severity from the priority (1 critical 900 ... 4 low 300), Message = the
transition's journal text, Time = the transition's time, Quality = the input variable's status,
Comment and ClientUserId = the alarm's last comment and who gave it, BranchId null (no branches).

Every transition is one event: a new EventId, sent to the event monitored items of the Server
object (i=2253) and of the station object whose filter it passes. The methods are the station's
commands (app/authority/) with the session's user, taken in the session's Call service like the
station's own methods (methods.py: `arguments`, `answered`), with the condition's NodeId (or its
ShelvingState's) as ObjectId and either the instance's method or the type's (Part 9 lets a client
use the ConditionId with the type's MethodId):

    Acknowledge(EventId, Comment)      acknowledge (operator), the comment journaled with it
    AddComment(EventId, Comment)       comment (operator): a journal record of the alarm
    TimedShelve(ShelvingTime ms)       shelve for that long (operator)
    OneShotShelve()                    shelve until the condition next returns to normal (operator)
    Unshelve()                         unshelve (operator)
    Disable(), RemoveFromService()     take out of service (engineer)
    Enable(), PlaceInService()         return to service (engineer)

Part 9's answers that depend on the condition's state are given from the state its last event
showed (Bad_EventIdUnknown for an EventId it never sent or no longer knows, Bad_ConditionBranch-
AlreadyAcked, Bad_ConditionAlreadyShelved, Bad_ConditionNotShelved, Bad_ConditionAlreadyEnabled
/ Disabled, Bad_ShelvingTimeOutOfRange), each journaled as a refusal by the layer; the role is
the layer's answer (Bad_UserAccessDenied, journaled once per cause). UserExecutable of a
condition's methods is answered per session from the same policy.

What asyncua (2.1) has and what is filled here. It ships the types (the standard nodeset) and an
event class per type, and no behaviour behind them:
- instances: its `instantiate` browses the type's hierarchy again for every instance (0.1 s each),
  so condition_nodes.py reads each type's declarations once and copies the nodes of each shape;
- events: its event generator fires at one notifier and knows nothing of conditions, and its Event
  deep-copies every field for every monitored item, so each event is a `Notification` built here
  from the condition's fields (the values its variables hold), queued to the event monitored items
  of every notifier in the chain through each one's filter;
- methods: the condition methods have no implementation; they are taken here;
- refresh: its ConditionRefresh (bound only on request) keeps one event per condition at one
  notifier, passes the RefreshStart/End events through the client's WhereClause (Part 9 4.5: they
  ignore it) and does not check that the subscription is the caller's. ConditionRefresh (i=3875)
  and ConditionRefresh2 (i=12912) are answered here instead: called on the ConditionType (i=2782)
  for a subscription of the calling session, one RefreshStart event to each of its event monitored
  items (or to the one named), the last event of every retained condition (its EventId unchanged)
  to each whose filter it passes, then one RefreshEnd event.
Monitored items are reached through asyncua's MonitoredItemService internals (`_monitored_events`,
`_monitored_items`), pinned with asyncua ~=2.1.

Where this deviates from Part 9: no ConfirmedState or Confirm (the station's ISA-18.2 model has
no confirmation); no branches (BranchId is always null: an alarm has one state, as in the
station's summary); TimedShelve and OneShotShelve carry no reason, so the journal names the method
as the reason; a OneShotShelved alarm returns after a day at the latest (ONE_SHOT_LIMIT, as a
MaxTimeShelved would); no LatchedState or Reset: a latched alarm acknowledged while active is reset
by the station's own Acknowledge (methods.py) or at the workstation; UnshelveTime is as of the
last event, not counted down between events; no Audit events (the station's journal records every
action with its user).
"""

from __future__ import annotations

import asyncio
import copy
import logging
import math
import time
import uuid
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any

from asyncua import Node, Server, ua

from app.authority import Action, Commands, Reason, Ticket, Who
from app.publish import condition_nodes as nodes
from app.publish.methods import answered, arguments
from app.publish.ua_types import SEVERITY
from app.scada.alarms import ONE_SHOT_LIMIT, PRIORITIES, STOPPED_ID, Alarm, Source
from netplc.records import Record

logger = logging.getLogger(__name__)

_O, _S, _V = ua.ObjectIds, ua.StatusCodes, ua.VariantType
TYPES = {Source.LIMIT: _O.ExclusiveLevelAlarmType, Source.DISCRETE: _O.OffNormalAlarmType,
         Source.QUALITY: _O.SystemOffNormalAlarmType, Source.STATION: _O.SystemOffNormalAlarmType,
         Source.MESSAGE: _O.AlarmConditionType}
PROCESS = (ua.NodeId(_O.ProcessConditionClassType), ua.LocalizedText("Process"))
SYSTEM = (ua.NodeId(_O.SystemConditionClassType), ua.LocalizedText("System"))
CLASSES = {Source.LIMIT: PROCESS, Source.DISCRETE: PROCESS, Source.MESSAGE: PROCESS,
           Source.QUALITY: SYSTEM, Source.STATION: SYSTEM}
LIMITS = {"HH": ("HighHighLimit", "HighHigh", _O.ExclusiveLimitStateMachineType_HighHigh),
          "H": ("HighLimit", "High", _O.ExclusiveLimitStateMachineType_High),
          "L": ("LowLimit", "Low", _O.ExclusiveLimitStateMachineType_Low),
          "LL": ("LowLowLimit", "LowLow", _O.ExclusiveLimitStateMachineType_LowLow)}
OPTIONAL = frozenset(("ShelvingState", "SuppressedState", "OutOfServiceState", "RemoveFromService",
                      "PlaceInService"))
SHELVING = {None: ("Unshelved", _O.ShelvedStateMachineType_Unshelved),  # by one_shot; None: not shelved
            False: ("TimedShelved", _O.ShelvedStateMachineType_TimedShelved),
            True: ("OneShotShelved", _O.ShelvedStateMachineType_OneShotShelved)}
# the methods of the types, which a client may call with a ConditionId (or a ShelvingState) as ObjectId
DECLARED = {_O.AcknowledgeableConditionType_Acknowledge: "Acknowledge",
            _O.ConditionType_AddComment: "AddComment", _O.ConditionType_Enable: "Enable",
            _O.ConditionType_Disable: "Disable",
            _O.AlarmConditionType_RemoveFromService: "RemoveFromService",
            _O.AlarmConditionType_PlaceInService: "PlaceInService",
            _O.ShelvedStateMachineType_TimedShelve: "TimedShelve",
            _O.ShelvedStateMachineType_OneShotShelve: "OneShotShelve",
            _O.ShelvedStateMachineType_Unshelve: "Unshelve",
            _O.AlarmConditionType_ShelvingState_TimedShelve: "TimedShelve",
            _O.AlarmConditionType_ShelvingState_OneShotShelve: "OneShotShelve",
            _O.AlarmConditionType_ShelvingState_Unshelve: "Unshelve"}
ACTIONS = {"Acknowledge": Action.ACKNOWLEDGE, "AddComment": Action.COMMENT, "TimedShelve": Action.SHELVE,
           "OneShotShelve": Action.SHELVE, "Unshelve": Action.UNSHELVE, "Disable": Action.OUT_OF_SERVICE,
           "RemoveFromService": Action.OUT_OF_SERVICE, "Enable": Action.OUT_OF_SERVICE,
           "PlaceInService": Action.OUT_OF_SERVICE}
ARITY = {"Acknowledge": 2, "AddComment": 2, "TimedShelve": 1}  # the others take none
ON_SHELVING = frozenset(("TimedShelve", "OneShotShelve", "Unshelve"))  # methods of the ShelvingState
REFRESH = ua.NodeId(_O.ConditionType_ConditionRefresh)
REFRESH2 = ua.NodeId(_O.ConditionType_ConditionRefresh2)
REMEMBERED = 64  # EventIds a condition keeps to answer an Acknowledge or AddComment
TWO_STATES = {"EnabledState": ("Enabled", "Disabled"), "ActiveState": ("Active", "Inactive"),
              "AckedState": ("Acknowledged", "Unacknowledged"),
              "SuppressedState": ("Suppressed", "Unsuppressed"),
              "OutOfServiceState": ("Out of Service", "In Service")}  # Part 9 Annex A's state names


class Notification:
    """One event: its fields by name ("AckedState/Id"; "NodeId" the ConditionId), each Variant made
    for it alone and shared by every monitored item it goes to (asyncua's Event deep-copies every
    field for every one). What asyncua's WhereClause evaluation asks of an event: its fields'
    values as attributes."""

    def __init__(self, fields: dict[str, ua.Variant]) -> None:
        self.fields = fields

    def __getattr__(self, name: str) -> Any:
        try:
            return self.__dict__["fields"][name].Value
        except KeyError:
            raise AttributeError(name) from None

    def to_event_fields(self, select: list[ua.SimpleAttributeOperand]) -> list[ua.Variant]:
        """The fields a monitored item's SelectClauses ask, null where there is none."""
        return [self.fields.get("/".join(q.Name for q in op.BrowsePath) if op.BrowsePath else
                                ua.AttributeIds(op.AttributeId).name, NULL) for op in select]


NULL = ua.Variant()


@dataclass
class Condition:
    """One alarm's condition: its nodes, and what its last event said."""

    alarm: Alarm  # as its last transition left it (a copy)
    nodeid: ua.NodeId
    type_id: ua.NodeId
    source: ua.NodeId
    source_name: str
    input: ua.NodeId
    normal: ua.NodeId
    shelving: ua.NodeId  # its ShelvingState object
    nodes: dict[str, ua.NodeId]  # its variables by field name ("AckedState/Id")
    methods: dict[ua.NodeId, str]  # its method nodes -> what they do
    event: Notification | None = None  # the last one: what a refresh sends again
    retain: bool = False  # of the last event
    acked: bool = True  # of the last event
    episode: int = 0  # counts the times it became unacknowledged
    known: OrderedDict[bytes, int] = field(default_factory=OrderedDict)  # EventId -> its episode
    comment: tuple[str, str] = ("", "")  # the last comment and who gave it, as shown
    fixed: dict[str, ua.Variant] = field(default_factory=dict)  # what never changes: Priority, NormalValue
    shown: dict[str, ua.Variant] = field(default_factory=dict)  # what its variables hold
    comment_time: datetime | None = None


class Conditions:
    """The conditions of a station's alarms in one asyncua server; runs on the server's loop except
    `post` (the engine thread)."""

    def __init__(self, commands: Commands, answers: dict[Reason, int], alarms: Sequence[Alarm]) -> None:
        self.commands = commands
        self.answers = answers
        self.alarms = {a.id: a for a in alarms}  # the station's live alarms (mutated on the engine thread)
        self.by_id: dict[str, Condition] = {}
        self.by_node: dict[ua.NodeId, Condition] = {}  # a condition or its ShelvingState
        self.methods: dict[ua.NodeId, tuple[Condition, str]] = {}  # instance method nodes
        self.notifiers: list[ua.NodeId] = []
        self.server: Server | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._queue: asyncio.Queue[tuple[Alarm, Record | None]] | None = None
        self._worker: asyncio.Task[None] | None = None
        self._lock = asyncio.Lock()  # events and refreshes one at a time, in order
        self._refreshing: set[int] = set()  # subscriptions being refreshed

    # --- the address space ---------------------------------------------------------------------

    async def build(self, server: Server, idx: int, folder: Node, station: Node,
                    sources: dict[str, ua.NodeId], plc: Node, plc_state: ua.NodeId) -> None:
        """One condition per alarm in `folder`; `sources` the tag variables by tag name."""
        self.server = server
        self._loop = asyncio.get_running_loop()
        self._queue = asyncio.Queue()
        aspace = server.iserver.aspace
        first: dict[tuple[int, str, ua.VariantType | None], list[ua.NodeId]] = {}  # of each shape
        for alarm in self.alarms.values():
            d = alarm.defn
            key = d.id.rsplit(".", 1)[-1] if d.source is Source.LIMIT else ""
            normal: ua.Variant | None = None  # the input's value when normal, where it has one
            if d.id == STOPPED_ID:  # PAIR.NO_STANDBY, the other station alarm, has no input variable
                normal = ua.Variant("running", _V.String)
            elif d.source is Source.DISCRETE and d.tag in sources and await _is_bit(server, sources[d.tag]):
                normal = ua.Variant(not d.when, _V.Boolean)
            shape = (TYPES[d.source], key, None if normal is None else normal.VariantType)
            optional = OPTIONAL | ({LIMITS[key][0]} if key in LIMITS else set())
            declared = await nodes.template(server, shape[0], optional) + nodes.own(idx, shape[2])
            root = f"Alarms.{d.id}"
            ids = [ua.NodeId(root, idx), *(ua.NodeId(".".join((root, *n.path)), idx) for n in declared)]
            if shape in first:
                nodes.clone(aspace, first[shape], ids, alarm.text)
            else:
                await nodes.add(server, ids, declared, folder.nodeid, shape[0], alarm.text)
                first[shape] = ids
            variables = {n.field: nodeid for n, nodeid in zip(declared, ids[1:])
                         if n.item.NodeClass == ua.NodeClass.Variable and n.path[-1] != "InputArguments"}
            methods = {nodeid: n.path[-1] for n, nodeid in zip(declared, ids[1:])
                       if n.item.NodeClass == ua.NodeClass.Method}
            if d.tag is not None and d.tag in sources:
                source, source_name, input_ = sources[d.tag], d.tag, sources[d.tag]
            else:
                source, source_name = plc.nodeid, "NetPlc"
                input_ = plc_state if d.id == STOPPED_ID else ua.NodeId()
            c = Condition(copy.copy(alarm), ids[0], ua.NodeId(shape[0]), source, source_name, input_,
                          variables.get("NormalValue", ua.NodeId()), ua.NodeId(f"{root}.ShelvingState", idx),
                          variables, methods)
            c.fixed["Priority"] = ua.Variant(PRIORITIES.get(d.priority, ""), _V.String)
            if normal is not None:
                c.fixed["NormalValue"] = normal
            self.by_id[d.id] = self.by_node[c.nodeid] = self.by_node[c.shelving] = c
            self.methods.update((node, (c, name)) for node, name in methods.items())
        await self._references(server, station, plc)
        for c in self.by_id.values():
            a = c.alarm
            await self._show(c, _stated(a), a.changed or time.time())
        self._worker = asyncio.get_running_loop().create_task(self._work())

    async def _references(self, server: Server, station: Node, plc: Node) -> None:
        """Server -HasNotifier-> station -HasEventSource-> each source -HasCondition-> its conditions."""
        await station.set_event_notifier([ua.EventNotifier.SubscribeToEvents])
        server_node = ua.NodeId(_O.Server)
        self.notifiers = [server_node, station.nodeid]
        refs = [nodes.reference(server_node, _O.HasNotifier, station.nodeid, ua.NodeClass.Object)]
        sources: dict[ua.NodeId, None] = {}
        for c in self.by_id.values():
            sources.setdefault(c.source)
            refs.append(nodes.reference(c.source, _O.HasCondition, c.nodeid, ua.NodeClass.Object))
        refs += [nodes.reference(station.nodeid, _O.HasEventSource, s,
                                 ua.NodeClass.Object if s == plc.nodeid else ua.NodeClass.Variable)
                 for s in sources]
        for result in await server.iserver.isession.add_references(refs):
            result.check()

    # --- transitions ---------------------------------------------------------------------------

    def post(self, record: Record) -> None:
        """The runtime's record observer, on the thread that journals the transition (the engine's):
        the alarm as this transition left it, handed to the server's loop."""
        self._hand(record.source or "", record)

    def adopt(self, alarm_ids: Sequence[str]) -> None:
        """On the engine thread: alarms whose states a pair's standby took from its primary
        (StationAlarms.adopt), which journals no transition for them: each condition shows its
        alarm's state as it is now, with an event (its message the state, as at the start), so a
        client of the standby, and of it once it leads, sees the primary's alarms."""
        for alarm_id in alarm_ids:
            self._hand(alarm_id, None)

    def _hand(self, alarm_id: str, record: Record | None) -> None:
        alarm, loop, queue = self.alarms.get(alarm_id), self._loop, self._queue
        if alarm is None or loop is None or queue is None:
            return
        view = copy.copy(alarm)
        try:
            loop.call_soon_threadsafe(queue.put_nowait, (view, record))
        except RuntimeError:  # no log: the server's loop has closed (the station is stopping)
            return

    async def _work(self) -> None:
        """The transitions in the order they were journaled, each giving the loop a turn (a flood
        of them does not keep the server from its clients)."""
        assert self._queue is not None
        while True:
            alarm, record = await self._queue.get()
            try:
                c = self.by_id[alarm.id]
                c.alarm = alarm
                if record is None:  # adopted from a pair's primary: no transition of this station's
                    text, ts = _stated(alarm), alarm.changed or time.time()
                else:
                    text, ts = record.text or "", record.ts
                async with self._lock:
                    event = await self._show(c, text, ts)
                    await self._send(event, list(self._subscriptions()))
            except Exception:  # the next transition is shown all the same
                logger.exception("condition %s not updated", alarm.id)
            await asyncio.sleep(0)

    async def _show(self, c: Condition, text: str, ts: float) -> Notification:
        """The condition's variables and its new event, as `c.alarm` is now."""
        assert self.server is not None
        aspace = self.server.iserver.aspace
        a = c.alarm
        when = datetime.fromtimestamp(ts, UTC)
        if (a.comment, a.comment_by) != c.comment:
            c.comment, c.comment_time = (a.comment, a.comment_by), when
        fields = self._fields(c, text, when, aspace)
        values = {**fields, **c.fixed, "State": ua.Variant(a.state.word, _V.String),
                  "Text": ua.Variant(a.text, _V.String)}  # the station's own properties: not event fields
        for name, nodeid in c.nodes.items():
            variant = values.get(name)
            if variant is not None and variant != c.shown.get(name):  # what changed, at its time
                result = await aspace.write_attribute_value(nodeid, ua.AttributeIds.Value,
                                                            ua.DataValue(variant, SourceTimestamp=when))
                if not result.is_good():
                    logger.error("condition variable %s not written: %s", nodeid.to_string(), result)
                c.shown[name] = variant
        event = Notification({**fields, "NodeId": ua.Variant(c.nodeid, _V.NodeId)})  # NodeId: the ConditionId
        if c.acked and not a.acked:
            c.episode += 1  # unacknowledged anew: the events before need no acknowledgement now
        c.known[fields["EventId"].Value] = c.episode
        while len(c.known) > REMEMBERED:
            c.known.popitem(last=False)
        c.event, c.retain, c.acked = event, fields["Retain"].Value, a.acked
        return event

    def _fields(self, c: Condition, text: str, when: datetime, aspace: Any) -> dict[str, ua.Variant]:
        """The condition's event fields (by field name, as its variables' paths) for `c.alarm`."""
        a, d = c.alarm, c.alarm.defn
        enabled = not a.out_of_service
        shelved = None if a.shelved_until is None else a.shelved_until - time.time()
        severity = ua.Variant(SEVERITY.get(d.priority, 500), _V.UInt16)
        quality, stamp = ua.StatusCode(_S.Good), when
        if not c.input.is_null() and c.input in aspace:  # the input variable's status
            dv = aspace.read_attribute_value(c.input, ua.AttributeIds.Value)
            quality, stamp = dv.StatusCode or quality, dv.SourceTimestamp or when
        state_name, state_id = SHELVING[None if shelved is None else a.one_shot]
        out = {
            "EventId": ua.Variant(uuid.uuid4().bytes, _V.ByteString),
            "EventType": ua.Variant(c.type_id, _V.NodeId),
            "SourceNode": ua.Variant(c.source, _V.NodeId),
            "SourceName": ua.Variant(c.source_name, _V.String),
            "Time": ua.Variant(when, _V.DateTime),
            "ReceiveTime": ua.Variant(datetime.now(UTC), _V.DateTime),
            "Message": ua.Variant(ua.LocalizedText(text), _V.LocalizedText),
            "Severity": severity,
            "ConditionClassId": ua.Variant(CLASSES[d.source][0], _V.NodeId),
            "ConditionClassName": ua.Variant(CLASSES[d.source][1], _V.LocalizedText),
            "ConditionName": ua.Variant(d.id, _V.String),
            "BranchId": ua.Variant(ua.NodeId(), _V.NodeId),
            "Retain": ua.Variant(enabled and (a.active or not a.acked), _V.Boolean),
            "Quality": ua.Variant(quality, _V.StatusCode),
            "Quality/SourceTimestamp": ua.Variant(stamp, _V.DateTime),
            "LastSeverity": severity,
            "LastSeverity/SourceTimestamp": ua.Variant(when, _V.DateTime),
            "Comment": ua.Variant(ua.LocalizedText(a.comment), _V.LocalizedText),
            "Comment/SourceTimestamp": _maybe(c.comment_time, _V.DateTime),
            "ClientUserId": ua.Variant(a.comment_by, _V.String),
            "InputNode": ua.Variant(c.input, _V.NodeId),
            "SuppressedOrShelved": ua.Variant(a.suppressed or shelved is not None, _V.Boolean),
            "ShelvingState/CurrentState": ua.Variant(ua.LocalizedText(state_name), _V.LocalizedText),
            "ShelvingState/CurrentState/Id": ua.Variant(ua.NodeId(state_id), _V.NodeId),
            "ShelvingState/UnshelveTime": ua.Variant(max(0.0, shelved or 0.0) * 1000.0, _V.Double),
        }
        for name, on in (("EnabledState", enabled), ("ActiveState", a.active), ("AckedState", a.acked),
                         ("SuppressedState", a.suppressed), ("OutOfServiceState", a.out_of_service)):
            out[name] = ua.Variant(ua.LocalizedText(TWO_STATES[name][0 if on else 1]), _V.LocalizedText)
            out[f"{name}/Id"] = ua.Variant(on, _V.Boolean)
        if "NormalState" in c.nodes:
            out["NormalState"] = ua.Variant(c.normal, _V.NodeId)
        key = d.id.rsplit(".", 1)[-1]
        if d.source is Source.LIMIT and key in LIMITS:
            limit, state, state_node = LIMITS[key]
            out[limit] = ua.Variant(d.limit, _V.Double)
            out["LimitState/CurrentState"] = _maybe(ua.LocalizedText(state) if a.active else None,
                                                    _V.LocalizedText)
            out["LimitState/CurrentState/Id"] = _maybe(ua.NodeId(state_node) if a.active else None, _V.NodeId)
        return out

    # --- subscriptions -------------------------------------------------------------------------

    def _subscriptions(self) -> Any:
        assert self.server is not None
        return self.server.iserver.subscription_service.subscriptions.values()

    async def _send(self, event: Notification, subscriptions: list[Any],
                    mids: set[int] | None = None) -> None:
        """`event` to the event monitored items of the notifiers in its chain whose filter it
        passes (of `mids` only, when given)."""
        for sub in subscriptions:
            service = sub.monitored_item_srv
            for notifier in self.notifiers:
                for mid in list(service._monitored_events.get(notifier, ())):
                    if mids is None or mid in mids:
                        await _enqueue(sub, mid, event, bypass=False)

    async def refresh(self, session_id: ua.NodeId, request: ua.CallMethodRequest) -> ua.CallMethodResult:
        """ConditionRefresh(SubscriptionId) and ConditionRefresh2(SubscriptionId, MonitoredItemId)."""
        second = request.MethodId == REFRESH2
        args, result = arguments(request, 2 if second else 1)
        if not result.StatusCode.is_good():
            return result
        if request.ObjectId != ua.NodeId(_O.ConditionType):  # Part 9 5.5.7's answer
            result.StatusCode = ua.StatusCode(_S.BadUserAccessDenied)
            return result
        sub = self.server.iserver.subscription_service.subscriptions.get(args[0]) if self.server else None
        if sub is None or sub.session_id != session_id:
            result.StatusCode = ua.StatusCode(_S.BadSubscriptionIdInvalid)
            return result
        service = sub.monitored_item_srv
        mids = {mid for items in service._monitored_events.values() for mid in items}
        if second:
            if args[1] not in mids:
                result.StatusCode = ua.StatusCode(_S.BadMonitoredItemIdInvalid)
                return result
            mids = {args[1]}
        if not mids:
            result.StatusCode = ua.StatusCode(_S.BadNothingToDo)
            return result
        if sub.data.SubscriptionId in self._refreshing:
            result.StatusCode = ua.StatusCode(_S.BadRefreshInProgress)
            return result
        self._refreshing.add(sub.data.SubscriptionId)
        try:
            async with self._lock:
                begin = _bracket(_O.RefreshStartEventType)
                for mid in sorted(mids):
                    await _enqueue(sub, mid, begin, bypass=True)
                for c in self.by_id.values():
                    if c.event is not None and c.retain:
                        await self._send(c.event, [sub], mids)
                end = _bracket(_O.RefreshEndEventType)
                for mid in sorted(mids):
                    await _enqueue(sub, mid, end, bypass=True)
        finally:
            self._refreshing.discard(sub.data.SubscriptionId)
        return result

    # --- methods -------------------------------------------------------------------------------

    def owns(self, request: ua.CallMethodRequest) -> bool:
        method = request.MethodId
        return method in self.methods or method in (REFRESH, REFRESH2) or (
            method.NamespaceIndex == 0 and method.Identifier in DECLARED)

    def executable(self, who: Who, nodeid: ua.NodeId) -> bool | None:
        """May `who` call the condition method at `nodeid`? None when it is none of them."""
        found = self.methods.get(nodeid)
        return None if found is None else self.commands.may(who, ACTIONS[found[1]])

    async def call(self, who: Who, session_id: ua.NodeId,
                   request: ua.CallMethodRequest) -> ua.CallMethodResult:
        if request.MethodId in (REFRESH, REFRESH2):
            return await self.refresh(session_id, request)
        c, name = self._resolve(request)
        args, result = arguments(request, ARITY.get(name, 0) if name else 0)
        if c is None or not name:
            result.StatusCode = ua.StatusCode(_S.BadNodeIdInvalid if c is None else _S.BadMethodInvalid)
            return result
        if not result.StatusCode.is_good():
            return result
        refused = self._refused(c, name, args, result)
        if refused is not None:
            code, why = refused
            self.commands.refuse(who, ACTIONS[name], c.alarm.id, Reason.INVALID, f"{name}: {why}")
            result.StatusCode = ua.StatusCode(code)
            return result
        return await answered(result, self._ticket(who, c, name, args), self.answers)

    def _resolve(self, request: ua.CallMethodRequest) -> tuple[Condition | None, str]:
        """The condition a call is for and what it asks ("" when the method is not one of its own)."""
        c = self.by_node.get(request.ObjectId)
        own = self.methods.get(request.MethodId)
        if own is not None:
            name = own[1] if c is own[0] else ""
        else:
            method = request.MethodId
            name = DECLARED.get(method.Identifier, "") if method.NamespaceIndex == 0 else ""
        if c is not None and request.ObjectId == c.shelving and name not in ON_SHELVING:
            name = ""  # the ShelvingState has the shelving methods; the condition has them all
        return c, name

    def _refused(self, c: Condition, name: str, args: list[Any],
                 result: ua.CallMethodResult) -> tuple[int, str] | None:
        """Part 9's answer when the call does not fit the condition as its last event showed it."""
        a = c.alarm
        if name in ("Acknowledge", "AddComment"):
            eid, comment = args
            if not isinstance(eid, bytes) or not (comment is None or isinstance(comment, ua.LocalizedText)):
                result.InputArgumentResults = [ua.StatusCode(_S.Good if ok else _S.BadTypeMismatch)
                                               for ok in (isinstance(eid, bytes), comment is None
                                                          or isinstance(comment, ua.LocalizedText))]
                return _S.BadInvalidArgument, "takes a ByteString EventId and a LocalizedText comment"
            episode = c.known.get(eid)
            if episode is None:
                return _S.BadEventIdUnknown, "the EventId is not one of the condition's recent events"
            if name == "Acknowledge" and (a.acked or episode != c.episode):
                return _S.BadConditionBranchAlreadyAcked, "that event's state needs no acknowledgement"
        elif name == "TimedShelve":
            ms = args[0]
            if isinstance(ms, bool) or not isinstance(ms, (int, float)) or not math.isfinite(ms) or ms <= 0:
                return _S.BadShelvingTimeOutOfRange, f"a shelving time of {ms!r} ms"
        elif name == "OneShotShelve" and a.shelved_until is not None and a.one_shot:
            return _S.BadConditionAlreadyShelved, "already shelved once (OneShotShelved)"
        elif name == "Unshelve" and a.shelved_until is None:
            return _S.BadConditionNotShelved, "not shelved"
        elif name in ("Disable", "RemoveFromService") and a.out_of_service:
            return _S.BadConditionAlreadyDisabled, "already out of service"
        elif name in ("Enable", "PlaceInService") and not a.out_of_service:
            return _S.BadConditionAlreadyEnabled, "already in service"
        return None

    def _ticket(self, who: Who, c: Condition, name: str, args: list[Any]) -> Ticket:
        commands, alarm_id = self.commands, c.alarm.id
        if name in ("Acknowledge", "AddComment"):
            comment = (args[1].Text or "") if args[1] is not None else ""
            if name == "AddComment":
                return commands.comment(who, alarm_id, comment)
            return commands.acknowledge(who, alarm_id, comment)
        if name == "TimedShelve":
            return commands.shelve(who, alarm_id, "TimedShelve over OPC UA (it gives no reason)",
                                   args[0] / 1000.0)
        if name == "OneShotShelve":
            return commands.shelve(who, alarm_id, "OneShotShelve over OPC UA (it gives no reason)",
                                   ONE_SHOT_LIMIT, once=True)
        if name == "Unshelve":
            return commands.unshelve(who, alarm_id)
        return commands.out_of_service(who, alarm_id, name in ("Disable", "RemoveFromService"))


# --- helpers ---------------------------------------------------------------------------------

def _maybe(value: Any, kind: ua.VariantType) -> ua.Variant:
    """A value, or for none its type's empty one where it has one (a LimitState while inactive),
    else null (the time of a comment never given)."""
    if value is None:
        value = {_V.LocalizedText: ua.LocalizedText(), _V.NodeId: ua.NodeId()}.get(kind)
    return NULL if value is None else ua.Variant(value, kind)


def _stated(a: Alarm) -> str:
    """The Message of a condition shown with no transition of its own (at the start, adopted)."""
    return f"{a.id} {a.state.word}: {a.text}"


def _bracket(event_type: int) -> Notification:
    """A RefreshStart or RefreshEnd event: one EventId for every copy of it."""
    now = ua.Variant(datetime.now(UTC), _V.DateTime)
    name = "RefreshStart" if event_type == _O.RefreshStartEventType else "RefreshEnd"
    return Notification({"EventId": ua.Variant(uuid.uuid4().bytes, _V.ByteString),
                         "EventType": ua.Variant(ua.NodeId(event_type), _V.NodeId),
                         "SourceNode": ua.Variant(ua.NodeId(_O.Server), _V.NodeId),
                         "SourceName": ua.Variant("Server", _V.String), "Time": now, "ReceiveTime": now,
                         "Message": ua.Variant(ua.LocalizedText(name), _V.LocalizedText),
                         "Severity": ua.Variant(1, _V.UInt16)})


async def _enqueue(sub: Any, mid: int, event: Notification, bypass: bool) -> None:
    """`event` to one monitored item, through its filter's WhereClause unless `bypass` (the refresh
    bracket: Part 9 4.5), with the fields its SelectClauses ask."""
    data = sub.monitored_item_srv._monitored_items.get(mid)
    if data is None or data.mode == ua.MonitoringMode.Disabled:
        return
    if not bypass and (data.where_clause_evaluator is None or not data.where_clause_evaluator.eval(event)):
        return
    fields = ua.EventFieldList(ClientHandle=data.client_handle,
                               EventFields=event.to_event_fields(data.filter.SelectClauses))
    await sub.enqueue_event(mid, fields, data.queue_size)


async def _is_bit(server: Server, variable: ua.NodeId) -> bool:
    return await server.get_node(variable).read_data_type() == ua.NodeId(_O.Boolean)
