"""OPC UA clients told which station of the pair to use (Part 4 6.6.2, non-transparent
redundancy): RedundancySupport Hot, ServerUriArray the partner's ApplicationUri, ServiceLevel
high on the primary and low on the standby, the tags' NodeIds the same on both; and a remote
Program view given both endpoints follows the primary by itself, through IntoStandBy and a kill."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

from asyncua import Client, ua

from app.publish.client import StationClient
from netplc.simulator import Simulator
from tests.app.pair.conftest import give_users, make_pair, serve_opcua, start_pair, wait_for, wait_paired


async def redundancy(client: Client) -> dict[str, Any]:
    node = await client.nodes.server.get_child(["0:ServerRedundancy"])
    return {"level": await client.get_node(ua.ObjectIds.Server_ServiceLevel).read_value(),
            "support": await (await node.get_child(["0:RedundancySupport"])).read_value(),
            "uris": await (await node.get_child(["0:ServerUriArray"])).read_value(),
            "type": (await node.read_type_definition()).Identifier,
            "uri": (await client.get_endpoints())[0].Server.ApplicationUri,
            "ns": await client.get_namespace_index("urn:netplc:station:pair")}


def test_clients_are_told_the_primary_and_a_monitor_follows_it(tmp_path: Path, node: Simulator) -> None:
    a, b = make_pair(tmp_path, node)
    a_url, b_url = serve_opcua(a), serve_opcua(b)
    give_users((a, b), ("eng1", "engineer", "eng1"))

    async def told() -> None:
        async with Client(a_url) as on_a, Client(b_url) as on_b:
            of_a, of_b = await redundancy(on_a), await redundancy(on_b)
        assert (of_a["level"], of_b["level"]) == (255, 100)
        assert of_a["support"] == of_b["support"] == ua.RedundancySupport.Hot
        assert of_a["type"] == of_b["type"] == ua.ObjectIds.NonTransparentRedundancyType
        assert (of_a["uri"], of_b["uri"]) == ("urn:netplc:station:pair:A", "urn:netplc:station:pair:B")
        assert (of_a["uris"], of_b["uris"]) == ([of_b["uri"]], [of_a["uri"]])
        assert of_a["ns"] == of_b["ns"] == 2  # after each ApplicationUri: NodeIds hold on either

    client = StationClient(a_url, partner=b_url, folder=tmp_path / "config", period=0.05)
    try:
        start_pair(a, b)
        asyncio.run(told())
        client.discover().result(10)
        client.open("eng1", "eng1").result(20)
        wait_for(lambda: client.snapshot is not None, what="the monitor reads A")
        wait_paired(a, b)
        assert a.rt.pair is not None and a.rt.pair.into_standby("IntoStandBy by test", wait=2)
        wait_for(lambda: client.url == b_url and client.switches == 1, what="the monitor on B")
        wait_for(lambda: client.service_level == 255, what="B's ServiceLevel the primary's")
        assert client.user == "eng1"
        b.kill()
        wait_for(lambda: a.role == "primary", what="A takes over")
        wait_for(lambda: client.url == a_url and client.switches == 2 and not client.error, timeout=10,
                 what="the monitor back on A")
        scan = client.snapshot.scan if client.snapshot is not None else 0
        wait_for(lambda: client.snapshot is not None and client.snapshot.scan > scan, what="it reads A on")
    finally:
        client.close()
        b.stop()
        a.stop()
