"""Conversions (manual group 3.2): BCDW WBCD ENCOD DECOD SWPB."""

from __future__ import annotations

from netplc.functions._util import (
    Step,
    bcd_to_bin,
    bin_to_bcd,
    built,
    byte_get,
    byte_set,
    fail,
    word_get,
    word_set,
)
from netplc.functions.registry import Fon, FonContext, register
from netplc.memory import Memory


@register(3, "BCDW", "M", "M")
@built
def bcdw(mem: Memory, fon: Fon) -> Step:
    """word[D] = binary value of the BCD word[S].

    The manual lists no error; decided as for ADDBCD: a nibble above 9 raises FErr1 and D is kept.
    """
    get, put = word_get(mem, fon.s), word_set(mem, fon.d)

    def step(ctx: FonContext) -> None:
        v = bcd_to_bin(get())
        if v is None:
            fail(ctx)
        else:
            put(v)

    return step


@register(4, "WBCD", "M", "M")
@built
def wbcd(mem: Memory, fon: Fon) -> Step:
    """word[D] = 4-digit BCD of word[S]; above 9999: FErr1 and no conversion."""
    get, put = word_get(mem, fon.s), word_set(mem, fon.d)

    def step(ctx: FonContext) -> None:
        v = get()
        if v > 9999:
            fail(ctx)
        else:
            put(bin_to_bcd(v))

    return step


@register(50, "ENCOD", "M", "M")
@built
def encod(mem: Memory, fon: Fon) -> Step:
    """word[D] = 1 << (low 4 bits of byte[S]) (the table: 0 -> 0001, F -> 8000)."""
    get, put = byte_get(mem, fon.s), word_set(mem, fon.d)
    return lambda ctx: put(1 << (get() & 0xF))


@register(51, "DECOD", "M", "M")
@built
def decod(mem: Memory, fon: Fon) -> Step:
    """byte[D] = number of the set bit of word[S]; C+1 Z = word[S] is 0.

    The manual does not cover a zero word or several set bits; decided: several bits give the
    highest one, and a zero word leaves D unchanged (Z = 1).
    """
    get, put = word_get(mem, fon.s), byte_set(mem, fon.d)
    b, c1 = mem.bits, fon.c + 1

    def step(ctx: FonContext) -> None:
        w = get()
        if w:
            put(w.bit_length() - 1)
            b[c1] = 0
        else:
            b[c1] = 1

    return step


@register(53, "SWPB", "M", "M")
@built
def swpb(mem: Memory, fon: Fon) -> Step:
    """byte[D] = byte[S] with its two nibbles swapped."""
    get, put = byte_get(mem, fon.s), byte_set(mem, fon.d)

    def step(ctx: FonContext) -> None:
        v = get()
        put(((v << 4) | (v >> 4)) & 0xFF)

    return step
