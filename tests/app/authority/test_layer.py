"""The command layer (app/authority/layer.py): one policy for every source, answers after the
commit, throttled refusals, typed and ranged tag writes, a full journal refused at once."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.authority import Action, Commands, Reason, Source, Who, policy_table
from app.authority.policy import POLICY, ROLES
from app.scada.tag import Scaling, Tag, TagType
from netplc.engine import Engine, FakeClock
from netplc.program import parse
from netplc.records import ListSink

ROLES_OF = {"vera": "viewer", "olga": "operator", "egor": "engineer", "anna": "admin"}
SP = Tag("TEMP_SP", 0o4010, TagType.WORD, "°C", Scaling(0, 1000, -50, 150), 1, "Уставка")
PUMP = Tag("PUMP", 0o2000, TagType.BIT)


class Durable(ListSink):
    """A sink that commits when told: answers must wait for it."""

    def __init__(self, room: int = 1 << 20) -> None:
        super().__init__()
        self.waiting: list = []
        self.space = room

    def after_commit(self, callback) -> None:
        self.waiting.append(callback)

    def room(self) -> int:
        return self.space

    def commit(self) -> None:
        waiting, self.waiting = self.waiting, []
        for callback in waiting:
            callback()


def rig(room: int = 1 << 20) -> tuple[Commands, Engine, Durable, FakeClock, list[float]]:
    sink, clock, mono = Durable(room), FakeClock(), [0.0]
    engine = Engine(parse("TNA $03760\nYON $02001\n"), clock=clock, sink=sink, wallclock=lambda: 1000.0)
    layer = Commands(engine, sink, role_of=ROLES_OF.get, tags=[SP, PUMP], monotonic=lambda: mono[0])
    return layer, engine, sink, clock, mono


def scan(engine: Engine, clock: FakeClock) -> None:
    clock.advance(engine.tick)
    engine.scan()


@pytest.mark.parametrize("source", list(Source))
@pytest.mark.parametrize("user", list(ROLES_OF))
def test_one_policy_for_every_source(source, user):
    layer, *_ = rig()
    who = Who(user, source, "10.0.0.5:5000")
    for action, role in POLICY.items():
        assert layer.may(who, action) == (ROLES.index(ROLES_OF[user]) >= ROLES.index(role)), (action, user)


def test_a_form_element_may_ask_more_never_less():
    layer, *_ = rig()
    olga = Who("olga", Source.CONSOLE)
    assert layer.may(olga, Action.WRITE, "viewer")
    assert not layer.may(olga, Action.WRITE, "engineer")


def test_user_less_sources_act_with_their_role_and_unknown_users_with_none():
    layer, *_ = rig()
    assert layer.may(Who("", Source.MODBUS, "127.0.0.1:5"), Action.WRITE)
    assert not layer.may(Who("", Source.MODBUS, "127.0.0.1:5"), Action.FORCE)
    assert not layer.may(Who("", Source.OPCUA, "127.0.0.1:5"), Action.WRITE)  # anonymous
    denial = layer.denial(Who("ghost", Source.OPCUA), Action.WRITE)
    assert denial is not None and "no longer a user" in str(denial)


def test_a_write_is_answered_once_applied_and_committed():
    layer, engine, sink, clock, _ = rig()
    ticket = layer.write_tag(Who("olga", Source.OPCUA, "10.0.0.5:5000"), "TEMP_SP", 100.0)
    assert not ticket.done()
    scan(engine, clock)
    assert engine.mem.get_word(0o4010) == 750
    assert not ticket.done()  # applied, not yet on disk
    sink.commit()
    assert ticket.result().ok
    [record] = [r for r in sink.records if r.kind == "operator"]
    assert record.source == "opcua:olga@10.0.0.5:5000"
    assert "TEMP_SP" in record.text and "100.0 °C" in record.text


@pytest.mark.parametrize(("value", "reason"), [
    ("42", Reason.TYPE_MISMATCH), (None, Reason.TYPE_MISMATCH), (1000.0, Reason.OUT_OF_RANGE),
    (-1000.0, Reason.OUT_OF_RANGE), (float("nan"), Reason.OUT_OF_RANGE), (float("inf"), Reason.OUT_OF_RANGE),
])
def test_a_tag_write_is_checked_for_type_and_physical_range(value, reason):
    layer, engine, *_ = rig()
    answer = layer.write_tag(Who("olga", Source.MQTT), "TEMP_SP", value).result(0)
    assert answer.reason is reason
    assert engine.writes_waiting == 0


def test_bits_take_0_or_1_and_unknown_tags_are_named():
    layer, *_ = rig()
    olga = Who("olga", Source.OPCUA)
    assert layer.write_tag(olga, "PUMP", 2).result(0).reason is Reason.OUT_OF_RANGE
    assert layer.write_tag(olga, "PUMP", True).done() is False
    assert layer.write_tag(olga, "NOPE", 1).result(0).reason is Reason.UNKNOWN


def test_refusals_are_journaled_once_per_cause_per_source_per_minute_with_a_count():
    layer, _engine, sink, _clock, mono = rig()
    vera = Who("vera", Source.OPCUA, "10.0.0.9:4000")
    for i in range(3000):
        who = Who("vera", Source.OPCUA, f"10.0.0.9:{4000 + i % 7}")  # reconnecting clients count as one
        assert layer.write_tag(who, "TEMP_SP", 20.0).result(0).reason is Reason.DENIED
    assert len(sink.records) == 1 and "needs the operator role" in sink.records[0].text
    mono[0] = 61.0
    layer.write_tag(vera, "TEMP_SP", 20.0)
    assert len(sink.records) == 2 and "2999 more refused" in sink.records[1].text
    layer.write_tag(Who("vera", Source.MQTT), "TEMP_SP", 20.0)  # another source: its own record
    layer.acknowledge_all(vera)  # another action: its own record (no alarms here: not running)
    assert len(sink.records) == 4


def test_a_full_journal_refuses_at_once():
    layer, engine, *_ = rig(room=10)
    answer = layer.write_bit(Who("", Source.MODBUS, "127.0.0.1:9"), 0o2010, 1).result(0)
    assert answer.reason is Reason.JOURNAL_FULL
    assert engine.writes_waiting == 0


def test_forcing_needs_the_engineer_and_is_journaled_with_who():
    layer, engine, sink, clock, _ = rig()
    assert layer.force_tag(Who("olga", Source.CONSOLE), "TEMP_SP", 20.0).result(0).reason is Reason.DENIED
    ticket = layer.force_tag(Who("egor", Source.PROGRAM_VIEW), "TEMP_SP", 20.0)
    scan(engine, clock)
    sink.commit()
    assert ticket.result(0).ok and engine.forces.count == 1
    assert sink.records[-1].source == "program view:egor"
    too_hot = layer.force_tag(Who("egor", Source.CONSOLE), "TEMP_SP", 500.0).result(0)
    assert too_hot.reason is Reason.OUT_OF_RANGE


def test_a_force_of_an_address_that_is_no_integer_is_refused_as_invalid_naming_it():
    """A caller's octal text reaches the layer as it was typed: refused, journaled, never raised."""
    layer, engine, *_ = rig()
    who = Who("egor", Source.OPCUA, "10.0.0.5:5000")
    for ticket in (layer.force(who, "word", "04010", 5), layer.unforce(who, "bit", "02000")):  # type: ignore[arg-type]
        answer = ticket.result(0)
        assert answer.reason is Reason.INVALID
        assert "'04010'" in answer.text or "'02000'" in answer.text
    assert engine.forces.count == 0 and engine.writes_waiting == 0


def test_run_and_stop_need_the_engineer():
    layer, engine, sink, clock, _ = rig()
    assert layer.stop(Who("olga", Source.CONSOLE)).result(0).reason is Reason.DENIED
    ticket = layer.stop(Who("egor", Source.CONSOLE))
    scan(engine, clock)
    sink.commit()
    assert ticket.result(0).ok and engine.state == "stopped"
    assert sink.records[-1].text == "NetPlc stopped" and sink.records[-1].source == "egor"


def test_the_policy_table_prints_every_action():
    table = policy_table()
    assert all(f"| {a.value} | {POLICY[a]} |" in table for a in Action)


def test_the_manual_prints_the_policy_table_the_layer_uses_and_the_readme_links_to_it():
    repo = Path(__file__).resolve().parents[3]
    roles = (repo / "docs" / "reference" / "roles.md").read_text(encoding="utf-8")
    assert policy_table() in roles, "the manual's policy table is stale: run `make reference`"
    assert "(docs/reference/roles.md)" in (repo / "README.md").read_text(encoding="utf-8")


def test_user_administration_needs_the_admin_and_is_answered_after_the_commit():
    layer, _engine, sink, _clock, _ = rig()
    made: list[str] = []

    def change() -> str:
        made.append("ivan")
        return "user ivan added as operator"

    assert layer.manage_users(Who("egor", Source.CONSOLE), "ivan", change).result(0).reason is Reason.DENIED
    assert not made and "refused users ivan: needs the admin role" in sink.records[-1].text
    ticket = layer.manage_users(Who("anna", Source.CONSOLE), "ivan", change)
    assert made == ["ivan"] and not ticket.done()  # made, not yet on disk
    sink.commit()
    assert ticket.result(0).ok and (sink.records[-1].source, sink.records[-1].text) == (
        "anna", "user ivan added as operator")

    def taken() -> str:
        from app.authority.users import UserError

        raise UserError("user exists", name="ivan")

    answer = layer.manage_users(Who("anna", Source.CONSOLE), "ivan", taken).result(0)
    assert answer.reason is Reason.INVALID and "exists already" in answer.text


def test_setting_the_stop_bit_needs_the_role_stop_needs_however_it_is_written():
    layer, *_ = rig()
    modbus = Who("", Source.MODBUS, "127.0.0.1:9")  # acts as operator
    assert layer.write_bit(modbus, 0o3770, 1).result(0).reason is Reason.DENIED
    assert layer.write_bits(modbus, 0o3760, [0] * 8 + [1]).result(0).reason is Reason.DENIED
    assert layer.write_word(Who("olga", Source.CONSOLE), 0o3760, 1 << 8).result(0).reason is Reason.DENIED
    assert not layer.write_bit(modbus, 0o3770, 0).done()  # clearing it is a plain write
    assert not layer.write_bit(Who("egor", Source.CONSOLE), 0o3770, 1).done()  # the engineer may stop
