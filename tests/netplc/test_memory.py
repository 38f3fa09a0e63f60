"""NetPlc memory: I/O bits, byte/word operands in the bit area, little-endian data, gaps, HMI bits
and immutable snapshots (docs/architecture.md section 3)."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import given
from hypothesis import strategies as st

from netplc.address import AddressError, BitRef
from netplc.memory import Memory, Snapshot


def test_bits_are_0_or_1():
    m = Memory()
    m.set_bit(0o2042, 5)
    assert m.get_bit(0o2042) == 1
    m.set_bit(0o2042, 0)
    assert m.get_bit(0o2042) == 0
    for bad in (-1, 0o4000):
        with pytest.raises(AddressError):
            m.set_bit(bad, 1)
        with pytest.raises(AddressError):
            m.get_bit(bad)


def test_words_are_little_endian():
    # the MOV example of the manual: 04000 = 0x76, 04001 = 0x98 is the word 0x9876
    m = Memory()
    m.set_word(0o4000, 0x9876)
    assert m.read(0o4000, 2) == b"\x76\x98"
    assert m.get_byte(0o4000) == 0x76 and m.get_byte(0o4001) == 0x98
    m.set_dword(0o4004, 0x00000100)  # MUL's product: low word first
    assert m.get_word(0o4004) == 0x0100 and m.get_word(0o4006) == 0
    assert m.get_dword(0o4004) == 0x100
    m.set_word(0o7775, 0xABCD)  # odd address
    assert m.get_word(0o7775) == 0xABCD


def test_byte_and_word_operands_below_04000_are_bits():
    m = Memory()
    m.set_word(0o2000, 0b1000_0000_0010_1001)
    assert [m.get_bit(0o2000 + k) for k in range(16)] == [1, 0, 0, 1, 0, 1, 0, 0] + [0] * 7 + [1]
    assert m.get_byte(0o2000) == 0b0010_1001 and m.get_byte(0o2010) == 0b1000_0000
    m.set_bit(0o2042, 1)  # Appendix 1 section 5: bit 02042 is bit 2 of the word at 02040
    assert m.get_word(0o2040) == 0b100
    m.set_byte(0o3750, 0xFF)
    assert m.read(0o3750, 1) == b"\xff"
    with pytest.raises(AddressError):
        m.get_word(0o3771)  # 16 bits would run past 03777


def test_gaps_are_invalid():
    m = Memory()
    for gap in (0o10000, 0o13777, 0o20000, 0o100000):
        with pytest.raises(AddressError):
            m.get_byte(gap)
        with pytest.raises(AddressError):
            m.set_word(gap, 1)
    with pytest.raises(AddressError):
        m.write(0o7777, b"\x01\x02")  # runs into the gap
    m.set_byte(0o14000, 7)  # bank 1 is separate from bank 0
    assert m.get_byte(0o14000) == 7 and m.get_byte(0o4000) == 0


def test_hmi_bit_addresses_reach_data_bits():
    m = Memory()
    m.set_hmi_bit(0o40042, 1)  # byte 04004 bit 2
    assert m.get_byte(0o4004) == 0b100
    assert m.get_hmi_bit(BitRef(0o40042)) == 1 and m.get_hmi_bit(0o40043) == 0
    m.set_hmi_bit(0o40042, 0)
    assert m.get_byte(0o4004) == 0
    m.set_hmi_bit(0o2005, 1)
    assert m.get_bit(0o2005) == 1 and m.get_hmi_bit(0o2005) == 1
    with pytest.raises(AddressError):
        m.set_hmi_bit(0o4000, 1)  # neither an I/O bit nor byte*8+bit


@given(st.integers(0, 0xFFFF), st.sampled_from([0o4000, 0o7776, 0o44001, 0o77776, 0o2000, 0o3760]))
def test_word_round_trip(value, addr):
    m = Memory()
    m.set_word(addr, value)
    assert m.get_word(addr) == value
    assert m.read(addr, 2) == value.to_bytes(2, "little")


def test_snapshots_are_immutable_copies():
    m = Memory()
    m.set_word(0o4000, 0x1234)
    snap = m.snapshot(scan=3, time=1.5, wall=2.0, state="running")
    m.set_word(0o4000, 0)
    m.set_bit(0, 1)
    assert snap.get_word(0o4000) == 0x1234 and snap.get_bit(0) == 0
    assert (snap.scan, snap.time, snap.wall, snap.state) == (3, 1.5, 2.0, "running")
    assert isinstance(snap.bits, tuple) and isinstance(snap.data, bytes)
    with pytest.raises(dataclasses.FrozenInstanceError):
        snap.scan = 4
    with pytest.raises(TypeError):
        snap.data[0] = 1
    empty = Snapshot.empty()
    assert empty.get_word(0o77776) == 0


def test_load_replaces_the_contents():
    a, b = Memory(), Memory()
    a.set_word(0o74000, 0xBEEF)
    a.set_bit(0o3000, 1)
    b.load(a.snapshot())
    assert b.get_word(0o74000) == 0xBEEF and b.get_bit(0o3000) == 1
