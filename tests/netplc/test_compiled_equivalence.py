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

import itertools
import tempfile
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
JUMPS = st.sampled_from(["JMY", "JMN", "JMP"])
# a scan's input bits drawn as one word: one draw, not 16 (the draws were half the test's time)
SCAN_INPUTS = st.integers(0, 2 ** len(INPUTS) - 1).map(lambda w: [w >> k & 1 for k in range(len(INPUTS))])
LENGTH, SHAPE, SHALLOW_SHAPE = st.integers(0, 8), st.integers(0, 10), st.integers(0, 6)
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


# An instruction is two draws: its kind, then one of the kind's instructions, each operation with
# each of its operands in one list (the same instructions as often as an operation and an operand
# drawn apart, in one draw fewer). The kinds' weights: 6 contacts, 3 coils, 1 each of the others.
CONTACT = st.sampled_from([f"{op} $0{a:o}" for op in ("TNA", "TFA", "TNO", "TFO", "TNE", "TFE")
                           for a in READ])
COIL = st.sampled_from([f"{op} $0{a:o}" for op in ("YON", "SON", "SOF") for a in WRITE])
TIM = st.sampled_from([f"TIM $0{t:o} N:{n}" for t in TIMERS for n in range(5)])
CTR = st.sampled_from([f"CTR $0{c:o} N:{n}" for c in COUNTERS for n in range(4)])
FON = st.composite(_fon)()
JMP0 = st.sampled_from(["JMP 0"] + ["NOP"] * 5)  # keep scans long enough
HLT = st.sampled_from(["HLT"] + ["NOP"] * 7)
KINDS = st.sampled_from([CONTACT] * 6 + [COIL] * 3 + [TIM, CTR, FON, st.just("NOP"), JMP0, HLT])


def instruction(draw) -> str:
    return draw(draw(KINDS))


class _Labels:
    def __init__(self) -> None:
        self.count = itertools.count()

    def new(self) -> str:
        return f"L{next(self.count)}"


def body(draw, labels: _Labels, depth: int) -> list[str]:
    lines: list[str] = []
    for _ in range(draw(LENGTH)):
        shape = draw(SHAPE if depth < 3 else SHALLOW_SHAPE)
        if shape <= 4:
            lines.append(instruction(draw))
        elif shape <= 6:  # SKP before an instruction, or before what follows (jump, label, end)
            lines.append("SKP")
            if shape == 5:
                lines.append(instruction(draw))
        elif shape <= 8:  # a forward jump over a nested body (the label may land mid-chain)
            label = labels.new()
            op = draw(JUMPS)
            lines.append(f"{op} {label}")
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
    too: a tuple is 100 times quicker to take), the run state and the scan count."""
    return (bytes(engine.mem.bits), bytes(engine.mem.data), tuple(engine.tim_ticks),
            tuple(engine.ctr_values), engine.state_text, engine.scan_counter)


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
    st.lists(SCAN_INPUTS, min_size=4, max_size=6),
    st.lists(st.sampled_from([0.01, 0.05, 0.1, 0.35, 1.0]), min_size=6, max_size=6),
    st.binary(min_size=len(INITIAL), max_size=len(INITIAL)),
)
def test_random_programs_leave_identical_state(text, inputs, dts, data):
    run_both(text, inputs, dts, data)


FORCEABLE = st.one_of(
    st.tuples(st.just("bit"), st.sampled_from([*INPUTS, *COILS, *TIMERS, *COUNTERS, 0o3773]),
              st.integers(0, 1)),
    st.tuples(st.just("word"), st.sampled_from([*DATA, 0o4001, 0o2000]), st.integers(0, 65535)),
    st.tuples(st.just("byte"), st.sampled_from([*DATA, 0o2010]), st.integers(0, 255)),
)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    programs(),
    st.lists(SCAN_INPUTS, min_size=4, max_size=5),
    st.lists(st.sampled_from([0.05, 0.1, 0.35]), min_size=5, max_size=5),
    st.binary(min_size=len(INITIAL), max_size=len(INITIAL)),
    st.lists(FORCEABLE, min_size=1, max_size=4).map(tuple),
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
