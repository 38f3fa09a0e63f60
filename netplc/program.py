"""STL program text -> a validated list of instructions (docs/architecture.md section 5).

An engineer's typo must come back as `file:line:col: message`, all of them at once, never as a
traceback, so the parser collects diagnostics and raises one ProgramError at the end.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path

from netplc.address import (
    IO_BITS,
    OCTAL_TEXT,
    AddressError,
    check_operand,
    fmt_octal,
    is_data_byte,
    parse_hmi_bit,
    parse_octal,
)
from netplc.functions.registry import DEFINED_CODES, FunctionSpec, lookup
from netplc.problems import Problems
from netplc.textfile import MAX_DIGITS, TextFileError, csv_rows, read_text
from netplc.words import Phrase, Say, WordedError, english, phrase, said

PROGRAM_WORDS = 0o20000  # 8 K words of program memory

# mnemonic -> (parameter keys it takes, size in words)
LOGIC = {
    "NOP": ((), 1), "TNA": (("C",), 1), "TFA": (("C",), 1), "TNO": (("C",), 1),
    "TFO": (("C",), 1), "TNE": (("C",), 1), "TFE": (("C",), 1), "SKP": ((), 1),
    "SON": (("C",), 1), "SOF": (("C",), 1), "YON": (("C",), 1), "HLT": ((), 1),
    "FON": (("C", "N", "S", "D", "R"), 5), "TIM": (("C", "N"), 2), "CTR": (("C", "N"), 2),
    "JMY": (("L",), 1), "JMN": (("L",), 1), "JMP": (("L",), 1),
}
CONTACTS = frozenset({"TNA", "TFA", "TNO", "TFO", "TNE", "TFE"})
JUMPS = frozenset({"JMY", "JMN", "JMP"})
ONE_BIT = CONTACTS | {"SON", "SOF", "YON"}  # one I/O bit at C
# bits used by a coil-like instruction at C: C..C+n-1 must be I/O bits
COIL_BITS = {"SON": 1, "SOF": 1, "YON": 1, "TIM": 2, "CTR": 3, "FON": 4}

_NAME = r"[^\W\d][\w.\[\]]*"
_LINE_NO = re.compile(r"\s*\d+\.\d+\s+")
_LABEL = re.compile(rf"\s*({_NAME})\s*:(?![^\s;])")
_SYMDEF = re.compile(rf"\s*({_NAME})\s*=\s*([^\s;#]+)\s*(?:[;#].*)?$")
_MNEMONIC = re.compile(r"\s*([^\W\d]\w*)")
_PARAM = re.compile(r"\s*(?:([A-Za-z])\s*:\s*)?([^\s;:]*)\s*;?")
_OFFSET = re.compile(rf"({_NAME}?)\[([0-9]+)\]")  # TA[2]: the bit two after symbol TA (manual's notation)
_DECIMAL = re.compile(r"-?[0-9]+")  # str.isdigit() also accepts '²', which int() refuses
_OCTAL = re.compile(r"[0-7]+")
_COMMENT = re.compile(r"\s[;#]|;;|\s//")
# A plain line (`_Parser._plain`): an optional line number, an optional label with an instruction
# after it, a mnemonic, parameters `K:token` or `token` (ASCII letters, digits, `$_.[]-`) separated
# by spaces or tabs, and a comment after a space or a tab, if any. Every other line (a symbol, a
# label alone, `;` between parameters, other white space, other characters) is read the general way.
# Groups: label, mnemonic, the first parameter's key and token (most lines have one), the others.
# Possessive (`*+`, `++`): a run is never given back, a third less time than backtracking.
_PLAIN = re.compile(
    r"[ \t]*+(?:[0-9]++\.[0-9]++[ \t]++)?(?:([A-Za-z_]\w*+)[ \t]*+:[ \t]++)?([A-Za-z]++)"
    r"(?:[ \t]++(?:([A-Za-z]):)?([\w$.\[\]-]++)((?:[ \t]++(?:[A-Za-z]:)?[\w$.\[\]-]++)*+))?"
    r"(?:[ \t]++(?:[;#]|//).*|[ \t]*+)",
    re.ASCII,
)
_PLAIN_PARAM = re.compile(r"(?:([A-Za-z]):)?([\w$.\[\]-]+)", re.ASCII)
_Unread = tuple[int, str, dict[str, object]]  # col, phrase, values: what stopped reading a line


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """A problem at a place: `message` a phrase of netplc/words.py (or a file's own problem, as
    it is), said in English by str() and in a station's language by `said(say)`."""

    file: str
    line: int
    col: int
    message: Phrase | str

    def said(self, say: Say = english) -> str:
        return f"{self.file}:{self.line}:{self.col}: {said(say, self.message)}"

    def __str__(self) -> str:
        return self.said()


class ProgramError(Problems):
    """All problems found in a program (or symbols file), each with its position in `errors`."""

    def __init__(self, errors: list[Diagnostic]) -> None:
        self.errors = errors
        super().__init__([str(e) for e in errors])


@dataclass(frozen=True, slots=True, init=False)
class Instr:
    """One instruction of a program, as parsed.

    `__init__` is written out: the one a frozen dataclass generates sets each field through
    `object.__setattr__`, 3.5 us an instruction here, a fifth of a program's parse and most of a
    parse-cache load; the slots' own setters (`_INSTR_SLOTS`) do the same in half the time.
    tests/netplc/test_parse_plain.py holds its parameters to the fields."""

    op: str
    c: int | None = None
    n: int | None = None  # TIM/CTR preset, FON function number
    s: int | None = None
    d: int | None = None
    r: int | None = None
    target: int | None = None  # jump: instruction index, or None for "end of scan" (JMP 0)
    addr: int = 0  # word address in program memory
    line: int = 0
    text: str = ""

    def __init__(self, op: str, c: int | None = None, n: int | None = None, s: int | None = None,
                 d: int | None = None, r: int | None = None, target: int | None = None, addr: int = 0,
                 line: int = 0, text: str = "") -> None:
        set_op, set_c, set_n, set_s, set_d, set_r, set_target, set_addr, set_line, set_text = _INSTR_SLOTS
        set_op(self, op)
        set_c(self, c)
        set_n(self, n)
        set_s(self, s)
        set_d(self, d)
        set_r(self, r)
        set_target(self, target)
        set_addr(self, addr)
        set_line(self, line)
        set_text(self, text)


_INSTR_SLOTS = tuple(getattr(Instr, f.name).__set__ for f in fields(Instr))


@dataclass
class Program:
    instrs: list[Instr]
    symbols: dict[str, int] = field(default_factory=dict)
    source: str = "<program>"
    words: int = 0

    def functions(self) -> list[tuple[Instr, FunctionSpec | None]]:
        return [(i, lookup(i.n or 0)) for i in self.instrs if i.op == "FON"]


def load_symbols(path: str | Path) -> dict[str, int]:
    """Read `symbols.csv` (name,address,comment); ProgramError names the file and line."""
    symbols, errors = read_symbols(path)
    if errors:
        raise ProgramError(errors)
    return symbols


def read_symbols(path: str | Path) -> tuple[dict[str, int], list[Diagnostic]]:
    """The symbols of the good lines of `symbols.csv`, and the problem of each other line (for
    `check`, which goes on to check the program against the good ones)."""
    path = Path(path)
    errors: list[Diagnostic] = []
    symbols: dict[str, int] = {}
    try:
        text = read_text(path, "read symbols")
    except TextFileError as e:
        return {}, [Diagnostic(str(path), e.line, 0, e.phrase)]
    for lineno, row in csv_rows(text):
        if isinstance(row, Phrase):
            errors.append(Diagnostic(str(path), lineno, 1, row))
            continue
        if not row or not row[0].strip() or row[0].lstrip().startswith(("#", ";")):
            continue
        if lineno == 1 and row[0].strip().lower() == "name":
            continue
        name = row[0].strip()
        if len(row) < 2:
            errors.append(Diagnostic(str(path), lineno, 1, phrase("sym no address", name=name)))
            continue
        try:
            addr = _symbol_address(row[1])
        except WordedError as e:
            errors.append(Diagnostic(str(path), lineno, len(row[0]) + 2, e.phrase))
            continue
        if not re.fullmatch(_NAME, name):
            errors.append(Diagnostic(str(path), lineno, 1, phrase("sym bad name", name=name)))
        elif name in symbols:
            errors.append(Diagnostic(str(path), lineno, 1, phrase("sym twice", name=name)))
        else:
            symbols[name] = addr
    return symbols, errors


def _symbol_address(text: str) -> int:
    """A symbol's address: an I/O bit, a data byte, or a data bit the HMI way (byte*8 + bit). A
    symbol no program uses is checked too: an address naming no memory is a typo all the same."""
    if len(text.strip()) > MAX_DIGITS:
        raise WordedError("addr too long", n=len(text.strip()))
    addr = parse_octal(text)
    if not (is_data_byte(addr) or _is_hmi_bit(addr)):
        raise AddressError("addr no memory", addr=fmt_octal(addr))
    return addr


def _is_hmi_bit(addr: int) -> bool:
    try:
        parse_hmi_bit(addr)
    except AddressError:
        return False
    return True


def parse_file(path: str | Path, symbols: dict[str, int] | None = None) -> Program:
    path = Path(path)
    return parse(read_program_text(path), source=str(path), symbols=symbols)


def read_program_text(path: Path) -> str:
    """The program file's text; a file that cannot be read is a ProgramError naming it."""
    try:
        return read_text(path, "read program")
    except TextFileError as e:
        raise ProgramError([Diagnostic(str(path), e.line, 0, e.phrase)]) from None


def load_program(path: str | Path, symbols_path: str | Path | None = None) -> Program:
    """Read the symbols file (if any) and parse the program with it: what every front end does."""
    symbols = load_symbols(symbols_path) if symbols_path else {}
    return parse_file(path, symbols)


@dataclass(slots=True)
class _Raw:
    line: int
    col: int
    op: str
    params: dict[str, tuple[str, int]]  # key -> (token, col)
    text: str
    extra: Sequence[tuple[str, int]] = ()  # FON positional S/D/R, by function


def parse(
    text: str, source: str = "<program>", symbols: dict[str, int] | None = None, *, fast: bool = True
) -> Program:
    """Parse STL text; raise ProgramError listing every problem. `fast=False` reads every line the
    general way, for the test that holds the plain lines' reading to it (the result is the same)."""
    p = _Parser(source, dict(symbols or {}), fast)
    return p.run(text)


class _Parser:
    def __init__(self, source: str, symbols: dict[str, int], fast: bool = True) -> None:
        self.source = source
        self.symbols = symbols
        self.fast = fast
        self.errors: list[Diagnostic] = []

    def err(self, line: int, col: int, name: str, /, **values: object) -> None:
        """A problem of the catalogue (netplc/words.py), said by whoever reports it."""
        self.errors.append(Diagnostic(self.source, line, col, phrase(name, **values)))

    def run(self, text: str) -> Program:
        raws: list[_Raw | tuple[str, int, int, str]] = []  # a tuple: (op, C, line, text), see `_plain`
        labels: dict[str, int] = {}  # label -> instruction index
        plain = self._plain if self.fast else None
        for lineno, line in enumerate(text.splitlines(), start=1):
            stripped = line.strip()
            if not stripped or stripped.startswith((";", "#", "//")):
                continue
            if plain is None or not plain(lineno, line, stripped, raws, labels):
                self._general(lineno, line, stripped, raws, labels)
        instrs: list[Instr] = []
        words = 0
        addr_of: list[int] = []
        for raw in raws:
            addr_of.append(words)
            words += 1 if type(raw) is tuple else LOGIC[raw.op][1]
        by_addr = {a: i for i, a in enumerate(addr_of)}
        build = self._build
        for raw, addr in zip(raws, addr_of):
            if type(raw) is tuple:  # a contact or coil read whole (`_plain`)
                op, c, line, text = raw
                instrs.append(Instr(op, c, None, None, None, None, None, addr, line, text))
                continue
            ins = build(raw, addr, labels, by_addr)
            if ins is not None:
                instrs.append(ins)
        if words > PROGRAM_WORDS:
            last = raws[-1]
            self.err(last[2] if type(last) is tuple else last.line, 1, "stl too big", words=words,
                     most=PROGRAM_WORDS)
        if self.errors:
            self.errors.sort(key=lambda d: (d.line, d.col))
            raise ProgramError(self.errors)
        return Program(instrs, self.symbols, self.source, words)

    def _plain(self, lineno: int, line: str, text: str, raws: list, labels: dict[str, int]) -> bool:
        """Read a plain line (`_PLAIN`) in one match; False, having done nothing, for any other line.

        A station's cold start parses its whole program, and nearly every line of one is plain: one
        match instead of a regex per part and per parameter reads the 8 K-word program of
        bench/scan.py in less than half the time. What it reads goes on as the general reading's
        would (`_label`, `_instruction`), so a construct has one meaning; a mnemonic that is no
        instruction is left to `_general`, which says why."""
        m = _PLAIN.fullmatch(line)
        if m is None:
            return False
        label, mnemonic, key, token, more = m.groups()
        op = mnemonic.upper()
        if op not in LOGIC:
            return False
        if label:
            self._label(lineno, m.start(1) + 1, label, labels, len(raws))
        if token is not None and not more:
            # one parameter, the most common line: given as keyed, or the first key if positional
            # (what `_instruction` makes of it; a key the instruction does not take goes there too)
            keys = LOGIC[op][0]
            name = key.upper() if key else keys[0] if keys else ""
            if name in keys:
                bit = OCTAL_TEXT.fullmatch(token) if op in ONE_BIT else None
                if bit is not None and (c := int(bit.group(1), 8)) < IO_BITS:
                    # a contact or a coil at an I/O bit given in octal, most of a program: what
                    # `_build` would make of it, without a _Raw and the look-ups on the way there
                    raws.append((op, c, lineno, text))
                else:
                    raws.append(_Raw(lineno, m.start(2) + 1, op, {name: (token, m.start(4) + 1)}, text))
                return True
        tokens = [] if token is None else [(key.upper() if key else "", token, m.start(4) + 1)]
        if more:
            tokens += [((p[1] or "").upper(), p[2], p.start(2) + 1)
                       for p in _PLAIN_PARAM.finditer(line, m.start(5), m.end(5))]
        self._instruction(lineno, m.start(2) + 1, op, tokens, None, text, raws)
        return True

    def _general(self, lineno: int, line: str, text: str, raws: list[_Raw], labels: dict[str, int]) -> None:
        """Read any line, part by part: a symbol, a line number, a label, a mnemonic, parameters
        (separated by white space or `;`), a comment; every problem of the line is said here."""
        m = _SYMDEF.match(line)
        if m:
            name, value = m.group(1), m.group(2)
            try:
                addr = parse_octal(value)
            except ValueError:
                self.err(lineno, m.start(2) + 1, "stl symbol not octal", name=name, value=value)
                return
            if name in self.symbols:
                self.err(lineno, m.start(1) + 1, "sym twice", name=name)
            self.symbols[name] = addr
            return
        pos = 0
        m = _LINE_NO.match(line, pos)
        if m:
            pos = m.end()
        m = _LABEL.match(line, pos)
        if m:
            self._label(lineno, m.start(1) + 1, m.group(1), labels, len(raws))
            pos = m.end()
            if not line[pos:].strip() or line[pos:].strip().startswith((";", "#")):
                return  # a label alone on its line names the next instruction
        m = _MNEMONIC.match(line, pos)
        if not m:
            self.err(lineno, pos + 1 + len(line[pos:]) - len(line[pos:].lstrip()), "stl expected")
            return
        op = m.group(1).upper()
        if op not in LOGIC:
            hint: Phrase | str = ""
            after = _MNEMONIC.match(line, m.end())
            if after and after.group(1).upper() in LOGIC:
                hint = phrase("stl label hint", name=m.group(1))
            self.err(lineno, m.start(1) + 1, "stl unknown", op=m.group(1), hint=hint)
            return
        pos = m.end()
        rest = line[pos:]
        # a trailing comment: ';' or '#' after white space, or ';;' ('C:$03000;N:56;' separates)
        cut = _COMMENT.search(rest)
        if cut:
            rest = rest[: cut.start()]
        tokens: list[tuple[str, str, int]] = []
        unread: _Unread | None = None
        i = 0
        while i < len(rest):
            if rest[i] in " \t;":
                i += 1
                continue
            pm = _PARAM.match(rest, i)
            if not pm or pm.end() == i:
                unread = (pos + i + 1, "stl cannot read", {"text": rest[i:].strip()})
                break
            key = (pm.group(1) or "").upper()
            if not pm.group(2):
                unread = (pos + pm.start(1) + 1, "stl no value", {"key": key})
                break
            tokens.append((key, pm.group(2), pos + pm.start(2) + 1))
            i = pm.end()
        self._instruction(lineno, m.start(1) + 1, op, tokens, unread, text, raws)

    def _label(self, lineno: int, col: int, label: str, labels: dict[str, int], index: int) -> None:
        """`label` names instruction `index` (the next one read), unless a line above took it."""
        if label in labels:
            self.err(lineno, col, "stl label twice", label=label)
        else:
            labels[label] = index

    def _instruction(
        self, lineno: int, col: int, op: str, tokens: list[tuple[str, str, int]], unread: _Unread | None,
        text: str, raws: list[_Raw],
    ) -> None:
        """Give each parameter (key, token, col; key "" if positional) its key and keep the
        instruction if all is well. `unread`: the problem that stopped the reading after `tokens`,
        said unless a parameter before it already stopped the line (then it was never reached)."""
        keys = LOGIC[op][0]
        params: dict[str, tuple[str, int]] = {}
        extra: list[tuple[str, int]] = []
        ok = True
        for key, token, tcol in tokens:
            if not key:
                # a positional parameter: the first one the instruction takes that is not given yet
                for key in keys:
                    if key not in params:
                        break
                else:
                    self.err(lineno, tcol, "stl no more", op=op, token=token)
                    return
                if op == "FON" and key in ("S", "D", "R"):
                    extra.append((token, tcol))  # which of S, D, R depends on the function
                    continue
            if key not in keys:
                self.err(lineno, tcol, "stl no such param" if keys else "stl takes none", op=op, key=key)
                ok = False
            elif key in params:
                self.err(lineno, tcol, "stl given twice", key=key)
                ok = False
            else:
                params[key] = (token, tcol)
        if unread is not None:
            ucol, name, values = unread
            self.err(lineno, ucol, name, **values)
        elif ok:
            raws.append(_Raw(lineno, col, op, params, text, extra))

    # --- values ------------------------------------------------------------------------------

    def _resolve(self, raw: _Raw, key: str) -> int | None:
        """An address parameter: `$octal`, bare octal digits, a symbol, or `symbol[k]` (k bits on)."""
        token, col = raw.params[key]
        if token[0] in "$0123456789":
            try:
                return parse_octal(token)
            except ValueError:
                self.err(raw.line, col, "stl not octal address", key=key, token=token)
                return None
        if token in self.symbols:
            return self.symbols[token]
        m = _OFFSET.fullmatch(token)
        if m and m.group(1) in self.symbols:
            if len(m.group(2)) > MAX_DIGITS:
                self.err(raw.line, col, "stl offset long", key=key, name=m.group(1), n=MAX_DIGITS)
                return None
            return self.symbols[m.group(1)] + int(m.group(2))
        self.err(raw.line, col, "stl unknown symbol", key=key, token=token)
        return None

    def _address(self, raw: _Raw, key: str, nbytes: int = 1) -> int | None:
        """A function operand of `nbytes` bytes (below 04000: 8*nbytes I/O bits)."""
        addr = self._resolve(raw, key)
        if addr is None:
            return None
        try:
            check_operand(addr, nbytes)
        except AddressError as e:
            self.err(raw.line, raw.params[key][1], "stl operand", key=key, error=e)
            return None
        return addr

    def _coil(self, raw: _Raw, nbits: int) -> int | None:
        """The C parameter: `nbits` consecutive I/O bits (a contact or a coil uses one)."""
        if "C" not in raw.params:
            self.err(raw.line, raw.col, "stl needs c", op=raw.op)
            return None
        addr = self._resolve(raw, "C")
        if addr is None:
            return None
        col = raw.params["C"][1]
        if addr >= IO_BITS:
            self.err(raw.line, col, "stl not io bit", addr=fmt_octal(addr))
            return None
        if addr + nbits > IO_BITS:
            self.err(raw.line, col, "stl coil past", op=raw.op, first=fmt_octal(addr),
                     last=fmt_octal(addr + nbits - 1))
            return None
        return addr

    def _const(self, raw: _Raw, key: str, kind: str, lo: int = 0, hi: int = 0xFFFF) -> int | None:
        token, col = raw.params[key]
        if token.startswith("$") or token in self.symbols:
            self.err(raw.line, col, "stl const not address", key=key, token=token)
            return None
        if kind == "B":
            if not re.fullmatch(r"[0-9]{1,4}", token):
                self.err(raw.line, col, "stl not bcd", key=key, token=token)
                return None
            return int(token, 16)
        octal = kind == "O"
        pattern, radix, name = (_OCTAL, 8, "stl not octal const") if octal else (
            _DECIMAL, 10, "stl not decimal")
        if not pattern.fullmatch(token):
            self.err(raw.line, col, name, key=key, token=token)
            return None
        if len(token) > MAX_DIGITS or not lo <= int(token, radix) <= hi:
            bounds = f"{lo:o}-{hi:o}" if octal else f"{lo}-{hi}"  # in the radix the constant is written in
            self.err(raw.line, col, "stl outside", key=key, token=token, bounds=bounds)
            return None
        return int(token, radix)

    def _build(
        self, raw: _Raw, addr: int, labels: dict[str, int], by_addr: dict[int, int]
    ) -> Instr | None:
        op = raw.op
        if op in ONE_BIT:
            c = self._coil(raw, 1)
            # positional: the fields in their order (op, c, n, s, d, r, target, addr, line, text)
            return None if c is None else Instr(op, c, None, None, None, None, None, addr, raw.line, raw.text)
        if op in ("NOP", "SKP", "HLT"):
            return Instr(op, addr=addr, line=raw.line, text=raw.text)
        if op in JUMPS:
            if "L" not in raw.params:
                self.err(raw.line, raw.col, "stl needs label", op=op)
                return None
            token, col = raw.params["L"]
            if token[0] in "$0123456789":
                try:
                    value = parse_octal(token)
                except ValueError:
                    self.err(raw.line, col, "stl not program address", token=token)
                    return None
                if value == 0:
                    return Instr(op, target=None, addr=addr, line=raw.line, text=raw.text)
                if value not in by_addr:
                    self.err(raw.line, col, "stl not start", token=token)
                    return None
                return Instr(op, target=by_addr[value], addr=addr, line=raw.line, text=raw.text)
            if token not in labels:
                self.err(raw.line, col, "stl undefined label", token=token)
                return None
            return Instr(op, target=labels[token], addr=addr, line=raw.line, text=raw.text)
        if op in ("TIM", "CTR"):
            c = self._coil(raw, COIL_BITS[op])
            if "N" not in raw.params:
                self.err(raw.line, raw.col, "stl needs preset", op=op)
                return None
            n = self._const(raw, "N", "D", 0, 255)
            if c is None or n is None:
                return None
            return Instr(op, c=c, n=n, addr=addr, line=raw.line, text=raw.text)
        return self._build_fon(raw, addr)

    def _build_fon(self, raw: _Raw, addr: int) -> Instr | None:
        c = self._coil(raw, COIL_BITS["FON"])
        if "N" not in raw.params:
            self.err(raw.line, raw.col, "stl fon needs n")
            return None
        token, col = raw.params["N"]
        spec: FunctionSpec | None = None
        if token[0] in "0123456789":
            if not _DECIMAL.fullmatch(token):
                self.err(raw.line, col, "stl not function number", token=token)
                return None
            number = int(token) if len(token) <= MAX_DIGITS else -1
            if number not in DEFINED_CODES:
                self.err(raw.line, col, "stl no function", number=number if number >= 0 else token)
                return None
            spec = lookup(number)
        else:
            spec = lookup(token)
            if spec is None:
                self.err(raw.line, col, "stl unknown function", token=token)
                return None
            number = spec.number
        # positional operands fill the parameters this function takes, in S, D, R order
        takes = [k for k, kind in spec.kinds().items() if kind] if spec else ["S", "D", "R"]
        free = [k for k in takes if k not in raw.params]
        for key, (token, col) in zip(free, raw.extra):
            raw.params[key] = (token, col)
        if len(raw.extra) > len(free):
            token, col = raw.extra[len(free)]
            self.err(raw.line, col, "stl fon no more", name=spec.mnemonic if spec else number, token=token)
            return None
        values: dict[str, int | None] = {"S": None, "D": None, "R": None}
        ok = c is not None
        if spec is not None:
            for key, kind in spec.kinds().items():
                if kind is None:
                    if key in raw.params:
                        self.err(raw.line, raw.params[key][1], "stl takes no key", name=spec.mnemonic,
                                 key=key)
                        ok = False
                    continue
                if key not in raw.params:
                    self.err(raw.line, raw.col, "stl needs key", name=spec.mnemonic, key=key,
                             kind=phrase(f"stl kind {kind}"))
                    ok = False
                    continue
                v = self._address(raw, key) if kind == "M" else self._const(raw, key, kind, *spec.bounds(key))
                ok = ok and v is not None
                values[key] = v
        else:  # a defined code not implemented on this build: keep the values, FErr1 at run time
            for key in ("S", "D", "R"):
                if key in raw.params:
                    values[key] = self._resolve(raw, key)
                    ok = ok and values[key] is not None
        if not ok:
            return None
        return Instr("FON", c=c, n=number, s=values["S"], d=values["D"], r=values["R"], addr=addr,
                     line=raw.line, text=raw.text)

