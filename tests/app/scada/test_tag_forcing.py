"""Forcing a tag (netplc/forcing.py `force_tag`): the physical value converted with the tag's
Scaling and type to its bit, word or both words (one command), bumpless without a value,
journaled with the tag's name, physical value and unit; unforcing releases every word."""

from __future__ import annotations

import struct

import pytest

from app.scada.forcing import forcing_tag, tag_forces, unforcing_tag
from app.scada.tag import Scaling, Tag, TagType
from netplc.engine import Engine, FakeClock
from netplc.records import ListSink
from tests.netplc.test_forcing import engine as forcing_engine
from tests.netplc.test_forcing import scans, texts

# the program copies the word 04000 to 04002 and the two words 04010/04012 to 04020/04022, and
# itself writes 04000's neighbour 04004 every scan
PROGRAM = """
TNA $03760
FON C:$02100 N:MOV S:$04000 D:$04002
TNA $03760
FON C:$02104 N:MOV S:$04010 D:$04020
TNA $03760
FON C:$02110 N:MOV S:$04012 D:$04022
TNA $03760
FON C:$02114 N:MVID S:7 D:$04010
"""

TEMP = Tag("TEMP_SP", 0o4000, TagType.WORD, "°C", Scaling(0, 1000, 0, 200), 1)
FLOW = Tag("FLOW", 0o4010, TagType.FLOAT32, "m3/h", Scaling(0, 100, 0, 50), 2)


def engine(compiled: bool) -> tuple[Engine, ListSink, FakeClock]:
    return forcing_engine(compiled, PROGRAM)


def test_a_tag_and_its_physical_value_become_raw_forces() -> None:
    assert [(f.kind, f.addr, f.value) for f in tag_forces(TEMP, 130.0, "eng1")] == [("word", 0o4000, 650)]
    lo, hi = struct.unpack("<HH", struct.pack("<f", 25.0))  # 12.5 m3/h is 25.0 raw
    assert [(f.addr, f.value) for f in tag_forces(FLOW, 12.5)] == [(0o4010, lo), (0o4012, hi)]
    bit = Tag("RUN", 0o40050, TagType.BIT)
    assert [(f.kind, f.addr, f.value) for f in tag_forces(bit, 1)] == [("bit", 0o40050, 1)]
    bcd = Tag("N", 0o4000, TagType.BCD)
    assert tag_forces(bcd, 1234)[0].value == 0x1234


@pytest.mark.parametrize("compiled", [True, False])
def test_word_and_float32_tags_forced_by_physical_value_are_what_the_program_reads(compiled: bool) -> None:
    eng, sink, clock = engine(compiled)
    scans(eng, clock)
    assert eng.snapshot.get_word(0o4010) == 7  # the program writes the float's low word
    eng.post(forcing_tag(eng.forces, TEMP, 130.0, user="eng1"))
    eng.post(forcing_tag(eng.forces, FLOW, 12.5, user="eng1"))
    scans(eng, clock, 2)
    snap = eng.snapshot
    assert snap.get_word(0o4000) == 650 and snap.get_word(0o4002) == 650
    assert FLOW.value(snap) == pytest.approx(12.5)
    assert struct.unpack("<f", snap.read(0o4020, 4))[0] == pytest.approx(25.0)  # the program's copy
    assert eng.forces.count == 3  # one word and two words
    assert texts(sink)[-2:] == [
        ("eng1", "force TEMP_SP: 0.0 -> 130.0 °C (raw 028Ah)"),
        ("eng1", "force FLOW: 0.00 -> 12.50 m3/h (raw 0000h 41C8h)"),
    ]
    rec = [r for r in sink.records if r.kind == "operator"][-2]
    assert rec.number == 0o4000 and rec.value == pytest.approx(130.0)


@pytest.mark.parametrize("compiled", [True, False])
def test_a_tag_forced_without_a_value_is_bumpless_and_unforce_releases_every_word(compiled: bool) -> None:
    eng, sink, clock = engine(compiled)
    eng.write_bytes(0o4010, struct.pack("<f", 40.0), user="op")  # 20.0 m3/h; the program then writes 7
    scans(eng, clock)
    before = eng.snapshot.read(0o4010, 4)
    eng.post(forcing_tag(eng.forces, FLOW, user="eng1"))
    scans(eng, clock, 3)
    assert eng.snapshot.read(0o4010, 4) == before and eng.forces.count == 2
    assert texts(sink)[-1][1].endswith("(bumpless)")
    eng.post(unforcing_tag(eng.forces, FLOW, user="eng2"))
    scans(eng, clock)
    assert eng.forces.count == 0
    assert texts(sink)[-1] == ("eng2", f"unforce FLOW (was forced {FLOW.format(FLOW.value(eng.snapshot))})")
    eng.write_bytes(0o4012, b"\x00\x00", user="op")  # live behaviour again: writes land
    scans(eng, clock)
    assert eng.snapshot.get_word(0o4012) == 0 and eng.snapshot.get_word(0o4010) == 7


def test_a_nan_value_is_refused() -> None:
    eng, _, _ = engine(True)
    with pytest.raises(ValueError, match="FLOW"):
        eng.post(forcing_tag(eng.forces, FLOW, float("nan"), user="eng1"))
