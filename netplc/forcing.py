"""Forcing: an engineer pins a bit, a byte or a word of NetPlc memory to a value while commissioning
(docs/architecture.md section 10; DIVAR's FRC mode of seed 004: forcing has the highest priority,
is bumpless, always visible and audited).

Priority is force > program > live: the engine applies the forces after the queued writes (the
exchange's results, operator, HMI and Modbus-server writes) and its own generator bits and RTC
bytes, just before the program, so the program reads the forced value, and again after the
program, so no snapshot ever shows an unforced value (`Forces.apply` at both points, in the
compiled engine and the interpreter alike). A force does not change the compiled program: a coil
the program writes in the middle of its scan is seen as written by the contacts after it within
that scan, and pinned again before anyone outside the engine reads it.

Commands come from any thread (the monitor, the runtime) and are queued to the engine thread like
writes, so the table changes between two scans only. Bumpless: a force without a value pins what
the memory holds when the force is applied. Every force and unforce is an 'operator' record naming
the user. `listing` is an immutable tuple replaced on each change: any thread reads it, and its
length is the "F: n forced" count. With no force the engine's cost is one truth test per hook.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, Protocol

from netplc.address import HMI_DATA_BIT_BASE, IO_BITS, check_operand, fmt_octal, parse_hmi_bit, parse_octal
from netplc.memory import Memory, MemoryView
from netplc.records import Record, RecordSink
from netplc.words import Say, english, phrase

Kind = Literal["bit", "byte", "word"]
KINDS: tuple[Kind, ...] = ("bit", "byte", "word")
_SIZE = {"byte": 1, "word": 2}
_MASK = {"bit": 1, "byte": 0xFF, "word": 0xFFFF}
SOURCE = "force"  # journal text prefix, so the viewer filters forcing with one word


class ForceError(ValueError):
    """A force that names no memory, or a value that does not fit: English as an exception, in
    parts (`name`, `values` of netplc/words.py) for the station's command layer to say it in its
    language."""

    def __init__(self, name: str, /, **values: object) -> None:
        super().__init__(english(name, **values))
        self.name = name
        self.values = values


@dataclass(frozen=True, slots=True)
class Force:
    kind: Kind
    addr: int  # bit: an HMI bit address (I/O bit, or byte*8+bit >= 040000); byte, word: an operand
    value: int
    user: str = ""

    @property
    def key(self) -> tuple[Kind, int]:
        return self.kind, self.addr

    @property
    def where(self) -> str:
        """The address as the documents print it, with its kind for bytes and words."""
        if self.kind == "bit":
            return fmt_octal(self.addr, 6 if self.addr >= HMI_DATA_BIT_BASE else 5)
        return f"{fmt_octal(self.addr)}:{self.kind}"

    @property
    def operands(self) -> range:
        """The I/O bits and data bytes it covers, as quality reads forcing (LinkView.forced)."""
        if self.kind == "bit":
            at = self.addr if self.addr < IO_BITS else self.addr // 8  # HMI bit: byte*8 + bit
            return range(at, at + 1)
        size = 1 if self.kind == "byte" else 2
        # below 04000 a byte or word operand is the 8 or 16 bits starting at its address
        return range(self.addr, self.addr + (8 * size if self.addr < IO_BITS else size))

    def read(self, mem: MemoryView) -> int:
        if self.kind == "bit":
            return mem.get_hmi_bit(self.addr)
        return mem.get_byte(self.addr) if self.kind == "byte" else mem.get_word(self.addr)

    def apply(self, mem: Memory) -> None:
        if self.kind == "bit":
            if self.addr < IO_BITS:
                mem.bits[self.addr] = self.value
            else:
                mem.set_hmi_bit(self.addr, self.value)
        elif self.kind == "byte":
            mem.set_byte(self.addr, self.value)
        else:
            mem.set_word(self.addr, self.value)


def given(addr: object) -> str:
    """An address as a caller handed it: octal as the documents print it if it is one, else as it
    came (a protocol's or a form's text, a float...), so a refusal names what was asked for."""
    if isinstance(addr, int) and not isinstance(addr, bool) and addr >= 0:
        return fmt_octal(addr)
    return repr(addr)


def check_target(kind: object, addr: object) -> None:
    """ForceError unless `kind` at `addr` names memory a force can pin. Anything is checked, not
    only what the types promise: a protocol or a form that hands octal text, a float or None gets a
    ForceError naming the kind and the address as given, like a bad integer address does."""
    if kind not in KINDS:
        raise ForceError("force kind", kind=kind, kinds=", ".join(KINDS))
    if not isinstance(addr, int) or isinstance(addr, bool) or addr < 0:
        raise ForceError("cannot force", kind=kind, addr=given(addr), error=phrase("addr not int"))
    try:
        if kind == "bit":
            parse_hmi_bit(addr)
        else:
            check_operand(addr, _SIZE[kind])
    except ValueError as e:
        raise ForceError("cannot force", kind=kind, addr=given(addr), error=e) from None


def check_value(kind: Kind, value: int) -> int:
    if not 0 <= value <= _MASK[kind]:
        raise ForceError("does not fit", value=value, kind=kind, most=_MASK[kind])
    return value


class ForceHost(Protocol):
    """What the forces need of the engine: its queue, its sink, its words and its wall clock."""

    sink: RecordSink
    words: Say

    def post(self, fn: Callable[[Memory], None]) -> None: ...

    def wall_time(self) -> float: ...


class Forces:
    """The force table of one engine."""

    def __init__(self, host: ForceHost) -> None:
        self.host = host
        self.listing: tuple[Force, ...] = ()  # what is forced now; replaced, never changed in place

    @property
    def count(self) -> int:
        return len(self.listing)

    def forced(self, kind: Kind, addr: int) -> Force | None:
        return next((f for f in self.listing if f.kind == kind and f.addr == addr), None)

    def apply(self, mem: Memory) -> None:
        """Pin every forced value (the engine calls this before and after the program)."""
        for force in self.listing:
            force.apply(mem)

    # --- commands: from any thread, applied by the engine thread between two scans -------------

    def force(self, kind: Kind, addr: int, value: int | None = None, *, user: str) -> None:
        """Force `kind` at `addr` to `value`, or bumpless to what it holds when applied.
        ForceError at once for an address or a value that cannot be forced."""
        self.host.post(self.forcing(kind, addr, value, user=user))

    def unforce(self, kind: Kind, addr: int, *, user: str) -> None:
        self.host.post(self.unforcing(kind, addr, user=user))

    def unforce_all(self, *, user: str) -> None:
        self.host.post(self.unforcing_all(user=user))

    # Each command as the closure the engine thread applies between two scans (the command layer
    # queues these through the engine's bounded queue; the methods above post them directly).

    def forcing(self, kind: Kind, addr: int, value: int | None = None, *,
                user: str) -> Callable[[Memory], None]:
        check_target(kind, addr)
        if value is not None:
            check_value(kind, value)

        def apply(mem: Memory) -> None:
            current = Force(kind, addr, 0).read(mem)
            old = self.forced(kind, addr)
            new = Force(kind, addr, current if value is None else value, user)
            self.listing = (*(f for f in self.listing if f.key != new.key), new)
            new.apply(mem)
            say = self.host.words
            was = say("forced value", value=old.value) if old else str(current)
            how = say("bumpless") if value is None else ""
            self.journal(user, new, say("force", where=new.where, was=was, value=new.value, how=how))

        return apply

    def unforcing(self, kind: Kind, addr: int, *, user: str) -> Callable[[Memory], None]:
        """Release one force: the memory keeps the value and live writers take over again.
        ForceError at once for a target no force could have pinned."""
        check_target(kind, addr)

        def apply(_mem: Memory) -> None:
            old = self.forced(kind, addr)
            if old is not None:
                self.listing = tuple(f for f in self.listing if f.key != old.key)
                self.journal(user, old, self.host.words("unforce", where=old.where, value=old.value))

        return apply

    def unforcing_all(self, *, user: str) -> Callable[[Memory], None]:
        """"Unforce all" as one command: every force released in the same scan, each journaled."""

        def apply(_mem: Memory) -> None:
            released, self.listing = self.listing, ()
            for old in released:
                self.journal(user, old, self.host.words("unforce all", where=old.where, value=old.value))

        return apply

    def restore(self, forces: Iterable[Force], *, user: str) -> None:
        """Install retained forces (RetainForces = true), each journaled as forced again."""
        for f in forces:
            self.force(f.kind, f.addr, f.value, user=user)

    def journal(self, user: str, force: Force, text: str) -> None:
        self.host.sink.put(Record(self.host.wall_time(), "operator", source=user, number=force.addr,
                                  value=float(force.value), text=text))


# --- retained forces (RetainForces = true) --------------------------------------------------------


def save_forces(path: Path, forces: Iterable[Force]) -> None:
    """Write the forces beside the retentive memory (write then rename: never half a file)."""
    rows = [{"kind": f.kind, "addr": fmt_octal(f.addr), "value": f.value, "user": f.user} for f in forces]
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
    tmp.replace(path)


def load_forces(path: Path) -> tuple[list[Force], list[str]]:
    """The forces saved in `path` and the problems of the entries that cannot be used, each
    naming the file and the entry; no file is no forces."""
    try:
        rows = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return [], []
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        return [], [f"{path}: cannot read the retained forces: {e}"]
    if not isinstance(rows, list):
        return [], [f"{path}: not a list of forces"]
    forces: list[Force] = []
    problems: list[str] = []
    for i, row in enumerate(rows):
        try:
            kind, addr, value = row["kind"], parse_octal(str(row["addr"])), row["value"]
            check_target(kind, addr)
            if not isinstance(value, int):
                raise ValueError(f"value {value!r} is not an integer")
            forces.append(Force(kind, addr, check_value(kind, value), str(row.get("user", ""))))
        except KeyError as e:
            problems.append(f"{path}: force [{i}]: missing {e}")
        except (TypeError, ValueError) as e:
            problems.append(f"{path}: force [{i}]: {e}")
    return forces, problems
