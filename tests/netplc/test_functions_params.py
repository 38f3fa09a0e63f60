"""Load-time checks of FON parameters against each function's kinds (M, O, D, B), via the parser."""

from __future__ import annotations

import pytest

from netplc.functions.registry import DEFINED_CODES, REGISTRY, lookup
from netplc.program import ProgramError, parse

PROLOGUE = "TNA $02000\n"


def load_error(fon: str) -> str:
    """The single diagnostic of a program whose second line is `fon`."""
    with pytest.raises(ProgramError) as e:
        parse(PROLOGUE + fon + "\n", source="t.stl")
    assert len(e.value.errors) == 1, str(e.value)
    return str(e.value.errors[0])


def col(fon: str, token: str) -> int:
    return fon.index(token) + 1


@pytest.mark.parametrize(
    ("fon", "token", "problem"),
    [
        # a constant where an address is needed (BCD digits are not an octal address)
        ("FON C:$03000 N:MOV S:9876 D:$04004", "9876", "S: '9876' is not an octal address"),
        # an address where a constant is needed
        ("FON C:$03000 N:MVID S:$04000 D:$04004", "$04000", "S: a constant is needed"),
        # BCD constants: a non-decimal digit, five digits
        ("FON C:$03000 N:MVIBCD S:98A6 D:$04000", "98A6", "S: '98A6' is not a BCD constant"),
        ("FON C:$03000 N:MVIBCD S:12345 D:$04000", "12345", "S: '12345' is not a BCD constant"),
        # values out of range / not in the parameter's radix
        ("FON C:$03000 N:MVID S:65536 D:$04000", "65536", "S: 65536 is outside"),
        ("FON C:$03000 N:NSYNC S:10 D:-1", "-1", "D: -1 is outside"),
        ("FON C:$03000 N:MVIO S:1238 D:$04000", "1238", "S: '1238' is not"),
        ("FON C:$03000 N:MVIO S:200000 D:$04000", "200000", "S: 200000 is outside"),
        ("FON C:$03000 N:MOV S:$10000 D:$04000", "$10000", "S: 010000 is not a valid address"),
        # NODE: the manual's node range 0...255
        ("FON C:$03000 N:NODE S:256", "256", "S: 256 is outside 0-255"),
        ("FON C:$03000 N:300 S:65535", "65535", "S: 65535 is outside 0-255"),
        # functions that do not exist
        ("FON C:$03000 N:17 S:$04000 D:$04000", "17", "N: function 17 does not exist"),
        ("FON C:$03000 N:NOSUCH S:$04000 D:$04000", "NOSUCH", "N: unknown function 'NOSUCH'"),
        # an extra parameter
        ("FON C:$03000 N:MOV S:$04000 D:$04004 R:$04010", "$04010", "MOV takes no R: parameter"),
        ("FON C:$03000 N:NMEM S:$04000 D:$04002", "$04002", "NMEM takes no D: parameter"),
    ],
)
def test_parameter_error_names_line_column_and_problem(fon: str, token: str, problem: str) -> None:
    message = load_error(fon)
    assert message.startswith(f"t.stl:2:{col(fon, token)}: "), message
    assert problem in message


@pytest.mark.parametrize(
    ("fon", "problem"),
    [
        ("FON C:$03000 N:ADD S:$04000 D:$04002", "ADD needs R: (an address)"),
        ("FON C:$03000 N:NSYNC S:5", "NSYNC needs D: (a decimal constant)"),
        ("FON C:$03000 N:MVIBCD D:$04000", "MVIBCD needs S: (a BCD constant)"),
        ("FON C:$03000 N:BMASK S:$04000 D:257", "BMASK needs R: (an octal constant)"),
    ],
)
def test_missing_parameter_is_reported_at_the_instruction(fon: str, problem: str) -> None:
    message = load_error(fon)
    assert message.startswith("t.stl:2:1: "), message
    assert problem in message


def test_every_error_of_a_program_is_reported_at_once() -> None:
    text = (PROLOGUE + "FON C:$03000 N:MVIBCD S:98A6 D:$04000\n"
            "TNA $02001\nFON C:$03004 N:ADD S:$04000 D:$04002\n")
    with pytest.raises(ProgramError) as e:
        parse(text, source="t.stl")
    assert [(d.line, d.col) for d in e.value.errors] == [(2, 25), (4, 1)]


def test_mnemonic_and_number_name_the_same_function() -> None:
    by_name = parse(PROLOGUE + "FON C:$03000 N:addbcd S:$04000 D:$04002 R:$04004\n").instrs[1]
    by_number = parse(PROLOGUE + "FON C:$03000 N:10 S:$04000 D:$04002 R:$04004\n").instrs[1]
    assert by_name.n == by_number.n == 10
    assert (by_name.s, by_name.d, by_name.r) == (by_number.s, by_number.d, by_number.r)


def test_constants_are_read_in_their_kind_radix() -> None:
    bcd, dec, octal = (
        parse(PROLOGUE + f"FON C:$03000 N:{fn} S:{value} D:$04000\n").instrs[1].s
        for fn, value in (("MVIBCD", "9876"), ("MVID", "32767"), ("MVIO", "123456"))
    )
    assert (bcd, dec, octal) == (0x9876, 32767, 0o123456)


def test_every_defined_code_is_registered_except_the_exchange_functions() -> None:
    """Codes 300-302 (NODE NREAD NWRITE) are registered by the exchange module, not here."""
    lookup(0)
    missing = sorted(DEFINED_CODES - set(REGISTRY) - {300, 301, 302})
    assert missing == []


def test_node_takes_the_manual_range_0_to_255() -> None:
    for n in (0, 255):
        assert parse(f"{PROLOGUE}FON C:$03000 N:NODE S:{n}\n").instrs[1].s == n
