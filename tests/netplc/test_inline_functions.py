"""The functions the compiler puts in line (FunctionSpec.inline) against the reference interpreter.

For each such function one program holds a FON for every combination of operands drawn from data
words at even and odd addresses, overlapping ones, I/O bits and a word that runs off its bank; both
engines scan it on the same random data, and the whole memory (data, every bit including C,
the outputs C+1.. and FErr1) must be the same after each scan, with the rung on and then off.
"""

from __future__ import annotations

import itertools
import logging
import random

import pytest

from netplc.address import FERR1
from netplc.compiler import generate_source
from netplc.engine import Engine, FakeClock
from netplc.functions._util import built
from netplc.functions.registry import BY_NAME, REGISTRY, FunctionSpec, lookup
from netplc.program import parse
from netplc.records import ListSink

lookup(0)  # imports every function module
INLINED = sorted((s for s in REGISTRY.values() if s.inline is not None), key=lambda s: s.number)
ADDRESSES = [0o4000, 0o4001, 0o4002, 0o4003, 0o7776, 0o7777, 0o2000]  # 07777: a word runs off bank 0
CONSTANTS = {"D": ["0", "1", "3", "255", "256", "40000", "65535"], "O": ["0", "1", "17", "177777"],
             "B": ["0", "1234", "9999"]}
RUNG = 0o2400


def program_text(mnemonic: str, kinds: list[str | None]) -> str:
    choices = [ADDRESSES if k == "M" else CONSTANTS[k] for k in kinds if k]
    lines = []
    for n, combo in enumerate(itertools.product(*choices)):
        params = " ".join(f"{key}:${v:05o}" if isinstance(v, int) else f"{key}:{v}"
                          for key, v in zip(("S", "D", "R"), combo))
        lines += [f"TNA $0{RUNG:o}", f"FON C:$0{0o2500 + 4 * (n % 0o200):o} N:{mnemonic} {params}"]
    return "\n".join(lines) + "\n"


def test_every_inlined_function_is_covered():
    names = {s.mnemonic for s in INLINED}
    assert {"MOV", "MOVB", "ADD", "SUB", "INCW", "DECW", "NSETDI", "NMOVW", "NMOVB", "AND", "OR", "XOR",
            "NGREAT", "NLESS", "NEQUAL", "NGREATI", "NLESSI", "CMP"} <= names


@pytest.mark.parametrize("spec", INLINED, ids=[s.mnemonic for s in INLINED])
def test_inlined_function_matches_the_reference(spec):
    program = parse(program_text(spec.mnemonic, list(spec.kinds().values())), source=spec.mnemonic)
    rnd = random.Random(spec.number)
    data = bytes(rnd.randrange(256) for _ in range(16))
    high = bytes(rnd.randrange(256) for _ in range(2))
    io_bits = [rnd.randrange(2) for _ in range(16)]
    engines = []
    for compiled in (False, True):
        clock = FakeClock()
        engine = Engine(program, clock=clock, wallclock=lambda: 0.0, compiled=compiled)
        engine.mem.write(0o4000, data)
        engine.mem.write(0o7776, high)
        engine.mem.bits[0o2000:0o2020] = bytes(io_bits)
        engines.append((engine, clock))
    for rung in (1, 1, 1, 0):
        for engine, clock in engines:
            engine.mem.bits[RUNG] = rung
            clock.advance(0.1)
            engine.scan()
        (ref, _), (fast, _) = engines
        assert bytes(fast.mem.bits) == bytes(ref.mem.bits)
        assert bytes(fast.mem.data) == bytes(ref.mem.data)


def test_data_operands_are_inlined_and_io_operands_called():
    program = parse("TNA $03760\nFON C:$03000 N:ADD S:$04000 D:$04002 R:$04004\n"
                    "TNA $03760\nFON C:$03004 N:ADD S:$02000 D:$04002 R:$04004\n")
    engine = Engine(program, clock=FakeClock(), wallclock=lambda: 0.0)
    inline = {i: lines for i, (fon, spec) in engine.fons.items()
              if spec is not None and spec.inline and (lines := spec.inline(fon)) is not None}
    assert list(inline) == [1]  # the one on I/O bits 02000-02017 is called
    source = generate_source(program, inline)
    assert "fon3 = steps[3]" in source and "fon1" not in source


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "reference"])
def test_a_builder_that_raises_fails_when_its_fon_runs(compiled, monkeypatch, caplog):
    def build(mem, fon):
        raise RuntimeError("bad table")

    spec = FunctionSpec(4247, "BROKEN", "M", None, None, built(build))
    monkeypatch.setitem(REGISTRY, 4247, spec)
    monkeypatch.setitem(BY_NAME, "BROKEN", spec)
    program = parse("TNA $02000\nFON C:$03000 N:BROKEN S:$04000\n")
    sink = ListSink()
    engine = Engine(program, clock=FakeClock(), wallclock=lambda: 0.0, sink=sink, compiled=compiled)
    engine.scan()
    assert engine.mem.bits[FERR1] == 0 and not sink.records  # loading does not run it
    engine.mem.bits[0o2000] = 1
    with caplog.at_level(logging.ERROR, logger="netplc.engine"):
        engine.scan()
        engine.scan()
    assert engine.mem.bits[FERR1] == 1 and engine.mem.bits[0o3000] == 1
    assert [r.text for r in sink.records] == ["FON BROKEN at line 2: RuntimeError: bad table"]
    [logged] = caplog.records  # with its traceback, once: it fails at every scan its chain is on
    assert "FON BROKEN at line 2" in logged.getMessage() and "bad table" in str(logged.exc_info[1])
