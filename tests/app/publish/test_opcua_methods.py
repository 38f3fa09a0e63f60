"""The station's OPC UA methods (run, stop, step, force, unforce) are its commands, with the
session's user: what a remote Program view needs to act as a logged-in user of the station."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from pathlib import Path

import pytest
from asyncua import ua

from app.station.runtime import Runtime
from tests.app.publish.conftest import STATION_URI, demo_with, free_port, opcua_client

BIT = 0o2120  # the demo's PUMP command bit


@pytest.fixture
def station(tmp_path: Path) -> Iterator[tuple[Runtime, str, list]]:
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    runtime = demo_with(tmp_path / "station", f'[opcua]\nenabled = true\nendpoint = "{url}"\n')
    records: list = []
    runtime.subscribe(records.append)
    yield runtime, url, records
    runtime.stop()


async def call(client: object, name: str, *args: ua.Variant) -> int:
    ns = await client.get_namespace_index(STATION_URI)
    station = client.get_node(ua.NodeId("Demo station", ns))
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
        station: tuple[Runtime, str, list]) -> None:
    runtime, url, records = station

    async def go() -> list[int]:
        async with opcua_client(url, "operator", "operator") as client:
            codes = [await call(client, "Force", *force(1)), await call(client, "Stop")]
        async with opcua_client(url, "engineer", "engineer") as client:
            codes += [await call(client, "Force", *force(1, "nibble")),
                      await call(client, "Force", *force(1, "bit", "09")),
                      await call(client, "Force", *force(1)[:2]),
                      await call(client, "Step")]  # NetPlc runs: one scan only while stopped
        return codes

    assert run(go()) == [ua.StatusCodes.BadUserAccessDenied] * 2 + [ua.StatusCodes.BadInvalidArgument] * 2 + [
        ua.StatusCodes.BadArgumentsMissing, ua.StatusCodes.BadInvalidArgument]
    assert runtime.engine.forces.count == 0 and runtime.engine.state_text == "running"
    refused = [r.text for r in records if r.kind == "operator" and "refused" in r.text]
    assert any("needs the engineer role; operator is operator" in t for t in refused)
    assert any("'nibble' is not one of bit, byte, word" in t for t in refused)


def test_user_executable_follows_the_sessions_role(station: tuple[Runtime, str, list]) -> None:
    _, url, _ = station

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
