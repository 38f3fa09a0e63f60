"""OPC UA writes are the station's commands: the role from the one policy, the type of the variable,
the tag's physical range, answered once applied, committed and readable, refusals journaled
throttled; UserAccessLevel per session."""

from __future__ import annotations

import asyncio
import sqlite3
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from asyncua import ua

from app.authority.users import Users
from app.station.runtime import Runtime
from tests.app.publish.conftest import STATION_URI, demo_with, free_port, opcua_client, tag_node
from tests.cheap_users import CHEAP

READ, WRITE, HISTORY = 1, 2, 4  # AccessLevel bits CurrentRead, CurrentWrite, HistoryRead


def _station(folder: Path) -> Iterator[tuple[Runtime, str, list]]:
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    runtime = demo_with(folder, f'[opcua]\nenabled = true\nendpoint = "{url}"\n'
                                'writable = ["TEMP_SP", "TRIGGER"]\n', language="en")
    records: list = []
    runtime.subscribe(records.append)
    yield runtime, url, records
    runtime.stop()


@pytest.fixture(scope="module")
def shared(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Runtime, str, list]]:
    yield from _station(tmp_path_factory.mktemp("writes") / "station")


@pytest.fixture
def station(shared: tuple[Runtime, str, list]) -> tuple[Runtime, str, list]:
    """One station for the tests that leave its users as they are, its records from the test's start
    (each client a source of its own: a refusal is journaled once per cause per source)."""
    shared[2].clear()
    return shared


@pytest.fixture
def own_station(tmp_path: Path) -> Iterator[tuple[Runtime, str, list]]:
    """A station of the test's own, whose users it may change."""
    yield from _station(tmp_path / "station")


def run(coro: object) -> object:
    return asyncio.run(coro)  # type: ignore[arg-type]


async def write(client: object, name: str, variant: ua.Variant,
                attribute: ua.AttributeIds = ua.AttributeIds.Value) -> int:
    """The StatusCode the server answers a write of `variant` to tag (or node id) `name`."""
    ns = await client.get_namespace_index(STATION_URI)
    node = client.get_node(ua.NodeId(name if "." in name else f"Tags.{name}", ns))
    try:
        await node.write_attribute(attribute, ua.DataValue(variant))
    except ua.UaStatusCodeError as e:
        return e.code
    return ua.StatusCodes.Good


def committed(runtime: Runtime, text: str) -> list[tuple[str, str]]:
    """The operator records on disk holding `text`, as (source, text); none while the day's table
    is not yet written (refusals are journaled without waiting for the commit)."""
    table = time.strftime("%d_%m_%Y")
    con = sqlite3.connect(f"file:{runtime.station.Archive}?mode=ro", uri=True)
    try:
        if not con.execute("SELECT 1 FROM sqlite_master WHERE name = ?", (table,)).fetchone():
            return []
        return con.execute(f'SELECT source, text FROM "{table}" WHERE kind = \'operator\' AND text LIKE ?',
                           (f"%{text}%",)).fetchall()
    finally:
        con.close()


def test_an_operator_writes_and_the_answer_comes_once_readable_and_committed(
        station: tuple[Runtime, str, list]) -> None:
    runtime, url, _ = station

    async def go() -> list[float]:
        seen = []
        async with opcua_client(url, "operator", "operator") as client:
            sp = await tag_node(client, "TEMP_SP")
            for value in (42.0, -20.5, 137.0):
                assert await write(client, "TEMP_SP", ua.Variant(value, ua.VariantType.Double)) == \
                    ua.StatusCodes.Good
                seen.append(await sp.read_value())  # at once: no waiting for a scan
                assert committed(runtime, "TEMP_SP")[-1][0].startswith("opcua:operator@127.0.0.1:")
            bit = ua.Variant(True, ua.VariantType.Boolean)
            assert await write(client, "TRIGGER", bit) == ua.StatusCodes.Good
        return seen

    seen = run(go())
    assert seen == [pytest.approx(v, abs=0.05) for v in (42.0, -20.5, 137.0)]


def test_wrong_types_ranges_and_what_is_never_writable_are_refused_each_with_its_code(
        station: tuple[Runtime, str, list]) -> None:
    _, url, records = station
    Double, Bad = ua.VariantType, ua.StatusCodes

    async def go() -> dict[str, int]:
        async with opcua_client(url, "operator", "operator") as client:
            codes = {
                "string": await write(client, "TEMP_SP", ua.Variant("42", Double.String)),
                "int32": await write(client, "TEMP_SP", ua.Variant(42, Double.Int32)),
                "float": await write(client, "TEMP_SP", ua.Variant(42.0, Double.Float)),
                "bit as double": await write(client, "TRIGGER", ua.Variant(1.0, Double.Double)),
                "hot": await write(client, "TEMP_SP", ua.Variant(1000.0, Double.Double)),
                "cold": await write(client, "TEMP_SP", ua.Variant(-1000.0, Double.Double)),
                "nan": await write(client, "TEMP_SP", ua.Variant(float("nan"), Double.Double)),
                "not named writable": await write(client, "LEVEL", ua.Variant(1.0, Double.Double)),
                "state": await write(client, "NetPlc.State", ua.Variant("stopped", Double.String)),
                "node": await write(client, "Nodes.0.Up", ua.Variant(False, Double.Boolean)),
                "name": await write(client, "TEMP_SP", ua.Variant(ua.LocalizedText("x")),
                                    ua.AttributeIds.DisplayName),
                "unknown": await write(client, "Tags.NOPE", ua.Variant(1.0, Double.Double)),
            }
            for _ in range(20):  # a client that insists: journaled once per cause per minute
                await write(client, "TEMP_SP", ua.Variant("42", Double.String))
                await write(client, "LEVEL", ua.Variant(1.0, Double.Double))
            sp = await tag_node(client, "TEMP_SP")
            codes["unchanged"] = await sp.read_value() < 150
        return codes

    codes = run(go())
    assert codes == {"string": Bad.BadTypeMismatch, "int32": Bad.BadTypeMismatch,
                     "float": Bad.BadTypeMismatch, "bit as double": Bad.BadTypeMismatch,
                     "hot": Bad.BadOutOfRange, "cold": Bad.BadOutOfRange,
                     "nan": Bad.BadOutOfRange, "not named writable": Bad.BadNotWritable,
                     "state": Bad.BadNotWritable, "node": Bad.BadNotWritable, "name": Bad.BadNotWritable,
                     "unknown": Bad.BadNodeIdUnknown, "unchanged": True}
    refused = [r for r in records if r.kind == "operator" and r.text.startswith("refused")]
    # one record per cause however often refused: type, range, not writable, unknown
    assert len(refused) == 4, [r.text for r in refused]
    assert all(r.source.startswith("opcua:operator@127.0.0.1:") for r in refused)
    assert [w for r in refused for w in ("a String for a Double variable", "outside -50.0 °C .. 150.0 °C",
                                         "[opcua] writable", "no such node") if w in r.text] == \
        ["a String for a Double variable", "outside -50.0 °C .. 150.0 °C", "[opcua] writable", "no such node"]


def test_a_viewer_and_an_anonymous_client_read_and_are_refused_writes(
        station: tuple[Runtime, str, list]) -> None:
    runtime, url, records = station

    async def attempts(user: str | None, password: str = "") -> list[int]:
        async with opcua_client(url, user, password) as client:
            sp = await tag_node(client, "TEMP_SP")
            assert await sp.read_value() is not None  # reading is for everyone let in
            codes = [await write(client, "TEMP_SP", ua.Variant(20.0 + i, ua.VariantType.Double))
                     for i in range(10)]
            codes.append(await write(client, "TEMP_SP", ua.Variant("20", ua.VariantType.String)))
            return codes

    for user, password in ((None, ""), ("viewer", "viewer")):
        assert set(run(attempts(user, password))) == {ua.StatusCodes.BadUserAccessDenied}
    refused = [r for r in records if r.kind == "operator" and "refused" in r.text]
    assert [r.source.split("@")[0].split(" ")[0] for r in refused] == ["opcua", "opcua:viewer"]
    assert "nobody is logged in (operator needed)" in refused[0].text
    assert "needs the operator role; viewer is viewer" in refused[1].text
    # what they tried is nowhere among the writes on disk (an operator's, of another test, may be)
    assert all("refused" in text for source, text in committed(runtime, "TEMP_SP")
               if not source.startswith("opcua:operator@"))


def test_user_access_level_follows_the_sessions_role(own_station: tuple[Runtime, str, list]) -> None:
    runtime, url, _ = own_station

    async def levels(user: str | None, password: str = "") -> dict[str, tuple[int, int]]:
        async with opcua_client(url, user, password) as client:
            out = {}
            for name in ("TEMP_SP", "LEVEL"):
                node = await tag_node(client, name)
                out[name] = (await node.read_attribute(ua.AttributeIds.AccessLevel)).Value.Value, \
                    (await node.read_attribute(ua.AttributeIds.UserAccessLevel)).Value.Value
            return out

    # both are archived (NSTORE): every user may read their history
    read, both = READ | HISTORY, READ | HISTORY | WRITE
    assert run(levels(None)) == {"TEMP_SP": (both, read), "LEVEL": (read, read)}
    assert run(levels("viewer", "viewer")) == {"TEMP_SP": (both, read), "LEVEL": (read, read)}
    assert run(levels("operator", "operator")) == {"TEMP_SP": (both, both), "LEVEL": (read, read)}
    users = Users(runtime.station.folder)  # demoted while the server runs: counts at the next read
    users.remove("operator")
    users.add("operator", "viewer", "operator", CHEAP)

    async def demoted() -> tuple[int, int]:
        async with opcua_client(url, "operator", "operator") as client:
            node = await tag_node(client, "TEMP_SP")
            before = (await node.read_attribute(ua.AttributeIds.UserAccessLevel)).Value.Value
            return before, await write(client, "TEMP_SP", ua.Variant(20.0, ua.VariantType.Double))

    assert run(demoted()) == (read, ua.StatusCodes.BadUserAccessDenied)
