"""Compile an STL program once into generated Python, so that a scan is a few function calls.

The program is cut into basic blocks at jump targets; each block becomes one straight-line
function over local variables `a` (ACC) and `s` (SUM) and the bit array `b`, returning the index
of the next block (None ends the scan, -1 halts). Contacts and coils become single indexing
statements; TIM, CTR and FON call the engine's shared implementations.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from netplc.program import Instr, Program

if TYPE_CHECKING:
    from netplc.engine import Engine

HALT = -1


def _block_starts(instrs: list[Instr]) -> list[int]:
    starts = {0}
    for i, ins in enumerate(instrs):
        if ins.op in ("JMP", "JMY", "JMN", "HLT"):
            if ins.target is not None:
                starts.add(ins.target)
            starts.add(i + 1)
    # the instruction after SKP must sit in SKP's block, unless it starts one: then the skip
    # jumps to the block after it
    for i, ins in enumerate(instrs):
        if ins.op == "SKP" and i + 1 in starts:
            starts.add(i + 2)
    return sorted(s for s in starts if s <= len(instrs))


def _target(t: int | None, n: int) -> str:
    return "None" if t is None or t >= n else str(t)


def _code(ins: Instr, index: int, n: int) -> list[str]:
    """Python lines for one instruction (without the chain reset of terminators)."""
    op, c = ins.op, ins.c
    if op == "TNA":
        return [f"a &= b[{c}]"]
    if op == "TFA":
        return [f"a &= b[{c}] ^ 1"]
    if op == "TNO":
        return [f"a |= b[{c}]"]
    if op == "TFO":
        return [f"a |= b[{c}] ^ 1"]
    if op == "TNE":
        return ["s |= a", f"a = b[{c}]"]
    if op == "TFE":
        return ["s |= a", f"a = b[{c}] ^ 1"]
    if op == "NOP":
        return []
    if op == "YON":
        return [f"b[{c}] = s | a", "a = 1; s = 0"]
    if op == "SON":
        return [f"if s | a: b[{c}] = 1", "a = 1; s = 0"]
    if op == "SOF":
        return [f"if s | a: b[{c}] = 0", "a = 1; s = 0"]
    if op == "TIM":
        return [f"tim({c}, {ins.n}, s | a)", "a = 1; s = 0"]
    if op == "CTR":
        return [f"ctr({c}, {ins.n}, s | a)", "a = 1; s = 0"]
    if op == "FON":
        return [f"fon({index}, s | a)", "a = 1; s = 0"]
    if op == "HLT":
        return [f"return {HALT}, a, s"]
    if op == "JMP":
        return [f"return {_target(ins.target, n)}, 1, 0"]
    if op == "JMY":
        return [f"if s | a: return {_target(ins.target, n)}, 1, 0", "a = 1; s = 0"]
    if op == "JMN":
        return [f"if not (s | a): return {_target(ins.target, n)}, 1, 0", "a = 1; s = 0"]
    raise AssertionError(op)


def generate_source(program: Program) -> str:
    instrs = program.instrs
    n = len(instrs)
    starts = _block_starts(instrs)
    lines = ["def _make(b, tim, ctr, fon):"]
    for k, start in enumerate(starts):
        end = starts[k + 1] if k + 1 < len(starts) else n
        lines.append(f"    def _b{start}(a, s):")
        body: list[str] = []
        i = start
        while i < end:
            ins = instrs[i]
            if ins.op == "SKP":
                body += ["r = s | a", "a = 1; s = 0"]
                if i + 1 >= end:  # nothing in this block to skip: the skipped one starts the next
                    body.append(f"if not r: return {_target(i + 2, n)}, 1, 0")
                elif i + 1 < n:
                    skipped = _code(instrs[i + 1], i + 1, n)
                    body.append("if r:")
                    body += ["    " + line for line in skipped] or ["    pass"]
                    i += 1
            else:
                body += _code(ins, i, n)
            i += 1
            if body and body[-1].startswith("return"):
                break
        if not body or not body[-1].startswith("return"):
            body.append(f"return {_target(end, n)}, a, s")
        lines += ["        " + line for line in body]
    lines.append("    return {" + ", ".join(f"{s}: _b{s}" for s in starts if s < n) + "}")
    return "\n".join(lines) + "\n"


def compile_program(program: Program, engine: Engine) -> Callable[[], str | None]:
    from netplc.engine import WATCHDOG_STEPS

    namespace: dict = {}
    exec(compile(generate_source(program), f"<compiled {program.source}>", "exec"), namespace)
    blocks = namespace["_make"](engine.mem.bits, engine.tim, engine.ctr, engine.fon)
    first = blocks.get(0)

    def run() -> str | None:
        if first is None:
            return None
        nxt, a, s = first(1, 0)
        steps = 0
        while nxt is not None:
            if nxt == HALT:
                return "halt"
            steps += 1
            if steps > WATCHDOG_STEPS:
                return "watchdog"
            nxt, a, s = blocks[nxt](a, s)
        return None

    return run
