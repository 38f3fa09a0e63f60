"""Octal addresses, the eight data banks and their gaps, operand rules and HMI bit addresses."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from netplc.address import (
    AddressError,
    BitRef,
    check_operand,
    data_address,
    data_index,
    fmt_octal,
    is_data_byte,
    is_io_bit,
    parse_hmi_bit,
    parse_octal,
)


@pytest.mark.parametrize("text, value", [("04000", 0o4000), ("$04000", 0o4000), ("4000", 0o4000),
                                         ("0o17", 0o17), (" 077700 ", 0o77700), ("0", 0)])
def test_parse_octal(text, value):
    assert parse_octal(text) == value


@pytest.mark.parametrize("text", ["", "$", "08", "12a", "0x10", "-1", "٣"])
def test_parse_octal_refuses_non_octal(text):
    with pytest.raises(ValueError, match="is not an octal number"):
        parse_octal(text)


def test_fmt_octal_writes_like_the_documents():
    assert fmt_octal(0o2042) == "02042"
    assert fmt_octal(0o4000) == "04000"
    assert fmt_octal(0o77700) == "077700"
    assert fmt_octal(0) == "00000"


def test_io_bits_and_data_banks_with_their_gaps():
    assert is_io_bit(0) and is_io_bit(0o3777) and not is_io_bit(0o4000)
    for k in range(8):
        first, last = k * 0o10000 + 0o4000, k * 0o10000 + 0o7777
        assert is_data_byte(first) and is_data_byte(last)
        assert data_index(first) == k * 0o4000 and data_index(last) == k * 0o4000 + 0o3777
    for gap in (0o10000, 0o13777, 0o20000, 0o70000, 0o73777, 0o100000, 0o3777):
        assert not is_data_byte(gap)
        with pytest.raises(AddressError):
            data_index(gap)


@given(st.integers(0, 8 * 0o4000 - 1))
def test_data_index_round_trips(index):
    assert data_index(data_address(index)) == index


def test_operand_rules():
    check_operand(0o3760, 2)  # 16 I/O bits 03760-03777
    check_operand(0o7776, 2)  # the last word of bank 0
    check_operand(0o7775, 2)  # odd word addresses are allowed
    with pytest.raises(AddressError, match="runs past bit 03777"):
        check_operand(0o3770, 2)
    with pytest.raises(AddressError, match="runs past the end of its bank"):
        check_operand(0o7777, 2)
    with pytest.raises(AddressError, match="runs past the end of its bank"):
        check_operand(0o77776, 4)
    with pytest.raises(AddressError, match="not a valid address"):
        check_operand(0o10000, 1)


def test_hmi_bit_addresses():
    ref = parse_hmi_bit("040042")
    assert (ref.is_io, ref.byte, ref.bit) == (False, 0o4004, 2)
    assert str(ref) == "040042"
    assert parse_hmi_bit("040005") == BitRef(0o40005) and parse_hmi_bit(0o40005).bit == 5
    assert parse_hmi_bit("0777777").byte == 0o77777  # the last data bit
    io = parse_hmi_bit("02042")
    assert io.is_io and str(io) == "02042"
    for bad in ("04000", "037777", "0100000", "01000000"):  # data byte as a bit, or a gap byte*8
        with pytest.raises(AddressError):
            parse_hmi_bit(bad)
