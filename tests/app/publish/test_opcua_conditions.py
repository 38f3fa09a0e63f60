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
from tests.app.conftest import DEMO_NAME, copy_demo
from tests.app.publish.conftest import STATION_URI, demo_with, free_port, opcua_client

BITS = {"ALM_EVENTS": 0o2600, "ALM_ACK": 0o2601, "ALM_STATION": 0o2602, "ALM_REFRESH": 0o2603,
        "ALM_COMMENT": 0o2604, "ALM_SERVICE": 0o2605}  # free bits of the demo, one alarm each
_O, _S = ua.ObjectIds, ua.StatusCodes
ACKNOWLEDGE = ua.NodeId(_O.AcknowledgeableConditionType_Acknowledge)
Station = tuple[Runtime, str, list[Record]]


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Station]:
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


def alarm_on(runtime: Runtime, name: str) -> None:
    assert runtime.engine is not None and runtime.engine.write_bit(BITS[name], 1, user="test")


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
        """The events of `alarm_id`'s condition with these fields ("__" for "/": ActiveState__Id)."""
        return [e for e in self.events if getattr(e, "ConditionName", None) == alarm_id and all(
            getattr(e, k.replace("__", "/"), None) == v for k, v in fields.items())]

    async def last(self, alarm_id: str, **fields: object) -> Any:
        """The newest such event, once there is one."""
        return (await until(lambda: self.of(alarm_id, **fields), f"event of {alarm_id} with {fields}"))[-1]


async def subscribe(client: Client, notifier: ua.NodeId | int = _O.Server) -> tuple[Events, Any, int]:
    """Events of the A&C types (AlarmConditionType and below, with their fields) at `notifier`:
    the handler, the subscription and the monitored item's id."""
    handler = Events()
    sub = await client.create_subscription(20, handler)
    mid = await sub.subscribe_events(client.get_node(notifier), _O.AlarmConditionType)
    return handler, sub, mid


async def ns(client: Client) -> int:
    return await client.get_namespace_index(STATION_URI)


async def call(client: Client, obj: ua.NodeId, method: ua.NodeId | int, *args: ua.Variant) -> int:
    method = ua.NodeId(method) if isinstance(method, int) else method
    try:
        await client.get_node(obj).call_method(method, *args)
    except ua.UaStatusCodeError as e:
        return e.code
    return _S.Good


def eid(event_id: bytes) -> ua.Variant:
    return ua.Variant(event_id, ua.VariantType.ByteString)


def text(words: str) -> ua.Variant:
    return ua.Variant(ua.LocalizedText(words), ua.VariantType.LocalizedText)


def test_events_arrive_at_the_server_object_and_the_station_with_the_a_and_c_fields(station: Station) -> None:
    runtime, url, records = station
    alarm_id = "ALM_EVENTS.ALARM"

    async def go() -> tuple[Any, Any, int]:
        async with Client(url, timeout=30) as client:
            at_server, _, _ = await subscribe(client)
            at_station, _, _ = await subscribe(client, ua.NodeId(DEMO_NAME, await ns(client)))
            alarm_on(runtime, "ALM_EVENTS")
            event = await at_server.last(alarm_id, ActiveState__Id=True)
            same = await at_station.last(alarm_id, ActiveState__Id=True)
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


def test_the_conditions_are_instances_of_the_standard_types_with_stable_node_ids(station: Station) -> None:
    _, url, _ = station

    async def go() -> dict[str, Any]:
        async with Client(url, timeout=30) as client:
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
                   "notifies": [ua.NodeId(DEMO_NAME, idx)], "normal": False}


def test_an_operator_acknowledges_and_shelves_a_viewer_is_refused_and_the_summary_agrees(
        station: Station) -> None:
    runtime, url, records = station
    alarm_id = "ALM_ACK.ALARM"
    assert runtime.alarms is not None

    async def go() -> dict[str, Any]:
        out: dict[str, Any] = {}
        async with opcua_client(url, "operator", "operator") as client:
            idx = await ns(client)
            cond = ua.NodeId(f"Alarms.{alarm_id}", idx)
            shelving = ua.NodeId(f"Alarms.{alarm_id}.ShelvingState", idx)
            events, _, _ = await subscribe(client)
            alarm_on(runtime, "ALM_ACK")
            active = await events.last(alarm_id, ActiveState__Id=True)
            async with opcua_client(url, "viewer", "viewer") as viewer:
                timed = ua.NodeId(f"Alarms.{alarm_id}.ShelvingState.TimedShelve", idx)
                out["viewer"] = [await call(viewer, cond, ACKNOWLEDGE, eid(active.EventId), text("")),
                                 await call(viewer, cond, ACKNOWLEDGE, eid(active.EventId), text("")),
                                 await call(viewer, shelving, timed, ua.Variant(60000.0))]
            out["still"] = state(runtime, alarm_id)
            out["stale"] = await call(client, cond, ACKNOWLEDGE, eid(b"\0" * 16), text(""))
            out["ack"] = await call(client, cond, ua.NodeId(f"Alarms.{alarm_id}.Acknowledge", idx),
                                    eid(active.EventId), text("seen"))
            out["acked"] = state(runtime, alarm_id)
            acked = await events.last(alarm_id, AckedState__Id=True)
            out["again"] = await call(client, cond, ACKNOWLEDGE, eid(active.EventId), text(""))
            out["timed"] = await call(client, shelving, _O.ShelvedStateMachineType_TimedShelve,
                                      ua.Variant(60000.0, ua.VariantType.Double))
            out["shelved"] = state(runtime, alarm_id)
            out["row"] = next(r.state for r in runtime.alarms.summary if r.id == alarm_id)
            shelved = await events.last(alarm_id, SuppressedOrShelved=True)
            out["one shot"] = await call(client, cond, _O.ShelvedStateMachineType_OneShotShelve)
            out["one shot again"] = await call(client, cond, _O.ShelvedStateMachineType_OneShotShelve)
            out["once"] = runtime.alarms.system.get(alarm_id).one_shot
            out["unshelve"] = await call(client, shelving, _O.ShelvedStateMachineType_Unshelve)
            out["unshelve again"] = await call(client, shelving, _O.ShelvedStateMachineType_Unshelve)
            out["out of range"] = await call(client, shelving, _O.ShelvedStateMachineType_TimedShelve,
                                             ua.Variant(-1.0, ua.VariantType.Double))
            out["wrong object"] = await call(client, shelving, ACKNOWLEDGE, eid(active.EventId), text(""))
            out["fields"] = (acked.Comment.Text, acked.ClientUserId,
                             getattr(shelved, "ShelvingState/CurrentState").Text,
                             getattr(shelved, "ShelvingState/UnshelveTime"))
        return out

    out = run(go())
    assert out["viewer"] == [_S.BadUserAccessDenied] * 3 and out["still"] is State.UNACK
    assert (out["stale"], out["ack"], out["acked"]) == (_S.BadEventIdUnknown, _S.Good, State.ACKED)
    assert out["again"] == _S.BadConditionBranchAlreadyAcked
    assert (out["timed"], out["shelved"], out["row"]) == (_S.Good, State.SHELVED, State.SHELVED)
    assert (out["one shot"], out["once"]) == (_S.Good, True)
    assert out["one shot again"] == _S.BadConditionAlreadyShelved
    assert (out["unshelve"], out["unshelve again"]) == (_S.Good, _S.BadConditionNotShelved)
    assert (out["out of range"], out["wrong object"]) == (_S.BadShelvingTimeOutOfRange, _S.BadMethodInvalid)
    comment, user, shelving, left = out["fields"]
    assert comment == "seen" and user.startswith("opcua:operator@127.0.0.1:")
    assert shelving == "TimedShelved" and 55_000 < left <= 60_000
    refused = [r.text for r in records if r.kind == "operator" and r.source.startswith("opcua:viewer@")]
    assert sorted(refused) == [  # once per cause: the two acknowledgements are one record
        f"отказ: квитирование {alarm_id}: нужна роль «оператор»; viewer — наблюдатель",
        f"отказ: откладывание {alarm_id}: нужна роль «оператор»; viewer — наблюдатель"]
    acts = [r.text for r in records if r.kind == "alarm" and r.source == alarm_id]
    assert all("оператор opcua:operator@127.0.0.1:" in t for t in acts[1:])  # the demo speaks Russian
    assert ["квитирована: seen" in t for t in acts[1:]] == [True, False, False, False]
    assert "TimedShelve over OPC UA" in acts[2] and "отложена до возврата" in acts[3]
    assert "возвращена из отложенных" in acts[4]


def test_an_alarm_acknowledged_at_the_station_updates_its_condition(station: Station) -> None:
    runtime, url, _ = station
    alarm_id = "ALM_STATION.ALARM"

    async def go() -> tuple[Any, bool, str]:
        async with Client(url, timeout=30) as client:
            idx = await ns(client)
            events, _, _ = await subscribe(client, ua.NodeId(DEMO_NAME, idx))
            alarm_on(runtime, "ALM_STATION")
            await events.last(alarm_id, ActiveState__Id=True)
            ticket = runtime.commands.acknowledge(Who("operator", Source.CONSOLE), alarm_id)
            assert (await asyncio.wrap_future(ticket)).ok
            event = await events.last(alarm_id, AckedState__Id=True)
            acked = await client.get_node(ua.NodeId(f"Alarms.{alarm_id}.AckedState.Id", idx)).read_value()
            word = await client.get_node(ua.NodeId(f"Alarms.{alarm_id}.State", idx)).read_value()
            return event, acked, word

    event, acked, word = run(go())
    assert acked is True and word == "active-acknowledged" and event.Retain is True
    assert event.Message.Text.endswith("квитирована; оператор operator")


def test_condition_refresh_sends_the_retained_conditions_between_refresh_start_and_end(
        station: Station) -> None:
    runtime, url, _ = station
    alarm_id = "ALM_REFRESH.ALARM"
    start, end = ua.NodeId(_O.RefreshStartEventType), ua.NodeId(_O.RefreshEndEventType)
    refresh = ua.NodeId(_O.ConditionType_ConditionRefresh)
    refresh2 = ua.NodeId(_O.ConditionType_ConditionRefresh2)
    condition_type = ua.NodeId(_O.ConditionType)
    assert runtime.alarms is not None

    async def go() -> dict[str, Any]:
        out: dict[str, Any] = {}
        async with Client(url, timeout=30) as client:
            live, _, _ = await subscribe(client)
            alarm_on(runtime, "ALM_REFRESH")
            out["first"] = await live.last(alarm_id, ActiveState__Id=True)
            events, sub, at_server = await subscribe(client)
            demo = client.get_node(ua.NodeId(DEMO_NAME, await ns(client)))
            at_station = await sub.subscribe_events(demo, _O.AlarmConditionType)
            out["items"] = at_server, at_station
            sid = ua.Variant(sub.subscription_id, ua.VariantType.UInt32)
            out["refresh"] = await call(client, condition_type, refresh, sid)
            await until(lambda: sum(e.EventType == end for e in events.events) == 2, "two RefreshEnd")
            out["events"] = list(events.events)
            out["wrong object"] = await call(client, ua.NodeId(_O.Server), refresh, sid)
            async with Client(url, timeout=30) as other:
                out["foreign"] = await call(other, condition_type, refresh, sid)
            events.events.clear()
            out["refresh2"] = await call(client, condition_type, refresh2, sid,
                                         ua.Variant(at_station, ua.VariantType.UInt32))
            await until(lambda: any(e.EventType == end for e in events.events), "RefreshEnd")
            out["events2"] = list(events.events)
        return out

    out = run(go())
    assert (out["refresh"], out["refresh2"]) == (_S.Good, _S.Good)
    assert (out["wrong object"], out["foreign"]) == (_S.BadUserAccessDenied, _S.BadSubscriptionIdInvalid)
    retained = {a.id for a in runtime.alarms.system.alarms
                if not a.out_of_service and (a.active or not a.acked)}
    assert alarm_id in retained
    starts = set()
    for item in out["items"]:  # at the Server object, at the station: each its own bracket
        events = [e for e in out["events"] if e.server_handle == item]
        kinds = [e.EventType for e in events]
        assert kinds[0] == start and kinds[-1] == end and kinds.count(start) == kinds.count(end) == 1
        starts.add(events[0].EventId)
        between = events[1:-1]
        assert all(e.Retain for e in between) and {e.ConditionName for e in between} == retained
        again = next(e for e in between if e.ConditionName == alarm_id)
        assert again.EventId == out["first"].EventId  # the condition's last event, as it was
    assert len(starts) == 1  # copies of one RefreshStart event
    events2 = out["events2"]
    assert {e.server_handle for e in events2} == {out["items"][1]}  # ConditionRefresh2: that item only
    assert [events2[0].EventType, events2[-1].EventType] == [start, end]
    assert len(events2) == 2 + len(retained)


def test_comments_and_out_of_service_through_the_condition(station: Station) -> None:
    runtime, url, records = station
    commented, service = "ALM_COMMENT.ALARM", "ALM_SERVICE.ALARM"

    async def executable(client: Client, idx: int) -> bool:
        node = client.get_node(ua.NodeId(f"Alarms.{service}.Disable", idx))
        return (await node.read_attribute(ua.AttributeIds.UserExecutable)).Value.Value

    async def go() -> dict[str, Any]:
        out: dict[str, Any] = {}
        async with opcua_client(url, "operator", "operator") as client:
            idx = await ns(client)
            events, _, _ = await subscribe(client)
            alarm_on(runtime, "ALM_COMMENT")
            active = await events.last(commented, ActiveState__Id=True)
            cond = ua.NodeId(f"Alarms.{commented}", idx)
            out["comment"] = await call(client, cond, _O.ConditionType_AddComment, eid(active.EventId),
                                        text("technician called"))
            said = await until(lambda: [e for e in events.of(commented)
                                        if e.Comment.Text == "technician called"], "the comment")
            out["said"] = (said[-1].ClientUserId, getattr(said[-1], "AckedState/Id"))
            out["disable"] = await call(client, ua.NodeId(f"Alarms.{service}", idx), _O.ConditionType_Disable)
            out["operator may"] = await executable(client, idx)
        async with opcua_client(url, "engineer", "engineer") as client:
            idx = await ns(client)
            cond = ua.NodeId(f"Alarms.{service}", idx)
            events, _, _ = await subscribe(client)
            out["engineer may"] = await executable(client, idx)
            out["remove"] = await call(client, cond, _O.AlarmConditionType_RemoveFromService)
            out["oos"] = state(runtime, service)
            out["disabled"] = await call(client, cond, _O.ConditionType_Disable)
            gone = await events.last(service, EnabledState__Id=False)
            out["gone"] = (gone.Retain, getattr(gone, "OutOfServiceState/Id"))
            out["enable"] = await call(client, cond, ua.NodeId(f"Alarms.{service}.Enable", idx))
            out["back"] = state(runtime, service)
            out["enabled"] = await call(client, cond, _O.AlarmConditionType_PlaceInService)
        return out

    out = run(go())
    assert out["comment"] == _S.Good and out["said"][0].startswith("opcua:operator@")
    assert out["said"][1] is False  # a comment acknowledges nothing
    assert (out["disable"], out["operator may"], out["engineer may"]) == (_S.BadUserAccessDenied, False, True)
    assert (out["remove"], out["oos"], out["gone"]) == (_S.Good, State.OUT_OF_SERVICE, (False, True))
    assert out["disabled"] == _S.BadConditionAlreadyDisabled
    assert (out["enable"], out["back"]) == (_S.Good, State.NORMAL)
    assert out["enabled"] == _S.BadConditionAlreadyEnabled
    assert any(r.kind == "alarm" and r.source == commented and "комментарий: technician called" in r.text
               for r in records)
