"""Tags: reading every type from memory, the manual's conversion and its inverse, and tags.csv."""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
import pytest

from app.scada.table import TagError, load_tags, read_tags
from app.scada.tag import Scaling, Tag, TagReader, TagType
from netplc.memory import Memory
from netplc.problems import Problems

HEADER = "name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description"


def write(tmp_path: Path, text: str, bom: bool = False) -> Path:
    path = tmp_path / "tags.csv"
    path.write_text(text, encoding="utf-8-sig" if bom else "utf-8")
    return path


def test_manual_conversion_and_its_inverse_rounded_and_clamped() -> None:
    s = Scaling(0, 1000, -50, 150)
    assert s.to_phy(0) == -50 and s.to_phy(1000) == 150 and s.to_phy(250) == 0
    assert s.to_hw(0) == 250
    assert s.to_hw(0.13) == 251  # 250.65 rounds to 251
    assert s.to_hw(500) == 1000 and s.to_hw(-999) == 0  # clamped to the hardware range


def memory_with(addr: int, payload: bytes) -> Memory:
    mem = Memory()
    mem.write(addr, payload)
    return mem


@pytest.mark.parametrize(("kind", "payload", "raw"), [
    (TagType.WORD, b"\xff\xff", 65535),
    (TagType.WORD, b"\x34\x12", 0x1234),
    (TagType.INT16, b"\xff\xff", -1),
    (TagType.INT16, b"\x00\x80", -32768),
    (TagType.BCD, b"\x76\x98", 9876),
    (TagType.INT32, (-123456).to_bytes(4, "little", signed=True), -123456),
    (TagType.INT32, b"\x00\x00\x01\x00", 65536),  # low word first: the high word is 1
    (TagType.FLOAT32, struct.pack("<f", 12.5), 12.5),
])
def test_every_type_reads_as_netplc_memory_holds_it(kind: TagType, payload: bytes, raw: float) -> None:
    mem = memory_with(0o4010, payload)
    tag = Tag("T", 0o4010, kind)
    assert tag.raw(mem) == raw
    assert tag.encode(raw) == payload
    assert TagReader([tag]).raw(mem.snapshot())[0] == raw


def test_a_bcd_word_with_a_digit_above_9_is_not_a_number() -> None:
    mem = memory_with(0o4010, b"\x0a\x00")
    tag = Tag("T", 0o4010, TagType.BCD)
    assert math.isnan(tag.raw(mem))
    assert math.isnan(TagReader([tag]).raw(mem.snapshot())[0])


def test_bits_io_and_data_and_words_made_of_io_bits() -> None:
    mem = Memory()
    mem.set_bit(0o2042, 1)
    mem.set_hmi_bit(0o40003, 1)  # byte 04000, bit 3
    mem.write(0o2100, b"\x05\x00")  # I/O bits 02100-02117 as a word
    tags = [Tag("A", 0o2042, TagType.BIT), Tag("B", 0o40003, TagType.BIT), Tag("C", 0o40004, TagType.BIT),
            Tag("W", 0o2100, TagType.WORD)]
    assert [t.raw(mem) for t in tags] == [1, 1, 0, 5]
    assert TagReader(tags).raw(mem.snapshot()).tolist() == [1, 1, 0, 5]


def test_the_vector_reader_converts_exactly_as_one_tag_does() -> None:
    rng = np.random.default_rng(1)
    mem = Memory()
    tags = []
    for i in range(200):
        kind = [TagType.WORD, TagType.INT16, TagType.INT32, TagType.FLOAT32, TagType.BCD][i % 5]
        addr = 0o4000 + 4 * i + (i % 2)  # odd addresses too
        if kind is TagType.FLOAT32:
            mem.write(addr, struct.pack("<f", float(rng.normal() * 1000)))
        elif kind is TagType.BCD:
            mem.write(addr, Tag("x", addr, kind).encode(int(rng.integers(0, 9999))))
        else:
            mem.write(addr, bytes(rng.integers(0, 256, 4, dtype=np.uint8))[:2 if i % 5 < 2 else 4])
        tags.append(Tag(f"T{i}", addr, kind, scaling=Scaling(0, 4095, -50, 150) if i % 3 else None))
    values = TagReader(tags).read(mem.snapshot())
    assert values.tolist() == [t.value(mem) for t in tags]


@pytest.mark.parametrize(("kind", "phy", "raw"), [
    (TagType.WORD, 150.0, 4095), (TagType.WORD, 100.0, 3071), (TagType.WORD, -1e9, 0),
    (TagType.INT16, -50.0, 0), (TagType.BCD, 150.0, 4095),
    (TagType.INT32, 12.3, 1276), (TagType.INT32, 1e9, 4095),
    (TagType.FLOAT32, 0.0, 4095 * 50 / 200),
])
def test_the_inverse_for_every_type(kind: TagType, phy: float, raw: float) -> None:
    tag = Tag("T", 0o4010, kind, scaling=Scaling(0, 4095, -50, 150))
    assert tag.to_raw(phy) == raw


def test_the_inverse_without_a_conversion_clamps_to_the_type() -> None:
    assert Tag("T", 0o4010, TagType.INT16).to_raw(40000.4) == 32767
    assert Tag("T", 0o4010, TagType.WORD).to_raw(-3) == 0
    assert Tag("T", 0o4010, TagType.BCD).to_raw(12345) == 9999
    assert Tag("T", 0o4010, TagType.FLOAT32).to_raw(1.25) == 1.25


def test_a_good_file_with_a_bom_and_symbols(tmp_path: Path) -> None:
    path = write(tmp_path, f"{HEADER},hh,h,deadband,on_delay,priority\n"
                           "# a comment\n"
                           "LEVEL,LEVEL_SYM,word,%,0,4095,0,100,1,Уровень,95,90,2,1.5,2\n"
                           "TRIG,040005,bit,,,,,,,Триггер,,,,,\n", bom=True)
    table = load_tags(path, {"LEVEL_SYM": 0o4010})
    level = table.get("LEVEL")
    assert level is not None and level.address == 0o4010 and level.unit == "%"
    assert level.format(93.25) == "93.2 %"
    assert table.alarms["LEVEL"].h == 90 and table.alarms["LEVEL"].priority == 2
    assert table.alarms["LEVEL"].quality_alarm  # a tag with process alarms gets its quality alarm
    assert "TRIG" not in table.alarms


@pytest.mark.parametrize(("line", "problem"), [
    ("A,04x10,word", "A: address '04x10' is neither an octal address nor a symbol"),
    ("A,04000,bit", "A: address '04000' cannot hold an I/O bit or a data bit"),
    ("A,03777,word", "A: address '03777' cannot hold a word value"),
    ("A,010000,word", "A: address '010000' cannot hold a word value"),
    ("A,04000,float", "A: type 'float' is not one of bit, word, int16, bcd, int32, float32"),
    ("A,04000,word,,5,5,0,100", "A: app_min = app_max = 5: the conversion is undefined"),
    ("A,04000,word,,0,100,7,7", "A: phy_min = phy_max = 7: the conversion is undefined"),
    ("A,04000,word,,0,100", "A: give all of app_min, app_max, phy_min, phy_max or none"),
    ("A,04000,word,,,,,,,,80,90", "A: HH 80 is below H 90"),
    ("A,04000,word,,,,,,,,,,10,20", "A: L 10 is below LL 20"),
    ("A,04000,word,,,,,,,,,50,60", "A: H 50 is below L 60"),
    ("A,04000,word,,,,,,,,,90,,,,-1", "A: on_delay -1 is negative"),
    ("A,04000,word,,,,,,,,,90,,,,,-0.5", "A: off_delay -0.5 is negative"),
    ("A,04000,word,,,,,,,,,90,,,-2", "A: deadband -2 is negative"),
    ("A,04000,word,,,,,,,,,90,,,,,,,5", "A: priority '5' is not a whole number 1-4"),
    ("A,04000,word,,,,,,,,,90,,,,,,,0", "A: priority '0' is not a whole number 1-4"),
    ("A,02000,bit,,,,,,,,,90", "A: a bit tag cannot have limit alarms"),
    ("A,04000,word,,,,,,,,,,,,,,,1", "A: alarm_when needs a bit tag"),
    ("A,02000,bit,,,,,,,,,,,,,,,2", "A: alarm_when '2' is not a whole number 0-1"),
    ("A,04000,word,,,,,,,,,70000", "A: H 70000 is outside what a word tag can take here (0..65535)"),
    ("A,04000,int16,,,,,,,,,,40000", "A: L 40000 is outside what a int16 tag can take here"),
    ("A,04000,word,,,,,,,,,90,,,,,,,,maybe", "A: latching 'maybe' is not yes/no"),
    ("A,04000,word,,,,,,,,,90,,,,,,,,,04000", "A: suppress_by '04000' is not a bit address"),
    ("4A,04000,word", "'4A' is not a valid tag name"),
])
def test_problems_name_the_file_line_and_tag(tmp_path: Path, line: str, problem: str) -> None:
    columns = ("name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description,"
               "hh,h,l,ll,deadband,on_delay,off_delay,alarm_when,priority,latching,suppress_by")
    path = write(tmp_path, f"{columns}\nGOOD,04100,word\n{line}\n")
    table, problems = read_tags(path)
    assert any(p.startswith(f"{path}:3: ") and problem in p for p in problems), problems
    assert [t.name for t in table.tags] == ["GOOD"]  # the good line still loads
    with pytest.raises(TagError):
        load_tags(path)


def test_iec_type_names_and_one_delay_for_both_ways(tmp_path: Path) -> None:
    path = write(tmp_path, "name,address,type,h,delay,off_delay\nA,04000,dint,5,2,\nB,04004,real,5,2,0.5\n"
                           "C,04010,int,-5,,\nD,04012,uint16,,-1,\n")
    table, problems = read_tags(path)
    assert [t.type for t in table.tags] == [TagType.INT32, TagType.FLOAT32, TagType.INT16]
    assert (table.alarms["A"].on_delay, table.alarms["A"].off_delay) == (2, 2)
    assert (table.alarms["B"].on_delay, table.alarms["B"].off_delay) == (2, 0.5)
    assert problems == [f"{path}:5: D: delay -1 is negative"]


def test_unknown_columns_and_duplicate_names(tmp_path: Path) -> None:
    path = write(tmp_path, "name,address,type,colour\nA,04000,word,red\nA,04002,word,blue\n")
    _, problems = read_tags(path)
    assert problems[0].startswith(f"{path}:1: unknown column 'colour'")
    assert f"{path}:3: A: the name is already used on line 2" in problems


def test_a_header_without_the_required_columns(tmp_path: Path) -> None:
    path = write(tmp_path, "LEVEL,04010,word\n")
    _, problems = read_tags(path)
    assert problems == [f"{path}:1: the header must name the columns name, address, type (missing: name, "
                        "address, type); known columns: " + problems[0].split("known columns: ")[1]]


def test_an_unreadable_file_is_a_problem_not_a_traceback(tmp_path: Path) -> None:
    path = tmp_path / "tags.csv"
    path.write_bytes(b"name,address,type\nA\x98,04000,word\n")  # 0x98: neither UTF-8 nor cp1251
    _, problems = read_tags(path)
    assert problems == [f"{path}:2: neither UTF-8 nor cp1251 text (byte 0x98)"]
    path.unlink()
    path.mkdir()
    _, problems = read_tags(path)
    assert problems == [f"{path}:0: cannot read the tags: it is a folder, not a file"]


def test_a_tags_file_written_in_cp1251_loads(tmp_path: Path) -> None:
    """What Excel saves as "CSV" on a Russian Windows: the same reader as messages.csv and symbols.csv."""
    path = tmp_path / "tags.csv"
    path.write_bytes("name,address,type,unit,app_min,app_max,phy_min,phy_max,description,h\n"
                     "Уровень,04010,word,м³/ч,0,4095,0,100,Уровень в баке,90\n"
                     "ТЕМП,04012,word,°C,0,1000,-50,150,Температура,\n".encode("cp1251", errors="replace"))
    table = load_tags(path)
    assert [(t.name, t.unit, t.description) for t in table.tags] == [
        ("Уровень", "м?/ч", "Уровень в баке"), ("ТЕМП", "°C", "Температура")]
    assert table.alarms["Уровень"].h == 90


def test_a_row_split_over_two_lines_is_named_by_its_line(tmp_path: Path) -> None:
    path = tmp_path / "tags.csv"
    path.write_text('name,address,type\n"SPL\nIT",04000,word\nC,04004,word\n', encoding="utf-8")
    table, problems = read_tags(path)
    assert problems == [f"{path}:2: a quoted field runs on to line 3: a row is one line (a closing quote "
                        "missing?)"]
    assert [t.name for t in table.tags] == ["C"]


def test_tag_error_is_a_problems_list(tmp_path: Path) -> None:
    path = tmp_path / "tags.csv"
    path.write_text("name,address,type\nA,09999,word\n", encoding="utf-8")
    with pytest.raises(Problems) as e:
        load_tags(path)
    assert isinstance(e.value, TagError) and e.value.problems[0].startswith(f"{path}:2: A: address '09999'")
