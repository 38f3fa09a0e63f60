"""The manual's worked examples (tests/vectors/functions.toml), run through the real parser and engine.

Each case becomes a two-line STL program (`TNA rung` + the case's FON), is parsed by
netplc.program.parse and scanned by the Engine on a FakeClock, in the compiled engine and the
reference interpreter. After each step the *whole* memory is compared: every data byte and I/O bit
the case does not name must be as it was, so a function that writes one byte too many fails.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import pytest

from netplc.address import ALWAYS_ONE, GEN_BASE, IO_BITS, RTC_CONTROL, data_address, fmt_octal, parse_octal
from netplc.engine import Engine, FakeClock
from netplc.memory import Memory
from netplc.program import parse
from netplc.records import ListSink

VECTORS = Path(__file__).resolve().parents[1] / "vectors" / "functions.toml"
CASES: list[dict[str, Any]] = tomllib.loads(VECTORS.read_text(encoding="utf-8"))["case"]
RTC_BYTES = 8
SYSTEM_BITS = {*range(GEN_BASE, GEN_BASE + 8), ALWAYS_ONE}  # driven by the engine clock


def program_text(case: dict[str, Any]) -> str:
    return f"TNA ${case.get('rung', '02000')}\nFON {case['fon']}\n"


def apply(mem: Memory, spec: dict[str, Any]) -> None:
    """Write a case's `bits`, `words` and `bytes` tables (octal address keys) into memory."""
    for addr, v in spec.get("bits", {}).items():
        mem.set_bit(parse_octal(addr), v)
    for addr, v in spec.get("words", {}).items():
        mem.set_word(parse_octal(addr), v)
    for addr, v in spec.get("bytes", {}).items():
        mem.write(parse_octal(addr), bytes.fromhex(v))


def steps(case: dict[str, Any]) -> list[dict[str, Any]]:
    """A case is a list of steps; a case with only `after` is one step of one scan."""
    if "compare" in case:
        return compare_steps(case["compare"])
    if "step" in case:
        return case["step"]
    return [{"after": case.get("after", {})}]


def compare_steps(spec: dict[str, Any]) -> list[dict[str, Any]]:
    """One step per operand pair of a `compare` table, expecting Python's unsigned comparison."""
    ops = {">": int.__gt__, "<": int.__lt__, "=": int.__eq__}
    out = parse_octal(spec["out"])
    pairs = [(x, spec["imm"]) for x in spec["values"]] if "imm" in spec else [
        (x, y) for x in spec["values"] for y in spec["values"]]
    result = []
    for x, y in pairs:
        words = {spec["s"]: x} if "imm" in spec else {spec["s"]: x, spec["d"]: y}
        if spec["op"] == "cmp":
            flags = [int(x > y), int(x == y), int(x < y)]
        else:
            flags = [int(ops[spec["op"]](x, y))]
        bits = {fmt_octal(out + k): v for k, v in enumerate(flags)}
        result.append({"set": {"words": words}, "after": {"bits": bits}})
    return result


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "reference"])
@pytest.mark.parametrize("case", CASES, ids=[c["name"] for c in CASES])
def test_vector(case: dict[str, Any], compiled: bool) -> None:
    program = parse(program_text(case), source=case["name"])
    clock = FakeClock(0.0)
    sink = ListSink()
    engine = Engine(program, clock=clock, wallclock=lambda: 0.0, sink=sink, compiled=compiled)
    mem = engine.mem
    c = program.instrs[1].c
    apply(mem, case)
    mem.set_bit(parse_octal(case.get("rung", "02000")), 1)
    for n, step in enumerate(steps(case)):
        apply(mem, step.get("set", {}))
        expected = Memory()
        expected.load(mem)
        traces = {parse_octal(a): v for a, v in step.get("trace", {}).items()}
        seen: dict[int, list[int]] = {a: [] for a in traces}
        for _ in range(step.get("scans", 1)):
            clock.advance(step.get("dt", 0.1))
            engine.scan()
            for a in traces:
                seen[a].append(mem.bits[a] if a < IO_BITS else mem.get_word(a))
        for a, want in traces.items():
            want_list = [int(ch) for ch in want] if isinstance(want, str) else want
            assert seen[a] == want_list, f"step {n}: trace of {fmt_octal(a)}"
            if a < IO_BITS:
                expected.set_bit(a, want_list[-1])
            else:
                expected.set_word(a, want_list[-1])
        apply(expected, step.get("after", {}))
        for k in (c, *SYSTEM_BITS):
            expected.bits[k] = mem.bits[k]
        expected.write(RTC_CONTROL, mem.read(RTC_CONTROL, RTC_BYTES))  # kept current by the engine
        bad_bits = [a for a in range(IO_BITS) if mem.bits[a] != expected.bits[a]]
        assert not bad_bits, f"step {n}: bits differ: " + ", ".join(
            f"{fmt_octal(a)} = {mem.bits[a]}, expected {expected.bits[a]}" for a in bad_bits)
        if mem.data != expected.data:
            diff = [i for i in range(len(mem.data)) if mem.data[i] != expected.data[i]]
            raise AssertionError(f"step {n}: data differs: " + ", ".join(
                f"{fmt_octal(data_address(i))} = {mem.data[i]:02X}, expected {expected.data[i]:02X}"
                for i in diff[:16]))
        if "records" in step:
            assert len(sink.records) == step["records"]


# every function of the spec's section 7 table, and the NetPlc functions the issue names
REQUIRED = [
    "MOV", "MVIBCD", "XCG", "BCDW", "WBCD", "MVID", "MVIO", "NEG", "ADDBCD", "SUBBCD", "CMP", "AND",
    "OR", "XOR", "ROR", "ROL", "BMASK", "WMASK", "ENCOD", "DECOD", "SWPB", "SCALE", "TIMSET", "TIMFIX",
    "ERCODE", "INCW", "DECW", "TGRP", "PUSH", "POP", "MOVBLK", "MVMBLK", "STM", "LDM", "MVM", "PRTO",
    "PRTOCH", "PRTE", "PRTECH", "MOVB", "SHFTBLK", "ADD", "SUB", "MUL", "DIV", "ADCWR", "NSYNC",
    "NAVG", "NMAX", "NGREAT", "NLESS", "NEQUAL", "NLESSI", "NGREATI",
]


def test_every_worked_example_has_a_case() -> None:
    covered = {c["fon"].split("N:")[1].split()[0] for c in CASES}
    assert [fn for fn in REQUIRED if fn not in covered] == []
