"""Historical Access (OPC UA Part 11) from the station's archive, read with a standard client
(asyncua's): the raw values of an archived tag in physical units with their quality, in pages with
continuation points that give every value exactly once, bounds, backward reads; the journal as
events at the station object and the Server object; Bad_HistoryOperationUnsupported elsewhere.

The archive is filled before the station starts with a minute of LEVEL's NSTORE series (5 values a
second, one of them a gap, one stale) and journal records, all before `T`; every read ends at `T`,
so what the running station adds after it changes no answer."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path

import pytest
from asyncua import Client, ua
from asyncua.common.events import get_filter_from_event_type

from app.publish import history
from app.scada.alarms import State
from app.station.runtime import Runtime
from netplc.records import Record
from registrar.query import Archive
from registrar.reading import SeriesKey
from registrar.store import Store
from tests.app.conftest import DEMO_NAME, copy_demo
from tests.app.publish.conftest import STATION_URI, demo_with, free_port

N = 250  # LEVEL values archived, 0.2 s apart, in the minute before T
GAP, STALE = 100, 101  # the value that is a gap (comm-fail, no value) and the one kept stale
MESSAGES = 40


def level_ts(t: float, k: int) -> int:
    """The k-th archived LEVEL value's time, ms."""
    return round((t - 60 + 0.2 * k) * 1000)


def raw(k: int) -> int:
    return (k * 16) % 4096


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Runtime, str, float]]:
    folder = copy_demo(tmp_path_factory.mktemp("history") / "station")
    t = time.time()
    store = Store(folder / "archive" / "journal.sqlite")
    store.start()
    for k in range(N):
        value, text = (None, "comm-fail") if k == GAP else (raw(k), "stale" if k == STALE else None)
        store.put(Record(level_ts(t, k) / 1000, "data", grp=1, type=1, source="04010", value=value,
                         text=text))
    store.put(Record(t - 50, "message", grp=1, type=2, number=3, text="Уровень выше 90 %"))
    store.put(Record(t - 49, "alarm", grp=2, type=int(State.UNACK), number=int(State.NORMAL),
                     source="LEVEL.H"))
    store.put(Record(t - 48, "operator", source="opcua:operator@127.0.0.1:5000", text="Пуск: 0 -> 1"))
    store.put(Record(t - 47, "system", source="station", text="station started"))
    for i in range(MESSAGES):
        store.put(Record(t - 40 + 0.5 * i, "message", grp=1, type=0, number=2, text=f"Уровень в норме {i}"))
    store.close()
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    runtime = demo_with(folder, f'[opcua]\nenabled = true\nendpoint = "{url}"\n')
    yield runtime, url, t
    runtime.stop()


def run(coro: object) -> object:
    return asyncio.run(coro)  # type: ignore[arg-type]


def utc(ms: float | None) -> datetime:
    """A time in ms, or DateTime.MinValue (no time given) for None."""
    return ua.get_win_epoch() if ms is None else datetime.fromtimestamp(ms / 1000, UTC)


def details(start: float | None, end: float | None, count: int = 0,
            bounds: bool = False) -> ua.ReadRawModifiedDetails:
    return ua.ReadRawModifiedDetails(IsReadModified=False, StartTime=utc(start), EndTime=utc(end),
                                     NumValuesPerNode=count, ReturnBounds=bounds)


def ms(dv: ua.DataValue) -> int:
    assert dv.SourceTimestamp is not None
    return round(dv.SourceTimestamp.timestamp() * 1000)


async def connect(url: str) -> tuple[Client, int]:
    client = Client(url, timeout=30)  # s: a loaded machine connects slowly
    await client.connect()
    return client, await client.get_namespace_index(STATION_URI)


def test_a_minute_of_an_archived_tag_in_physical_units_with_its_quality(
        station: tuple[Runtime, str, float]) -> None:
    _, url, t = station

    async def go() -> list[ua.DataValue]:
        client, ns = await connect(url)
        try:
            level = client.get_node(ua.NodeId("Tags.LEVEL", ns))
            return await level.read_raw_history(utc((t - 61) * 1000), utc(t * 1000), return_bounds=False)
        finally:
            await client.disconnect()

    values = run(go())
    assert [ms(v) for v in values] == [level_ts(t, k) for k in range(N)]
    for k, dv in enumerate(values):
        assert dv.ServerTimestamp == dv.SourceTimestamp
        if k == GAP:
            assert dv.StatusCode.value == ua.StatusCodes.BadCommunicationError and dv.Value.Value is None
            continue
        assert dv.Value.VariantType == ua.VariantType.Double
        assert dv.Value.Value == pytest.approx(raw(k) * 100 / 4095)  # LEVEL: 0..4095 -> 0..100 %
        expected = ua.StatusCodes.UncertainLastUsableValue if k == STALE else ua.StatusCodes.Good
        assert dv.StatusCode.value == expected


def test_pages_of_the_clients_limit_give_every_value_exactly_once(
        station: tuple[Runtime, str, float]) -> None:
    _, url, t = station

    async def go() -> tuple[list[int], list[bytes | None], int]:
        client, ns = await connect(url)
        try:
            level = client.get_node(ua.NodeId("Tags.LEVEL", ns))
            asked = details((t - 61) * 1000, t * 1000, count=100)
            got: list[int] = []
            points: list[bytes | None] = []
            point = None
            while True:
                result = await level.history_read(asked, point)
                result.StatusCode.check()
                got += [ms(v) for v in result.HistoryData.DataValues]
                point = result.ContinuationPoint
                points.append(point)
                if point is None:
                    break
            # the same point again is refused for another request; a released point frees nothing
            other = await level.history_read(details((t - 30) * 1000, t * 1000, count=100), points[0])
            params = ua.HistoryReadParameters(HistoryReadDetails=asked, ReleaseContinuationPoints=True,
                                              TimestampsToReturn=ua.TimestampsToReturn.Both,
                                              NodesToRead=[ua.HistoryReadValueId(NodeId=level.nodeid,
                                                                                 ContinuationPoint=points[0])])
            released = (await client.uaclient.history_read(params))[0]
            assert released.StatusCode.is_good() and not released.HistoryData
            return got, points, other.StatusCode.value
        finally:
            await client.disconnect()

    got, points, other = run(go())
    assert len(points) == 3 and points[-1] is None and all(points[:2])
    assert got == [level_ts(t, k) for k in range(N)]  # 100 + 100 + 50, each once, in order
    assert other == ua.StatusCodes.BadContinuationPointInvalid


def test_bounds_and_reading_backward(station: tuple[Runtime, str, float]) -> None:
    _, url, t = station
    start, end = level_ts(t, 10) + 50, level_ts(t, 20) + 50  # between values: 11..20 inside

    async def go() -> list[list[ua.DataValue]]:
        client, ns = await connect(url)
        try:
            level = client.get_node(ua.NodeId("Tags.LEVEL", ns))
            out = []
            for asked in (details(start, end, bounds=True), details(end, start),
                          details(end, start, bounds=True), details(start, end, count=3, bounds=True),
                          details((t - 70) * 1000, level_ts(t, 2), bounds=True),
                          details(level_ts(t, 5), level_ts(t, 5))):
                result = await level.history_read(asked)
                result.StatusCode.check()
                out.append(result.HistoryData.DataValues)
            return out
        finally:
            await client.disconnect()

    forward, backward, backward_bounded, counted, before, exact = run(go())
    assert [ms(v) for v in forward] == [level_ts(t, k) for k in range(10, 22)]  # bound 10, 11..20, bound 21
    assert [ms(v) for v in backward] == [level_ts(t, k) for k in range(20, 10, -1)]
    assert [ms(v) for v in backward_bounded] == [level_ts(t, k) for k in range(21, 9, -1)]
    assert [ms(v) for v in counted] == [level_ts(t, k) for k in (10, 11, 12)]  # the bound counts
    first = before[0]  # nothing before the archive's first value: Bad_BoundNotFound at the start time
    assert first.StatusCode.value == ua.StatusCodes.BadBoundNotFound and ms(first) == round((t - 70) * 1000)
    assert [ms(v) for v in before[1:]] == [level_ts(t, k) for k in (0, 1, 2)]  # 2 is the end bound
    assert [ms(v) for v in exact] == [level_ts(t, 5)]


def test_the_journal_as_events_of_the_station_and_the_server(station: tuple[Runtime, str, float]) -> None:
    _, url, t = station

    async def go() -> tuple[list[list[object]], list[int], list[object], list[object]]:
        client, ns = await connect(url)
        try:
            base = client.get_node(ua.ObjectIds.BaseEventType)
            evfilter = await get_filter_from_event_type([base])
            condition = ua.NodeId(ua.ObjectIds.ConditionType)
            evfilter.SelectClauses += [  # an alarm's: its condition's fields
                ua.SimpleAttributeOperand(TypeDefinitionId=condition, AttributeId=ua.AttributeIds.NodeId),
                *(ua.SimpleAttributeOperand(TypeDefinitionId=condition, AttributeId=ua.AttributeIds.Value,
                                            BrowsePath=[ua.QualifiedName(n, 0) for n in path.split("/")])
                  for path in ("ConditionName", "ActiveState/Id", "AckedState/Id"))]
            names = ["/".join(q.Name for q in c.BrowsePath) or "ConditionId" for c in evfilter.SelectClauses]
            asked = ua.ReadEventDetails(StartTime=utc((t - 61) * 1000), EndTime=utc(t * 1000),
                                        NumValuesPerNode=10, Filter=evfilter)
            pages: list[list[object]] = []
            sizes: list[int] = []
            for node in (client.get_node(ua.NodeId(DEMO_NAME, ns)), client.nodes.server):
                events: list[object] = []
                point = None
                while True:
                    params = ua.HistoryReadParameters(
                        HistoryReadDetails=asked, TimestampsToReturn=ua.TimestampsToReturn.Both,
                        ReleaseContinuationPoints=False,
                        NodesToRead=[ua.HistoryReadValueId(NodeId=node.nodeid, ContinuationPoint=point)])
                    result = (await client.uaclient.history_read(params))[0]
                    result.StatusCode.check()
                    sizes.append(len(result.HistoryData.Events))
                    events += [dict(zip(names, (f.Value for f in e.EventFields)))
                               for e in result.HistoryData.Events]
                    point = result.ContinuationPoint
                    if point is None:
                        break
                pages.append(events)
            system = await client.get_node(ua.NodeId(DEMO_NAME, ns)).read_event_history(
                utc((t - 61) * 1000), utc(t * 1000), evtypes=ua.ObjectIds.SystemEventType)
            level = client.get_node(ua.NodeId("Tags.LEVEL", ns))
            asked.NumValuesPerNode = 0
            params = ua.HistoryReadParameters(HistoryReadDetails=asked, NodesToRead=[
                ua.HistoryReadValueId(NodeId=level.nodeid)], TimestampsToReturn=ua.TimestampsToReturn.Both,
                ReleaseContinuationPoints=False)
            not_events = (await client.uaclient.history_read(params))[0].StatusCode.value
            return pages, sizes, system, [not_events]
        finally:
            await client.disconnect()

    pages, sizes, system, (not_events,) = run(go())
    station_events, server_events = pages
    assert max(sizes) <= 10
    assert len(station_events) == 4 + MESSAGES
    assert [e["Message"] for e in server_events] == [e["Message"] for e in station_events]
    # the source is the station (an alarm's: its condition's), wherever its history is read
    assert {e["SourceNode"] for e in station_events + server_events} == {
        ua.NodeId(DEMO_NAME, 1), ua.NodeId("Tags.LEVEL", 1)}
    assert len({e["EventId"] for e in station_events}) == len(station_events)  # each once
    message, alarm, operator, record = station_events[:4]
    assert message["Message"].Text == "Уровень выше 90 %" and message["SourceName"] == "MSG3"
    assert message["EventType"] == ua.NodeId(ua.ObjectIds.BaseEventType) and message["Severity"] == 700
    assert message["Time"] == utc(round((t - 50) * 1000)) == message["ReceiveTime"]
    # an alarm's transition is its condition's event, as the live one was
    assert alarm["EventType"] == ua.NodeId(ua.ObjectIds.ExclusiveLevelAlarmType)
    assert (alarm["SourceNode"], alarm["SourceName"]) == (ua.NodeId("Tags.LEVEL", 1), "LEVEL")
    assert (alarm["ConditionName"], alarm["ConditionId"]) == ("LEVEL.H", ua.NodeId("Alarms.LEVEL.H", 1))
    assert (alarm["ActiveState/Id"], alarm["AckedState/Id"], alarm["Severity"]) == (True, False, 700)
    assert alarm["Message"].Text == "LEVEL.H normal -> active-unacknowledged"
    assert message["ConditionName"] is None  # a message is no condition's
    assert operator["SourceName"] == "opcua:operator@127.0.0.1:5000"
    assert operator["Message"].Text == "Пуск: 0 -> 1"
    assert record["EventType"] == ua.NodeId(ua.ObjectIds.SystemEventType)
    assert [e["Message"].Text for e in station_events[4:]] == [
        f"Уровень в норме {i}" for i in range(MESSAGES)]
    assert [e.Message.Text for e in system] == ["station started"]  # the where clause: one type
    assert not_events == ua.StatusCodes.BadHistoryOperationUnsupported


def test_the_journal_filtered_by_a_like_of_its_message_and_a_severity(
        station: tuple[Runtime, str, float]) -> None:
    """Part 4's Like (7.7.3): % any text, _ one character, [..] one of; with And, a Severity."""
    _, url, t = station

    def operand(name: str) -> ua.SimpleAttributeOperand:
        return ua.SimpleAttributeOperand(TypeDefinitionId=ua.NodeId(ua.ObjectIds.BaseEventType),
                                         BrowsePath=[ua.QualifiedName(name, 0)],
                                         AttributeId=ua.AttributeIds.Value)

    def element(op: ua.FilterOperator, *operands: object) -> ua.ContentFilterElement:
        return ua.ContentFilterElement(FilterOperator=op, FilterOperands=list(operands))

    def like(pattern: str) -> ua.ContentFilterElement:
        return element(ua.FilterOperator.Like, operand("Message"),
                       ua.LiteralOperand(Value=ua.Variant(pattern, ua.VariantType.String)))

    severe = element(ua.FilterOperator.GreaterThanOrEqual, operand("Severity"),
                     ua.LiteralOperand(Value=ua.Variant(700, ua.VariantType.UInt16)))
    both = element(ua.FilterOperator.And, ua.ElementOperand(Index=1), ua.ElementOperand(Index=2))

    async def go() -> list[list[str]]:
        client, ns = await connect(url)
        try:
            texts = []
            wheres = ([like("Уровень в норме 1_")], [like("%норме [23]")], [both, like("Уровень%"), severe])
            for where in wheres:
                flt = ua.EventFilter(SelectClauses=[operand("Message")],
                                     WhereClause=ua.ContentFilter(Elements=where))
                asked = ua.ReadEventDetails(StartTime=utc((t - 61) * 1000), EndTime=utc(t * 1000), Filter=flt)
                params = ua.HistoryReadParameters(
                    HistoryReadDetails=asked, TimestampsToReturn=ua.TimestampsToReturn.Both,
                    ReleaseContinuationPoints=False,
                    NodesToRead=[ua.HistoryReadValueId(NodeId=ua.NodeId(DEMO_NAME, ns))])
                result = (await client.uaclient.history_read(params))[0]
                result.StatusCode.check()
                texts.append([e.EventFields[0].Value.Text for e in result.HistoryData.Events])
            return texts
        finally:
            await client.disconnect()

    teens, two_three, high = run(go())
    assert teens == [f"Уровень в норме {i}" for i in range(10, 20)]
    assert two_three == ["Уровень в норме 2", "Уровень в норме 3"]
    assert high == ["Уровень выше 90 %"]  # severity 700; "в норме" ones are info


def test_what_is_not_archived_says_so(station: tuple[Runtime, str, float]) -> None:
    _, url, t = station

    async def go() -> dict[str, object]:
        client, ns = await connect(url)
        try:
            out: dict[str, object] = {}
            asked = details((t - 61) * 1000, t * 1000)
            for name, nodeid in (("TRIGGER", ua.NodeId("Tags.TRIGGER", ns)),
                                 ("state", ua.NodeId("NetPlc.State", ns)),
                                 ("unknown", ua.NodeId("Tags.NOSUCH", ns))):
                out[name] = (await client.get_node(nodeid).history_read(asked)).StatusCode.value
            level = client.get_node(ua.NodeId("Tags.LEVEL", ns))
            modified = details((t - 61) * 1000, t * 1000)
            modified.IsReadModified = True
            out["modified"] = (await level.history_read(modified)).StatusCode.value
            out["one time"] = (await level.history_read(details((t - 61) * 1000, None))).StatusCode.value
            counted = await level.history_read(details(None, t * 1000, count=3))
            out["last three"] = [ms(v) for v in counted.HistoryData.DataValues], counted.ContinuationPoint
            later = await level.history_read(details((t + 3600) * 1000, (t + 3601) * 1000))
            out["later"] = later.StatusCode.value
            trigger = client.get_node(ua.NodeId("Tags.TRIGGER", ns))
            out["historizing"] = (await level.read_attribute(ua.AttributeIds.Historizing)).Value.Value, \
                (await trigger.read_attribute(ua.AttributeIds.Historizing)).Value.Value
            out["user access"] = (await level.read_attribute(ua.AttributeIds.UserAccessLevel)).Value.Value, \
                (await trigger.read_attribute(ua.AttributeIds.UserAccessLevel)).Value.Value
            out["notifier"] = await client.get_node(ua.NodeId(DEMO_NAME, ns)).read_event_notifier()
            out["capabilities"] = [await client.get_node(n).read_value() for n in (
                ua.ObjectIds.HistoryServerCapabilities_AccessHistoryDataCapability,
                ua.ObjectIds.HistoryServerCapabilities_AccessHistoryEventsCapability,
                ua.ObjectIds.HistoryServerCapabilities_InsertDataCapability,
                ua.ObjectIds.HistoryServerCapabilities_MaxReturnDataValues,
                ua.ObjectIds.Server_ServerCapabilities_OperationLimits_MaxNodesPerHistoryReadData)]
            params = ua.HistoryReadParameters(HistoryReadDetails=asked, ReleaseContinuationPoints=False,
                                              TimestampsToReturn=ua.TimestampsToReturn.Both,
                                              NodesToRead=[ua.HistoryReadValueId(NodeId=level.nodeid)] * 101)
            try:
                await client.uaclient.history_read(params)
            except ua.UaStatusCodeError as e:
                out["too many"] = e.code
            return out
        finally:
            await client.disconnect()

    out = run(go())
    assert out["TRIGGER"] == out["state"] == out["modified"] == ua.StatusCodes.BadHistoryOperationUnsupported
    assert out["unknown"] == ua.StatusCodes.BadNodeIdUnknown
    assert out["one time"] == ua.StatusCodes.BadHistoryOperationInvalid  # a start alone and no count
    # backward from the end, that many and no more
    assert out["last three"] == ([level_ts(t, k) for k in (N - 1, N - 2, N - 3)], None)
    assert out["later"] == ua.StatusCodes.GoodNoData
    assert out["historizing"] == (True, False)
    history_read, read = 1 << ua.AccessLevel.HistoryRead, 1 << ua.AccessLevel.CurrentRead
    assert out["user access"] == (read | history_read, read)
    assert ua.EventNotifier.HistoryRead in out["notifier"]
    assert out["capabilities"] == [True, True, False, history.MAX_VALUES, history.MAX_NODES]
    assert out["too many"] == ua.StatusCodes.BadTooManyOperations


def test_pages_across_midnight_and_the_scan_limit_give_every_record_once(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The reading itself, without a server: a series and a journal spanning two days' tables, read
    forward and backward in pages that end at a day's edge, with the journal's scan limit small."""
    midnight = datetime(2026, 3, 5).timestamp()  # local midnight: the archive's tables change there
    db = tmp_path / "journal.sqlite"
    store = Store(db)
    store.start()
    for i in range(-10, 10):
        store.put(Record(midnight + i, "data", grp=1, type=1, source="04010", value=float(i + 10)))
        store.put(Record(midnight + i + 0.5, "message", grp=1, type=0, number=1, text=f"m{i}"))
    store.close()
    key = SeriesKey("data", 1, 1, "04010")
    span = history.domain(utc((midnight - 20) * 1000), utc((midnight + 20) * 1000), 0)
    backward = history.domain(utc((midnight + 20) * 1000), utc((midnight - 20) * 1000), 0)
    assert span is not None and backward is not None
    with Archive(db) as archive:
        assert len(archive.days()) == 2
        for d, order in ((span, 1), (backward, -1)):
            for limit in (11, 5):  # 11: the first page (a bound and ten records) ends at the day's edge
                got: list[float | None] = []
                after = None
                while True:
                    samples, after = history.read_raw(archive, key, d, True, after, limit)
                    got += [row.value if row is not None else None for _, row in samples]
                    if after is None:
                        break
                assert got == [None, *[float(v) for v in range(20)][::order], None]  # no bound found
            for limit, scan in ((10, history.SCAN_ROWS), (3, 7)):  # 10: a page ends at the day's edge
                monkeypatch.setattr(history, "SCAN_ROWS", scan)  # 7: a few records examined a page
                texts: list[str] = []
                after, pages = None, 0
                while True:
                    rows, after = history.read_journal(archive, d, after, limit)
                    texts += [row.text for _, row in rows if row.text]
                    pages += 1
                    if after is None:
                        break
                assert texts == [f"m{i}" for i in range(-10, 10)][::order] and pages >= 20 / limit
