"""The station's alarms as OPC UA Alarms & Conditions (Part 9), seen by asyncua's client: events at
the Server object, the condition methods as the station's commands, the state agreeing both ways,
ConditionRefresh. One station for the module; each test raises alarms of its own (a bit of the
demo that nothing else drives, with a discrete alarm on it)."""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from asyncua import Client, ua

from app.authority import Source, Who
from app.scada.alarms import State
from app.station.runtime import Runtime
from netplc.records import Record
from tests.app.conftest import copy_demo
from tests.app.publish.conftest import STATION_URI, demo_with, free_port, opcua_client

BITS = {"ALM_EVENTS": 0o2600, "ALM_ACK": 0o2601, "ALM_STATION": 0o2602, "ALM_REFRESH": 0o2603,
        "ALM_COMMENT": 0o2604, "ALM_SERVICE": 0o2605}  # free bits of the demo, one alarm each
_O = ua.ObjectIds


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Runtime, str, list[Record]]]:
    folder = copy_demo(tmp_path_factory.mktemp("conditions") / "station")
    tags = folder / "tags.csv"
    text = tags.read_text(encoding="utf-8").rstrip("\n") + "\n"
    for name, bit in BITS.items():  # alarm_when = 1, priority 2
        text += f"{name},0{bit:o},bit,,,,,,,Test {name},,,,,,,,1,2,,,\n"
    tags.write_text(text, encoding="utf-8")
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    runtime = demo_with(folder, f'[opcua]\nenabled = true\nendpoint = "{url}"\n')
    records: list[Record] = []
    runtime.subscribe(records.append)
    yield runtime, url, records
    runtime.stop()


def run(coro: object) -> Any:
    return asyncio.run(coro)  # type: ignore[arg-type]


def alarm_on(runtime: Runtime, name: str, value: int = 1) -> None:
    assert runtime.engine is not None and runtime.engine.write_bit(BITS[name], value, user="test")


def state(runtime: Runtime, alarm_id: str) -> State:
    assert runtime.alarms is not None
    return runtime.alarms.system.get(alarm_id).state


async def until(check: Callable[[], Any], what: str, timeout: float = 10.0) -> Any:
    deadline = asyncio.get_running_loop().time() + timeout
    while not (found := check()):
        assert asyncio.get_running_loop().time() < deadline, f"no {what} within {timeout:g} s"
        await asyncio.sleep(0.02)
    return found


class Events:
    """An event subscription's notifications, in order."""

    def __init__(self) -> None:
        self.events: list[Any] = []

    def event_notification(self, event: Any) -> None:
        self.events.append(event)

    def of(self, alarm_id: str, **fields: object) -> list[Any]:
        """The events of `alarm_id`'s condition whose fields (by name, "/" for "_") are these."""
        return [e for e in self.events if getattr(e, "ConditionName", None) == alarm_id and all(
            getattr(e, k.replace("__", "/"), None) == v for k, v in fields.items())]


async def subscribe(client: Client, notifier: ua.NodeId | int = _O.Server) -> tuple[Events, Any]:
    """Events of the A&C types (AlarmConditionType and below, its fields) at `notifier`."""
    handler = Events()
    sub = await client.create_subscription(20, handler)
    await sub.subscribe_events(client.get_node(notifier), _O.AlarmConditionType)
    return handler, sub


async def ns(client: Client) -> int:
    return await client.get_namespace_index(STATION_URI)


async def call(client: Client, obj: ua.NodeId, method: ua.NodeId | int, *args: ua.Variant) -> int:
    try:
        await client.get_node(obj).call_method(ua.NodeId(method) if isinstance(method, int) else method, *args)
    except ua.UaStatusCodeError as e:
        return e.code
    return ua.StatusCodes.Good


def eid(event_id: bytes) -> ua.Variant:
    return ua.Variant(event_id, ua.VariantType.ByteString)


def text(words: str) -> ua.Variant:
    return ua.Variant(ua.LocalizedText(words), ua.VariantType.LocalizedText)


def test_events_arrive_at_the_server_object_and_the_station_with_the_a_and_c_fields(
        station: tuple[Runtime, str, list[Record]]) -> None:
    runtime, url, records = station
    alarm_id = "ALM_EVENTS.ALARM"

    async def go() -> tuple[Any, Any, int]:
        async with Client(url) as client:
            at_server, _ = await subscribe(client)
            at_station, _ = await subscribe(client, ua.NodeId("Demo station", await ns(client)))
            alarm_on(runtime, "ALM_EVENTS")
            event = (await until(lambda: at_server.of(alarm_id, ActiveState__Id=True), "event at i=2253"))[0]
            same = (await until(lambda: at_station.of(alarm_id, ActiveState__Id=True), "event at the station"))[0]
            return event, same, await ns(client)

    event, same, idx = run(go())
    record = next(r for r in records if r.kind == "alarm" and r.source == alarm_id)
    assert same.EventId == event.EventId
    assert event.EventType == ua.NodeId(_O.OffNormalAlarmType)
    assert event.NodeId == ua.NodeId(f"Alarms.{alarm_id}", idx)  # the ConditionId
    assert (event.SourceNode, event.SourceName) == (ua.NodeId("Tags.ALM_EVENTS", idx), "ALM_EVENTS")
    assert event.Message.Text == record.text and event.Message.Text.count(alarm_id) == 1
    assert (event.Severity, event.Retain, event.BranchId) == (700, True, ua.NodeId())
    assert (getattr(event, "AckedState/Id"), getattr(event, "EnabledState/Id")) == (False, True)
    assert (event.ActiveState.Text, event.AckedState.Text) == ("Active", "Unacknowledged")
    assert getattr(event, "ShelvingState/CurrentState").Text == "Unshelved"
    assert event.SuppressedOrShelved is False and event.Quality.is_good()
    assert event.ConditionClassId == ua.NodeId(_O.ProcessConditionClassType)
    assert isinstance(event.EventId, bytes) and len(event.EventId) == 16


def test_the_conditions_are_instances_of_the_standard_types_with_stable_node_ids(
        station: tuple[Runtime, str, list[Record]]) -> None:
    _, url, _ = station

    async def go() -> dict[str, Any]:
        async with Client(url) as client:
            idx = await ns(client)
            out: dict[str, Any] = {}
            for alarm_id in ("LEVEL.H", "TRIGGER.BAD", "NETPLC.STOPPED", "MSG3", "ALM_EVENTS.ALARM"):
                node = client.get_node(ua.NodeId(f"Alarms.{alarm_id}", idx))
                out[alarm_id] = (await node.read_type_definition(), await node.read_browse_name())
            level = client.get_node(ua.NodeId("Alarms.LEVEL.H", idx))
            out["limit"] = await (await level.get_child("0:HighLimit")).read_value()
            out["acked id"] = (await level.get_child(["0:AckedState", "0:Id"])).nodeid
            out["shelve"] = (await level.get_child(["0:ShelvingState", "0:TimedShelve"])).nodeid
            out["state"] = await (await level.get_child(f"{idx}:State")).read_value()
            out["input"] = await (await level.get_child("0:InputNode")).read_value()
            source = client.get_node(ua.NodeId("Tags.LEVEL", idx))
            out["has condition"] = [n.nodeid for n in await source.get_referenced_nodes(_O.HasCondition)]
            server = client.get_node(_O.Server)
            out["notifies"] = [n.nodeid for n in await server.get_referenced_nodes(_O.HasNotifier)]
            bit = client.get_node(ua.NodeId("Alarms.ALM_EVENTS.ALARM.NormalState", idx))
            out["normal"] = await client.get_node(await bit.read_value()).read_value()
            out["idx"] = idx
            return out

    out = run(go())
    idx = out.pop("idx")
    assert out.pop("LEVEL.H") == (ua.NodeId(_O.ExclusiveLevelAlarmType), ua.QualifiedName("LEVEL.H", idx))
    assert out.pop("TRIGGER.BAD")[0] == ua.NodeId(_O.SystemOffNormalAlarmType)
    assert out.pop("NETPLC.STOPPED")[0] == ua.NodeId(_O.SystemOffNormalAlarmType)
    assert out.pop("MSG3")[0] == ua.NodeId(_O.AlarmConditionType)
    assert out.pop("ALM_EVENTS.ALARM")[0] == ua.NodeId(_O.OffNormalAlarmType)
    assert out == {"limit": 90.0, "acked id": ua.NodeId("Alarms.LEVEL.H.AckedState.Id", idx),
                   "shelve": ua.NodeId("Alarms.LEVEL.H.ShelvingState.TimedShelve", idx), "state": "normal",
                   "input": ua.NodeId("Tags.LEVEL", idx),
                   "has condition": [ua.NodeId(f"Alarms.LEVEL.{key}", idx) for key in ("HH", "H", "BAD")],
                   "notifies": [ua.NodeId("Demo station", idx)], "normal": False}


def test_an_operator_acknowledges_and_shelves_a_viewer_is_refused_and_the_summary_agrees(
        station: tuple[Runtime, str, list[Record]]) -> None:
    runtime, url, records = station
    alarm_id = "ALM_ACK.ALARM"

    async def go() -> dict[str, Any]:
        out: dict[str, Any] = {}
        async with opcua_client(url, "operator", "operator") as client:
            idx = await ns(client)
            cond = ua.NodeId(f"Alarms.{alarm_id}", idx)
            shelving = ua.NodeId(f"Alarms.{alarm_id}.ShelvingState", idx)
            events, _ = await subscribe(client)
            alarm_on(runtime, "ALM_ACK")
            active = (await until(lambda: events.of(alarm_id, ActiveState__Id=True), "the alarm"))[-1]
            async with opcua_client(url, "viewer", "viewer") as viewer:
                out["viewer"] = [await call(viewer, cond, _O.AcknowledgeableConditionType_Acknowledge,
                                            eid(active.EventId), text("")),
                                 await call(viewer, cond, _O.AcknowledgeableConditionType_Acknowledge,
                                            eid(active.EventId), text("")),
                                 await call(viewer, shelving, ua.NodeId(f"Alarms.{alarm_id}.ShelvingState.TimedShelve",
                                                                        idx), ua.Variant(60000.0))]
            out["still"] = state(runtime, alarm_id)
            out["stale"] = await call(client, cond, _O.AcknowledgeableConditionType_Acknowledge,
                                      eid(b"\0" * 16), text(""))
            out["ack"] = await call(client, cond, ua.NodeId(f"Alarms.{alarm_id}.Acknowledge", idx),
                                    eid(active.EventId), text("seen"))
            out["acked"] = state(runtime, alarm_id)
            acked = (await until(lambda: events.of(alarm_id, AckedState__Id=True), "the acknowledgement"))[-1]
            out["again"] = await call(client, cond, _O.AcknowledgeableConditionType_Acknowledge,
                                      eid(active.EventId), text(""))
            out["timed"] = await call(client, shelving, _O.ShelvedStateMachineType_TimedShelve,
                                      ua.Variant(60000.0, ua.VariantType.Double))
            out["shelved"] = state(runtime, alarm_id)
            out["row"] = next(r for r in runtime.alarms.summary if r.id == alarm_id).state  # type: ignore[union-attr]
            shelved = (await until(lambda: events.of(alarm_id, SuppressedOrShelved=True), "the shelving"))[-1]
            out["one shot"] = await call(client, cond, _O.ShelvedStateMachineType_OneShotShelve)
            out["one shot again"] = await call(client, cond, _O.ShelvedStateMachineType_OneShotShelve)
            out["once"] = runtime.alarms.system.get(alarm_id).one_shot  # type: ignore[union-attr]
            out["unshelve"] = await call(client, shelving, _O.ShelvedStateMachineType_Unshelve)
            out["unshelve again"] = await call(client, shelving, _O.ShelvedStateMachineType_Unshelve)
            out["out of range"] = await call(client, shelving, _O.ShelvedStateMachineType_TimedShelve,
                                             ua.Variant(-1.0, ua.VariantType.Double))
            out["wrong object"] = await call(client, shelving, _O.AcknowledgeableConditionType_Acknowledge,
                                             eid(active.EventId), text(""))
            out["fields"] = (acked.Comment.Text, acked.ClientUserId,
                             getattr(shelved, "ShelvingState/CurrentState").Text,
                             getattr(shelved, "ShelvingState/UnshelveTime"))
        return out

    out = run(go())
    s = ua.StatusCodes
    assert out["viewer"] == [s.BadUserAccessDenied] * 3 and out["still"] is State.UNACK
    assert (out["stale"], out["ack"], out["acked"]) == (s.BadEventIdUnknown, s.Good, State.ACKED)
    assert out["again"] == s.BadConditionBranchAlreadyAcked
    assert (out["timed"], out["shelved"], out["row"]) == (s.Good, State.SHELVED, State.SHELVED)
    assert (out["one shot"], out["one shot again"], out["once"]) == (s.Good, s.BadConditionAlreadyShelved, True)
    assert (out["unshelve"], out["unshelve again"]) == (s.Good, s.BadConditionNotShelved)
    assert (out["out of range"], out["wrong object"]) == (s.BadShelvingTimeOutOfRange, s.BadMethodInvalid)
    comment, user, shelving, left = out["fields"]
    assert comment == "seen" and user.startswith("opcua:operator@127.0.0.1:")
    assert shelving == "TimedShelved" and 55_000 < left <= 60_000
    refused = [r.text for r in records if r.kind == "operator" and r.source.startswith("opcua:viewer@")]
    assert sorted(refused) == [  # once per cause: the two acknowledgements are one record
        f"refused acknowledge {alarm_id}: needs the operator role; viewer is viewer",
        f"refused shelve {alarm_id}: needs the operator role; viewer is viewer"]
    acts = [r.text for r in records if r.kind == "alarm" and r.source == alarm_id and "by opcua:operator@" in r.text]
    assert any("acknowledged: seen" in t for t in acts) and any("shelved once" in t for t in acts)
    assert any("TimedShelve over OPC UA" in t for t in acts) and any("unshelved" in t for t in acts)


def test_an_alarm_acknowledged_at_the_station_updates_its_condition(
        station: tuple[Runtime, str, list[Record]]) -> None:
    runtime, url, _ = station
    alarm_id = "ALM_STATION.ALARM"

    async def go() -> tuple[Any, bool, str]:
        async with Client(url) as client:
            idx = await ns(client)
            events, _ = await subscribe(client, ua.NodeId("Demo station", idx))
            alarm_on(runtime, "ALM_STATION")
            await until(lambda: events.of(alarm_id, ActiveState__Id=True), "the alarm")
            ticket = runtime.commands.acknowledge(Who("operator", Source.CONSOLE), alarm_id)
            assert (await asyncio.wrap_future(ticket)).ok
            event = (await until(lambda: events.of(alarm_id, AckedState__Id=True), "the acknowledgement"))[-1]
            acked = await client.get_node(ua.NodeId(f"Alarms.{alarm_id}.AckedState.Id", idx)).read_value()
            word = await client.get_node(ua.NodeId(f"Alarms.{alarm_id}.State", idx)).read_value()
            return event, acked, word

    event, acked, word = run(go())
    assert acked is True and word == "active-acknowledged" and event.Retain is True
    assert event.Message.Text.endswith("acknowledged; by operator")


def test_condition_refresh_sends_the_retained_conditions_between_refresh_start_and_end(
        station: tuple[Runtime, str, list[Record]]) -> None:
    runtime, url, _ = station
    alarm_id = "ALM_REFRESH.ALARM"
    start, end = ua.NodeId(_O.RefreshStartEventType), ua.NodeId(_O.RefreshEndEventType)
    refresh = ua.NodeId(_O.ConditionType_ConditionRefresh)
    condition_type = ua.NodeId(_O.ConditionType)

    async def go() -> dict[str, Any]:
        out: dict[str, Any] = {}
        async with Client(url) as client:
            live, _ = await subscribe(client)
            alarm_on(runtime, "ALM_REFRESH")
            first = (await until(lambda: live.of(alarm_id, ActiveState__Id=True), "the alarm"))[-1]
            events, sub = await subscribe(client)
            handles = [*sub._monitored_items.values()][0].server_handle, await sub.subscribe_events(
                client.get_node(ua.NodeId("Demo station", await ns(client))), _O.AlarmConditionType)
            sid = ua.Variant(sub.subscription_id, ua.VariantType.UInt32)
            out["refresh"] = await call(client, condition_type, refresh, sid)
            await until(lambda: sum(e.EventType == end for e in events.events) == 2, "two RefreshEnd")
            out["events"] = list(events.events)
            out["first"] = first
            out["wrong object"] = await call(client, ua.NodeId(_O.Server), refresh, sid)
            async with Client(url) as other:
                out["foreign"] = await call(other, condition_type, refresh, sid)
            events.events.clear()
            out["refresh2"] = await call(client, condition_type, ua.NodeId(_O.ConditionType_ConditionRefresh2),
                                         sid, ua.Variant(handles[1], ua.VariantType.UInt32))
            await until(lambda: any(e.EventType == end for e in events.events), "RefreshEnd")
            out["events2"] = list(events.events)
            out["handles"] = handles
        return out

    out = run(go())
    s = ua.StatusCodes
    assert (out["refresh"], out["refresh2"]) == (s.Good, s.Good)
    assert (out["wrong object"], out["foreign"]) == (s.BadUserAccessDenied, s.BadSubscriptionIdInvalid)
    retained = {a.id for a in runtime.alarms.system.alarms  # type: ignore[union-attr]
                if not a.out_of_service and (a.active or not a.acked)}
    assert alarm_id in retained
    starts = set()
    for handle in out["handles"]:  # at the Server object, at the station: each its own bracket
        events = [e for e in out["events"] if e.server_handle == handle]
        kinds = [e.EventType for e in events]
        assert kinds[0] == start and kinds[-1] == end and kinds.count(start) == kinds.count(end) == 1
        starts.add(events[0].EventId)
        between = events[1:-1]
        assert all(e.Retain for e in between) and {e.ConditionName for e in between} == retained
        again = next(e for e in between if e.ConditionName == alarm_id)
        assert again.EventId == out["first"].EventId  # the condition's last event, as it was
    assert len(starts) == 1  # copies of one RefreshStart event
    events2 = out["events2"]
    assert {e.server_handle for e in events2} == {out["handles"][1]}  # ConditionRefresh2: that item only
    assert [e.EventType for e in events2][::len(events2) - 1] == [start, end] and len(events2) == 2 + len(retained)


def test_comments_and_out_of_service_through_the_condition(station: tuple[Runtime, str, list[Record]]) -> None:
    runtime, url, records = station

    async def go() -> dict[str, Any]:
        out: dict[str, Any] = {}
        async with opcua_client(url, "operator", "operator") as client:
            idx = await ns(client)
            cond = ua.NodeId("Alarms.ALM_COMMENT.ALARM", idx)
            events, _ = await subscribe(client)
            alarm_on(runtime, "ALM_COMMENT")
            active = (await until(lambda: events.of("ALM_COMMENT.ALARM", ActiveState__Id=True), "the alarm"))[-1]
            out["comment"] = await call(client, cond, _O.ConditionType_AddComment, eid(active.EventId),
                                        text("technician called"))
            said = await until(lambda: [e for e in events.of("ALM_COMMENT.ALARM")
                                        if e.Comment.Text == "technician called"], "the comment")
            out["said"] = (said[-1].ClientUserId, getattr(said[-1], "AckedState/Id"))
            out["disable"] = await call(client, ua.NodeId("Alarms.ALM_SERVICE.ALARM", idx), _O.ConditionType_Disable)
            executable = client.get_node(ua.NodeId("Alarms.ALM_SERVICE.ALARM.Disable", idx))
            out["operator may"] = (await executable.read_attribute(ua.AttributeIds.UserExecutable)).Value.Value
        async with opcua_client(url, "engineer", "engineer") as client:
            idx = await ns(client)
            cond = ua.NodeId("Alarms.ALM_SERVICE.ALARM", idx)
            events, _ = await subscribe(client)
            out["engineer may"] = (await client.get_node(ua.NodeId("Alarms.ALM_SERVICE.ALARM.Disable", idx))
                                   .read_attribute(ua.AttributeIds.UserExecutable)).Value.Value
            out["remove"] = await call(client, cond, _O.AlarmConditionType_RemoveFromService)
            out["oos"] = state(runtime, "ALM_SERVICE.ALARM")
            out["disabled"] = await call(client, cond, _O.ConditionType_Disable)
            gone = (await until(lambda: events.of("ALM_SERVICE.ALARM", EnabledState__Id=False), "disabled"))[-1]
            out["gone"] = (gone.Retain, getattr(gone, "OutOfServiceState/Id"))
            out["enable"] = await call(client, cond, ua.NodeId("Alarms.ALM_SERVICE.ALARM.Enable", idx))
            out["back"] = state(runtime, "ALM_SERVICE.ALARM")
            out["enabled"] = await call(client, cond, _O.AlarmConditionType_PlaceInService)
        return out

    out = run(go())
    s = ua.StatusCodes
    assert out["comment"] == s.Good and out["said"][0].startswith("opcua:operator@") and out["said"][1] is False
    assert (out["disable"], out["operator may"], out["engineer may"]) == (s.BadUserAccessDenied, False, True)
    assert (out["remove"], out["oos"], out["disabled"]) == (s.Good, State.OUT_OF_SERVICE, s.BadConditionAlreadyDisabled)
    assert out["gone"] == (False, True)
    assert (out["enable"], out["back"], out["enabled"]) == (s.Good, State.NORMAL, s.BadConditionAlreadyEnabled)
    assert any(r.kind == "alarm" and r.source == "ALM_COMMENT.ALARM" and "comment: technician called" in r.text
               for r in records)

