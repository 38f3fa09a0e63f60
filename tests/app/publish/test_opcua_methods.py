"""The station's OPC UA methods (run, stop, step, force and unforce an address or a tag) are its
commands, with the session's user, and NetPlc's memory and forces are read-only variables: what a
remote Program view needs to act as a logged-in user of the station."""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from asyncua import ua

from app.scada.alarms import STOPPED_ID, State
from app.scada.forcing import tag_keys
from app.station.runtime import Runtime
from netplc.address import DATA_SIZE, IO_BITS, data_index
from tests.app.conftest import DEMO_NAME
from tests.app.publish.conftest import STATION_URI, demo_with, free_port, opcua_client

BIT = 0o2120  # the demo's PUMP command bit


def _station(folder: Path) -> Iterator[tuple[Runtime, str, list]]:
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    runtime = demo_with(folder, f'[opcua]\nenabled = true\nendpoint = "{url}"\n', language="en")
    records: list = []
    runtime.subscribe(records.append)
    yield runtime, url, records
    runtime.stop()


@pytest.fixture
def station(tmp_path: Path) -> Iterator[tuple[Runtime, str, list]]:
    """A station of the test's own, which it may stop, force and alarm."""
    yield from _station(tmp_path / "station")


@pytest.fixture(scope="module")
def untouched(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Runtime, str, list]]:
    """One station for the tests whose every command is refused or only reads: NetPlc runs on,
    nothing forced."""
    yield from _station(tmp_path_factory.mktemp("methods") / "station")


async def call(client: object, name: str, *args: ua.Variant) -> int:
    ns = await client.get_namespace_index(STATION_URI)
    station = client.get_node(ua.NodeId(DEMO_NAME, ns))
    try:
        await station.call_method(f"{ns}:{name}", *args)
    except ua.UaStatusCodeError as e:
        return e.code
    return ua.StatusCodes.Good


def run(coro: object) -> object:
    return asyncio.run(coro)  # type: ignore[arg-type]


def force(value: int, kind: str = "bit", address: str = "02120") -> tuple[ua.Variant, ...]:
    return (ua.Variant(kind, ua.VariantType.String), ua.Variant(address, ua.VariantType.String),
            ua.Variant(value, ua.VariantType.Int32))


def test_an_engineer_stops_steps_forces_and_runs_each_answered_once_applied(
        station: tuple[Runtime, str, list]) -> None:
    runtime, url, records = station

    async def go() -> dict[str, object]:
        out: dict[str, object] = {}
        async with opcua_client(url, "engineer", "engineer") as client:
            out["stop"] = await call(client, "Stop")
            out["stopped"] = runtime.engine.state_text
            scans = runtime.engine.scan_counter
            out["step"] = await call(client, "Step")
            out["stepped"] = "step one scan" in records[-1].text and runtime.engine.scan_counter > scans
            out["force"] = await call(client, "Force", *force(1))
            out["forced"] = runtime.engine.forces.count
            out["unforce"] = await call(client, "Unforce", *force(0)[:2])
            out["force again"] = await call(client, "Force", *force(1))
            out["unforce all"] = await call(client, "UnforceAll")
            out["none forced"] = runtime.engine.forces.count
            out["run"] = await call(client, "Run")
            out["running"] = runtime.engine.state_text
        return out

    good = ua.StatusCodes.Good
    assert run(go()) == {"stop": good, "stopped": "stopped", "step": good, "stepped": True, "force": good,
                         "forced": 1, "unforce": good, "force again": good, "unforce all": good,
                         "none forced": 0, "run": good, "running": "running"}
    acts = [r for r in records if r.kind == "operator" and r.source.startswith("opcua:engineer@127.0.0.1:")]
    assert any("NetPlc stopped" in r.text for r in acts) and any("force" in r.text for r in acts)


def test_an_operator_may_not_force_or_stop_and_bad_arguments_are_named(
        untouched: tuple[Runtime, str, list]) -> None:
    runtime, url, records = untouched

    async def go() -> list[int]:
        async with opcua_client(url, "operator", "operator") as client:
            codes = [await call(client, "Force", *force(1)), await call(client, "Stop")]
        async with opcua_client(url, "engineer", "engineer") as client:
            codes += [await call(client, "Force", *force(1, "nibble")),
                      await call(client, "Force", *force(1, "bit", "09")),
                      await call(client, "Force", *force(1)[:2]),
                      await call(client, "Step"),  # NetPlc runs: one scan only while stopped
                      # an Address is octal text: the number 1000 is not taken for the bit 01000
                      await call(client, "Force", force(1)[0], ua.Variant(1000, ua.VariantType.Int32),
                                 force(1)[2])]
        return codes

    assert run(go()) == [ua.StatusCodes.BadUserAccessDenied] * 2 + [ua.StatusCodes.BadInvalidArgument] * 2 + [
        ua.StatusCodes.BadArgumentsMissing] + [ua.StatusCodes.BadInvalidArgument] * 2
    assert runtime.engine.forces.count == 0 and runtime.engine.state_text == "running"
    refused = [r.text for r in records if r.kind == "operator" and "refused" in r.text]
    assert any("needs the engineer role; operator is operator" in t for t in refused)
    assert any("'nibble' is not one of bit, byte, word" in t for t in refused)


def test_user_executable_follows_the_sessions_role(untouched: tuple[Runtime, str, list]) -> None:
    _, url, _ = untouched

    async def executable(user: str, password: str) -> dict[str, bool]:
        async with opcua_client(url, user, password) as client:
            ns = await client.get_namespace_index(STATION_URI)
            out = {}
            for name in ("Force", "Run", "UnforceAll"):
                node = client.get_node(ua.NodeId(f"Station.{name}", ns))
                out[name] = (await node.read_attribute(ua.AttributeIds.UserExecutable)).Value.Value
            return out

    assert run(executable("viewer", "viewer")) == {"Force": False, "Run": False, "UnforceAll": False}
    assert run(executable("engineer", "engineer")) == {"Force": True, "Run": True, "UnforceAll": True}


def test_memory_and_forces_are_read_only_variables_of_the_station(station: tuple[Runtime, str, list]) -> None:
    runtime, url, _ = station
    engine = runtime.engine
    assert engine is not None
    engine.write_word(0o14002, 0xBEEF, user="test")  # bank 1
    engine.write_bit(0o2177, 1, user="test")

    async def go() -> dict[str, object]:
        async with opcua_client(url, "engineer", "engineer") as client:
            ns = await client.get_namespace_index(STATION_URI)
            assert await call(client, "Force", ua.Variant("word", ua.VariantType.String),
                              ua.Variant("04010", ua.VariantType.String),
                              ua.Variant(310, ua.VariantType.Int32)) == ua.StatusCodes.Good
            plc = client.get_node(ua.NodeId("NetPlc", ns))
            memory = await plc.get_child(ua.QualifiedName("Memory", ns))
            bits = await memory.get_child(ua.QualifiedName("Bits", ns))
            data = client.get_node(ua.NodeId("NetPlc.Memory.Data", ns))
            forces = client.get_node(ua.NodeId("NetPlc.Forces", ns))
            deadline = time.monotonic() + 10
            while json.loads(await forces.read_value()) == []:  # until a scan with the force is published
                assert time.monotonic() < deadline
                await asyncio.sleep(0.02)
            out = {"bits id": bits.nodeid, "names": [await n.read_browse_name()
                                                     for n in (memory, bits, data, forces)],
                   "bits": await bits.read_value(), "data": await data.read_value(),
                   "forces": json.loads(await forces.read_value()),
                   "kind": (await data.read_data_value()).Value.VariantType,
                   "level": await data.read_attribute(ua.AttributeIds.UserAccessLevel)}
            try:
                await data.write_value(ua.Variant(bytes(DATA_SIZE), ua.VariantType.ByteString))
                out["write"] = ua.StatusCodes.Good
            except ua.UaStatusCodeError as e:
                out["write"] = e.code
            out["ns"] = ns
            return out

    out = run(go())
    ns = out["ns"]
    assert out["bits id"] == ua.NodeId("NetPlc.Memory.Bits", ns)
    assert out["names"] == [ua.QualifiedName(n, ns) for n in ("Memory", "Bits", "Data", "Forces")]
    bits, data = out["bits"], out["data"]
    assert out["kind"] == ua.VariantType.ByteString and len(bits) == IO_BITS and len(data) == DATA_SIZE
    assert bits[0o2177] == 1 and bits[0o2176] == 0 and bits[0o3760] == 1  # 03760 is always 1
    i = data_index(0o14002)
    assert data[i:i + 2] == bytes((0xEF, 0xBE))
    j = data_index(0o4010)
    assert data[j:j + 2] == (310).to_bytes(2, "little")  # forced, as every reader sees it
    assert out["forces"] == [{"kind": "word", "address": "04010", "value": 310,
                              "user": out["forces"][0]["user"]}]
    assert out["forces"][0]["user"].startswith("opcua:engineer@127.0.0.1:")
    assert out["level"].Value.Value == 1 << ua.AccessLevel.CurrentRead  # read only, whoever asks
    assert out["write"] == ua.StatusCodes.BadNotWritable


def test_a_tag_is_forced_and_written_in_its_units_and_an_address_forced_at_its_value(
        station: tuple[Runtime, str, list]) -> None:
    """ForceTag and UnforceTag (the Program view, a faceplate), WriteTag (a remote console's
    faceplate): the layer's commands of a tag, its range and the role checked."""
    runtime, url, records = station
    engine = runtime.engine
    assert engine is not None
    temp = runtime.tags.by_name["TEMP_SP"]

    async def go() -> list[int]:
        async with opcua_client(url, "engineer", "engineer") as client:
            codes = [await call(client, "ForceTag", ua.Variant("TEMP_SP", ua.VariantType.String),
                                ua.Variant(55.5, ua.VariantType.Double)),
                     await call(client, "Force", ua.Variant("bit", ua.VariantType.String),
                                ua.Variant("02120", ua.VariantType.String), ua.Variant()),  # Null: bumpless
                     await call(client, "ForceTag", ua.Variant("NOPE", ua.VariantType.String), ua.Variant()),
                     await call(client, "ForceTag", ua.Variant("TEMP_SP", ua.VariantType.String),
                                ua.Variant("hot", ua.VariantType.String))]
            forced = engine.forces.count
            codes += [await call(client, "UnforceTag", ua.Variant("TEMP_SP", ua.VariantType.String)), forced]
        name = ua.Variant("TEMP_SP", ua.VariantType.String)
        async with opcua_client(url, "operator", "operator") as client:
            codes.append(await call(client, "ForceTag", name, ua.Variant(1.0, ua.VariantType.Double)))
            codes += [await call(client, "WriteTag", name, ua.Variant(100.0, ua.VariantType.Double)),
                      await call(client, "WriteTag", name, ua.Variant(900.0, ua.VariantType.Double)),
                      await call(client, "WriteTag", name, ua.Variant("hot", ua.VariantType.String)),
                      await call(client, "WriteTag", ua.Variant("NOPE", ua.VariantType.String),
                                 ua.Variant(1.0, ua.VariantType.Double))]
        async with opcua_client(url, "viewer", "viewer") as client:
            codes.append(await call(client, "WriteTag", name, ua.Variant(50.0, ua.VariantType.Double)))
        return codes

    good = ua.StatusCodes.Good
    assert run(go()) == [good, good, ua.StatusCodes.BadNodeIdUnknown, ua.StatusCodes.BadInvalidArgument, good,
                         len(tag_keys(temp)) + 1, ua.StatusCodes.BadUserAccessDenied,
                         good, ua.StatusCodes.BadOutOfRange, ua.StatusCodes.BadTypeMismatch,
                         ua.StatusCodes.BadNodeIdUnknown, ua.StatusCodes.BadUserAccessDenied]
    texts = [r.text for r in records if r.kind == "operator" and (r.source or "").startswith("opcua:")]
    assert any(t.startswith("force TEMP_SP: ") and "-> 55.5" in t for t in texts)
    assert any(t.startswith("force 02120: ") and t.endswith("(bumpless)") for t in texts)
    assert any(t.startswith("unforce TEMP_SP") for t in texts)
    assert engine.forces.count == 1  # the bit stays forced
    written = [r for r in records if r.kind == "operator" and (r.text or "").startswith("write ")]
    assert len(written) == 1 and (written[0].source or "").startswith("opcua:operator@")
    assert "TEMP_SP" in (written[0].text or "") and "-> 100.0 °C" in (written[0].text or "")  # applied


def alarm(alarm_id: str) -> ua.Variant:
    return ua.Variant(alarm_id, ua.VariantType.String)


def test_a_viewer_may_not_acknowledge_or_shelve_an_operator_may(station: tuple[Runtime, str, list]) -> None:
    """The alarm summary's actions over OPC UA are the same commands as at the workstation."""
    runtime, url, records = station

    def state() -> State:
        return runtime.alarms.system.get(STOPPED_ID).state

    async def go() -> dict[str, object]:
        out: dict[str, object] = {}
        async with opcua_client(url, "engineer", "engineer") as client:
            await call(client, "Stop")  # NetPlc stopped: its station alarm comes, unacknowledged
        deadline = asyncio.get_running_loop().time() + 10
        while state() is not State.UNACK and asyncio.get_running_loop().time() < deadline:
            await asyncio.sleep(0.05)
        async with opcua_client(url, "viewer", "viewer") as client:
            out["viewer"] = {await call(client, name, *args) for name, args in (
                ("Acknowledge", (alarm(STOPPED_ID),)), ("Acknowledge", (alarm(STOPPED_ID),)),
                ("AcknowledgeAll", ()),
                ("Shelve", (alarm(STOPPED_ID), ua.Variant("test"), ua.Variant(60.0))))}
        out["still"] = state()
        async with opcua_client(url, "operator", "operator") as client:
            out["ack"] = await call(client, "Acknowledge", alarm(STOPPED_ID))
            out["acked"] = state()
            out["unknown"] = await call(client, "Acknowledge", alarm("NO.SUCH"))
            out["shelve"] = await call(client, "Shelve", alarm(STOPPED_ID), ua.Variant("commissioning"),
                                       ua.Variant(60.0))
            out["shelved"] = state()
            out["unshelve"] = await call(client, "Unshelve", alarm(STOPPED_ID))
        return out

    out = run(go())
    assert out["viewer"] == {ua.StatusCodes.BadUserAccessDenied} and out["still"] is State.UNACK
    assert out["ack"] == ua.StatusCodes.Good and out["acked"] is State.ACKED
    assert out["unknown"] == ua.StatusCodes.BadNodeIdUnknown
    assert out["shelve"] == ua.StatusCodes.Good and out["shelved"] is State.SHELVED
    assert out["unshelve"] == ua.StatusCodes.Good
    refused = [r.text for r in records if r.kind == "operator" and r.source.startswith("opcua:viewer@")
               and r.text.startswith("refused")]
    assert sorted(refused) == [  # one record per cause: acknowledge (3 refusals) and shelve
        f"refused acknowledge {STOPPED_ID}: needs the operator role; viewer is viewer",
        f"refused shelve {STOPPED_ID}: needs the operator role; viewer is viewer"]
    acts = [r.text for r in records if r.kind == "alarm" and "operator" in (r.text or "")]
    assert acts  # the transitions name the operator, as at the workstation

