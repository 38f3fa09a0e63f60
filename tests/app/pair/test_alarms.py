"""The alarm states follow the primary to its standby (issue 26): acknowledged on the primary, the
primary killed, the new primary shows the alarm acknowledged by the same user; shelving and
out-of-service likewise, and a standby that comes late gets every alarm's state at once."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from app.authority import Source, Who
from app.authority.users import Users
from app.scada.alarms import NO_STANDBY_ID, Alarm, State
from netplc.simulator import Simulator
from tests.app.pair.conftest import Station, make_pair, wait_for

TAGS = """\
name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description,hh,h,l,ll,deadband,on_delay,off_delay,alarm_when,priority,latching,suppress_by,quality_alarm
TRIP,02600,bit,,,,,,,Pump trip,,,,,,,,1,2,,,
DOOR,02601,bit,,,,,,,Door open,,,,,,,,1,3,,,
FAN,02602,bit,,,,,,,Fan fault,,,,,,,,1,3,,,
"""
BITS = {"TRIP.ALARM": 0o2600, "DOOR.ALARM": 0o2601, "FAN.ALARM": 0o2602}
IVAN = Who("ivan", Source.CONSOLE, "test")
OLGA = Who("olga", Source.CONSOLE, "test")  # an engineer: out of service is hers


@pytest.fixture
def alarm_pair(tmp_path: Path, node: Simulator) -> Iterator[tuple[Station, Station]]:
    a, b = make_pair(tmp_path, node, top='Tags = "tags.csv"\n', files={"tags.csv": TAGS})
    for st in (a, b):
        users = Users(st.folder)
        users.add("ivan", "operator", "ivan-secret")
        users.add("olga", "engineer", "olga-secret")
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
    a.start()
    b.start()
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
