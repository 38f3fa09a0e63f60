"""What a SCADA client learns of the station's nodes, browsing it with a standard client (asyncua's):
the tags as Part 8's AnalogItemType and TwoStateDiscreteType with the ranges and units of tags.csv,
stable string NodeIds and proper QualifiedNames everywhere, both timestamps on every value, and a
BuildInfo that names NetPlc Station."""

from __future__ import annotations

import asyncio
import csv
import importlib.metadata
import json
import time
from collections.abc import Callable, Iterator

import pytest
from asyncua import Client, Node, ua

from app.publish.ua_types import eu_information, unit_id
from app.station.runtime import Runtime
from tests.app.conftest import DEMO, DEMO_NAME
from tests.app.publish.conftest import STATION_URI, demo_with, free_port

PERCENT, CELSIUS = 20529, 4408652  # UnitId of P1 and CEL (OPC UA Part 8 5.6.3)


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Runtime, str]]:
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    runtime = demo_with(tmp_path_factory.mktemp("nodes") / "station",
                        f'[opcua]\nenabled = true\nendpoint = "{url}"\nwritable = ["TEMP_*"]\n')
    yield runtime, url
    runtime.stop()


def run(coro: object) -> object:
    return asyncio.run(coro)  # type: ignore[arg-type]


def demo_tags() -> list[dict[str, str]]:
    """tags.csv of the demo as written, read apart from the station's own loader."""
    lines = (DEMO / "tags.csv").read_text(encoding="utf-8").splitlines()
    return list(csv.DictReader(line for line in lines if not line.startswith("#")))


def test_unece_units() -> None:
    assert unit_id("CEL") == CELSIUS and unit_id("P1") == PERCENT and unit_id("2N") == 12878
    celsius = eu_information("°C")
    assert celsius.UnitId == CELSIUS and celsius.Description.Text == "degree Celsius"
    assert eu_information("кПа").UnitId == unit_id("KPA")
    assert eu_information("об/мин").UnitId == unit_id("RPM")
    assert eu_information("м3/ч").UnitId == eu_information("m³/h").UnitId == unit_id("MQH")
    unknown = eu_information("попугаи")
    assert (unknown.UnitId, unknown.DisplayName.Text, unknown.Description.Text) == (-1, "попугаи", "попугаи")


def test_tags_are_of_part_8_types_with_the_ranges_and_units_of_tags_csv(station: tuple[Runtime, str]) -> None:
    _, url = station
    rows = demo_tags()

    async def go() -> dict[str, dict[str, object]]:
        out: dict[str, dict[str, object]] = {}
        async with Client(url, timeout=30) as client:
            ns = await client.get_namespace_index(STATION_URI)
            for row in rows:
                node = client.get_node(ua.NodeId(f"Tags.{row['name']}", ns))
                props = {}
                for child in await node.get_children(refs=ua.ObjectIds.HasProperty):
                    name = await child.read_browse_name()
                    assert name.NamespaceIndex == 0  # the standard's BrowseNames
                    assert child.nodeid == ua.NodeId(f"Tags.{row['name']}.{name.Name}", ns)
                    props[name.Name] = await child.read_value()
                props["type"] = (await node.read_type_definition()).Identifier
                out[row["name"]] = props
        return out

    nodes = run(go())
    analog = [r for r in rows if r["type"] != "bit"]
    assert analog and len(analog) < len(rows)
    for row in analog:
        props = nodes[row["name"]]
        assert props["type"] == ua.ObjectIds.AnalogItemType
        eu_range = props["EURange"]
        assert (eu_range.Low, eu_range.High) == (float(row["phy_min"]), float(row["phy_max"])), row["name"]
        raw = props["InstrumentRange"]
        assert (raw.Low, raw.High) == (float(row["app_min"]), float(row["app_max"])), row["name"]
        units = props["EngineeringUnits"]
        assert units.DisplayName.Text == row["unit"]
        assert units.NamespaceUri == "http://www.opcfoundation.org/UA/units/un/cefact"
    assert nodes["LEVEL"]["EngineeringUnits"].UnitId == PERCENT
    assert nodes["TEMP"]["EngineeringUnits"].UnitId == CELSIUS
    trigger = nodes["TRIGGER"]
    assert trigger["type"] == ua.ObjectIds.TwoStateDiscreteType
    # in the station's language (the demo's is Russian): "On" and "Off" in an English one
    assert (trigger["TrueState"].Text, trigger["FalseState"].Text) == ("Вкл", "Выкл")


def test_every_node_of_the_station_has_a_string_nodeid_and_a_plain_browse_name(
        station: tuple[Runtime, str]) -> None:
    """... so a NodeId is the same at every start, and a browse path a client builds from the
    names it sees resolves (an alarm's property, a tag's EURange)."""
    _, url = station

    async def go() -> tuple[list[str], ua.NodeId, ua.NodeId]:
        bad: list[str] = []
        async with Client(url, timeout=30) as client:
            ns = await client.get_namespace_index(STATION_URI)

            async def children(nodes: list[ua.NodeId]) -> list[ua.NodeId]:
                """The hierarchical children of `nodes`, one Browse request for all (as get_children
                asks for one node): a level of the tree per round trip, not a node per round trip."""
                params = ua.BrowseParameters()
                params.View = ua.ViewDescription()
                params.RequestedMaxReferencesPerNode = 0
                params.NodesToBrowse = [ua.BrowseDescription(
                    NodeId=n, BrowseDirection=ua.BrowseDirection.Forward,
                    ReferenceTypeId=ua.NodeId(ua.ObjectIds.HierarchicalReferences), IncludeSubtypes=True,
                    NodeClassMask=0, ResultMask=ua.BrowseResultMask.All) for n in nodes]
                found = []
                for result in await client.uaclient.browse(params):
                    result.StatusCode.check()
                    assert not result.ContinuationPoint  # every reference in one answer
                    found += [r.NodeId for r in result.References]
                return found

            level, seen = [ua.NodeId(DEMO_NAME, ns)], set()
            while level:
                # a reference to a standard node (a type, a modelling rule) is not the station's
                level = [n for n in await children(level) if n.NamespaceIndex == ns and n not in seen]
                if not level:
                    break
                seen.update(level)
                for nodeid, read in zip(level, await client.uaclient.read_attributes(
                        level, ua.AttributeIds.BrowseName), strict=True):
                    name = read.Value.Value
                    if nodeid.NodeIdType != ua.NodeIdType.String or ":" in name.Name[:3]:
                        bad.append(f"{nodeid.to_string()} {name.to_string()}")
            assert len(seen) > 500  # the tags, alarms, programs and memory, each walked (985 in the demo)
            objects = client.nodes.objects
            priority = await objects.get_child([f"{ns}:{DEMO_NAME}", f"{ns}:Alarms", f"{ns}:LEVEL.H",
                                                f"{ns}:Priority"])
            eu_range = await objects.get_child([f"{ns}:{DEMO_NAME}", f"{ns}:Tags", f"{ns}:LEVEL",
                                                "0:EURange"])
        return bad, priority.nodeid, eu_range.nodeid

    bad, priority, eu_range = run(go())
    assert bad == []
    assert priority == ua.NodeId("Alarms.LEVEL.H.Priority", 1)
    assert eu_range == ua.NodeId("Tags.LEVEL.EURange", 1)


def test_values_carry_source_and_server_timestamps(station: tuple[Runtime, str]) -> None:
    _, url = station

    async def go() -> list[ua.DataValue]:
        async with Client(url, timeout=30) as client:
            ns = await client.get_namespace_index(STATION_URI)
            level = client.get_node(ua.NodeId("Tags.LEVEL", ns))
            deadline = time.monotonic() + 10
            while not (dv := await level.read_data_value(raise_on_bad_status=False)).StatusCode.is_good():
                assert time.monotonic() < deadline, dv.StatusCode
                await asyncio.sleep(0.05)
            data = await client.get_node(ua.NodeId("NetPlc.Memory.Data", ns)).read_data_value()
            return [dv, data]

    for dv in run(go()):
        assert dv.SourceTimestamp is not None and dv.ServerTimestamp is not None
        assert dv.SourceTimestamp <= dv.ServerTimestamp


def test_build_info_and_application_name_name_netplc_station(station: tuple[Runtime, str]) -> None:
    _, url = station

    async def go() -> tuple[ua.BuildInfo, list[ua.ApplicationDescription]]:
        async with Client(url, timeout=30) as client:
            info = await client.get_node(ua.ObjectIds.Server_ServerStatus_BuildInfo).read_value()
            return info, await client.find_servers()

    info, servers = run(go())
    version = importlib.metadata.version("netplc-station")
    assert (info.ProductName, info.SoftwareVersion, info.BuildNumber) == ("NetPlc Station", version, version)
    assert info.ProductUri == "urn:netplc:station" and info.ManufacturerName and info.BuildDate
    assert [s.ApplicationName.Text for s in servers] == [f"NetPlc Station {DEMO_NAME}"]
    assert servers[0].ProductUri == "urn:netplc:station"
    assert servers[0].ApplicationType == ua.ApplicationType.Server


def test_method_arguments_are_described(station: tuple[Runtime, str]) -> None:
    _, url = station

    async def go() -> tuple[ua.NodeId, list[ua.Argument], int]:
        async with Client(url, timeout=30) as client:
            ns = await client.get_namespace_index(STATION_URI)
            force = client.get_node(ua.NodeId("Station.Force", ns))
            args = await force.get_child("0:InputArguments")
            return args.nodeid, await args.read_value(), await args.read_value_rank()

    nodeid, args, rank = run(go())
    assert nodeid == ua.NodeId("Station.Force.InputArguments", 1)
    assert [a.Name for a in args] == ["Kind", "Address", "Value"] and rank == ua.ValueRank.OneDimension


def test_a_read_with_an_index_range_is_answered_that_part_of_the_memory(station: tuple[Runtime, str]) -> None:
    """Part 4 7.27: a Read's IndexRange selects a part of an array or ByteString (asyncua's own
    Read service ignores it); a range past the end is Bad_IndexRangeNoData, a malformed one
    Bad_IndexRangeInvalid, and a read without one still gets the whole value."""
    _, url = station

    async def go() -> list[ua.DataValue]:
        async with Client(url, timeout=30) as client:
            ns = await client.get_namespace_index(STATION_URI)
            data, bits = ua.NodeId("NetPlc.Memory.Data", ns), ua.NodeId("NetPlc.Memory.Bits", ns)
            params = ua.ReadParameters()
            params.NodesToRead = [ua.ReadValueId(NodeId=node, AttributeId=ua.AttributeIds.Value, IndexRange=r)
                                  for node, r in ((data, ""), (data, "16:31"), (data, "16383:20000"),
                                                  (bits, "5"), (data, "20000:20001"), (data, "7:7"),
                                                  (data, "x"))]
            return await client.uaclient.read(params)

    whole, part, tail, bit, past, equal, bad = run(go())
    memory = whole.Value.Value
    assert len(memory) == 16 * 1024
    assert part.Value.Value == memory[16:32]  # one Read: one snapshot of the memory
    assert len(tail.Value.Value) == 1
    assert len(bit.Value.Value) == 1 and part.SourceTimestamp is not None
    assert past.StatusCode.value == ua.StatusCodes.BadIndexRangeNoData
    assert equal.StatusCode.value == bad.StatusCode.value == ua.StatusCodes.BadIndexRangeInvalid


def _item(node: ua.NodeId, handle: int, index_range: str = "") -> ua.MonitoredItemCreateRequest:
    params = ua.MonitoringParameters(ClientHandle=handle, SamplingInterval=0, QueueSize=1, DiscardOldest=True)
    return ua.MonitoredItemCreateRequest(
        ItemToMonitor=ua.ReadValueId(NodeId=node, AttributeId=ua.AttributeIds.Value, IndexRange=index_range),
        MonitoringMode=ua.MonitoringMode.Reporting, RequestedParameters=params)


def test_a_monitored_item_with_an_index_range_reports_that_part_when_it_changes(
        station: tuple[Runtime, str]) -> None:
    """Part 4 7.27 on CreateMonitoredItems: an item on a part of the memory is sent that part only,
    and only when that part changed (not at each scan that changed something elsewhere); a range
    that is no NumericRange is refused with Bad_IndexRangeInvalid."""
    _, url = station
    seen: dict[int, list[bytes]] = {1: [], 2: [], 3: []}

    class Handler:
        def datachange_notification(self, node: Node, value: object, data: object) -> None:
            seen[data.monitored_item.ClientHandle].append(value)  # type: ignore[attr-defined]

    async def go() -> list[object]:
        async with Client(url, timeout=30) as client:
            ns = await client.get_namespace_index(STATION_URI)
            data, tick = ua.NodeId("NetPlc.Memory.Data", ns), ua.NodeId("NetPlc.Tick", ns)
            sub = await client.create_subscription(50, Handler())
            # LEVEL (04010: index 8), moved by node 0's simulation; 01750-... of bank 0, unused
            made = await sub.create_monitored_items([_item(data, 1, "8:9"), _item(data, 2, "1000:1099"),
                                                     _item(tick, 3), _item(data, 4, "9:8")])
            deadline = time.monotonic() + 30
            while len(seen[3]) < 15 or len(set(seen[1])) < 2:
                assert time.monotonic() < deadline, f"{len(seen[3])} ticks, LEVEL {seen[1]} within 30 s"
                await asyncio.sleep(0.05)
            await sub.delete()
            return made

    made = run(go())
    assert made[3] == ua.StatusCode(ua.StatusCodes.BadIndexRangeInvalid)
    assert all(len(v) == 2 for v in seen[1]) and len(seen[1]) < len(seen[3])
    assert seen[2] == [bytes(100)]  # once, at creation: nothing changed there since


def test_the_station_files_are_file_type_objects_each_read_as_written(station: tuple[Runtime, str]) -> None:
    """The first file is added through AddNodes, the others are copies of its nodes (files.py):
    each is a FileType object of its own name, size and content, Open and Read as Part 5 C.2 has
    them, also a file added while the station runs. Last in the module: it adds forms."""
    from asyncua.client.ua_file import UaFile

    runtime, url = station
    folder = runtime.station.folder

    async def served(client: Client, ns: int) -> dict[str, str]:
        return json.loads(await client.get_node(ua.NodeId("Files.Manifest", ns)).read_value())["files"]

    async def check(client: Client, ns: int, rel: str) -> None:
        node = client.get_node(ua.NodeId(f"Files.{rel}", ns))
        assert (await node.read_browse_name()).Name == rel
        assert (await node.read_display_name()).Text == rel
        assert (await node.read_type_definition()) == ua.NodeId(ua.ObjectIds.FileType)
        assert await (await node.get_child("0:Size")).read_value() == (folder / rel).stat().st_size
        async with UaFile(node, "r") as f:
            assert await f.read() == (folder / rel).read_bytes()

    async def until(client: Client, ns: int, what: Callable[[dict[str, str]], bool]) -> dict[str, str]:
        deadline = time.monotonic() + 20
        while not what(files := await served(client, ns)):
            assert time.monotonic() < deadline, files
            await asyncio.sleep(0.05)
        return files

    async def go() -> None:
        async with Client(url, timeout=30) as client:
            ns = await client.get_namespace_index(STATION_URI)
            files = await served(client, ns)
            assert {"netplc.stl", "symbols.csv", "tags.csv", "messages.csv"} < set(files)
            assert any(rel.startswith("forms/") for rel in files)
            for rel in files:
                await check(client, ns, rel)
            for n in (1, 2):
                (folder / "forms" / f"new{n}.hmi").write_text(f"; form {n}\n", encoding="utf-8")
                await until(client, ns, lambda f, n=n: f"forms/new{n}.hmi" in f)
                await check(client, ns, f"forms/new{n}.hmi")

    run(go())
