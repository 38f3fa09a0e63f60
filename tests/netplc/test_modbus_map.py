"""The cpu165 and modbus profiles: one mapping shared by the exchange (client) and the server."""

from __future__ import annotations

import pytest

from netplc.memory import Memory
from netplc.modbus.map import (
    MapError,
    bits_from_bytes,
    bits_target,
    bytes_from_bits,
    locate,
    read_bits,
    register_slice,
    registers_target,
    words_from_bytes,
)


def test_register_1024_is_word_04000_little_endian() -> None:
    mem = Memory()
    mem.set_word(0o4000, 0x1234)
    mem.set_word(0o4002, 0xBEEF)
    assert register_slice(mem.data, 1024, 2) == bytes([0x12, 0x34, 0xBE, 0xEF])  # as the answer carries them
    assert registers_target(1024, 1) == 0o4000
    # bank 1 starts at 014000 = register 3072
    mem.set_word(0o14000, 7)
    assert register_slice(mem.data, 0o14000 // 2, 1) == b"\x00\x07"


def test_coil_n_is_io_bit_n() -> None:
    mem = Memory()
    mem.set_bit(0o2042, 1)
    assert read_bits(mem, 0o2040, 4) == [0, 0, 1, 0]
    assert bits_target(0o2042, 1) == 0o2042


@pytest.mark.parametrize(
    ("address", "count"),
    [(0, 1), (1023, 1), (0o4000 // 2 - 1, 2), (0o10000 // 2, 1), (0o14000 // 2 - 1, 2),
     (0o77777 // 2 + 1, 1), (0o77776 // 2, 2), (65535, 125)],
)
def test_registers_outside_data_memory_are_refused(address: int, count: int) -> None:
    with pytest.raises(MapError):
        register_slice(Memory().data, address, count)
    with pytest.raises(MapError):
        registers_target(address, count)


def test_coils_past_the_io_bits_are_refused() -> None:
    with pytest.raises(MapError):
        read_bits(Memory(), 0o3777, 2)
    with pytest.raises(MapError):
        bits_target(0o4000, 1)


def test_packing_round_trips() -> None:
    data = bytes([0x01, 0x80, 0xFF, 0x00])
    assert words_from_bytes(data) == [0x8001, 0x00FF]
    bits = bits_from_bytes(data)
    assert bits[0] == 1 and bits[15] == 1 and bits[7] == 0
    assert bytes_from_bits(bits) == data


def test_cpu165_data_block_even_and_odd_edges() -> None:
    even = locate("cpu165", "holding", 0o4000, 4)
    assert (even.table, even.address, even.count, even.skip) == ("holding", 1024, 2, 0)
    assert not even.odd_end
    odd = locate("cpu165", "input", 0o4001, 2)  # the table setting is ignored: cpu165 uses holding
    assert (odd.table, odd.address, odd.count, odd.skip) == ("holding", 1024, 2, 1)
    assert odd.odd_end
    # decode drops the bytes outside the block
    assert odd.decode([0xAA11, 0x33BB]) == bytes([0xAA, 0xBB])
    # encode keeps the neighbouring bytes of the edge registers (read-modify-write)
    assert odd.encode(bytes([0x01, 0x02]), first=0xAA11, last=0x33BB) == [0x0111, 0x3302]


def test_cpu165_io_block_is_coils() -> None:
    b = locate("cpu165", "holding", 0o2000, 2)
    assert (b.table, b.address, b.count) == ("coils", 0o2000, 16)
    assert b.decode([1, 0, 0, 1, 0, 1] + [0] * 10) == bytes([0b101001, 0])
    assert b.encode(bytes([0x03, 0x80])) == [1, 1] + [0] * 13 + [1]


def test_modbus_profile_uses_register_numbers_and_the_table() -> None:
    b = locate("modbus", "input", 100, 3)
    assert (b.table, b.address, b.count, b.skip) == ("input", 100, 2, 0)
    assert b.decode([0x0201, 0x0403]) == bytes([1, 2, 3])
    c = locate("modbus", "coils", 5, 1)
    assert (c.table, c.address, c.count) == ("coils", 5, 8)


def test_large_blocks_split_at_protocol_limits() -> None:
    b = locate("cpu165", "holding", 0o4000, 300)  # 150 registers
    assert b.spans(write=False) == [(1024, 125), (1149, 25)]
    assert b.spans(write=True) == [(1024, 123), (1147, 27)]


@pytest.mark.parametrize(
    ("profile", "table", "remote", "length", "message"),
    [
        ("cpu165", "holding", 0o10000, 2, "not a valid address"),
        ("cpu165", "holding", 0o7777, 2, "past the end of its bank"),
        ("cpu165", "holding", 0o3777, 2, "past bit 03777"),
        ("modbus", "holding", 65535, 4, "past Modbus address 65535"),
        ("modbus", "registers", 0, 2, "not one of"),
        ("siemens", "holding", 0, 2, "profile"),
        ("cpu165", "holding", 0o4000, 0, "at least 1 byte"),
    ],
)
def test_bad_blocks_name_the_problem(
    profile: str, table: str, remote: int, length: int, message: str
) -> None:
    with pytest.raises(MapError, match=message):
        locate(profile, table, remote, length)


@pytest.mark.parametrize(("remote", "length"),
                         [(0o4000, 4), (0o4001, 2), (0o4001, 5), (0o4000, 251), (0o2040, 3)])
def test_decoding_the_wire_bytes_equals_decoding_the_values(remote: int, length: int) -> None:
    block = locate("cpu165", "holding", remote, length)
    values = [(0x1234 + 0x0101 * i) & (1 if block.bits else 0xFFFF) for i in range(block.count)]
    wire = bytes_from_bits(values) if block.bits else b"".join(v.to_bytes(2, "big") for v in values)
    assert block.decode_wire(wire) == block.decode(values)
