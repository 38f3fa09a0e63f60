"""32-bit tags in the four byte orders Modbus tools name (1234 ABCD, 4321 DCBA, 2143 BADC, 3412
CDAB): a value as a third-party device places it in two registers, landed in NetPlc memory as
NREAD lands registers (each word as it is), reads back through the tag, the vector reader and
the forces, and a write puts back the very registers the device expects."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from app.scada.forcing import tag_forces
from app.scada.table import read_tags
from app.scada.tag import BYTE_ORDERS, NETPLC_ORDER, Scaling, Tag, TagReader, TagType
from netplc.memory import Memory
from netplc.modbus import bytes_from_words

INT = 123456789  # 0x075BCD15: bytes A=07 B=5B C=CD D=15
FLOAT = 12.5  # 0x41480000
# the two registers a device holds in each order, from the tools' own tables (not from our code)
REGISTERS = {
    "1234": ([0x075B, 0xCD15], [0x4148, 0x0000]),  # ABCD: big-endian, mbpoll -B
    "4321": ([0x15CD, 0x5B07], [0x0000, 0x4841]),  # DCBA: little-endian
    "2143": ([0x5B07, 0x15CD], [0x4841, 0x0000]),  # BADC: big-endian, bytes of each word swapped
    "3412": ([0xCD15, 0x075B], [0x0000, 0x4148]),  # CDAB: words swapped; NetPlc's, mbpoll's default
}


def landed(registers: list[int], addr: int = 0o4100) -> Memory:
    """NetPlc memory after an NREAD of profile modbus copied `registers` to `addr`."""
    mem = Memory()
    mem.write(addr, bytes_from_words(registers))
    return mem


@pytest.mark.parametrize("order", BYTE_ORDERS)
def test_a_device_value_reads_and_writes_back_in_each_order(order: str) -> None:
    ints, floats = REGISTERS[order]
    for kind, registers, value in ((TagType.INT32, ints, INT), (TagType.FLOAT32, floats, FLOAT)):
        tag = Tag("T", 0o4100, kind, byte_order=order)
        mem = landed(registers)
        assert tag.raw(mem) == value
        assert TagReader([tag]).raw(mem.snapshot())[0] == value
        assert tag.encode(value) == bytes_from_words(registers)  # an NWRITE sends the device's registers
        assert [f.value for f in tag_forces(tag, value)] == registers  # a force pins those words


@pytest.mark.parametrize("order", BYTE_ORDERS)
def test_negative_and_scaled_values_in_each_order(order: str) -> None:
    tag = Tag("T", 0o4101, TagType.INT32, scaling=Scaling(0, 1000, 0, 100), byte_order=order)  # odd address
    mem = Memory()
    mem.write(0o4101, tag.encode(-2_000_000_000))
    assert tag.raw(mem) == -2_000_000_000 and tag.value(mem) == -200_000_000
    f = Tag("F", 0o4101, TagType.FLOAT32, byte_order=order)
    mem.write(0o4101, f.encode(-1234.5678))
    assert f.raw(mem) == struct.unpack("<f", struct.pack("<f", -1234.5678))[0]


def test_netplc_order_is_what_memory_always_held() -> None:
    assert NETPLC_ORDER == "3412" and Tag("T", 0o4100, TagType.INT32).byte_order == "3412"
    assert Tag("T", 0o4100, TagType.INT32).encode(INT) == INT.to_bytes(4, "little")
    assert Tag("T", 0o4100, TagType.FLOAT32).encode(FLOAT) == struct.pack("<f", FLOAT)


def test_the_vector_reader_reads_mixed_orders_as_each_tag_does() -> None:
    mem = Memory()
    tags = []
    for i, order in enumerate(BYTE_ORDERS * 3):
        kind = TagType.FLOAT32 if i % 2 else TagType.INT32
        tag = Tag(f"T{i}", 0o4200 + 5 * i, kind, scaling=Scaling(0, 10, 0, 1) if i % 3 else None,
                  byte_order=order)
        mem.write(tag.address, tag.encode(-1.5 * i if kind is TagType.FLOAT32 else 1000 * i - 7))
        tags.append(tag)
    values = TagReader(tags).read(mem.snapshot())
    assert values.tolist() == [t.value(mem) for t in tags]
    assert [t.raw(mem) for t in tags[:4]] == [-7, -1.5, 1993, -4.5]


HEADER = "name,address,type,byte_order"


def test_tags_csv_names_the_order_by_digits_or_letters(tmp_path: Path) -> None:
    path = tmp_path / "tags.csv"
    path.write_text(f"{HEADER}\nA,04100,int32,1234\nB,04104,float32,badc\nC,04110,dint,\nD,04114,real,3412\n",
                    encoding="utf-8")
    table, problems = read_tags(path)
    assert problems == []
    assert [t.byte_order for t in table.tags] == ["1234", "2143", "3412", "3412"]


@pytest.mark.parametrize(("line", "problem"), [
    ("A,04100,int32,1243", "A: byte_order '1243' is not one of 1234, 4321, 2143, 3412 "
                           "(or ABCD, DCBA, BADC, CDAB)"),
    ("A,04100,float32,big", "A: byte_order 'big' is not one of"),
    ("A,04100,word,1234", "A: byte_order is for int32 and float32 tags; a word tag is read as NetPlc "
                          "memory holds it"),
    ("A,02000,bit,4321", "A: byte_order is for int32 and float32 tags; a bit tag is read"),
])
def test_a_bad_byte_order_is_named_by_file_line_and_tag(tmp_path: Path, line: str, problem: str) -> None:
    path = tmp_path / "tags.csv"
    path.write_text(f"{HEADER}\nGOOD,04200,int32,1234\n{line}\n", encoding="utf-8")
    table, problems = read_tags(path)
    assert len(problems) == 1 and problems[0].startswith(f"{path}:3: {problem}"), problems
    assert [t.name for t in table.tags] == ["GOOD"]
