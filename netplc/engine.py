"""The NetPlc engine: one scan every NetSyncTime tick (docs/architecture.md sections 1 and 4).

Only the engine thread mutates memory. Everything else (network results, operator writes, Modbus
server writes) is queued with `post`/`write_*` and applied at the start of the next scan, and
readers use the immutable snapshot published after each scan.

Writes from outside (HMI operators, Modbus clients) are the one input nobody inside the station
bounds, so they have a queue of their own with a per-scan budget (DESIGN 1): a scan applies at most
`write_budget` of them, so the scan period holds whatever clients send, and a full queue refuses
the next write (`write_*` returns False; the Modbus server answers exception 6, server busy). A
writer that must answer someone passes `done`: it is called with True once the write is applied
and durable as the sink's `after_commit` says (the station's: its journal record committed and the
memory of its scan in the retentive save, registrar/retain.py), False if it could not be applied.

The program is compiled once into generated Python (netplc/compiler.py); netplc/interpreter.py is
the plain reference kept beside it.
"""

from __future__ import annotations

import functools
import logging
import threading
import time
import traceback
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path

from netplc.address import (
    ALWAYS_ONE,
    EMERGENCY_STOP,
    FERR1,
    IO_BITS,
    TIMEBASE_HI,
    TIMEBASE_LO,
    BitRef,
    fmt_octal,
)
from netplc.backend import Backend
from netplc.codecache import CodeCache
from netplc.compile_behind import compile_program_behind
from netplc.compiler import compile_program
from netplc.forcing import Forces
from netplc.functions._util import Step, bind, fail
from netplc.functions.registry import Fon, FunctionSpec, NetLink, lookup
from netplc.interpreter import Interpreter
from netplc.memory import Memory, Snapshot
from netplc.program import Program
from netplc.records import NullSink, Record, RecordSink
from netplc.rtc import Rtc
from netplc.timers import held, make_ctr, make_tim, update_generators
from netplc.words import Say, english

WRITE_BUDGET = 256  # outside writes applied per scan: a few ms at most, whatever clients send
WRITE_QUEUE = 4096  # outside writes waiting; the next one is refused (Modbus exception 6)
JOURNAL_ROOM = 1000  # records the sink must have room for beyond a scan's writes to apply them

Done = Callable[[bool], None]
Listener = Callable[[Snapshot], None]
BUSY = "busy"  # the queue of outside writes is full (Modbus exception 6, OPC UA BadTooManyOperations)
JOURNAL_FULL = "journal full"  # the archive has no room for the record (Modbus exception 6)

logger = logging.getLogger(__name__)


class RunState(StrEnum):
    RUNNING = "running"
    HALTED = "halted"  # by HLT
    STOPPED = "stopped"  # by the emergency-stop bit 03770 (code 11), the operator, or the watchdog


@dataclass
class ScanStats:
    count: int = 0
    last_ms: float = 0.0
    max_ms: float = 0.0
    mean_ms: float = 0.0
    overruns: int = 0  # scans that took longer than the tick

    def add(self, ms: float, tick_ms: float) -> None:
        self.count += 1
        self.last_ms = ms
        self.max_ms = max(self.max_ms, ms)
        self.mean_ms += (ms - self.mean_ms) / self.count
        if ms > tick_ms:
            self.overruns += 1


class FakeClock:
    """A clock that moves only when told to: for tests and `python -m netplc run`."""

    def __init__(self, start: float = 0.0) -> None:
        self.t = start

    def __call__(self) -> float:
        return self.t

    def advance(self, seconds: float) -> None:
        self.t += seconds


class Engine:
    def __init__(
        self,
        program: Program,
        *,
        clock: Callable[[], float] = time.monotonic,
        wallclock: Callable[[], float] = time.time,
        sink: RecordSink | None = None,
        exchange: NetLink | None = None,
        tick: float = 0.1,
        memory: Memory | None = None,
        compiled: bool = True,
        code_cache: str | Path | None = None,
        write_budget: int = WRITE_BUDGET,
        write_queue: int = WRITE_QUEUE,
    ) -> None:
        self.mem = memory or Memory()
        self.clock = clock
        self.wallclock = wallclock
        self.sink: RecordSink = sink or NullSink()
        self.words: Say = english  # the station's words for its records (netplc/words.py)
        self.exchange = exchange
        self.tick = tick
        self.compiled = compiled
        self.code_cache = CodeCache(code_cache) if code_cache is not None else None  # compiled code
        self.node = 0
        self.scan_counter = 0
        self.now = clock()
        self.dt = 0.0
        self._start = self.now
        self.state = RunState.RUNNING
        self.stop_code = 0
        self.stats = ScanStats()
        # TIM and CTR current values, indexed by coil address C (netplc/timers.py). The compiled
        # program holds these very lists: change them in place, as restore_values does.
        self.tim_ticks: list[float] = [0.0] * IO_BITS
        self.ctr_values: list[int] = [0] * IO_BITS
        self.rtc = Rtc()
        # engine listeners (`subscribe`): replaced whole on change, so the scan iterates a tuple
        # any thread may swap while it runs; faults by listener name, for the health strip
        self._listeners: tuple[tuple[str, Listener], ...] = ()
        self.listener_faults: dict[str, str] = {}
        self._queue: deque[Callable[[Memory], None]] = deque()
        # outside writes: (apply, done, user), at most write_queue waiting, write_budget per scan
        self._writes: deque[tuple[Callable[[Memory], None], Done | None, str]] = deque()
        self.write_budget = write_budget
        self.write_queue = write_queue
        self.writes_refused = 0  # outside writes refused because the queue was full
        self.writes_applied = 0  # outside writes applied (refused addresses included)
        self._stop_by = ""  # who set the emergency-stop bit 03770 from outside, for the record
        self._faulted: set[int] = set()
        self.mem.bits[TIMEBASE_LO] = 1  # 0.1 s time base after start, as on a CPU-165
        self.mem.bits[TIMEBASE_HI] = 0
        self.forces = Forces(self)  # netplc/forcing.py: applied by the scan's two force hooks
        self._stepping = False  # `step`: this scan runs the program although NetPlc is stopped
        # the standby of a hot-standby pair: its memory, timers, forces and run state are the
        # primary's, put by the pair link (app/station/pair.py); it never runs the program
        self.follower = False
        self.snapshot: Snapshot = self._publish()
        # the backend is swapped under this lock: a compiled program that a child process made
        # (netplc/compile_behind.py) replaces the interpreter between two scans; compiled_ready is
        # set once the scans run compiled code
        self._swap = threading.Lock()
        self.compiled_ready = threading.Event()
        self.scanned = threading.Event()  # set by the first scan that ran the program or could have
        self.load(program)

    # --- program -------------------------------------------------------------------------------

    def load(self, program: Program) -> None:
        """Install a program (memory, timer and counter values are kept)."""
        self.program = program
        self._faulted.clear()
        self.fons: dict[int, tuple[Fon, FunctionSpec | None]] = {}
        self._calls: dict[int, Callable[[int], None]] = {}
        bits = self.mem.bits
        for index, ins in enumerate(program.instrs):
            if ins.op == "TIM":
                self._calls[index] = make_tim(bits, self.tim_ticks, ins.c or 0, ins.n or 0, self)
            elif ins.op == "CTR":
                self._calls[index] = make_ctr(bits, self.ctr_values, ins.c or 0, ins.n or 0)
            elif ins.op == "FON":
                fon = Fon(ins.c or 0, ins.n or 0, ins.s, ins.d, ins.r, index, ins.line)
                self.fons[index] = (fon, lookup(fon.f))
                self._calls[index] = self._make_fon(index)
        with self._swap:
            run: Backend | None = None
            if self.compiled and self.code_cache is None:
                run = compile_program(program, self)
            elif self.compiled:  # None while a child process compiles it: the interpreter until then
                run = compile_program_behind(program, self, self.code_cache,
                                             functools.partial(self._take_compiled, program), self.scanned)
            self._run = run or Interpreter(program, self).run
            if run is None:
                self.compiled_ready.clear()
            else:
                self.compiled_ready.set()

    def _take_compiled(self, program: Program, run: Backend) -> None:
        """The compiled program a child process made (netplc/compile_behind.py): it runs from the
        next scan on, unless another program was loaded meanwhile."""
        with self._swap:
            if self.program is program:
                self._run = run
                self.compiled_ready.set()

    # --- what the program calls ----------------------------------------------------------------

    def wall_time(self) -> float:
        return self.wallclock()

    def instruction_call(self, index: int) -> Callable[[int], None]:
        """The closure that runs the TIM, CTR or FON at `index` with its chain result RES.

        The reference interpreter calls these; the compiled program writes TIM and CTR out and
        calls `fon_step` (or the function's inline source) itself, with the same effects.
        """
        return self._calls[index]

    def fon_step(self, index: int) -> Step:
        """The function of the FON at `index`, bound to its operands once, for the compiled program
        to call while RES is 1 (after setting bit C), reporting an exception to `fon_failed`."""
        fon, spec = self.fons[index]
        if spec is None or spec.hardware:
            return fail
        try:
            return bind(spec.run, self.mem, fon)
        except Exception as e:  # no log: a builder bug fails when the function runs, logged by fon_failed
            error = e

            def broken(ctx: object) -> None:
                raise error

            return broken

    def fon_failed(self, index: int, e: Exception) -> None:
        """FErr1, and the first fault of each FON logged with its traceback and journaled: a FON
        that raises does so every scan while its chain is on."""
        fon, spec = self.fons[index]
        self.mem.bits[FERR1] = 1
        name = spec.mnemonic if spec else fon.f
        if index not in self._faulted:
            logger.error("FON %s at line %d failed (FErr1 set)", name, fon.line, exc_info=e)
        self._fault_once(index, self.words("FON failed", name=name, line=fon.line,
                                           error=f"{type(e).__name__}: {e}"))

    def _make_fon(self, index: int) -> Callable[[int], None]:
        """Bit C = RES; while RES is 1 the function runs every scan (level semantics).

        A function this build lacks, or a CPU-165 module function, only sets FErr1. A function
        that raises sets FErr1 too and is reported once as a system record: a bug in one function
        must not stop the plant, and the operator must still learn of it.
        """
        fon, spec = self.fons[index]
        bits = self.mem.bits
        c = fon.c
        if spec is None or spec.hardware:

            def unavailable(res: int) -> None:
                bits[c] = 1 if res else 0
                if res:
                    bits[FERR1] = 1

            return unavailable
        run = spec.run

        def call(res: int) -> None:
            bits[c] = 1 if res else 0
            if res:
                try:
                    run(self, fon)
                except Exception as e:  # no log: fon_failed logs it
                    self.fon_failed(index, e)

        return call

    def _fault_once(self, index: int, text: str) -> None:
        if index not in self._faulted:
            self._faulted.add(index)
            self.sink.put(Record(self.wall_time(), "system", source="netplc", text=text))

    def held_values(self) -> tuple[dict[int, float], dict[int, int]]:
        """The timers' and counters' non-zero current values by coil address (for retentive saves)."""
        return held(self.tim_ticks, self.ctr_values)

    def restore_values(self, tim: dict[int, float], ctr: dict[int, int]) -> None:
        """Set every timer and counter current value: those given, the others 0; IndexError for a
        coil address outside the I/O bits."""
        for c in (*tim, *ctr):
            if not 0 <= c < IO_BITS:
                raise IndexError(f"timer or counter address {c} is not an I/O bit")
        self.tim_ticks[:] = [0.0] * IO_BITS
        self.ctr_values[:] = [0] * IO_BITS
        for c, v in tim.items():
            self.tim_ticks[c] = v
        for c, v in ctr.items():
            self.ctr_values[c] = v

    # --- queued writes -------------------------------------------------------------------------

    def post(self, fn: Callable[[Memory], None]) -> None:
        """Run `fn(memory)` at the start of the next scan (thread-safe). For the station's own
        producers (exchange results, retentive capture, sync generators): outside writers go
        through `write_*`, which are bounded."""
        self._queue.append(fn)

    def refusal(self) -> str | None:
        """Why an outside write or command would be refused now (BUSY, JOURNAL_FULL), or None.
        A full journal refuses at once rather than leaving the writer without an answer: a Modbus
        client that gets none retries, and a retried write may have been applied."""
        if len(self._writes) >= self.write_queue:
            return BUSY
        room = getattr(self.sink, "room", None)
        if room is not None and room() <= JOURNAL_ROOM + len(self._writes):
            return JOURNAL_FULL
        return None

    def command(self, apply: Callable[[Memory], None], user: str, done: Done | None = None) -> bool:
        """Queue an outside action (a write, a force, an acknowledgement, run or stop) to be applied
        at the start of the next scan within the per-scan budget; `apply` journals it. `done(True)`
        once applied and its record is durable, `done(False)` if it could not be. False at once
        (nothing queued) when `refusal()` says why not."""
        if self.refusal() is not None:
            self.writes_refused += 1
            return False
        self._writes.append((apply, done, user))
        return True

    # Each outside write is an `apply` closure that changes memory and journals the change as an
    # 'operator' record naming `user` (the command layer's wording: app/authority/layer.py); the
    # write_* methods queue one with `command`.

    def bit_writer(self, addr: int | BitRef, value: int, user: str,
                   label: str | None = None) -> Callable[[Memory], None]:
        """An HMI bit address, journaled naming `label` (the HMI element or tag), so the log reads
        "write Пуск (040042)" rather than a bare address."""
        hmi = addr.hmi if isinstance(addr, BitRef) else addr

        def apply(mem: Memory) -> None:
            old = mem.get_hmi_bit(hmi)
            mem.set_hmi_bit(hmi, value)
            where = fmt_octal(hmi, 6 if hmi >= 0o40000 else 5)
            self._journal(user, where, old, 1 if value else 0, hmi, label)

        return apply

    def bits_writer(self, addr: int, values: list[int], user: str) -> Callable[[Memory], None]:
        """Consecutive I/O bits from `addr`: one journal record for the block."""
        new = "".join("1" if v else "0" for v in values)

        def apply(mem: Memory) -> None:
            bits = mem.bits
            if addr < 0 or addr + len(values) > IO_BITS:
                raise ValueError(self.words("not io bits", addr=fmt_octal(addr), n=len(values)))
            old = "".join("1" if b else "0" for b in bits[addr : addr + len(values)])
            bits[addr : addr + len(values)] = [1 if v else 0 for v in values]
            self._journal(user, self.words("bits", addr=fmt_octal(addr), n=len(values)), old, new, addr)

        return apply

    def word_writer(self, addr: int, value: int, user: str, label: str | None = None,
                    describe: Callable[[int, int], str] | None = None) -> Callable[[Memory], None]:
        """A word. `describe(old, new)` says the change in the plant's terms ("0.0 -> 130.0 °C", a
        tag's); the record keeps the raw words and the address too."""
        def apply(mem: Memory) -> None:
            old = mem.get_word(addr)
            mem.set_word(addr, value)
            new = value & 0xFFFF
            if describe is None:
                self._journal(user, fmt_octal(addr), old, new, addr, label)
            else:
                self.sink.put(Record(self.wall_time(), "operator", source=user, number=addr, value=float(new),
                                     text=self.words("write change", where=label or fmt_octal(addr),
                                                     change=describe(old, new), old=old, new=new,
                                                     addr=fmt_octal(addr))))

        return apply

    def bytes_writer(self, addr: int, payload: bytes, user: str,
                     label: str | None = None) -> Callable[[Memory], None]:
        def apply(mem: Memory) -> None:
            old = mem.read(addr, len(payload))
            mem.write(addr, payload)
            where = f"{fmt_octal(addr)}:{len(payload)}"
            self._journal(user, where, old.hex(" "), payload.hex(" "), addr, label)

        return apply

    def write_bit(
        self, addr: int | BitRef, value: int, *, user: str = "operator", label: str | None = None,
        done: Done | None = None,
    ) -> bool:
        """Queue a write of an HMI bit address; False: refused (`refusal()` says why)."""
        return self.command(self.bit_writer(addr, value, user, label), user, done)

    def write_bits(self, addr: int, values: list[int], *, user: str = "operator",
                   done: Done | None = None) -> bool:
        return self.command(self.bits_writer(addr, values, user), user, done)

    def write_word(self, addr: int, value: int, *, user: str = "operator", label: str | None = None,
                   describe: Callable[[int, int], str] | None = None, done: Done | None = None) -> bool:
        return self.command(self.word_writer(addr, value, user, label, describe), user, done)

    def write_bytes(self, addr: int, payload: bytes, *, user: str = "operator",
                    done: Done | None = None) -> bool:
        return self.command(self.bytes_writer(addr, payload, user), user, done)

    @property
    def writes_waiting(self) -> int:
        return len(self._writes)

    def _journal(self, user: str, where: str, old: object, new: object, addr: int,
                 label: str | None = None) -> None:
        value = float(new) if isinstance(new, int) else None
        if label:
            where = f"{label} ({where})"
        self.sink.put(
            Record(self.wall_time(), "operator", source=user, number=addr, value=value,
                   text=self.words("write", where=where, old=old, new=new))
        )

    # --- run control ---------------------------------------------------------------------------

    def start(self) -> None:
        """Leave HALTED/STOPPED: clears the emergency-stop bit, as an operator's restart does."""
        self.mem.bits[EMERGENCY_STOP] = 0
        self.state = RunState.RUNNING
        self.stop_code = 0

    def stop(self, code: int = 0) -> None:
        self.state = RunState.STOPPED
        self.stop_code = code

    @property
    def state_text(self) -> str:
        if self.state is RunState.STOPPED and self.stop_code:
            return f"stopped, code {self.stop_code}"
        return self.state.value

    # --- the scan ------------------------------------------------------------------------------

    def scan(self) -> Snapshot:
        t0 = time.perf_counter()
        now = self.clock()
        self.dt = max(0.0, now - self.now)
        self.now = now
        mem = self.mem
        queue = self._queue
        while queue:
            self._apply(queue.popleft(), mem)
        if self._writes:
            if self.follower:
                self._refuse_writes()
            else:
                self._apply_writes(mem)
        bits = mem.bits
        bits[ALWAYS_ONE] = 1
        update_generators(bits, now - self._start)
        self.rtc.update(mem, self.wall_time())
        forces = self.forces
        if forces.listing:  # force hook 1: over the queued writes, generators and RTC: what the program reads
            forces.apply(mem)
        if self.follower:  # what the pair link applied is published as it is: no program, no requests
            self.snapshot = self._publish()
            self._notify()
            return self.snapshot
        if bits[EMERGENCY_STOP] and self.state is RunState.RUNNING:
            self.stop(11)
            if self._stop_by:
                self.sink.put(Record(self.wall_time(), "system", source=self._stop_by, number=EMERGENCY_STOP,
                                     text=self.words("emergency stop by", user=self._stop_by)))
        self._stop_by = ""
        if self.state is RunState.RUNNING or self._stepping:
            outcome = self._run()
            if outcome == "halt":
                self.state = RunState.HALTED
            elif outcome == "watchdog":
                self.stop(0)
                self.sink.put(Record(self.wall_time(), "system", source="netplc",
                                     text=self.words("watchdog")))
            if bits[EMERGENCY_STOP]:
                self.stop(11)
            self.rtc.watch(mem)
        if forces.listing:  # force hook 2: over what the program wrote, before the snapshot
            forces.apply(mem)
        if self.scan_counter == 0:
            self.scanned.set()
        self.scan_counter += 1
        self.snapshot = self._publish()
        self.stats.add((time.perf_counter() - t0) * 1000.0, self.tick * 1000.0)
        self._notify()
        return self.snapshot

    def _notify(self) -> None:
        for name, listener in self._listeners:
            try:
                listener(self.snapshot)
            except Exception as e:  # no log: _listener_failed logs it; the others and the scan go on
                self._listener_failed(name, e)

    # --- listeners -----------------------------------------------------------------------------

    def subscribe(self, listener: Listener, name: str | None = None) -> Callable[[], None]:
        """Call `listener(snapshot)` on the engine thread after every scan, in the order subscribed.
        A listener that raises is logged with its traceback, journaled once per fault and named in
        `listener_faults` (the health strip); the other listeners and the scan go on. Returns the
        call that unsubscribes it. Thread-safe."""
        label = name or getattr(listener, "__qualname__", None) or repr(listener)
        self._listeners = (*self._listeners, (label, listener))
        return lambda: self.unsubscribe(listener)

    def unsubscribe(self, listener: Listener) -> None:
        self._listeners = tuple(e for e in self._listeners if e[1] != listener)

    @property
    def listeners(self) -> tuple[Listener, ...]:
        """The subscribed listeners, in order (read-only: subscribe and unsubscribe change them)."""
        return tuple(listener for _, listener in self._listeners)

    def _listener_failed(self, name: str, e: Exception) -> None:
        """Logged with its traceback and journaled once per fault: a listener that raises at every
        scan must not fill the log and the journal."""
        where = traceback.extract_tb(e.__traceback__)[-1:]
        at = f" at {where[0].filename}:{where[0].lineno}" if where else ""
        text = f"{type(e).__name__}: {e}{at}"
        if self.listener_faults.get(name) != text:
            logger.error("engine listener %s failed at scan %d", name, self.scan_counter, exc_info=e)
            self.listener_faults[name] = text
            self.sink.put(Record(self.wall_time(), "system", source="netplc",
                                 text=self.words("listener failed", name=name, error=text)))

    def step(self) -> Snapshot:
        """Step one scan: with NetPlc stopped or halted, run exactly one scan with the program, one
        tick after the previous scan (an injected clock that can `advance`, a FakeClock, is advanced
        by the tick; another clock is read as the previous scan's time plus the tick). The state
        stays as it was unless the scan itself halts or stops NetPlc. Call it on the engine thread
        or between two scans (ScanThread.lock)."""
        if self.state is RunState.RUNNING:
            raise RuntimeError("NetPlc is running: stop it to step one scan")
        clock = self.clock
        advance = getattr(clock, "advance", None)
        if callable(advance):
            advance(self.tick)
        else:
            target = self.now + self.tick
            self.clock = lambda: target
        self._stepping = True
        try:
            return self.scan()
        finally:
            self._stepping = False
            self.clock = clock

    def _apply(self, fn: Callable[[Memory], None], mem: Memory) -> bool:
        try:
            fn(mem)
        except ValueError as e:  # a queued write to an address that does not exist
            self.sink.put(Record(self.wall_time(), "system", source="netplc",
                                 text=self.words("write refused", error=e)))
            return False
        except Exception as e:  # a faulty producer must not cost the scan or the writes after it
            logger.exception("queued write failed")
            text = self.words("write failed", error=f"{type(e).__name__}: {e}")
            self.sink.put(Record(self.wall_time(), "system", source="netplc", text=text))
            return False
        finally:
            self.rtc.watch(mem)
        return True

    def _refuse_writes(self) -> None:
        """A follower applies no outside write (its memory is the primary's): the writes queued
        before it began to follow are answered as not applied, never left waiting."""
        while self._writes:
            _apply, done, _user = self._writes.popleft()
            self.writes_refused += 1
            if done is not None:
                done(False)

    def _apply_writes(self, mem: Memory) -> None:
        """This scan's share of the outside writes: at most the budget, and none the journal has no
        room for (a write is never applied without its record). Their writers are told once the
        sink says the writes are durable, all at once: one commit and one retentive save for the
        whole scan's writes (the save is taken at the end of this scan, after the program ran)."""
        writes, bits = self._writes, mem.bits
        n = min(len(writes), self.write_budget)
        room = getattr(self.sink, "room", None)
        finished: list[tuple[Done, bool]] = []
        if room is not None and (left := max(0, room() - JOURNAL_ROOM)) < n:
            # the journal filled after these were queued: refuse what it cannot take, never hold
            # a writer without an answer (it would retry a write that may then be applied twice)
            for _ in range(n - left):
                _apply, done, _user = writes.pop()
                self.writes_refused += 1
                if done is not None:
                    done(False)
            n = left
        for _ in range(n):
            apply, done, user = writes.popleft()
            stopped = bits[EMERGENCY_STOP]
            ok = self._apply(apply, mem)
            if not stopped and bits[EMERGENCY_STOP]:
                self._stop_by = user
            if done is not None:
                finished.append((done, ok))
        self.writes_applied += n
        if not finished:
            return

        def tell() -> None:
            for done, ok in finished:
                done(ok)

        after_commit = getattr(self.sink, "after_commit", None)
        if after_commit is None:
            tell()
        else:
            after_commit(tell)

    def _publish(self) -> Snapshot:
        return self.mem.snapshot(self.scan_counter, self.now, self.wall_time(), self.state_text,
                                 self.forces.listing)
