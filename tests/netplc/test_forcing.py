"""Forcing (netplc/forcing.py): force > program > live, bumpless, journaled with the user, one
"unforce all"; and stepping one scan with NetPlc stopped."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from netplc.engine import Engine, FakeClock, RunState
from netplc.forcing import Force, ForceError, load_forces, save_forces
from netplc.program import parse
from netplc.records import ListSink
from tests.hmi_forms.helpers import engine_target

# input 00000 -> coil 02000; the word 04000 is copied to 04002 by the program (MOV), and the
# program itself writes 04004 every scan; TIM 03000 counts while 00001 is on
PROGRAM = """
TNA $00000
YON $02000
TNA $03760
FON C:$02100 N:MOV S:$04000 D:$04002
TNA $03760
FON C:$02104 N:MVID S:7 D:$04004
TNA $00001
TIM $03000 N:5
"""


def engine(compiled: bool = True, program: str = PROGRAM) -> tuple[Engine, ListSink, FakeClock]:
    sink, clock = ListSink(), FakeClock()
    eng = Engine(parse(program), clock=clock, sink=sink, wallclock=lambda: 1000.0, compiled=compiled)
    return eng, sink, clock


def scans(eng: Engine, clock: FakeClock, n: int = 1) -> None:
    for _ in range(n):
        clock.advance(eng.tick)
        eng.scan()


def texts(sink: ListSink) -> list[tuple[str | None, str | None]]:
    return [(r.source, r.text) for r in sink.records if r.kind == "operator"]


@pytest.mark.parametrize("compiled", [True, False])
def test_a_forced_coil_beats_the_program_and_the_program_reads_a_forced_input(compiled: bool) -> None:
    eng, _, clock = engine(compiled)
    eng.mem.bits[0] = 1
    scans(eng, clock)
    assert eng.snapshot.get_bit(0o2000) == 1
    eng.forces.force("bit", 0o2000, 0, user="eng1")
    scans(eng, clock, 3)
    assert eng.snapshot.get_bit(0o2000) == 0 and eng.mem.get_bit(0o2000) == 0
    eng.forces.force("bit", 0o0, 0, user="eng1")  # the input: the program reads the forced 0
    eng.forces.unforce("bit", 0o2000, user="eng1")
    scans(eng, clock)
    assert eng.snapshot.get_bit(0o2000) == 0
    eng.forces.force("word", 0o4004, 0x1234, user="eng1")  # a word the program writes
    scans(eng, clock, 2)
    assert eng.snapshot.get_word(0o4004) == 0x1234


@pytest.mark.parametrize("compiled", [True, False])
def test_operator_modbus_and_exchange_writes_lose_to_the_force(compiled: bool) -> None:
    eng, sink, clock = engine(compiled)
    eng.forces.force("word", 0o4000, 500, user="eng1")
    eng.forces.force("bit", 0o40050, 1, user="eng1")  # byte 04005 bit 0: an HMI data bit
    scans(eng, clock)
    hmi = engine_target(eng)  # what a form's element writes through
    hmi.write_word(0o4000, 1, user="operator", label="Setpoint")
    eng.write_bytes(0o4000, b"\x02\x00", user="modbus 127.0.0.1:5000")  # the Modbus server's write
    eng.post(lambda mem: mem.set_word(0o4000, 3))  # how the exchange lands an NREAD result
    hmi.write_bit(0o40050, 0, user="operator", label="Пуск")
    scans(eng, clock)
    snap = eng.snapshot
    assert snap.get_word(0o4000) == 500 and snap.get_word(0o4002) == 500  # the program copied the force
    assert snap.get_hmi_bit(0o40050) == 1
    # the writes were applied and journaled all the same: they just lose (the exchange's result
    # lands first, then the outside writers in their order: netplc/engine.py)
    assert ("operator", "write Setpoint (04000): 3 -> 1") in texts(sink)
    assert ("modbus 127.0.0.1:5000", "write 04000:2: 01 00 -> 02 00") in texts(sink)


@pytest.mark.parametrize("compiled", [True, False])
def test_unforce_restores_live_behaviour_and_unforce_all_is_one_command(compiled: bool) -> None:
    eng, sink, clock = engine(compiled)
    eng.mem.bits[0] = 1
    for kind, addr, value in (("bit", 0o2000, 0), ("word", 0o4004, 9), ("byte", 0o4000, 0x55)):
        eng.forces.force(kind, addr, value, user="eng1")
    scans(eng, clock)
    assert eng.forces.count == 3 and len(eng.forces.listing) == 3
    assert eng.snapshot.forces == eng.forces.listing  # every reader of a snapshot sees what is forced
    assert [f.where for f in eng.snapshot.forces] == ["02000", "04004:word", "04000:byte"]
    eng.forces.unforce_all(user="eng2")
    scans(eng, clock)
    assert eng.forces.count == 0 and eng.snapshot.forces == ()
    snap = eng.snapshot
    assert snap.get_bit(0o2000) == 1 and snap.get_word(0o4004) == 7  # the program writes again
    assert snap.get_byte(0o4000) == 0x55  # nothing writes 04000: it keeps the value it was left
    eng.write_word(0o4000, 0x0102, user="op")
    scans(eng, clock)
    assert eng.snapshot.get_word(0o4000) == 0x0102
    unforced = [t for s, t in texts(sink) if s == "eng2"]
    assert unforced == ["unforce 02000 (was forced 0; unforce all)",
                        "unforce 04004:word (was forced 9; unforce all)",
                        "unforce 04000:byte (was forced 85; unforce all)"]


def test_a_force_without_a_value_is_bumpless_and_every_change_is_journaled_with_the_user() -> None:
    eng, sink, clock = engine()
    eng.mem.set_word(0o4000, 321)
    eng.mem.bits[0] = 1
    eng.forces.force("word", 0o4000, user="eng1")
    eng.forces.force("bit", 0o0, user="eng1")
    scans(eng, clock)
    assert eng.forces.forced("word", 0o4000) == Force("word", 0o4000, 321, "eng1")
    assert eng.snapshot.get_word(0o4000) == 321 and eng.snapshot.get_bit(0o2000) == 1
    eng.mem.bits[0] = 0  # a live input change while forced: no effect
    eng.forces.force("word", 0o4000, 5, user="eng2")  # re-force to another value
    scans(eng, clock)
    assert eng.snapshot.get_bit(0o2000) == 1 and eng.snapshot.get_word(0o4000) == 5
    eng.forces.unforce("bit", 0o0, user="eng2")
    scans(eng, clock)
    assert eng.snapshot.get_bit(0o2000) == 1  # the input keeps its value until a live writer changes it
    ops = [r for r in sink.records if r.kind == "operator"]
    assert [(r.source, r.number, r.value, r.text) for r in ops] == [
        ("eng1", 0o4000, 321.0, "force 04000:word: 321 -> 321 (bumpless)"),
        ("eng1", 0, 1.0, "force 00000: 1 -> 1 (bumpless)"),
        ("eng2", 0o4000, 5.0, "force 04000:word: forced 321 -> 5"),
        ("eng2", 0, 1.0, "unforce 00000 (was forced 1)"),
    ]
    assert all(r.ts == 1000.0 for r in ops)


@pytest.mark.parametrize("compiled", [True, False])
def test_the_program_reads_forced_generators_and_rtc_bytes(compiled: bool) -> None:
    program = parse("TNA $03750\nYON $02010\nTNA $03760\nFON C:$02100 N:MOV S:$077701 D:$04010\n")
    sink, clock = ListSink(), FakeClock()
    eng = Engine(program, clock=clock, sink=sink, compiled=compiled)
    eng.forces.force("bit", 0o3750, 1, user="eng1")  # the 0.1 s square wave, pinned
    eng.forces.force("byte", 0o77701, 0x42, user="eng1")  # the RTC's seconds, pinned
    for _ in range(4):
        clock.advance(0.05)
        eng.scan()
        assert eng.snapshot.get_bit(0o2010) == 1 and eng.snapshot.get_byte(0o4010) == 0x42


def test_bad_forces_are_refused_at_once_naming_the_address() -> None:
    eng, _, _ = engine()
    with pytest.raises(ForceError, match="cannot force word 03777"):
        eng.forces.force("word", 0o3777, 1, user="x")
    with pytest.raises(ForceError, match="010000"):
        eng.forces.force("byte", 0o10000, 1, user="x")
    with pytest.raises(ForceError, match="does not fit a byte"):
        eng.forces.force("byte", 0o4000, 256, user="x")
    with pytest.raises(ForceError, match="kind 'dword'"):
        eng.forces.force("dword", 0o4000, 1, user="x")  # type: ignore[arg-type]


@pytest.mark.parametrize(("addr", "named"), [("04000", "'04000'"), (0o4000 * 1.0, "2048.0"), (None, "None"),
                                             (True, "True"), (-8, "-8"), (b"\x08", "b'\\x08'")])
@pytest.mark.parametrize("kind", ["bit", "byte", "word"])
def test_an_address_that_is_no_integer_is_a_force_error_naming_it_as_given(kind, addr, named) -> None:
    """A protocol or a form may hand octal text or a float: refused like a bad address, never a
    ValueError of the octal formatting; octal text is not taken for an address either."""
    eng, _, _ = engine()
    for command in (lambda: eng.forces.force(kind, addr, 1, user="x"),
                    lambda: eng.forces.unforce(kind, addr, user="x")):
        with pytest.raises(ForceError, match=f"cannot force {kind} {re.escape(named)}") as caught:
            command()
        assert caught.value.values["kind"] == kind and caught.value.values["addr"] == named
    assert eng.forces.count == 0


def test_with_no_force_the_scan_is_unchanged() -> None:
    forced, plain = engine(), engine()
    for eng, _, clock in (forced, plain):
        eng.mem.bits[0] = 1
        scans(eng, clock, 3)
    forced[0].forces.force("bit", 0o2000, 0, user="x")
    forced[0].forces.unforce("bit", 0o2000, user="x")
    for eng, _, clock in (forced, plain):
        scans(eng, clock, 2)
    a, b = forced[0].snapshot, plain[0].snapshot
    assert a.bits == b.bits and a.data == b.data


@pytest.mark.parametrize("compiled", [True, False])
def test_step_one_scan_runs_the_program_exactly_once_a_tick_later(compiled: bool) -> None:
    eng, _, clock = engine(compiled)
    eng.mem.bits[1] = 1
    scans(eng, clock)
    eng.stop()
    scans(eng, clock, 3)  # stopped: no program, the timer does not count
    assert eng.tim_ticks[0o3000] == 0.0
    before, t = eng.snapshot.scan, clock()
    snap = eng.step()
    assert snap.scan == before + 1 and eng.snapshot is snap
    assert clock() == pytest.approx(t + eng.tick)
    assert eng.tim_ticks[0o3000] == pytest.approx(1.0)  # one 0.1 s tick of the 0.1 s time base
    assert eng.state is RunState.STOPPED
    eng.mem.bits[0] = 1
    eng.step()
    assert eng.snapshot.get_bit(0o2000) == 1 and eng.tim_ticks[0o3000] == pytest.approx(2.0)
    eng.start()
    with pytest.raises(RuntimeError, match="running"):
        eng.step()


def test_step_with_a_real_clock_advances_the_engine_time_by_one_tick() -> None:
    eng = Engine(parse(PROGRAM), clock=lambda: 50.0)
    eng.mem.bits[1] = 1
    eng.scan()
    eng.stop()
    now = eng.now
    eng.step()
    assert eng.now == pytest.approx(now + eng.tick) and eng.clock() == 50.0


def test_forces_save_and_load_and_bad_entries_name_the_file(tmp_path: Path) -> None:
    path = tmp_path / "retain.forces.json"
    assert load_forces(path) == ([], [])
    forces = [Force("bit", 0o40042, 1, "eng1"), Force("word", 0o4000, 65535, "eng1")]
    save_forces(path, forces)
    assert load_forces(path) == (forces, [])
    path.write_text('[{"kind": "word", "addr": "03777", "value": 1}, {"kind": "bit", "addr": "02000"}]')
    found, problems = load_forces(path)
    assert found == []
    assert problems[0].startswith(f"{path}: force [0]: cannot force word 03777")
    assert problems[1] == f"{path}: force [1]: missing 'value'"
    path.write_text("{nope")
    assert load_forces(path)[1][0].startswith(f"{path}: cannot read the retained forces")
