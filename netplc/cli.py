"""`python -m netplc run`: try a program from the command line (engineers and tests use it)."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

from netplc.address import IO_BITS, AddressError, check_operand, fmt_octal, parse_octal
from netplc.engine import Engine, FakeClock
from netplc.memory import Memory
from netplc.program import ProgramError, load_program
from netplc.records import ListSink


@dataclass(frozen=True)
class Assignment:
    addr: int
    value: int

    def apply(self, mem: Memory) -> None:
        if self.addr < IO_BITS:
            mem.set_bit(self.addr, self.value)
        else:
            mem.set_word(self.addr, self.value)


def _assignment(text: str) -> Assignment:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"{text!r}: expected ADDR=VALUE")
    a, v = text.split("=", 1)
    try:
        addr = parse_octal(a)
        value = int(v, 0) if v.strip().lower().startswith(("0x", "0o", "0b")) else int(v, 10)
    except ValueError as e:
        raise argparse.ArgumentTypeError(f"{text!r}: {e}") from None
    if addr < IO_BITS:
        if value not in (0, 1):
            raise argparse.ArgumentTypeError(f"{text!r}: bit {fmt_octal(addr)} takes 0 or 1")
        return Assignment(addr, value)
    if not 0 <= value <= 0xFFFF:
        raise argparse.ArgumentTypeError(f"{text!r}: a word takes 0-65535")
    try:
        check_operand(addr, 2)
    except AddressError as e:
        raise argparse.ArgumentTypeError(f"{text!r}: {e}") from None
    return Assignment(addr, value)


def _timed(text: str) -> tuple[int, Assignment]:
    k, sep, rest = text.partition(":")
    if not sep or not k.isascii() or not k.isdigit():
        raise argparse.ArgumentTypeError(f"{text!r}: expected K:ADDR=VALUE")
    return int(k), _assignment(rest)


def _printed(text: str) -> tuple[int, int | None]:
    a, sep, n = text.partition(":")
    try:
        addr = parse_octal(a)
        length = int(n) if sep else None
        if length is not None and length < 1:
            raise ValueError("LEN must be at least 1")
        if length is not None or addr >= IO_BITS:
            check_operand(addr, length or 2)
    except ValueError as e:  # AddressError is a ValueError
        raise argparse.ArgumentTypeError(f"{text!r}: {e}") from None
    return addr, length


def _count(text: str) -> int:
    if not text.isascii() or not text.isdigit():
        raise argparse.ArgumentTypeError(f"{text!r}: expected a number of scans (0 or more)")
    return int(text)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m netplc", description="NetPlc soft PLC tools")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run a program for N scans on a stepped clock and print memory")
    r.add_argument("program", help="STL program file")
    r.add_argument("--symbols", help="symbols.csv (name,address,comment)")
    r.add_argument("--scans", type=_count, default=1, help="number of scans (default 1)")
    r.add_argument("--dt", type=float, default=0.1, help="clock step per scan in seconds (default 0.1)")
    r.add_argument("--set", type=_assignment, action="append", default=[], metavar="ADDR=VALUE",
                   help="set before the first scan; ADDR < 04000 is a bit, otherwise a word")
    r.add_argument("--at", type=_timed, action="append", default=[], metavar="K:ADDR=VALUE",
                   help="set before scan K (0-based)")
    r.add_argument("--print", type=_printed, action="append", default=[], dest="prints",
                   metavar="ADDR[:LEN]", help="print a bit, a word, or LEN bytes after the last scan")
    return p


def run(args: argparse.Namespace) -> int:
    try:
        program = load_program(args.program, args.symbols)
    except ProgramError as e:
        print(e, file=sys.stderr)
        return 2
    clock = FakeClock(0.0)
    sink = ListSink()
    engine = Engine(program, clock=clock, sink=sink, wallclock=lambda: 0.0)
    for a in args.set:
        a.apply(engine.mem)
    for k in range(args.scans):
        for when, a in args.at:
            if when == k:
                a.apply(engine.mem)
        clock.advance(args.dt)
        engine.scan()
    mem = engine.mem
    for addr, n in args.prints:  # validated by _printed
        if n is not None:
            print(f"{fmt_octal(addr)}:{n} = {mem.read(addr, n).hex(' ')}")
        elif addr < IO_BITS:
            print(f"{fmt_octal(addr)} = {mem.get_bit(addr)}")
        else:
            print(f"{fmt_octal(addr)} = 0x{mem.get_word(addr):04X}")
    if engine.state_text != "running":
        print(f"state: {engine.state_text}", file=sys.stderr)
    for rec in sink.records:
        print(f"record: {rec.kind} grp={rec.grp} type={rec.type} source={rec.source} "
              f"number={rec.number} value={rec.value} text={rec.text}", file=sys.stderr)
    return 0


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "run":
        return run(args)
    return 2
