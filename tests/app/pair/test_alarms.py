"""The alarm states follow the primary to its standby (issue 26): acknowledged on the primary, the
primary killed, the new primary shows the alarm acknowledged by the same user; shelving and
out-of-service likewise, and a standby that comes late gets every alarm's state at once."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from asyncua import Client, ua

from app.authority import Source, Who
from app.scada.alarms import NO_STANDBY_ID, Alarm, State
from app.scada.horn import Horn
from netplc.simulator import Simulator
from tests.app.pair.conftest import Station, give_users, make_pair, serve_opcua, start_pair, wait_for
from tests.app.publish.conftest import opcua_client
from tests.app.publish.test_opcua_conditions import call, eid, subscribe, text, until

TAGS = """\
name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description,hh,h,l,ll,deadband,on_delay,off_delay,alarm_when,priority,latching,suppress_by,quality_alarm
TRIP,02600,bit,,,,,,,Pump trip,,,,,,,,1,2,,,
DOOR,02601,bit,,,,,,,Door open,,,,,,,,1,3,,,
FAN,02602,bit,,,,,,,Fan fault,,,,,,,,1,3,,,
"""
BITS = {"TRIP.ALARM": 0o2600, "DOOR.ALARM": 0o2601, "FAN.ALARM": 0o2602}
TRIP = "TRIP.ALARM"
IVAN = Who("ivan", Source.CONSOLE, "test")
OLGA = Who("olga", Source.CONSOLE, "test")  # an engineer: out of service is hers


@pytest.fixture
def alarm_pair(tmp_path: Path, node: Simulator) -> Iterator[tuple[Station, Station]]:
    a, b = make_pair(tmp_path, node, top='Tags = "tags.csv"\n', files={"tags.csv": TAGS})
    give_users((a, b), ("ivan", "operator", "ivan-secret"), ("olga", "engineer", "olga-secret"))
    yield a, b
    for st in (b, a):
        st.stop()


def alarm(station: Station, alarm_id: str) -> Alarm:
    assert station.rt.alarms is not None
    return station.rt.alarms.system.get(alarm_id)


def raise_alarm(station: Station, alarm_id: str) -> None:
    assert station.rt.engine is not None and station.rt.engine.write_bit(BITS[alarm_id], 1, user="test")
    wait_for(lambda: alarm(station, alarm_id).state is State.UNACK, what=f"{alarm_id} active")


def test_acknowledged_on_the_primary_acknowledged_on_the_new_primary(
        alarm_pair: tuple[Station, Station]) -> None:
    a, b = alarm_pair
    start_pair(a, b)
    for alarm_id in BITS:
        raise_alarm(a, alarm_id)
    assert a.rt.commands is not None
    assert a.rt.commands.acknowledge(IVAN, "TRIP.ALARM").result(3).ok
    assert a.rt.commands.shelve(IVAN, "DOOR.ALARM", "door propped open for the fitters", 3600).result(3).ok
    assert a.rt.commands.out_of_service(OLGA, "FAN.ALARM").result(3).ok  # answered: B holds it
    a.kill()
    wait_for(lambda: b.role == "primary", what="takeover")
    trip, door, fan = (alarm(b, alarm_id) for alarm_id in BITS)
    assert (trip.state, trip.acked_by) == (State.ACKED, "ivan")
    assert (door.state, door.shelved_by, door.reason) == (State.SHELVED, "ivan",
                                                          "door propped open for the fitters")
    assert (fan.state, fan.oos_by) == (State.OUT_OF_SERVICE, "olga")
    assert b.rt.alarms is not None
    # nothing to do again, but one new alarm: B leads with no standby (in the banner, it sounds)
    wait_for(lambda: alarm(b, NO_STANDBY_ID).state is State.UNACK, what="PAIR.NO_STANDBY")
    assert [r.id for r in b.rt.alarms.summary if r.state is State.UNACK] == [NO_STANDBY_ID]
    assert alarm(b, NO_STANDBY_ID).text.startswith("No standby: the pair runs on one station: pair link to")


def test_a_standby_that_comes_late_gets_every_alarm_s_state(alarm_pair: tuple[Station, Station]) -> None:
    a, b = alarm_pair
    a.start()
    raise_alarm(a, "TRIP.ALARM")
    assert a.rt.commands is not None
    assert a.rt.commands.acknowledge(IVAN, "TRIP.ALARM").result(3).ok
    b.start()
    assert b.role == "standby"
    wait_for(lambda: alarm(b, "TRIP.ALARM").acked_by == "ivan", what="B has A's acknowledgement")
    assert alarm(b, "TRIP.ALARM").state is State.ACKED


def test_no_standby_is_an_alarm_of_the_primary_until_its_partner_is_back(
        alarm_pair: tuple[Station, Station]) -> None:
    a, b = alarm_pair
    a.start()  # alone: it leads with no standby
    wait_for(lambda: alarm(a, NO_STANDBY_ID).state is State.UNACK, what="A has no standby")
    b.start()
    wait_for(lambda: alarm(a, NO_STANDBY_ID).state is State.RTNUN, what="B is A's standby")
    wait_for(lambda: alarm(b, NO_STANDBY_ID).state is State.RTNUN, what="and B shows A's")


def test_the_conditions_show_the_adopted_states_and_take_the_acknowledgement_after_a_takeover(
        alarm_pair: tuple[Station, Station]) -> None:
    """The standby journals no transition of the primary's alarms, yet its OPC UA conditions show
    them (it answers reads), and so do the new primary's after a kill: ConditionRefresh there
    reports the alarm active and unacknowledged, and its Acknowledge works."""
    a, b = alarm_pair
    b_url = serve_opcua(b)  # B's server: A's is not asked
    refresh = ua.NodeId(ua.ObjectIds.ConditionType_ConditionRefresh)
    end = ua.NodeId(ua.ObjectIds.RefreshEndEventType)

    async def refreshed(client: Client) -> Any:
        """TRIP's condition as a ConditionRefresh of a new subscription reports it."""
        events, sub, _ = await subscribe(client)
        assert await call(client, ua.NodeId(ua.ObjectIds.ConditionType), refresh,
                          ua.Variant(sub.subscription_id, ua.VariantType.UInt32)) == ua.StatusCodes.Good
        await until(lambda: any(e.EventType == end for e in events.events), "RefreshEnd")
        return next(e for e in events.events if getattr(e, "ConditionName", None) == TRIP)

    async def on_b() -> tuple[Any, Any, int]:
        async with opcua_client(b_url, "ivan", "ivan-secret") as client:
            before = await refreshed(client)  # B still the standby
            a.kill()
            await until(lambda: b.role == "primary", "B takes over")
        async with opcua_client(b_url, "ivan", "ivan-secret") as client:  # the client logs in anew
            after = await refreshed(client)
            cond = ua.NodeId(f"Alarms.{TRIP}", await client.get_namespace_index("urn:netplc:station:pair"))
            acked = await call(client, cond, ua.ObjectIds.AcknowledgeableConditionType_Acknowledge,
                               eid(after.EventId), text("seen after the takeover"))
        return before, after, acked

    try:
        start_pair(a, b)
        raise_alarm(a, TRIP)
        wait_for(lambda: alarm(b, TRIP).state is State.UNACK, what="B holds A's alarm")
        before, after, acked = asyncio.run(on_b())
        wait_for(lambda: alarm(b, TRIP).state is State.ACKED, what="acknowledged on B")
        assert alarm(b, TRIP).acked_by.startswith("opcua:ivan@")
    finally:
        b.stop()
        a.stop()
    for event in (before, after):
        assert (getattr(event, "ActiveState/Id"), getattr(event, "AckedState/Id")) == (True, False)
        assert (event.Severity, event.Retain) == (700, True)  # priority 2
    assert acked == ua.StatusCodes.Good


def test_the_standby_s_horn_bit_is_the_primary_s_and_a_silence_holds_after_a_takeover(
        tmp_path: Path, node: Simulator) -> None:
    """The standby mirrors the primary's memory, the horn bit (`alarm_horn`) included: its own
    adopted alarm states never set it; the primary's silence is mirrored, so after a takeover
    the silenced horn stays silent."""
    horn = 0o3600
    a, b = make_pair(tmp_path, node, top=f'Tags = "tags.csv"\nalarm_horn = "0{horn:o}"\n',
                     files={"tags.csv": TAGS})
    give_users((a, b), ("ivan", "operator", "ivan-secret"))
    try:
        start_pair(a, b)
        raise_alarm(a, TRIP)  # priority 2: it sounds
        wait_for(lambda: alarm(b, TRIP).state is State.UNACK, what="B holds A's alarm")
        wait_for(lambda: a.bit(horn) == 1 and b.bit(horn) == 1, what="the horn bit on both")
        assert a.rt.commands is not None and a.rt.commands.silence(IVAN).result(3).ok
        wait_for(lambda: a.bit(horn) == 0 and b.bit(horn) == 0, what="silenced on both")
        assert b.rt.alarms is not None and not b.rt.alarms.horn.sounding
        scan = b.rt.engine.snapshot.scan if b.rt.engine is not None else 0
        wait_for(lambda: b.rt.engine is not None and b.rt.engine.snapshot.scan > scan + 10,
                 what="B's scans go on")
        assert b.bit(horn) == 0  # no scan of B's own set it
        silenced = b.rt.alarms.horn.silenced_at
        assert a.rt.alarms is not None and silenced == a.rt.alarms.horn.silenced_at > 0
        a.kill()
        wait_for(lambda: b.role == "primary", what="takeover")
        # B sounds for its own new alarm, PAIR.NO_STANDBY, and not again for the silenced TRIP
        wait_for(lambda: b.bit(horn) == 1, what="B's horn for PAIR.NO_STANDBY")
        assert b.rt.alarms.horn.silenced_at == silenced
        others = [r for r in b.rt.alarms.summary if r.id != NO_STANDBY_ID]
        assert not Horn(silenced_at=silenced).update(others)
    finally:
        b.stop()
        a.stop()
