"""What the Program view shows, computed from a snapshot only (no Qt here, so it is tested plainly).

The listing is the program's source, line for line, with each instruction's operands. A line's
live state is worked out when the line is drawn, from the last snapshot: the contact's or coil's
bit, and the chain result up to that line, evaluated from the chain's first contact with the
snapshot's bits (the end-of-scan image, as every PLC monitor shows it: a coil written later in the
scan shows its final value). Only the lines on screen are ever evaluated, so a 2,000-line listing
costs what its 40 visible lines cost.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from app.scada.tag import Tag, TagType
from netplc.address import HMI_DATA_BIT_BASE, IO_BITS, fmt_octal, is_data_byte, parse_octal
from netplc.forcing import Force, Kind, check_target, check_value
from netplc.functions.registry import lookup
from netplc.memory import MemoryView
from netplc.program import _LABEL, CONTACTS, Instr, Program

FORMATS = ("hex", "dec", "BCD")
TERMINATORS = frozenset({"YON", "SON", "SOF", "SKP", "JMY", "JMN", "TIM", "CTR", "FON"})


def fmt_value(value: int, fmt: str, digits: int = 4) -> str:
    """A byte or word as the engineer chose: hex, decimal or BCD ("----" when not BCD digits)."""
    if fmt == "hex":
        return f"{value:0{digits}X}h"
    if fmt == "BCD":
        text = f"{value:0{digits}X}"
        return text if text.isdigit() else "-" * digits
    return str(value)


@dataclass(frozen=True, slots=True)
class Operand:
    """One memory operand of an instruction: what to show and what "uses" follows."""

    role: str  # C, S, D, R
    kind: Kind
    addr: int

    def read(self, view: MemoryView) -> int:
        return Force(self.kind, self.addr, 0).read(view)


@dataclass(frozen=True, slots=True)
class Row:
    line: int  # 1-based source line
    text: str  # the source line as written (comments included)
    instr: int | None  # index into Program.instrs, None for a comment, a label or a blank line
    label: str | None = None


def operands(ins: Instr) -> list[Operand]:
    """The memory an instruction reads or writes: its coil bits, and the FON's address operands."""
    if ins.c is None:
        return []
    out = [Operand("C", "bit", ins.c)]
    if ins.op == "FON":
        spec = lookup(ins.n or 0)
        if spec is not None:
            for role, kind in spec.kinds().items():
                addr = getattr(ins, role.lower())
                if kind == "M" and addr is not None and (addr < IO_BITS - 15 or is_data_byte(addr + 1)):
                    out.append(Operand(role, "word", addr))
    return out


class Listing:
    def __init__(self, program: Program) -> None:
        self.program = program
        self.rows = _rows(program)
        self.labels = {r.label: i for i, r in enumerate(self.rows) if r.label}
        self.row_of = {r.instr: i for i, r in enumerate(self.rows) if r.instr is not None}
        instrs = program.instrs
        # chain_start[i]: the first instruction of the chain instruction i belongs to
        self.chain_start: list[int] = []
        start = 0
        for i, ins in enumerate(instrs):
            self.chain_start.append(start)
            if ins.op not in CONTACTS and ins.op != "NOP":
                start = i + 1
        self.operands = [operands(ins) for ins in instrs]
        # jump targets start a fresh chain too (the interpreter resets ACC and SUM on a jump)
        self._targets = {ins.target for ins in instrs if ins.target is not None}

    def __len__(self) -> int:
        return len(self.rows)

    def find(self, text: str, after: int = -1) -> int | None:
        """The next row (wrapping) whose text contains `text`, case-insensitively."""
        needle = text.casefold()
        n = len(self.rows)
        for k in range(1, n + 1):
            i = (after + k) % n
            if needle in self.rows[i].text.casefold():
                return i
        return None

    def uses(self, addr: int) -> list[int]:
        """Rows whose instruction has `addr` among its operands (a bit, or a word covering it)."""
        out = []
        for index, ops in enumerate(self.operands):
            if any(_covers(op, addr) for op in ops):
                out.append(self.row_of[index])
        return out

    def chain(self, view: MemoryView, index: int) -> int:
        """The chain's value (SUM | ACC) after instruction `index`, from the snapshot's bits."""
        instrs = self.program.instrs
        bits = view.bits
        acc, sm = 1, 0
        start = self.chain_start[index]
        for i in range(start, index + 1):
            if i in self._targets and i != start:
                acc, sm = 1, 0
            ins = instrs[i]
            op = ins.op
            if op not in CONTACTS:
                continue
            bit = 1 if bits[ins.c] else 0
            if op in ("TFA", "TFO", "TFE"):
                bit ^= 1
            if op in ("TNA", "TFA"):
                acc &= bit
            elif op in ("TNO", "TFO"):
                acc |= bit
            else:
                sm |= acc
                acc = bit
        return sm | acc


def _covers(op: Operand, addr: int) -> bool:
    if op.kind == "bit":
        return op.addr == addr
    return op.addr <= addr < op.addr + (16 if op.addr < IO_BITS else 2)


def _rows(program: Program) -> list[Row]:
    """Source lines with their instructions; without a readable source, one row per instruction."""
    by_line = {ins.line: i for i, ins in enumerate(program.instrs)}
    try:
        lines = Path(program.source).read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError, ValueError):
        lines = []
    if len(lines) < max(by_line, default=0):
        return [Row(ins.line, ins.text, i) for i, ins in enumerate(program.instrs)]
    rows = []
    for n, text in enumerate(lines, start=1):
        m = _LABEL.match(text)
        rows.append(Row(n, text, by_line.get(n), m.group(1) if m else None))
    return rows


# --- the watch table ------------------------------------------------------------------------------

WATCH_KINDS: dict[str, Kind] = {"bit": "bit", "b": "byte", "byte": "byte", "w": "word", "word": "word"}
_SUFFIX = re.compile(r"^(.+?)\s*:\s*(bit|byte|word|b|w)$", re.IGNORECASE)


@dataclass(frozen=True, slots=True)
class WatchItem:
    text: str  # as typed
    kind: Kind
    addr: int
    tag: Tag | None = None  # a tag of tags.csv: shown and forced in physical units

    @property
    def where(self) -> str:
        if self.tag is not None:
            return self.tag.name
        if self.kind == "bit":
            return fmt_octal(self.addr, 6 if self.addr >= HMI_DATA_BIT_BASE else 5)
        return f"{fmt_octal(self.addr)}:{self.kind}"


def parse_watch(text: str, symbols: dict[str, int], tags: dict[str, Tag] | None = None) -> WatchItem:
    """An address, a symbol or a tag as the engineer types it: `02000` and `040042` are bits,
    `04000` a word, `04000:b` a byte, `02000:w` the 16 bits from 02000, a tag name its bit or its
    (first) word in physical units; ValueError says what is wrong."""
    typed = text.strip()
    tag = (tags or {}).get(typed)
    if tag is not None:
        return WatchItem(typed, "bit" if tag.type is TagType.BIT else "word", tag.address, tag)
    m = _SUFFIX.match(typed)
    name, suffix = (m.group(1), WATCH_KINDS[m.group(2).lower()]) if m else (typed, None)
    if not name:
        raise ValueError("type an address (04000, 040042, 02000:w) or a symbol")
    if name in symbols:
        addr = symbols[name]
    else:
        try:
            addr = parse_octal(name)
        except ValueError:
            raise ValueError(f"{name!r} is neither an octal address nor a symbol of symbols.csv "
                             "nor a tag of tags.csv") from None
    kind: Kind = suffix or ("bit" if addr < IO_BITS or addr >= HMI_DATA_BIT_BASE else "word")
    check_target(kind, addr)  # the rule a force is held to
    return WatchItem(typed, kind, addr)


def parse_phy(text: str, tag: Tag) -> float:
    """A physical value typed for a tag (decimal point or comma); ValueError names the tag."""
    try:
        value = float(text.strip().replace(",", "."))
    except ValueError:
        raise ValueError(f"{text!r} is not a value for {tag.name} (a number in {tag.unit or 'its units'})") \
            from None
    if value != value:
        raise ValueError(f"{text!r} is not a value for {tag.name}")
    return value


def parse_value(text: str, kind: Kind) -> int:
    """A value typed for a write or a force: decimal, 0x.. hex or ..h hex; ValueError if it does not fit."""
    t = text.strip().lower()
    try:
        value = int(t[:-1], 16) if t.endswith("h") else int(t, 0)
    except ValueError:
        raise ValueError(f"{text!r} is not a number (decimal, 0x1F or 1Fh)") from None
    return check_value(kind, value)
