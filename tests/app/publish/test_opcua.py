"""The OPC UA server of a running headless station, seen by asyncua's own client (and its CLI)."""

from __future__ import annotations

import asyncio
import logging
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from asyncua import Client, ua

from app.publish.opcua import is_loopback
from app.station.runtime import Runtime
from tests.app.conftest import DEMO_NAME
from tests.app.publish.conftest import STATION_URI, demo_with, free_port, opcua_client, tag_node


def _station(folder: Path) -> Iterator[tuple[Runtime, str]]:
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    runtime = demo_with(folder, f'[opcua]\nenabled = true\nendpoint = "{url}"\nwritable = ["TEMP_*"]\n')
    yield runtime, url
    runtime.stop()


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Runtime, str]]:
    """One station for the module's tests that only read it."""
    yield from _station(tmp_path_factory.mktemp("opcua") / "station")


@pytest.fixture
def own_station(tmp_path: Path) -> Iterator[tuple[Runtime, str]]:
    """A station of the test's own, whose node it may kill."""
    yield from _station(tmp_path / "station")


def run(coro: object) -> object:
    return asyncio.run(coro)  # type: ignore[arg-type]


async def _tag(client: Client, name: str) -> object:
    ns = await client.get_namespace_index(STATION_URI)
    return client.get_node(ua.NodeId(f"Tags.{name}", ns))


def test_security_follows_the_endpoint() -> None:
    assert is_loopback("opc.tcp://127.0.0.1:4840/netplc/")
    assert is_loopback("opc.tcp://localhost:4840/")
    assert not is_loopback("opc.tcp://10.0.0.5:4840/netplc/")
    assert not is_loopback("opc.tcp://plant-pc:4840/")


def test_browse_read_units_and_quality(station: tuple[Runtime, str]) -> None:
    _, url = station

    async def go() -> None:
        async with Client(url, timeout=30) as client:
            root = client.nodes.objects
            names = [(await n.read_browse_name()).Name for n in await root.get_children()]
            assert DEMO_NAME in names
            ns = await client.get_namespace_index(STATION_URI)
            tags = client.get_node(ua.NodeId("Tags", ns))
            tag_names = {(await n.read_browse_name()).Name for n in await tags.get_children()}
            assert {"LEVEL", "TEMP", "TEMP_SP", "TRIGGER"} <= tag_names
            level = await _tag(client, "LEVEL")
            deadline = time.monotonic() + 5
            while True:
                dv = await level.read_data_value(raise_on_bad_status=False)
                if dv.StatusCode.is_good() or time.monotonic() > deadline:
                    break
                await asyncio.sleep(0.05)
            assert dv.StatusCode.is_good()
            assert isinstance(dv.Value.Value, float) and dv.SourceTimestamp is not None
            eu = await (await level.get_child(["0:EngineeringUnits"])).read_value()
            assert eu.DisplayName.Text == "%"
            rng = await (await level.get_child(["0:EURange"])).read_value()
            assert (rng.Low, rng.High) == (0.0, 100.0)  # PhyMin..PhyMax: what a client may write
            assert (await level.read_description()).Text == "Уровень"
            state = client.get_node(ua.NodeId("NetPlc.State", ns))
            assert await state.read_value() == "running"
            up = client.get_node(ua.NodeId("Nodes.0.Up", ns))
            assert await up.read_value() is True
            alarms = client.get_node(ua.NodeId("Alarms", ns))
            assert await alarms.get_children()

    run(go())


def test_subscription_sees_changes_within_two_ticks(station: tuple[Runtime, str]) -> None:
    runtime, url = station
    received: list[tuple[int, float]] = []

    class Handler:
        def datachange_notification(self, node: object, val: object, data: object) -> None:
            received.append((runtime.engine.scan_counter, val))

    async def go() -> None:
        async with Client(url, timeout=30) as client:
            tick = client.get_node(ua.NodeId("NetPlc.Tick", await client.get_namespace_index(
                STATION_URI)))
            sub = await client.create_subscription(50, Handler())
            await sub.subscribe_data_change(tick)
            deadline = time.monotonic() + 10
            while len(received) < 5:
                assert time.monotonic() < deadline, received
                await asyncio.sleep(0.02)
            await sub.delete()

    run(go())
    assert len(received) >= 5
    # each notification carries a tick no more than 2 scans behind the engine's at delivery
    assert all(engine - int(val) <= 2 for engine, val in received[1:])


def test_quality_goes_bad_when_the_node_is_killed(own_station: tuple[Runtime, str]) -> None:
    """... and TRIGGER's quality alarm comes: its condition's state and an event on the station."""
    runtime, url = own_station
    events: list = []

    class Handler:
        def event_notification(self, event: object) -> None:
            events.append(event)

    async def go() -> None:
        async with Client(url, timeout=30) as client:
            ns = await client.get_namespace_index(STATION_URI)
            sub = await client.create_subscription(50, Handler())
            await sub.subscribe_events(client.get_node(ua.NodeId(DEMO_NAME, ns)),
                                       ua.ObjectIds.AlarmConditionType)
            level = await _tag(client, "LEVEL")
            deadline = time.monotonic() + 5
            while not (await level.read_data_value(raise_on_bad_status=False)).StatusCode.is_good():
                assert time.monotonic() < deadline
                await asyncio.sleep(0.05)
            runtime.simulators[0].stop()
            deadline = time.monotonic() + 10
            while True:
                dv = await level.read_data_value(raise_on_bad_status=False)
                if dv.StatusCode.value == ua.StatusCodes.BadCommunicationError:
                    break
                assert time.monotonic() < deadline, dv.StatusCode
                await asyncio.sleep(0.05)
            alarm = client.get_node(ua.NodeId("Alarms.TRIGGER.BAD.State", ns))
            while await alarm.read_value() != "active-unacknowledged":
                assert time.monotonic() < deadline
                await asyncio.sleep(0.05)
            while not any(getattr(e, "ConditionName", "") == "TRIGGER.BAD" for e in events):
                assert time.monotonic() < deadline
                await asyncio.sleep(0.05)

    run(go())


def test_asyncua_command_line_tools(station: tuple[Runtime, str], capsys: pytest.CaptureFixture[str],
                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """uals and uaread, as their console scripts call them: the function, with the command line in
    sys.argv, ending in sys.exit (in this process: the tools' work is the client's, a fresh
    interpreter's would be asyncua's import)."""
    from asyncua.tools import uals, uaread

    _, url = station
    root = logging.getLogger()
    handlers, level = list(root.handlers), root.level  # a tool's logging.basicConfig
    out = {}
    try:
        for tool, args in ((uals, ["-n", "i=85", "-l", "0"]), (uaread, ["-n", "ns=1;s=NetPlc.State"])):
            monkeypatch.setattr(sys, "argv", [tool.__name__, "-u", url, *args])
            capsys.readouterr()
            with pytest.raises(SystemExit) as done:
                tool()
            assert done.value.code == 0, capsys.readouterr()
            out[tool.__name__] = capsys.readouterr().out
    finally:
        root.handlers[:], root.level = handlers, level
    assert DEMO_NAME in out["uals"]
    assert "running" in out["uaread"], out


def test_a_taken_port_is_a_problem_and_the_station_runs_on(tmp_path: Path) -> None:
    import socket
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        url = f"opc.tcp://127.0.0.1:{taken.getsockname()[1]}/netplc/"
        runtime = demo_with(tmp_path / "station", f'[opcua]\nenabled = true\nendpoint = "{url}"\n',
                            language="en")
        try:
            status = runtime.status()
            assert status.running and runtime.publishers == []
            assert any("OPC UA server not started" in p and "opcua.endpoint" in p for p in status.problems)
        finally:
            runtime.stop()


def test_symbols_are_served_with_their_quality_where_there_is_no_tags_file(tmp_path: Path) -> None:
    from tests.app.conftest import copy_demo

    folder = copy_demo(tmp_path / "station")
    toml = folder / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8").replace('Tags = "tags.csv"', ""), encoding="utf-8")
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    runtime = demo_with(folder, f'[opcua]\nenabled = true\nendpoint = "{url}"\nwritable = ["SETPOINT"]\n')

    async def go() -> tuple[object, int]:
        async with opcua_client(url, "operator", "operator") as client:
            level = await tag_node(client, "LEVEL")
            deadline = time.monotonic() + 5
            while not (dv := await level.read_data_value(raise_on_bad_status=False)).StatusCode.is_good():
                assert time.monotonic() < deadline, dv.StatusCode
                await asyncio.sleep(0.05)
            kind = dv.Value.VariantType
            sp = await tag_node(client, "SETPOINT")
            await sp.write_value(ua.DataValue(ua.Variant(1234, ua.VariantType.UInt16)))
            written = await sp.read_value()
            runtime.simulators[0].stop()  # LEVEL is filled by node 0's NREAD: its quality follows the link
            deadline = time.monotonic() + 10
            while (dv := await level.read_data_value(raise_on_bad_status=False)).StatusCode.value != \
                    ua.StatusCodes.BadCommunicationError:
                assert time.monotonic() < deadline, dv.StatusCode
                await asyncio.sleep(0.05)
            return kind, written

    try:
        assert run(go()) == (ua.VariantType.UInt16, 1234)
    finally:
        runtime.stop()
