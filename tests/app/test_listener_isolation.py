"""Issue 23's acceptance: an engine listener that raises costs nothing but itself. The runtime's
other listeners (quality and alarms), the workstation's feed and the OPC UA server keep updating;
the fault is logged with its traceback, journaled once and named in the health strip."""

from __future__ import annotations

import asyncio
import sqlite3
import time
from pathlib import Path

from asyncua import Client, ua

from app.gui.bridge import RuntimeBridge
from tests.app.publish.conftest import STATION_URI, demo_with, free_port


def test_a_listener_that_raises_stops_neither_quality_nor_the_hmi_nor_opc_ua(qtbot, tmp_path: Path,
                                                                            caplog) -> None:
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    runtime = demo_with(tmp_path / "station", f'[opcua]\nenabled = true\nendpoint = "{url}"\n', language="en")
    try:
        engine = runtime.engine
        assert engine is not None

        def faulty(snapshot: object) -> None:
            raise RuntimeError("a faulty listener")

        engine.subscribe(faulty, "faulty")
        bridge = RuntimeBridge(runtime)
        scans: list[int] = []
        bridge.readings.connect(lambda r: scans.append(r.snapshot.scan))
        qtbot.waitUntil(lambda: len(scans) >= 3, timeout=10_000)  # the HMI's feed goes on
        first = runtime.readings()
        assert first is not None
        qtbot.waitUntil(lambda: runtime.readings().snapshot.scan >= first.snapshot.scan + 5, timeout=10_000)

        async def opcua_scans() -> list[int]:
            async with Client(url, timeout=30) as client:
                ns = await client.get_namespace_index(STATION_URI)
                scan = client.get_node(ua.NodeId("NetPlc.Tick", ns))
                seen = [await scan.read_value()]
                deadline = time.monotonic() + 10
                while seen[-1] <= seen[0] + 3 and time.monotonic() < deadline:
                    await asyncio.sleep(0.05)
                    seen.append(await scan.read_value())
                return seen

        seen = asyncio.run(opcua_scans())
        assert seen[-1] > seen[0] + 3  # OPC UA goes on
        assert "faulty" in engine.listener_faults
        assert any("engine listener faulty failed" in p for p in runtime.status().problems)
        assert any(r.exc_info and "a faulty listener" in str(r.exc_info[1]) for r in caplog.records)
        bridge.detach()
    finally:
        runtime.stop()
    with sqlite3.connect(runtime.station.Archive) as db:
        tables = [r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type='table' "
                                           "AND name GLOB '[0-9][0-9]_[0-9][0-9]_*'")]
        texts = [t for table in tables
                 for (t,) in db.execute(f'SELECT text FROM "{table}" WHERE text LIKE ?',
                                        ("engine listener faulty failed%",))]
    assert len(texts) == 1  # journaled once, not once per scan
