"""A big program's first compile by a child process (netplc/compile_behind.py): the interpreter runs
the first scans, the compiled code takes over between two scans, and memory is at every scan what
the interpreter alone leaves; a child that fails costs only the compile in the station's process."""

from __future__ import annotations

import logging
import threading
import time
from pathlib import Path

import pytest

from netplc import compile_behind
from netplc.engine import Engine, FakeClock
from netplc.program import Program, parse

# timers, counters, functions, generators and a jump: state the two backends must hand over
TEXT = """TNA $02000
TIM $03000 N:2
TNA $03001
FON C:$03004 N:INCW S:$04002 D:$04000
TNA $03751
CTR $03010 N:5
TNA $03012
YON $02001
TFA $02001
JMY skip
FON C:$03020 N:INCW S:$04010 D:$04010
skip:
TNA $03752
TFO $03001
SON $02002
JMP 0
"""


@pytest.fixture(autouse=True)
def small_programs_compile_behind(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(compile_behind, "BEHIND_MIN", 5)  # the test program, not 2,000 instructions


def engine(program: Program, **kw: object) -> Engine:
    eng = Engine(program, clock=FakeClock(), wallclock=lambda: 0.0, **kw)
    eng.mem.set_bit(0o2000, 1)
    return eng


def state(eng: Engine) -> tuple:
    return bytes(eng.mem.bits), bytes(eng.mem.data), eng.held_values()


def scan(*engines: Engine) -> None:
    for eng in engines:
        assert isinstance(eng.clock, FakeClock)
        eng.clock.advance(0.1)
        eng.scan()


def wait_for_compilers() -> None:
    for thread in threading.enumerate():
        if thread.name == "netplc-compile":
            thread.join(60)


def test_the_interpreter_scans_until_the_childs_code_takes_over(tmp_path: Path) -> None:
    program = parse(TEXT, source="p.stl")
    behind = engine(program, code_cache=tmp_path)
    reference = engine(program, compiled=False)
    assert not behind.compiled_ready.is_set()  # a child Python is still starting
    deadline = time.monotonic() + 60
    scans = 0
    while not behind.compiled_ready.is_set() and time.monotonic() < deadline:
        scan(behind, reference)
        scans += 1
        assert state(behind) == state(reference), f"scan {scans}, on the interpreter"
    assert behind.compiled_ready.is_set()
    for n in range(40):  # the generators, the timer, the counter and both functions move on
        scan(behind, reference)
        assert state(behind) == state(reference), f"scan {n + 1} after the compiled code took over"
    assert len(list(tmp_path.glob("program-*.code"))) == 1
    assert engine(program, code_cache=tmp_path).compiled_ready.is_set()  # the next start: from the cache


def test_a_failing_child_costs_only_the_compile(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                caplog: pytest.LogCaptureFixture) -> None:
    monkeypatch.setattr(compile_behind, "PYTHON", "/bin/false")  # a real process that fails
    caplog.set_level(logging.ERROR, logger="netplc.compile_behind")
    program = parse(TEXT, source="p.stl")
    behind = engine(program, code_cache=tmp_path)
    reference = engine(program, compiled=False)
    scan(behind, reference)  # the child starts after the first scan
    assert behind.compiled_ready.wait(60)
    assert "the child process compiling p.stl failed (exit code 1)" in caplog.text
    for _ in range(20):
        scan(behind, reference)
    assert state(behind) == state(reference)
    assert len(list(tmp_path.glob("program-*.code"))) == 1


def test_a_program_loaded_meanwhile_is_not_replaced_by_the_older_ones_code(tmp_path: Path) -> None:
    first = parse(TEXT, source="first.stl")
    second = parse("TNA $02000\nYON $02003\n", source="second.stl")  # compiled in place: below BEHIND_MIN
    eng = engine(first, code_cache=tmp_path)
    eng.load(second)
    assert eng.compiled_ready.is_set()
    reference = engine(second, compiled=False)
    scan(eng, reference)  # the first scan: the first program's child starts
    wait_for_compilers()  # the first program's child is done and its code offered
    for _ in range(3):
        scan(eng, reference)
    assert state(eng) == state(reference)
    assert eng.mem.bits[0o2001] == 0  # the first program's coil: never run
