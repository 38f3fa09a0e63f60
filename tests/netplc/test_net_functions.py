"""NODE / NREAD / NWRITE as instructions: parameters, the current node, and C+1 with no exchange."""

from __future__ import annotations

import pytest

from netplc.engine import Engine, FakeClock
from netplc.program import ProgramError, parse
from tests.netplc.test_exchange import NETPLC_PROGRAM


def test_without_exchange_the_link_outputs_are_0() -> None:
    engine = Engine(parse(NETPLC_PROGRAM), clock=FakeClock())
    engine.scan()
    snap = engine.snapshot
    assert snap.get_bit(0o2110) == 1 and snap.get_bit(0o2104) == 1  # the coils follow the rung
    assert snap.get_bit(0o2111) == 0 and snap.get_bit(0o2105) == 0


def test_node_selects_the_node_until_the_next_node() -> None:
    engine = Engine(parse("TNA $03760\nFON C:$02100 N:NODE S:17\nJMP 0\n"), clock=FakeClock())
    engine.scan()
    assert engine.node == 17
    engine.load(parse("TNA $03760\nFON C:$02100 N:NREAD S:4000 D:$04000 R:2\nJMP 0\n"))
    engine.scan()
    assert engine.node == 17


def test_numbers_and_mnemonics_take_the_documented_parameter_kinds() -> None:
    by_number = parse("FON C:$02100 N:301 S:4010 D:$04000 R:4\nFON C:$02104 N:302 S:$04000 D:4010 R:4\n")
    read, write = by_number.instrs
    assert (read.s, read.d, read.r) == (0o4010, 0o4000, 4)  # S octal constant, D address, R decimal
    assert (write.s, write.d, write.r) == (0o4000, 0o4010, 4)


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("FON C:$02100 N:NREAD S:$04000 D:$04000 R:2", "S: a constant is needed here"),
        ("FON C:$02100 N:NWRITE S:$04000 D:4009 R:2", "D: '4009' is not an octal number"),
        ("FON C:$02100 N:NODE S:x", "S: 'x' is not a decimal number"),
        ("FON C:$02100 N:NODE S:1 D:2", "NODE takes no D: parameter"),
    ],
)
def test_bad_parameters_are_load_errors(line: str, message: str) -> None:
    with pytest.raises(ProgramError) as e:
        parse(line + "\n", "net.stl")
    assert message in str(e.value)
    assert str(e.value).startswith("net.stl:1:")
