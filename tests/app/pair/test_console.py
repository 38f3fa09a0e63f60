"""A remote console given both stations of the pair follows the primary with no action of the
operator (issue 26): through IntoStandBy and a kill of the new primary it shows live values and the
alarms of whichever leads, says in its header which station it is on and that it switched,
and a write from it after the switch is applied by the new primary."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from app.gui.console.source import StationSource
from app.gui.console.window import ConsoleWindow
from app.publish.console import ConsoleClient
from app.scada.alarms import State
from app.scada.readings import Readings
from app.station.config import Station as StationSettings
from netplc.simulator import Simulator
from tests.app.pair.conftest import TICK_MS, give_users, make_pair, serve_opcua, start_pair, wait_for
from tests.app.pair.test_alarms import TAGS, raise_alarm
from tests.app.test_consoles import WAIT, qualities, shown

WORD = 0o4000  # the operator's word of the pair's program
FORM = json.dumps({"form": {"title": "Pair", "width": 300, "height": 200}, "elements": [
    {"type": "AnalogBase", "Name": "Word", "x": 8, "y": 8, "w": 250, "h": 120, "InAddr": "04000",
     "AppMin": 0, "AppMax": 1000, "PhyMin": 0, "PhyMax": 1000}]})


def slower_failover(settings: StationSettings) -> StationSettings:
    assert settings.redundancy is not None
    return replace(settings, redundancy=replace(settings.redundancy, failover_after=1000 // TICK_MS))  # 1 s


def test_a_console_follows_the_primary_through_a_switchover_and_a_kill(
        qtbot, tmp_path: Path, node: Simulator) -> None:
    a, b = make_pair(tmp_path, node, top='Tags = "tags.csv"\nHMIload = "forms/"\n',
                     files={"tags.csv": TAGS, "forms/pair.hmi": FORM})
    a_url, b_url = serve_opcua(a), serve_opcua(b)
    for st in (a, b):  # a GUI and two endpoints in this process: the pair's silence judged less tightly
        served = st.adjust
        st.adjust = lambda settings, served=served: slower_failover(served(settings))
    give_users((a, b), ("operator", "operator", "operator"))
    client = ConsoleClient(a_url, partner=b_url, folder=tmp_path / "config", period=0.05)
    window: ConsoleWindow | None = None
    try:
        start_pair(a, b)
        wait_for(lambda: b.role == "standby", what="B the standby")
        raise_alarm(a, "TRIP.ALARM")
        client.discover().result(20)
        client.open("operator", "operator").result(30)
        window = ConsoleWindow(StationSource(client))
        window.show()
        seen: list[Readings] = []
        window.source.readings.connect(seen.append)
        console = window
        qtbot.waitUntil(lambda: bool(console.views) and qualities(console) == {""}
                        and "TRIP.ALARM" in shown(console), timeout=WAIT)
        assert console.header.title.text() == "pair A"

        assert a.rt.pair is not None and a.rt.pair.into_standby("IntoStandBy by test", wait=2)
        qtbot.waitUntil(lambda: client.url == b_url and client.switches == 1, timeout=WAIT)
        scan = client.snapshot.scan if client.snapshot is not None else 0
        qtbot.waitUntil(lambda: qualities(console) == {""} and seen[-1].snapshot.scan > scan
                        and console.header.title.text() == "pair B", timeout=WAIT)  # live from B
        assert "switched from pair A" in console.header.title.toolTip()
        raise_alarm(b, "DOOR.ALARM")  # the alarms read from B now
        qtbot.waitUntil(lambda: shown(console).get("DOOR.ALARM") is State.UNACK, timeout=WAIT)
        assert client.write_word(WORD, 321, "Word", None).result(20).ok
        assert b.word(WORD) == 321  # applied by the new primary (its journal names the console's user)
        assert any("opcua:operator@" in (r.source or "") for r in b.journal if r.kind == "operator")

        b.kill()
        wait_for(lambda: a.role == "primary", what="A takes over")
        qtbot.waitUntil(lambda: client.url == a_url and not client.error and qualities(console) == {""}
                        and console.header.title.text() == "pair A", timeout=WAIT)
        assert a.word(WORD) == 321 and shown(console).get("TRIP.ALARM") is State.UNACK
    finally:
        if window is not None:
            window.close()
            window.deleteLater()
        else:
            client.close()
        b.stop()
        a.stop()
