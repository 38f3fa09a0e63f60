"""Helpers shared by the NetPlc core tests: build an engine on a stepped clock and drive it."""

from __future__ import annotations

from netplc.engine import Engine, FakeClock
from netplc.program import Instr, Program, parse
from netplc.records import ListSink

BOTH = [True, False]  # parametrize: compiled engine, reference interpreter
ENGINE_IDS = ["compiled", "interpreter"]


class Rig:
    """An engine on a FakeClock with a ListSink; `step` advances the clock and scans."""

    def __init__(self, program: str | Program, compiled: bool = True, *, tick: float = 0.1,
                 wall: float = 0.0, symbols: dict[str, int] | None = None) -> None:
        if isinstance(program, str):
            program = parse(program, source="test.stl", symbols=symbols)
        self.clock = FakeClock(0.0)
        self.sink = ListSink()
        self.wall = wall
        self.engine = Engine(program, clock=self.clock, wallclock=lambda: self.wall, sink=self.sink,
                             tick=tick, compiled=compiled)
        self.bits = self.engine.mem.bits

    def step(self, dt: float = 0.1, scans: int = 1, **inputs: int) -> None:
        """Set bits given as `b02042=1` (octal after the b), then run `scans` scans of `dt` each."""
        for name, value in inputs.items():
            self.bits[int(name[1:], 8)] = value
        for _ in range(scans):
            self.clock.advance(dt)
            self.wall += dt
            self.engine.scan()

    def bit(self, addr: int) -> int:
        return self.bits[addr]


def with_fon(text: str, number: int, c: int = 0o3010, s: int = 0o4000, d: int = 0o4002) -> Program:
    """Parse `text`, turning each line `FON?` into `FON C:c N:number S:s D:d`.

    The instruction is built directly, so `number` may be one that no module registers (the
    parser refuses such a number, the engine must still cope with it).
    """
    program = parse(text.replace("FON?", "NOP"), source="test.stl")
    lines = text.splitlines()
    instrs = [
        Instr("FON", c=c, n=number, s=s, d=d, addr=ins.addr, line=ins.line, text="FON?")
        if lines[ins.line - 1].strip() == "FON?" else ins
        for ins in program.instrs
    ]
    return Program(instrs, program.symbols, program.source, program.words)
