"""The reference interpreter: the instruction semantics of docs/architecture.md section 4, written plainly.

The compiled engine must leave memory exactly as this does (tests/netplc/test_compiled_equivalence.py).
"""

from __future__ import annotations

from netplc import backend
from netplc.backend import Outcome, ScanHost
from netplc.program import Program


class Interpreter:
    def __init__(self, program: Program, engine: ScanHost) -> None:
        self.instrs = program.instrs
        self.engine = engine

    def run(self) -> Outcome:
        """One scan; returns None at the end, "halt" on HLT, "watchdog" on an endless loop."""
        eng = self.engine
        bits = eng.mem.bits
        instrs = self.instrs
        acc, sm = 1, 0
        pc = 0
        steps = 0
        limit = backend.WATCHDOG_STEPS
        while pc < len(instrs):
            steps += 1
            if steps > limit:
                return "watchdog"
            ins = instrs[pc]
            op = ins.op
            pc += 1
            if op == "TNA":
                acc &= bits[ins.c]
            elif op == "TFA":
                acc &= bits[ins.c] ^ 1
            elif op == "TNO":
                acc |= bits[ins.c]
            elif op == "TFO":
                acc |= bits[ins.c] ^ 1
            elif op == "TNE":
                sm |= acc
                acc = bits[ins.c]
            elif op == "TFE":
                sm |= acc
                acc = bits[ins.c] ^ 1
            elif op == "NOP":
                continue
            elif op == "HLT":
                return "halt"
            elif op == "JMP":
                if ins.target is None:
                    return None
                pc = ins.target
                acc, sm = 1, 0
            else:
                res = sm | acc
                acc, sm = 1, 0
                if op == "YON":
                    bits[ins.c] = res
                elif op == "SON":
                    if res:
                        bits[ins.c] = 1
                elif op == "SOF":
                    if res:
                        bits[ins.c] = 0
                elif op == "SKP":
                    if not res:
                        pc += 1
                elif op in ("TIM", "CTR", "FON"):
                    eng.instruction_call(pc - 1)(res)
                elif (op == "JMY" and res) or (op == "JMN" and not res):
                    if ins.target is None:
                        return None
                    pc = ins.target
        return None
