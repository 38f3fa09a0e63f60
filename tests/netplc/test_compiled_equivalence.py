"""The compiled engine must leave memory, timer and counter values and the run state exactly as
the reference interpreter does (docs/architecture.md section 5), for random valid programs over several scans.

Programs are generated as nested structures so that every jump terminates: forward jumps to a
label after a nested body, and backward loops guarded by a loop bit the body never writes (each
loop runs its body twice per entry). SKP may precede any instruction, a jump, or a label.

FON draws every function the compiler puts in line (and some it calls), with operands that are
data words at even and odd addresses, I/O bits (the coils the program reads), or a word that runs
off its bank (FErr1), on random initial data; the compiled side is run both with its usual chunk
size and with tiny chunks, so that chunk boundaries fall everywhere.
"""

from __future__ import annotations

import bisect
import itertools
import math
import tempfile
from fractions import Fraction
from unittest import mock

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from netplc import compiler
from netplc.engine import Engine, FakeClock
from netplc.functions.registry import lookup
from netplc.program import parse

INPUTS = list(range(0o20))  # set by the test each scan
COILS = list(range(0o2000, 0o2020))  # written and read by the program
SPECIAL = [0o3750, 0o3751, 0o3760, 0o3771, 0o3773, 0o3774]  # generators, always 1, FErr1, time base
READ = INPUTS + COILS + SPECIAL
WRITE = [*COILS, 0o3771, 0o3773, 0o3774]
TIMERS = [0o3000 + 2 * k for k in range(4)]  # C, C+1
COUNTERS = [0o3100 + 3 * k for k in range(4)]  # C, C+1 (reset), C+2
LOOP_BITS = [0o3200 + k for k in range(32)]  # written only by loop control
SCRATCH = 0o3277  # ends the loop body's chain; never read
DATA = [0o4000 + 2 * k for k in range(8)]
INITIAL = range(0o4000, 0o4022)  # data bytes given random values before the first scan
OPERANDS = [*DATA, 0o4001, 0o4003, 0o4011, 0o2000, 0o2010, 0o7777]  # odd, I/O bits, off the bank

# functions with plain memory semantics (no exchange, no records, no module state): those the
# compiler puts in line, and a few it calls
CANDIDATES = ("MOV", "MVIBCD", "MVID", "MVIO", "MOVB", "ADD", "SUB", "INCW", "DECW", "NSETDI", "NMOVW",
              "NMOVB", "AND", "OR", "XOR", "NEG", "NGREAT", "NLESS", "NEQUAL", "NGREATI", "NLESSI", "CMP",
              "XCG", "WMASK", "MUL")
FUNCTIONS = [s for name in CANDIDATES if (s := lookup(name)) is not None and not s.hardware]
UNREGISTERED = next((n for n in (9, 3, 4, 12) if lookup(n) is None), None)
CONSTANTS = {"D": st.integers(0, 65535).map(str), "O": st.integers(0, 0o177777).map(lambda v: f"{v:o}"),
             "B": st.integers(0, 9999).map(str)}

# the strategies drawn from, made once: hypothesis validates each new one (more time than the draws)
COUNTS = {kind: st.one_of(st.integers(0, 5).map(str), constant) for kind, constant in CONSTANTS.items()}
SPECS, OPERAND = st.sampled_from(FUNCTIONS), st.sampled_from(OPERANDS)


def scan_inputs(fewest: int, most: int) -> st.SearchStrategy[list[list[int]]]:
    """`fewest` to `most` scans' input bits, a 16-bit word a scan, drawn as one string of bytes (an
    odd last byte left over): one draw, not 16 a scan (the draws were half the test's time)."""
    def bits(data: bytes) -> list[list[int]]:
        words = [int.from_bytes(data[at:at + 2], "little") for at in range(0, len(data) - 1, 2)]
        return [[w >> k & 1 for k in range(len(INPUTS))] for w in words]
    return st.binary(min_size=2 * fewest, max_size=2 * most).map(bits)


def scan_times(values: list[float], scans: int) -> st.SearchStrategy[list[float]]:
    """`scans` times each one of `values`, drawn as one integer, the times its digits in base
    len(values)."""
    n = len(values)
    return st.integers(0, n ** scans - 1).map(lambda i: [values[i // n ** k % n] for k in range(scans)])


LENGTH_MAX = 8
LENGTH = st.integers(0, LENGTH_MAX)
FON_NUMBER, FON_SPEC = st.integers(0, 7), st.integers(0, 4)


def _fon(draw) -> str:
    c = 0o3300 + 4 * draw(FON_NUMBER)
    if not FUNCTIONS or draw(FON_SPEC) == 0:
        if UNREGISTERED is None:
            return f"TIM $0{c:o} N:1"
        return f"FON C:$0{c:o} N:{UNREGISTERED}"  # a defined number no module implements: FErr1
    spec = draw(SPECS)
    params = []
    for key, kind in spec.kinds().items():
        if kind == "M":
            params.append(f"{key}:$0{draw(OPERAND):o}")
        elif kind is not None:  # a count (NMOVB/NMOVW R) is mostly small, sometimes off the bank
            params.append(f"{key}:{draw(COUNTS[kind])}")
    return f"FON C:$0{c:o} N:{spec.mnemonic} " + " ".join(params)


# A body's steps are one draw: three bytes a step, read as a number below 2**24 that picks the step
# (its shape and, for an instruction, the instruction with its operands) at its weight in one table
# of every step (a FON's operands are drawn after). Hypothesis draws bytes uniformly, and not
# integers past 256 (it favours the small), so not one integer. The weights: of 11 shapes, 5 an
# instruction, 1 SKP before an instruction, 1 SKP before what follows, 2 a forward jump (JMY, JMN or
# JMP), 2 a loop; below depth 3, the first three shapes alone. An instruction's kind: 6 contacts, 3
# coils, 1 each of the others; each kind's instructions alike. Drawn as three a step (shape, kind,
# instruction), as they once were, the same programs cost three times the generation.
CONTACT_LINES = [f"{op} $0{a:o}" for op in ("TNA", "TFA", "TNO", "TFO", "TNE", "TFE") for a in READ]
COIL_LINES = [f"{op} $0{a:o}" for op in ("YON", "SON", "SOF") for a in WRITE]
TIM_LINES = [f"TIM $0{t:o} N:{n}" for t in TIMERS for n in range(5)]
CTR_LINES = [f"CTR $0{c:o} N:{n}" for c in COUNTERS for n in range(4)]
JMP0_LINES = ["JMP 0"] + ["NOP"] * 5  # keep scans long enough
HLT_LINES = ["HLT"] + ["NOP"] * 7
FON = "FON"  # an instruction whose operands are drawn next (`_fon`)
KINDS = ((6, CONTACT_LINES), (3, COIL_LINES), (1, TIM_LINES), (1, CTR_LINES), (1, ["NOP"]), (1, JMP0_LINES),
         (1, HLT_LINES), (1, [FON]))
INSTRUCTIONS = [(Fraction(weight, 15 * len(kind)), line) for weight, kind in KINDS for line in kind]


class Steps:
    """The steps a body draws from, each (SKP before it?, an instruction, "jump" with its opcode, or
    "loop"), and the draw of `n` of them at their weights."""

    def __init__(self, nested: bool) -> None:
        shape = Fraction(1, 11 if nested else 7)
        steps = [(5 * shape * p, (False, line)) for p, line in INSTRUCTIONS]
        steps += [(shape * p, (True, line)) for p, line in INSTRUCTIONS]
        steps.append((shape, (True, None)))
        if nested:
            steps += [(2 * shape / 3, (False, ("jump", op))) for op in ("JMY", "JMN", "JMP")]
            steps.append((2 * shape, (False, ("loop",))))
        assert sum(p for p, _ in steps) == 1
        self.scale = math.lcm(*(p.denominator for p, _ in steps))
        assert min(p for p, _ in steps) * 2**24 >= 100  # each step's share of the numbers off by under 1 %
        self.steps = [step for _, step in steps]
        self.ends = list(itertools.accumulate(int(p * self.scale) for p, _ in steps))
        self.bytes = [st.binary(min_size=3 * n, max_size=3 * n) for n in range(LENGTH_MAX + 1)]

    def picks(self, draw, n: int) -> list[tuple]:
        data = draw(self.bytes[n])
        return [self.steps[bisect.bisect_right(self.ends, int.from_bytes(data[at:at + 3]) * self.scale >> 24)]
                for at in range(0, len(data), 3)]


NESTED, SHALLOW = Steps(nested=True), Steps(nested=False)


def instruction(draw, line: str) -> str:
    return _fon(draw) if line is FON else line


class _Labels:
    def __init__(self) -> None:
        self.count = itertools.count()

    def new(self) -> str:
        return f"L{next(self.count)}"


def body(draw, labels: _Labels, depth: int) -> list[str]:
    lines: list[str] = []
    for skp, step in (NESTED if depth < 3 else SHALLOW).picks(draw, draw(LENGTH)):
        if skp:  # SKP before an instruction, or before what follows (jump, label, end)
            lines.append("SKP")
        if isinstance(step, str):
            lines.append(instruction(draw, step))
        elif step is None:
            pass
        elif step[0] == "jump":  # a forward jump over a nested body (the label may land mid-chain)
            label = labels.new()
            lines.append(f"{step[1]} {label}")
            lines += body(draw, labels, depth + 1)
            lines.append(f"{label}:")
        else:  # a backward loop: the body runs twice, then the loop bit is cleared
            top, out = labels.new(), labels.new()
            bit = f"$0{LOOP_BITS[int(top[1:]) % len(LOOP_BITS)]:o}"
            lines.append(f"{top}:")
            lines += body(draw, labels, depth + 1)
            lines += [f"YON $0{SCRATCH:o}", f"TNA {bit}", f"JMY {out}", f"SON {bit}", f"JMP {top}",
                      f"{out}: TNA $03760", f"SOF {bit}"]  # YON: the body's open chain must not reach TNA
    return lines


@st.composite
def programs(draw) -> str:
    return "\n".join(body(draw, _Labels(), 0)) + "\n"


def state(engine: Engine) -> tuple:
    """Memory, every timer's and counter's current value (what `held_values` keeps of them, zeroes
    too), the run state and the scan count: the engine's own arrays and lists, not copies, compared
    before the next scan changes them (copies of them were a tenth of the test's time)."""
    return (engine.mem.bits, engine.mem.data, engine.tim_ticks, engine.ctr_values, engine.state_text,
            engine.scan_counter)


def run_both(text: str, inputs: list[list[int]], dts: list[float], data: bytes = b"",
             forces: tuple[tuple[str, int, int], ...] = ()) -> None:
    """Scan `text` in the reference interpreter and in the compiled engine (usual and tiny chunks,
    and the usual code once more as a second start takes it from the compiled-program cache the
    first start filled); `forces` (kind, address, value) are in effect from the second scan to the
    one before the last."""
    program = parse(text, source="random.stl")
    engines = []
    with tempfile.TemporaryDirectory() as cache:
        usual = compiler._CHUNK_CONSTS
        kinds = ((False, 0, None), (True, usual, cache), (True, 3, None), (True, usual, cache))
        for compiled, chunk, cached in kinds:
            clock = FakeClock()
            with mock.patch.object(compiler, "_CHUNK_CONSTS", chunk):
                engines.append((Engine(program, clock=clock, wallclock=lambda: 0.0, compiled=compiled,
                                       code_cache=cached), clock))
    for engine, _ in engines:
        if data:
            engine.mem.write(INITIAL[0], data)
    for n, (scan_inputs, dt) in enumerate(zip(inputs, dts)):
        for eng, clock in engines:
            if forces and n == 1:
                for kind, addr, value in forces:
                    eng.forces.force(kind, addr, value, user="test")  # type: ignore[arg-type]
            elif forces and n == len(inputs) - 1:
                eng.forces.unforce_all(user="test")
            for addr, v in zip(INPUTS, scan_inputs):
                eng.mem.bits[addr] = v
            clock.advance(dt)
            eng.scan()
        reference = state(engines[0][0])
        for eng, _ in engines[1:]:
            assert state(eng) == reference, text


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    programs(),
    scan_inputs(4, 6),
    scan_times([0.01, 0.05, 0.1, 0.35, 1.0], 6),
    st.binary(min_size=len(INITIAL), max_size=len(INITIAL)),
)
def test_random_programs_leave_identical_state(text, inputs, dts, data):
    run_both(text, inputs, dts, data)


# each kind's addresses, and the number of its values
FORCEABLE = {"bit": ([*INPUTS, *COILS, *TIMERS, *COUNTERS, 0o3773], 2),
             "word": ([*DATA, 0o4001, 0o2000], 65536),
             "byte": ([*DATA, 0o2010], 256)}


def force(drawn: tuple[bytes, int]) -> tuple[str, int, int]:
    """A force (kind, address, value): two bytes pick the kind (a third each) and an address of its
    kind, an integer (hypothesis favours 0, 65535 and the like) its value of that kind (bit, word or
    byte). Three draws, not five (a one_of of tuples of just, sampled_from and integers)."""
    (kind_byte, address_byte), value = drawn
    kind = ("bit", "word", "byte")[kind_byte * 3 // 256]
    addresses, values = FORCEABLE[kind]
    return kind, addresses[address_byte * len(addresses) // 256], value % values


FORCES = st.lists(st.tuples(st.binary(min_size=2, max_size=2), st.integers(0, 65535)).map(force),
                  min_size=1, max_size=4).map(tuple)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    programs(),
    scan_inputs(4, 5),
    scan_times([0.05, 0.1, 0.35], 5),
    st.binary(min_size=len(INITIAL), max_size=len(INITIAL)),
    FORCES,
)
def test_forced_random_programs_leave_identical_state(text, inputs, dts, data, forces):
    """Forces on inputs, coils, timer and counter bits, the time base and data words: the
    compiled engine and the interpreter agree, forced and after "unforce all"."""
    run_both(text, inputs, dts, data, forces)


def test_long_chains_are_split_before_the_parser_chokes():
    # hundreds of alternating AND/OR groups and parallel branches in one chain
    ops = itertools.cycle(["TNA", "TNO", "TFA", "TFO", "TNE", "TNA", "TFE"])
    text = "\n".join(f"{next(ops)} $0{READ[k % len(READ)]:o}" for k in range(3000)) + "\nYON $02000\n"
    inputs = [[(k * 7 + s) % 3 == 0 for k in range(len(INPUTS))] for s in range(4)]
    run_both(text, [[int(v) for v in row] for row in inputs], [0.1] * 4)


def test_skp_corner_cases_match():
    text = "\n".join([
        "TNA $0", "SKP", "SKP", "YON $02000",  # a skipped SKP
        "TNA $1", "SKP", "TNE $2", "YON $02001",  # a skipped contact leaves a live chain
        "TNA $3", "JMY a", "TNA $4", "SKP", "a: YON $02002",  # SKP before a label
        "TNA $5", "SKP", "JMP b", "YON $02003", "b: TNA $6", "SKP",  # SKP before a jump; SKP last
    ]) + "\n"
    # one set of engines scans each combination of the inputs in turn, twice, compared after every
    # scan: the outputs are YONs of the inputs, so a scan starts from what the last one left in both
    # engines alike (an output a jump leaves unwritten keeps its value: a fresh start's 0, or another)
    combos = [list(bits) + [0] * (len(INPUTS) - 7) for bits in itertools.product((0, 1), repeat=7)]
    run_both(text, [c for c in combos for _ in range(2)], [0.1] * 2 * len(combos))
