"""The ISA-18.2 alarm life cycle, stepped with an injected clock: every transition, delays and
deadband, shelving, suppression, out of service, latching, acknowledgements and their records."""

from __future__ import annotations

import numpy as np
import pytest

from app.scada.alarms import ONE_SHOT_LIMIT, AlarmError, AlarmSystem, State
from app.scada.quality import Quality
from app.scada.table import TagAlarms, TagTable
from app.scada.tag import Scaling, Tag, TagType
from netplc.memory import Memory
from netplc.records import ListSink
from registrar.catalog import Message

LEVEL = Tag("LEVEL", 0o4010, TagType.WORD, "%", Scaling(0, 4095, 0, 100), 1, "Уровень")
TRIG = Tag("TRIG", 0o2005, TagType.BIT, description="Триггер")
SUPPRESS = 0o2300
T0 = 1_800_000_000.0  # wall clock of the first scan


class Rig:
    """An alarm system over one memory, scanned at the times the test names."""

    def __init__(self, level: TagAlarms | None = None, trig: TagAlarms | None = None,
                 messages: list[Message] | None = None, saved: dict | None = None) -> None:
        alarms = {}
        if level is not None:
            alarms["LEVEL"] = level
        if trig is not None:
            alarms["TRIG"] = trig
        self.table = TagTable([LEVEL, TRIG], alarms)
        self.mem = Memory()
        self.sink = ListSink()
        self.saved: dict = {}
        self.system = AlarmSystem(self.table, messages or [], sink=self.sink, saved=saved,
                                  on_change=self.saved.update, clock=lambda: self.now)
        self.now = T0
        self.quality = np.zeros(2, dtype=np.int8)

    def level(self, phy: float) -> None:
        self.mem.set_word(LEVEL.address, int(LEVEL.to_raw(phy)))

    def scan(self, at: float, messages: tuple[int, ...] = ()) -> list[tuple[str, str, str]]:
        """Scan at T0 + `at` seconds; the transitions as (alarm, old, new)."""
        self.now = T0 + at
        out = self.system.evaluate(self.mem.snapshot(), self.now, self.quality, messages)
        return [(t.alarm, t.old.word, t.new.word) for t in out]

    def state(self, alarm_id: str) -> State:
        return self.system.get(alarm_id).state


HIGH = TagAlarms(hh=95, h=90, l=10, ll=5, deadband=2, on_delay=1.0, off_delay=0.5, priority=2)


def test_a_limit_alarm_through_on_delay_ack_deadband_and_off_delay() -> None:
    r = Rig(HIGH)
    r.level(50)
    assert r.scan(0) == []
    r.level(92)
    assert r.scan(0.1) == []  # on delay: 1 s
    assert r.scan(1.0) == []
    assert r.scan(1.1) == [("LEVEL.H", "normal", "active-unacknowledged")]
    assert r.system.get("LEVEL.H").acked_by == ""
    ack = r.system.acknowledge("LEVEL.H", "ivanov")
    assert [(t.old, t.new, t.user) for t in ack] == [(State.UNACK, State.ACKED, "ivanov")]
    assert r.system.get("LEVEL.H").acked_by == "ivanov"  # kept with the state (a pair's standby too)
    r.level(88.5)  # below H but inside the deadband (90 - 2): still active
    assert r.scan(2.0) == []
    r.level(87)
    assert r.scan(3.0) == []  # off delay: 0.5 s
    assert r.scan(3.5) == [("LEVEL.H", "active-acknowledged", "normal")]


def test_returned_unacknowledged_then_back_and_acknowledged() -> None:
    r = Rig(TagAlarms(h=90, priority=2))
    r.level(91)
    assert r.scan(0) == [("LEVEL.H", "normal", "active-unacknowledged")]
    r.level(80)
    assert r.scan(1) == [("LEVEL.H", "active-unacknowledged", "returned-unacknowledged")]
    r.level(95)  # comes again before anyone acknowledged: the same alarm, unacknowledged again
    assert r.scan(2) == [("LEVEL.H", "returned-unacknowledged", "active-unacknowledged")]
    r.level(80)
    r.scan(3)
    assert [(t.old.word, t.new.word) for t in r.system.acknowledge("LEVEL.H", "op")] == [
        ("returned-unacknowledged", "normal")]
    assert r.system.acknowledge("LEVEL.H", "op") == []  # nothing left to acknowledge
    r.level(95)
    r.scan(4)
    assert r.system.get("LEVEL.H").acked_by == ""  # a new alarm: nobody has acknowledged it


def test_the_deadband_keeps_a_noisy_value_from_chattering() -> None:
    r = Rig(TagAlarms(h=90, deadband=2))
    changes = []
    for k, v in enumerate([90.2, 89.0, 90.5, 88.3, 90.1, 87.9]):
        r.level(v)
        changes += r.scan(k)
    assert changes == [("LEVEL.H", "normal", "active-unacknowledged"),
                       ("LEVEL.H", "active-unacknowledged", "returned-unacknowledged")]


def test_a_condition_shorter_than_the_on_delay_raises_nothing() -> None:
    r = Rig(TagAlarms(h=90, on_delay=2))
    for k, v in enumerate([95, 95, 80, 95, 95, 80]):
        r.level(v)
        assert r.scan(k) == []


def test_an_on_delay_alarm_is_not_raised_when_its_condition_cleared_before_the_delay_ended() -> None:
    """LEVEL.H came on at 89.9 % (limit 90 %, deadband 2): the deadband held the pending condition,
    not only the alarm that was on."""
    r = Rig(TagAlarms(h=90, deadband=2, on_delay=2, off_delay=1))
    r.level(90.5)
    assert r.scan(0) == []  # the on delay starts
    r.level(89.9)  # back below the limit, inside the deadband, before the delay ended
    for k in range(1, 6):
        assert r.scan(k) == []
    assert r.state("LEVEL.H") is State.NORMAL
    r.level(90.5)  # a condition that lasts raises the alarm after the delay; the deadband then holds it
    assert r.scan(6) == [] and r.scan(8) == [("LEVEL.H", "normal", "active-unacknowledged")]
    r.level(89.9)
    assert r.scan(9) == [] and r.scan(11) == []
    r.level(87.5)
    assert r.scan(12) == []
    assert r.scan(13) == [("LEVEL.H", "active-unacknowledged", "returned-unacknowledged")]


def test_high_high_and_low_low_are_alarms_of_their_own() -> None:
    r = Rig(TagAlarms(hh=95, h=90, l=10, ll=5))
    r.level(97)
    assert sorted(r.scan(0)) == [("LEVEL.H", "normal", "active-unacknowledged"),
                                 ("LEVEL.HH", "normal", "active-unacknowledged")]
    r.level(3)
    assert sorted(r.scan(1)) == [("LEVEL.H", "active-unacknowledged", "returned-unacknowledged"),
                                 ("LEVEL.HH", "active-unacknowledged", "returned-unacknowledged"),
                                 ("LEVEL.L", "normal", "active-unacknowledged"),
                                 ("LEVEL.LL", "normal", "active-unacknowledged")]


@pytest.mark.parametrize("when", [0, 1])
def test_a_discrete_alarm_on_the_bits_value(when: int) -> None:
    r = Rig(trig=TagAlarms(alarm_when=when, priority=1))
    r.mem.set_bit(TRIG.address, 1 - when)
    assert r.scan(0) == []
    r.mem.set_bit(TRIG.address, when)
    assert r.scan(1) == [("TRIG.ALARM", "normal", "active-unacknowledged")]
    assert r.system.get("TRIG.ALARM").defn.priority == 1


def test_latching_holds_the_alarm_until_it_is_acknowledged() -> None:
    r = Rig(TagAlarms(h=90, latching=True))
    r.level(95)
    r.scan(0)
    r.level(50)
    assert r.scan(1) == []  # the condition has gone: still active-unacknowledged
    assert r.state("LEVEL.H") is State.UNACK
    assert [t.new for t in r.system.acknowledge("LEVEL.H", "op")] == [State.NORMAL]
    # acknowledged while active, then the condition goes: latched until reset by an acknowledgement
    r.level(95)
    r.scan(2)
    r.system.acknowledge("LEVEL.H", "op")
    r.level(50)
    assert r.scan(3) == []
    assert r.state("LEVEL.H") is State.ACKED
    reset = r.system.acknowledge("LEVEL.H", "op")
    assert [(t.old, t.new) for t in reset] == [(State.ACKED, State.NORMAL)] and "reset" in reset[0].text


def test_shelving_by_a_named_operator_runs_out_by_itself() -> None:
    r = Rig(TagAlarms(h=90))
    r.level(95)
    r.scan(0)
    shelved = r.system.shelve("LEVEL.H", "petrov", "sensor being replaced", 60)
    assert [(t.old, t.new, t.user) for t in shelved] == [(State.UNACK, State.SHELVED, "petrov")]
    assert "sensor being replaced" in shelved[0].text and "60 s" in shelved[0].text
    assert r.system.get("LEVEL.H").shelved_until == T0 + 60
    r.level(50)
    assert r.scan(10) == []  # nothing is annunciated while shelved
    r.level(95)
    assert r.scan(20) == []
    assert r.scan(59.9) == []
    assert r.scan(60) == [("LEVEL.H", "shelved", "active-unacknowledged")]  # back, still active
    r.system.acknowledge("LEVEL.H", "op")
    r.system.shelve("LEVEL.H", "petrov", "again", 5)
    r.level(50)
    r.scan(61)
    assert r.scan(66) == [("LEVEL.H", "shelved", "normal")]  # back, the condition has gone


def test_shelving_needs_a_name_a_reason_and_a_duration_and_unshelve_ends_it() -> None:
    r = Rig(TagAlarms(h=90))
    for user, reason, duration in (("", "x", 10), ("op", " ", 10), ("op", "x", 0), ("op", "x", float("nan"))):
        with pytest.raises(AlarmError):
            r.system.shelve("LEVEL.H", user, reason, duration)
    with pytest.raises(AlarmError, match="no alarm 'NOPE'"):
        r.system.acknowledge("NOPE", "op")
    r.system.shelve("LEVEL.H", "op", "test", 100)
    assert [(t.old, t.new) for t in r.system.unshelve("LEVEL.H", "op")] == [(State.SHELVED, State.NORMAL)]


def test_a_one_shot_shelving_ends_when_the_condition_next_returns_to_normal() -> None:
    r = Rig(TagAlarms(h=90))
    r.level(50)
    r.scan(0)
    once = r.system.shelve("LEVEL.H", "petrov", "known fault", ONE_SHOT_LIMIT, once=True)
    assert [(t.old, t.new) for t in once] == [(State.NORMAL, State.SHELVED)]
    assert "shelved once, until it returns to normal" in once[0].text and r.system.get("LEVEL.H").one_shot
    r.level(95)
    assert r.scan(1) == []  # comes while shelved: not annunciated
    r.level(50)
    back = r.scan(2)  # goes: the shelving has done its one shot
    assert back == [("LEVEL.H", "shelved", "normal")]
    assert "one-shot shelving by petrov ended: returned to normal" in r.sink.records[-1].text
    a = r.system.get("LEVEL.H")
    assert (a.shelved_until, a.one_shot, a.shelved_by) == (None, False, "")
    r.system.shelve("LEVEL.H", "petrov", "never comes back", 10, once=True)
    assert r.scan(12) == [("LEVEL.H", "shelved", "normal")]  # and runs out at its limit
    assert not r.system.get("LEVEL.H").one_shot


def test_comments_are_journaled_with_the_alarm_and_kept_as_its_last() -> None:
    r = Rig(TagAlarms(h=90))
    r.level(95)
    r.scan(0)
    said = r.system.comment("LEVEL.H", "petrov", "technician called")
    assert [(t.old, t.new, t.user) for t in said] == [(State.UNACK, State.UNACK, "petrov")]
    assert "comment: technician called; by petrov" in said[0].text
    ack = r.system.acknowledge("LEVEL.H", "ivanov", comment="seen, valve closed")
    assert "acknowledged: seen, valve closed; by ivanov" in ack[0].text
    a = r.system.get("LEVEL.H")
    assert (a.comment, a.comment_by) == ("seen, valve closed", "ivanov")
    with pytest.raises(AlarmError, match="empty"):
        r.system.comment("LEVEL.H", "petrov", " ")


def test_suppressed_by_design_while_the_condition_bit_is_1() -> None:
    r = Rig(TagAlarms(h=90, suppress_by=SUPPRESS))
    r.mem.set_bit(SUPPRESS, 1)
    assert r.scan(0) == [("LEVEL.H", "normal", "suppressed")]
    r.level(95)
    assert r.scan(1) == []
    r.mem.set_bit(SUPPRESS, 0)
    assert r.scan(2) == [("LEVEL.H", "suppressed", "active-unacknowledged")]


def test_out_of_service_and_back() -> None:
    r = Rig(TagAlarms(h=90))
    r.level(95)
    r.scan(0)
    oos = r.system.set_out_of_service("LEVEL.H", "engineer")
    assert [(t.old, t.new, t.user) for t in oos] == [(State.UNACK, State.OUT_OF_SERVICE, "engineer")]
    r.level(50)
    assert r.scan(1) == []
    assert r.system.acknowledge_all("op") == []
    back = r.system.set_out_of_service("LEVEL.H", "engineer", False)
    assert [(t.old, t.new) for t in back] == [(State.OUT_OF_SERVICE, State.NORMAL)]


def test_bad_quality_is_its_own_alarm_and_freezes_the_process_alarms() -> None:
    r = Rig(TagAlarms(h=90, quality_alarm=True))
    r.level(50)
    r.scan(0)
    r.quality[0] = Quality.COMM_FAIL
    r.level(95)  # a value that cannot be trusted raises no process alarm
    assert r.scan(1) == [("LEVEL.BAD", "normal", "active-unacknowledged")]
    assert r.scan(2) == []
    r.quality[0] = Quality.GOOD
    assert sorted(r.scan(3)) == [("LEVEL.BAD", "active-unacknowledged", "returned-unacknowledged"),
                                 ("LEVEL.H", "normal", "active-unacknowledged")]
    r.quality[0] = Quality.STALE
    r.level(50)  # nor does it say the alarm has gone
    r.scan(4)
    assert r.state("LEVEL.H") is State.UNACK
    r.quality[0] = Quality.FORCED  # forced is shown, not bad
    r.scan(5)
    assert r.state("LEVEL.H") is State.RTNUN


def test_quality_may_be_given_by_tag_name() -> None:
    r = Rig(TagAlarms(h=90, quality_alarm=True))
    out = r.system.evaluate(r.mem.snapshot(), T0, {"LEVEL": Quality.COMM_FAIL})
    assert [(t.alarm, t.new) for t in out] == [("LEVEL.BAD", State.UNACK)]


def test_nmsg_alarm_and_critical_messages_are_alarms_with_one_identity() -> None:
    catalog = [Message(1, 1, 0, "Пуск нажат"), Message(3, 1, 2, "Уровень выше 90 %"),
               Message(7, 1, 3, "Авария насоса")]
    r = Rig(messages=catalog)
    assert sorted(a.id for a in r.system.alarms) == ["MSG3", "MSG7"]
    assert r.system.get("MSG3").defn.priority == 2 and r.system.get("MSG7").defn.priority == 1
    assert r.scan(0, messages=(1, 3)) == [("MSG3", "normal", "active-unacknowledged")]
    assert r.scan(1) == [("MSG3", "active-unacknowledged", "returned-unacknowledged")]
    assert r.scan(2, messages=(3,)) == [("MSG3", "returned-unacknowledged", "active-unacknowledged")]
    assert len(r.system.alarms) == 2  # a repeating message does not pile up


def test_acknowledge_all_acknowledges_each_unacknowledged_alarm_once_naming_it() -> None:
    r = Rig(TagAlarms(hh=95, h=90, priority=3), TagAlarms(alarm_when=1, priority=1))
    r.level(97)
    r.mem.set_bit(TRIG.address, 1)
    r.scan(0)
    r.system.acknowledge("LEVEL.HH", "op")
    r.mem.set_bit(TRIG.address, 0)
    r.scan(1)  # TRIG.ALARM returned unacknowledged
    before = len(r.sink.records)
    done = r.system.acknowledge_all("sidorov")
    assert [(t.alarm, t.new) for t in done] == [("TRIG.ALARM", State.NORMAL), ("LEVEL.H", State.ACKED)]
    records = r.sink.records[before:]
    assert len(records) == 2 and all("by sidorov" in rec.text for rec in records)
    assert [rec.source for rec in records] == ["TRIG.ALARM", "LEVEL.H"]
    assert r.system.acknowledge_all("sidorov") == []


def test_every_transition_is_one_alarm_record_with_identity_states_value_and_user() -> None:
    r = Rig(TagAlarms(h=90, priority=2))
    r.level(93.2)
    r.scan(0)
    r.system.acknowledge("LEVEL.H", "ivanov")
    first, second = r.sink.records
    raw = LEVEL.to_raw(93.2)
    assert (first.kind, first.source, first.grp, first.number, first.type) == (
        "alarm", "LEVEL.H", 2, State.NORMAL, State.UNACK)
    assert first.value == pytest.approx(LEVEL.scaling.to_phy(raw))
    assert first.ts == T0
    assert first.text == (f"LEVEL.H normal -> active-unacknowledged: Уровень: high (H 90.0 %); "
                          f"LEVEL = {LEVEL.format(LEVEL.scaling.to_phy(raw))} (raw {raw:g})")
    assert (second.number, second.type) == (State.UNACK, State.ACKED)
    assert second.text.endswith("; acknowledged; by ivanov")


def test_the_summary_lists_by_priority_then_newest_and_counts_per_priority() -> None:
    r = Rig(TagAlarms(h=90, priority=3), TagAlarms(alarm_when=1, priority=1))
    r.level(95)
    r.scan(0)
    r.mem.set_bit(TRIG.address, 1)
    r.scan(1)
    assert [a.id for a in r.system.listed()] == ["TRIG.ALARM", "LEVEL.H"]
    assert r.system.counts() == {1: 1, 2: 0, 3: 1, 4: 0}
    r.system.acknowledge("TRIG.ALARM", "op")
    first = r.system.first_unacknowledged()
    assert first is not None and first.id == "LEVEL.H"


def test_the_state_survives_a_restart_without_a_second_alarm() -> None:
    r = Rig(TagAlarms(hh=95, h=90, l=10), TagAlarms(alarm_when=1))
    r.level(97)
    r.mem.set_bit(TRIG.address, 1)
    r.scan(0)
    r.system.acknowledge("LEVEL.HH", "op")
    r.system.shelve("TRIG.ALARM", "op", "maintenance", 3600)
    saved = dict(r.saved)
    # the restart: a new system from the saved states; the conditions are still active
    again = Rig(TagAlarms(hh=95, h=90, l=10), TagAlarms(alarm_when=1), saved=saved)
    again.level(97)
    again.mem.set_bit(TRIG.address, 1)
    assert again.scan(5) == []
    assert again.state("LEVEL.H") is State.UNACK and again.state("LEVEL.HH") is State.ACKED
    assert again.state("TRIG.ALARM") is State.SHELVED
    assert again.system.get("TRIG.ALARM").shelved_until == T0 + 3600
    assert again.scan(3600) == [("TRIG.ALARM", "shelved", "active-unacknowledged")]
