"""Shared machinery of the FON functions: build-once operand accessors, BCD, error flags.

A function runs inside the scan on every scan its rung is true, so the work that depends only on
the instruction's S/D/R (validating operands, locating them in the data array) is done once per
instruction and memory: each function is written as a *builder* that returns the closure the scan
calls. An operand that cannot be read or written (a word on the last byte of a bank, a block running
past its bank) makes the builder raise AddressError; the function then only sets FErr1, every scan
it runs, and writes nothing - the same as a bad indirect address at run time.
"""

from __future__ import annotations

import sys
from collections.abc import Callable

from netplc.address import (
    FERR1,
    IO_BITS,
    AddressError,
    check_operand,
    data_index,
    fmt_octal,
    is_valid_operand,
)
from netplc.functions.registry import Fon, FonContext, Run
from netplc.memory import Memory

Step = Callable[[FonContext], None]
Builder = Callable[[Memory, Fon], Step]

def fail(ctx: FonContext) -> None:
    """Raise FErr1 (sticky: only the program clears it)."""
    ctx.mem.bits[FERR1] = 1


_BUILDERS: dict[Run, Builder] = {}  # run function -> the builder it was made from, for `bind`


def built(build: Builder) -> Run:
    """Turn a builder into a FON run function that builds once per instruction and memory.

    The reference interpreter calls that function; the compiled engine binds the step itself, once
    at load time (`bind`), so a scan skips this layer.
    """

    def run(ctx: FonContext, fon: Fon) -> None:
        mem = ctx.mem
        cached = fon.state.get("_step")
        if cached is None or cached[0] is not mem:
            cached = fon.state["_step"] = (mem, _build(build, mem, fon))
        cached[1](ctx)

    run.__doc__ = build.__doc__
    run.__name__ = build.__name__
    _BUILDERS[run] = build
    return run


def bind(run: Run, mem: Memory, fon: Fon) -> Step:
    """The step that runs `fon` on `mem`: the built step itself, or a call of a plain run function."""
    build = _BUILDERS.get(run)
    if build is not None:
        return _build(build, mem, fon)
    return lambda ctx: run(ctx, fon)


def _build(build: Builder, mem: Memory, fon: Fon) -> Step:
    try:
        return build(mem, fon)
    except AddressError:
        return fail


# --- operand accessors: closures bound to one memory and one operand address -------------------


def word_get(mem: Memory, addr: int | None) -> Callable[[], int]:
    """Reader of the 16-bit word at operand `addr` (data bytes, or 16 I/O bits below 04000)."""
    a = _operand(addr, 2)
    if a >= IO_BITS:
        d = mem.data
        i = data_index(a)
        j = i + 1
        return lambda: d[i] | d[j] << 8
    b = mem.bits
    return lambda: sum(b[a + k] << k for k in range(16))


def word_set(mem: Memory, addr: int | None) -> Callable[[int], None]:
    a = _operand(addr, 2)
    if a >= IO_BITS:
        d = mem.data
        i = data_index(a)
        j = i + 1

        def set_data(v: int) -> None:
            d[i] = v & 0xFF
            d[j] = (v >> 8) & 0xFF

        return set_data
    b = mem.bits

    def set_bits(v: int) -> None:
        for k in range(16):
            b[a + k] = (v >> k) & 1

    return set_bits


def byte_get(mem: Memory, addr: int | None) -> Callable[[], int]:
    a = _operand(addr, 1)
    if a >= IO_BITS:
        d = mem.data
        i = data_index(a)
        return lambda: d[i]
    b = mem.bits
    return lambda: sum(b[a + k] << k for k in range(8))


def byte_set(mem: Memory, addr: int | None) -> Callable[[int], None]:
    a = _operand(addr, 1)
    if a >= IO_BITS:
        d = mem.data
        i = data_index(a)

        def set_data(v: int) -> None:
            d[i] = v & 0xFF

        return set_data
    b = mem.bits

    def set_bits(v: int) -> None:
        for k in range(8):
            b[a + k] = (v >> k) & 1

    return set_bits


def block_get(mem: Memory, addr: int | None, n: int) -> Callable[[], bytes]:
    """Reader of `n` bytes at operand `addr` (n > 0)."""
    a = _operand(addr, n)
    if a >= IO_BITS:
        d = mem.data
        i = data_index(a)
        j = i + n
        return lambda: d[i:j]
    return lambda: mem.read(a, n)


def block_set(mem: Memory, addr: int | None, n: int) -> Callable[[bytes | bytearray], None]:
    a = _operand(addr, n)
    if a >= IO_BITS:
        d = mem.data
        i = data_index(a)
        j = i + n

        def set_data(v: bytes | bytearray) -> None:
            d[i:j] = v

        return set_data
    return lambda v: mem.write(a, v)


def bit_get(mem: Memory, addr: int) -> Callable[[], int]:
    """Reader of bit k of an operand: an I/O bit (addr < 04000) or bit addr&7 of data byte addr>>3.

    Used with `addr = operand + k` for I/O operands and `operand * 8 + k` for data operands; see
    `operand_bit`.
    """
    if addr < IO_BITS:
        b = mem.bits
        return lambda: b[addr]
    d = mem.data
    i = data_index(addr >> 3)
    mask = 1 << (addr & 7)
    return lambda: 1 if d[i] & mask else 0


def operand_bit(base: int, k: int) -> int:
    """Bit k of the bit string at operand `base`, as a `bit_get` address (bit k = bit k%8 of byte k//8)."""
    if base < IO_BITS:
        if base + k >= IO_BITS:
            raise AddressError("addr bit past", k=k, addr=fmt_octal(base))
        return base + k
    check_operand(base + k // 8, 1)
    return (base + k // 8) * 8 + k % 8


def at(addr: int | None, k: int) -> int:
    """Operand address k bytes after `addr` (8*k bits further in the I/O area)."""
    a = addr or 0
    return a + 8 * k if a < IO_BITS else a + k


def span(first: int | None, last: int | None) -> int:
    """Bytes from operand `first` to operand `last` inclusive (0 or less when last < first).

    In the I/O area a byte is 8 bits, so bits 00100..00170 are 8 bytes; an area that mixes the
    I/O bits and data memory, or ends inside a byte of bits, is invalid (AddressError).
    """
    a, b = first or 0, last or 0
    if a < IO_BITS and b < IO_BITS:
        if (b - a) % 8:
            raise AddressError("addr not bytes", first=fmt_octal(a), last=fmt_octal(b))
        return (b - a) // 8 + 1
    if (a < IO_BITS) != (b < IO_BITS):
        raise AddressError("addr mixes", first=fmt_octal(a), last=fmt_octal(b))
    return b - a + 1


def valid_block(addr: int, n: int) -> bool:
    """Whether `n` bytes at `addr` are all addressable (n = 0 is an empty, valid block)."""
    if n == 0:
        return addr >= 0
    try:
        check_operand(addr, n)
    except AddressError:
        return False
    return True


def _operand(addr: int | None, n: int) -> int:
    if addr is None:
        raise AddressError("addr missing")
    check_operand(addr, n)
    return addr


# --- inline source (FunctionSpec.inline): data operands only, resolved when the program compiles --


def data_at(addr: int | None, n: int) -> int | None:
    """Index in the data array of the `n`-byte operand `addr`; None for I/O-bit or invalid operands
    (the function is then called, and does what it does with them)."""
    if addr is None or addr < IO_BITS or not is_valid_operand(addr, n):
        return None
    return data_index(addr)


def sdr_data_at(fon: Fon, n: int, flags: int) -> tuple[int, int, int, list[int]] | None:
    """Data indexes of the `n`-byte operands S, D and R and the `flags` output bits of a
    three-operand function (ADD, SUB, AND, OR, XOR), or None when any of them cannot be inlined."""
    i, j, k, bits = data_at(fon.s, n), data_at(fon.d, n), data_at(fon.r, n), flag_bits(fon, flags)
    if i is None or j is None or k is None or bits is None:
        return None
    return i, j, k, bits


# The compiled program also sees the data array as native 16-bit words `w` (w[k] = bytes 2k, 2k+1):
# one subscript instead of two for a word at an even index, on a little-endian machine.
_WORDS = sys.byteorder == "little"


def word_src(i: int) -> str:
    """Expression reading the (little-endian) data word at index `i`."""
    return f"w[{i >> 1}]" if _WORDS and i % 2 == 0 else f"(d[{i}] | d[{i + 1}] << 8)"


def word_store(i: int, v: str) -> list[str]:
    """Lines storing `v` (0..65535) as the data word at index `i`, as `word_set` does."""
    if _WORDS and i % 2 == 0:
        return [f"w[{i >> 1}] = {v}"]
    return [f"d[{i}] = {v} & 255", f"d[{i + 1}] = {v} >> 8"]


def copy_inline(s: int | None, d: int | None, n: int) -> list[str] | None:
    """Lines copying n data bytes from operand s to d (n > 0): byte by byte, or as one slice (read
    whole before writing, as `block_get`/`block_set` do) when the areas overlap or are long."""
    i, k = data_at(s, n), data_at(d, n)
    if i is None or k is None:
        return None
    if n == 2 and i != k:  # the word is read whole before it is stored, so an overlap is fine
        store = word_store(k, word_src(i))
        return store if len(store) == 1 else [f"_v = {word_src(i)}", *word_store(k, "_v")]
    if abs(i - k) < n or n > 4:
        return [f"d[{k}:{k + n}] = d[{i}:{i + n}]"]
    return [f"d[{k + j}] = d[{i + j}]" for j in range(n)]


def constant_inline(d: int | None, value: int) -> list[str] | None:
    """Lines storing the constant word `value` at operand d."""
    k = data_at(d, 2)
    return None if k is None else word_store(k, str(value & 0xFFFF))


FAIL_LINE = f"b[{FERR1}] = 1"  # what `fail` does, as a line


def flag_bits(fon: Fon, count: int) -> list[int] | None:
    """The output bits C+1..C+count, or None when one is past the I/O bits."""
    bits = [fon.c + k for k in range(1, count + 1)]
    return bits if bits[-1] < IO_BITS else None


# --- BCD -----------------------------------------------------------------------------------------


# value 0-99 of a BCD byte, or -1 if a nibble is above 9: BCDW and ADDBCD run in the scan
_BCD_BYTE = [(b >> 4) * 10 + (b & 0xF) if b >> 4 < 10 and b & 0xF < 10 else -1 for b in range(256)]


def bcd_to_bin(w: int) -> int | None:
    """Value of a 4-digit BCD word, or None if a nibble is above 9."""
    hi, lo = _BCD_BYTE[w >> 8], _BCD_BYTE[w & 0xFF]
    if hi < 0 or lo < 0:
        return None
    return hi * 100 + lo


def bin_to_bcd(v: int) -> int:
    """4-digit BCD word of 0 <= v <= 9999."""
    return (v // 1000) << 12 | (v // 100 % 10) << 8 | (v // 10 % 10) << 4 | v % 10
