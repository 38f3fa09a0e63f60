"""Compile an STL program once into generated Python, so that a scan is a few function calls.

The program is cut into basic blocks at jump targets; each block becomes one straight-line
function of the chain state `a` (ACC) and `s` (SUM) on entry, returning the index of the next
block (None ends the scan, HALT halts) and the state on exit. Inside a block the chain state is
kept symbolically: a chain of contacts becomes one short-circuit expression (contacts have no side
effects, so `and`/`or` give the same RES as the bitwise model of docs/architecture.md section 4), evaluated
once by its terminator. TIM and CTR are written out from the source lines netplc/timers.py keeps
beside its closures; a FON runs its function's inline source lines (FunctionSpec.inline, for simple
functions on data operands) or calls the step the engine binds once per instruction. The reference
interpreter reaches the same timers and functions through the engine's closures, and the equivalence
tests hold the two to identical memory.
"""

from __future__ import annotations

import functools
import marshal
import re
from collections.abc import Callable
from pathlib import Path
from types import CodeType

from netplc import backend, timers
from netplc.backend import Backend, Outcome, ScanHost
from netplc.codecache import CodeCache, cache_key
from netplc.program import Instr, Program
from netplc.timers import QUOTIENT, TIME_BASE_BITS, TIME_BASES, ctr_lines, tim_lines

HALT = -1
_MAX_DEPTH = 24  # nested and/or groups before the state is stored in a and s (parser limits)
_MAX_TERMS = 200  # contacts in one expression before the same
# A long block is cut into functions of at most about this many distinct constants, between
# instructions where no chain state is pending: beyond 256 constants CPython needs an EXTENDED_ARG
# before every LOAD_CONST of the rest, which costs more than a call per chunk.
_CHUNK_CONSTS = 200
_CONST = re.compile(r"(?<![\w.])\d+(?:\.\d*)?(?:e-?\d+)?")


def _block_starts(instrs: list[Instr]) -> list[int]:
    starts = {0}
    for i, ins in enumerate(instrs):
        if ins.op in ("JMP", "JMY", "JMN", "HLT"):
            if ins.target is not None:
                starts.add(ins.target)
            starts.add(i + 1)
    # the instruction after SKP must sit in SKP's block, unless it starts one: then the skip
    # jumps to the block after it (in index order, so a start added here is seen by a later SKP)
    for i, ins in enumerate(instrs):
        if ins.op == "SKP" and i + 1 in starts:
            starts.add(i + 2)
    return sorted(s for s in starts if s <= len(instrs))


def _target(t: int | None, n: int) -> str:
    return "None" if t is None or t >= n else str(t)


class _Expr:
    """A boolean expression over the bit array, with its precedence and nesting for the parser."""

    __slots__ = ("depth", "kind", "terms", "text")

    def __init__(self, text: str, kind: str = "atom", depth: int = 0, terms: int = 1) -> None:
        self.text, self.kind, self.depth, self.terms = text, kind, depth, terms

    def join(self, op: str, other: _Expr) -> _Expr:
        """self <op> other, op being 'and' or 'or'; constants fold (contacts have no effects)."""
        absorbing, neutral = ("0", "1") if op == "and" else ("1", "0")
        if self.text == absorbing or other.text == neutral:
            return self
        if self.text == neutral or other.text == absorbing:
            return other
        left, depth = self.text, self.depth
        if self.kind not in ("atom", op) and not (op == "or" and self.kind == "and"):
            left, depth = f"({left})", depth + 1
        right = other.text if other.kind == "atom" else f"({other.text})"
        depth = max(depth, other.depth + (other.kind != "atom"))
        return _Expr(f"{left} {op} {right}", op, depth, self.terms + other.terms)

    def heavy(self) -> bool:
        return self.depth > _MAX_DEPTH or self.terms > _MAX_TERMS


ONE, ZERO = _Expr("1"), _Expr("0")


def _contact(ins: Instr) -> _Expr:
    negated = ins.op in ("TFA", "TFO", "TFE")
    return _Expr(f"(not b[{ins.c}])" if negated else f"b[{ins.c}]")


def _branch(res: str, on: list[str], off: list[str]) -> list[str]:
    """Lines running `on` when the expression `res` is true, else `off`."""
    if res == "1":
        return on
    if res == "0":
        return off
    out = [f"if {res}:", *("    " + line for line in on or ["pass"])]
    if off:
        out += ["else:", *("    " + line for line in off)]
    return out


class _Block:
    """Code of one basic block, generated with the chain state (acc, sm) tracked symbolically."""

    def __init__(self, n: int, inline: dict[int, list[str]]) -> None:
        self.n = n
        self.inline = inline  # FON index -> the function's source lines
        self.quotient = False  # _q holds the TIM time-base quotient (see netplc/timers.py)
        self.cuts = [0]  # line indices where chunks start
        self.consts: set[str] = set()  # the constants of the current chunk
        self.counted = 0  # lines whose constants are in self.consts
        self.lines: list[str] = []
        self.acc, self.sm = _Expr("a"), _Expr("s")
        self.ended = False  # the last line returns

    def res(self) -> str:
        return self.sm.join("or", self.acc).text

    def store(self) -> None:
        """Put the symbolic state into the variables (both at once: each may read the other)."""
        self.lines.append(f"s, a = {self.sm.text}, {self.acc.text}")
        self.acc, self.sm = _Expr("a"), _Expr("s")

    def chain_end(self) -> None:
        self.acc, self.sm = ONE, ZERO

    def emit(self, ins: Instr, index: int) -> None:
        op, c, lines = ins.op, ins.c, self.lines
        if op in ("TNA", "TFA"):
            self.acc = self.acc.join("and", _contact(ins))
        elif op in ("TNO", "TFO"):
            self.acc = self.acc.join("or", _contact(ins))
        elif op in ("TNE", "TFE"):
            self.sm = self.sm.join("or", self.acc)
            self.acc = _contact(ins)
        elif op == "NOP":
            return
        elif op == "YON":
            lines.append(f"b[{c}] = {self.res()}")
            self.chain_end()
            self.wrote(c, 1)
        elif op in ("SON", "SOF"):
            res = self.res()
            if res != "0":
                lines.append(f"b[{c}] = {int(op == 'SON')}" if res == "1" else
                             f"if {res}: b[{c}] = {int(op == 'SON')}")
            self.chain_end()
            self.wrote(c, 1)
        elif op == "TIM":
            if not self.quotient:
                lines.append(QUOTIENT)
                self.quotient = True
            lines += _branch(self.res(), *tim_lines(c or 0, ins.n or 0))
            self.chain_end()
            self.wrote(c, 2)
        elif op == "CTR":
            lines += _branch(self.res(), *ctr_lines(c or 0, ins.n or 0))
            self.chain_end()
            self.wrote(c, 3)
        elif op == "FON":
            body = self.inline.get(index)
            if body is None:
                body = ["try:", f"    fon{index}(eng)", "except Exception as _e:", f"    failed({index}, _e)"]
                self.quotient = False  # the function may write any bit
            elif any(f"b[{bit}]" in line for bit in TIME_BASE_BITS for line in body):
                self.quotient = False
            lines += _branch(self.res(), [f"b[{c}] = 1", *body], [f"b[{c}] = 0"])
            self.chain_end()
            self.wrote(c, 1)
        elif op == "HLT":
            lines.append(f"return {HALT}, 1, 0")
            self.ended = True
        elif op == "JMP":
            lines.append(f"return {_target(ins.target, self.n)}, 1, 0")
            self.ended = True
        elif op in ("JMY", "JMN"):
            cond = self.res() if op == "JMY" else f"not ({self.res()})"
            lines.append(f"if {cond}: return {_target(ins.target, self.n)}, 1, 0")
            self.chain_end()
        else:
            raise AssertionError(op)
        if self.acc.heavy() or self.sm.heavy():
            self.store()

    def maybe_cut(self) -> None:
        """Start a new chunk here if the current one is long and no chain state is pending."""
        for line in self.lines[self.counted:]:
            self.consts.update(_CONST.findall(line))
        self.counted = len(self.lines)
        if (self.acc is ONE and self.sm is ZERO and not self.ended
                and len(self.consts) >= _CHUNK_CONSTS):
            self.cuts.append(len(self.lines))
            self.consts.clear()
            self.quotient = False  # _q is local to a chunk

    def wrote(self, c: int | None, count: int) -> None:
        """Bits C..C+count-1 were (maybe) written: a time-base bit among them voids _q."""
        if c is not None and any(c <= bit < c + count for bit in TIME_BASE_BITS):
            self.quotient = False

    def skip(self, nxt: Instr | None, index: int, block_end: int) -> None:
        """SKP at `index`: when RES is 0, skip instruction index+1 (`nxt`, None if past the block)."""
        self.lines.append(f"r = {self.res()}")
        self.chain_end()
        if nxt is None:  # the skipped instruction starts the next block: go past it
            self.lines.append(f"if not r: return {_target(index + 2, self.n)}, 1, 0")
            return
        if nxt.op in ("SKP", "NOP"):  # a SKP reached right after a terminator sees RES = 1: no-op
            return
        inner = _Block(self.n, self.inline)
        inner.acc, inner.sm = ONE, ZERO
        inner.quotient = self.quotient
        inner.emit(nxt, index + 1)
        self.quotient = self.quotient and inner.quotient  # _q set only on one path is not set
        contact = inner.acc is not ONE or inner.sm is not ZERO
        if contact:
            inner.store()
        if not inner.lines:  # e.g. TNO: with ACC = 1 it changes nothing
            return
        self.lines.append("if r:")
        self.lines += ["    " + line for line in inner.lines]
        if contact:  # the two paths leave different chain states: keep it in a and s
            self.lines += ["else:", "    s, a = 0, 1"]
            self.acc, self.sm = _Expr("a"), _Expr("s")

    def finish(self, end: int) -> None:
        if not self.ended:
            self.lines.append(f"return {_target(end, self.n)}, {self.acc.text}, {self.sm.text}")


_ARGS = "b, d, w, eng, tk, cv, TB, failed"  # bits, data bytes and words, engine, TIM/CTR values, time bases


def generate_source(program: Program, inline: dict[int, list[str]] | None = None) -> str:
    """Python source of `_make(steps, {_ARGS})`, returning {block start: block function}.

    `inline` maps a FON's index to its function's source lines; any other FON calls steps[index].
    """
    inline = inline or {}
    instrs = program.instrs
    n = len(instrs)
    starts = _block_starts(instrs)
    out = [f"def _make(steps, {_ARGS}):"]
    out += [f"    fon{i} = steps[{i}]" for i, ins in enumerate(instrs) if ins.op == "FON" and i not in inline]
    for k, start in enumerate(starts):
        if start >= n:
            continue
        end = starts[k + 1] if k + 1 < len(starts) else n
        block = _Block(n, inline)
        i = start
        while i < end and not block.ended:
            ins = instrs[i]
            if ins.op == "SKP":
                block.skip(instrs[i + 1] if i + 1 < end else None, i, end)
                i += 1  # past the skipped instruction too (if it was in this block)
            else:
                block.emit(ins, i)
            block.maybe_cut()
            i += 1
        block.finish(end)
        out += ["    " + line for line in _chunked(f"_b{start}", block)]
    out.append("    return {" + ", ".join(f"{s}: _b{s}" for s in starts if s < n) + "}")
    return "\n".join(out) + "\n"


def _chunked(name: str, block: _Block) -> list[str]:
    """The block's function, its middle chunks as functions it calls (a jump out of one returns)."""
    defaults = ", ".join(f"{v}={v}" for v in _ARGS.split(", "))
    cuts = [*block.cuts, len(block.lines)]
    chunks = [block.lines[cuts[j]:cuts[j + 1]] for j in range(len(cuts) - 1)]
    out: list[str] = []
    calls: list[str] = []
    for j, chunk in enumerate(chunks[1:-1], start=1):
        out += [f"def {name}_{j}({defaults}):", *("    " + line for line in chunk)]
        if any("return " in line for line in chunk):
            calls += [f"_r = {name}_{j}()", "if _r is not None:", "    return _r"]
        else:
            calls.append(f"{name}_{j}()")
    body = chunks[0] + calls + (chunks[-1] if len(chunks) > 1 else [])
    return [*out, f"def {name}(a, s, {defaults}):", *("    " + line for line in body)]


def fon_code(engine: ScanHost) -> tuple[dict[int, list[str]], dict[int, Callable]]:
    """The FONs' code: {index: source lines} of those put in line, {index: bound step} of the rest."""
    inline: dict[int, list[str]] = {}
    steps = {}
    for i, (fon, spec) in engine.fons.items():
        lines = spec.inline(fon) if spec is not None and spec.inline and not spec.hardware else None
        if lines is None:
            steps[i] = engine.fon_step(i)
        else:
            inline[i] = lines
    return inline, steps


@functools.cache
def _compiler_version() -> bytes:
    """What the generated code depends on besides the program: this module and the TIM/CTR lines."""
    return cache_key(Path(__file__).read_bytes(), Path(timers.__file__ or "").read_bytes())


def code_rows(program: Program) -> list[tuple]:
    """The fields of each instruction that `generate_source` reads (op, c, n, s, d, r, target): what
    the cache key covers and what a child process compiles from (netplc/compile_behind.py)."""
    return [(i.op, i.c, i.n, i.s, i.d, i.r, i.target) for i in program.instrs]


def program_key(program: Program, inline: dict[int, list[str]]) -> bytes:
    """The cache key of the code `generate_source` makes from `program` with these in-line FONs."""
    # marshal's version 2 writes no back-references, so equal instructions give equal bytes however
    # they were made (a repr of them cost 13 ms a start for the 8 K-word program, this 3)
    instrs = marshal.dumps(code_rows(program), 2)
    return cache_key(_compiler_version(), f"{_CHUNK_CONSTS},{_MAX_DEPTH},{_MAX_TERMS}", program.source,
                     instrs, repr(sorted(inline.items())))


def compile_code(program: Program, inline: dict[int, list[str]]) -> CodeType:
    """The code object of `program` with these in-line FONs (the same wherever it is compiled)."""
    return compile(generate_source(program, inline), f"<compiled {program.source}>", "exec")


def compile_program(program: Program, engine: ScanHost, cache: CodeCache | None = None) -> Backend:
    """One scan of `program` on `engine`: returns None at the end, "halt" or "watchdog". With a
    `cache`, the code object is taken from it when it holds this program's, else stored there."""
    inline, steps = fon_code(engine)
    key = program_key(program, inline) if cache is not None else b""
    code = cache.load(key) if cache is not None else None
    if code is None:
        code = compile_code(program, inline)
        if cache is not None:
            cache.store(key, code)
    return backend_of(code, program, engine, steps)


def backend_of(code: CodeType, program: Program, engine: ScanHost, steps: dict[int, Callable]) -> Backend:
    """One scan of `program` on `engine` by its compiled `code`, with the FON `steps` of `fon_code`."""
    instrs = program.instrs
    namespace: dict = {}
    exec(code, namespace)
    data = engine.mem.data
    blocks = namespace["_make"](steps, engine.mem.bits, data, memoryview(data).cast("H"), engine,
                                engine.tim_ticks, engine.ctr_values, TIME_BASES, engine.fon_failed)
    starts = sorted(blocks)
    sizes = {s: (starts[k + 1] if k + 1 < len(starts) else len(instrs)) - s for k, s in enumerate(starts)}
    first = blocks.get(0)

    def run() -> Outcome:
        if first is None:
            return None
        nxt, a, s = first(1, 0)
        steps = sizes[0]
        limit = backend.WATCHDOG_STEPS
        while nxt is not None:
            if nxt == HALT:
                return "halt"
            steps += sizes[nxt]
            if steps > limit:
                return "watchdog"
            nxt, a, s = blocks[nxt](a, s)
        return None

    return run
