"""Logical functions (manual group 3.3): NEG AND OR XOR BMASK WMASK PRTO PRTOCH PRTE PRTECH."""

from __future__ import annotations

import operator
from collections.abc import Callable

from netplc.functions._util import (
    Builder,
    Step,
    built,
    byte_get,
    byte_set,
    data_at,
    fail,
    flag_bits,
    sdr_data_at,
    word_get,
    word_set,
    word_src,
    word_store,
)
from netplc.functions.registry import Fon, FonContext, Inline, register
from netplc.memory import Memory


def _neg_inline(fon: Fon) -> list[str] | None:
    i, k, flags = data_at(fon.s, 1), data_at(fon.d, 1), flag_bits(fon, 1)
    if i is None or k is None or flags is None:
        return None
    return [f"_v = ~d[{i}] & 255", f"d[{k}] = _v", f"b[{flags[0]}] = _v == 0"]


@register(9, "NEG", "M", "M", inline=_neg_inline)
@built
def neg(mem: Memory, fon: Fon) -> Step:
    """byte[D] = ~byte[S]; C+1 Z (result 0)."""
    get, put = byte_get(mem, fon.s), byte_set(mem, fon.d)
    b, c1 = mem.bits, fon.c + 1

    def step(ctx: FonContext) -> None:
        v = ~get() & 0xFF
        put(v)
        b[c1] = 1 if v == 0 else 0

    return step


def _byte_logic(op: Callable[[int, int], int]) -> Builder:
    """byte[R] = byte[S] op byte[D]; C+1 Z (result 0)."""

    def build(mem: Memory, fon: Fon) -> Step:
        gs, gd, put = byte_get(mem, fon.s), byte_get(mem, fon.d), byte_set(mem, fon.r)
        b, c1 = mem.bits, fon.c + 1

        def step(ctx: FonContext) -> None:
            v = op(gs(), gd())
            put(v)
            b[c1] = 1 if v == 0 else 0

        return step

    return build


def _byte_logic_inline(symbol: str) -> Inline:
    def inline(fon: Fon) -> list[str] | None:
        ops = sdr_data_at(fon, 1, 1)
        if ops is None:
            return None
        i, j, k, flags = ops
        return [f"_v = d[{i}] {symbol} d[{j}]", f"d[{k}] = _v", f"b[{flags[0]}] = _v == 0"]

    return inline


register(13, "AND", "M", "M", "M", inline=_byte_logic_inline("&"))(built(_byte_logic(operator.and_)))
register(14, "OR", "M", "M", "M", inline=_byte_logic_inline("|"))(built(_byte_logic(operator.or_)))
register(18, "XOR", "M", "M", "M", inline=_byte_logic_inline("^"))(built(_byte_logic(operator.xor)))


@register(38, "BMASK", "M", "O", "O")
@built
def bmask(mem: Memory, fon: Fon) -> Step:
    """byte[S] = (byte[S] & ~D) | R, in place. Masks wider than a byte (> 0377) raise FErr1."""
    and_mask, or_mask = fon.d or 0, fon.r or 0
    if and_mask > 0xFF or or_mask > 0xFF:
        return fail
    get, put = byte_get(mem, fon.s), byte_set(mem, fon.s)
    return lambda ctx: put((get() & ~and_mask) | or_mask)


def _wmask_inline(fon: Fon) -> list[str] | None:
    i = data_at(fon.s, 2)
    if i is None:
        return None
    return [f"_v = {word_src(i)} & {~(fon.d or 0) & 0xFFFF} | {fon.r or 0}", *word_store(i, "_v")]


@register(39, "WMASK", "M", "O", "O", inline=_wmask_inline)
@built
def wmask(mem: Memory, fon: Fon) -> Step:
    """word[S] = (word[S] & ~D) | R, in place."""
    and_mask, or_mask = fon.d or 0, fon.r or 0
    get, put = word_get(mem, fon.s), word_set(mem, fon.s)
    return lambda ctx: put((get() & ~and_mask & 0xFFFF) | or_mask)


def _parity_set(odd: bool) -> Builder:
    """word[D] = word[S] with bit 15 chosen so that the count of 1 bits is even (PRTO) or odd (PRTE)."""

    def build(mem: Memory, fon: Fon) -> Step:
        get, put = word_get(mem, fon.s), word_set(mem, fon.d)

        def step(ctx: FonContext) -> None:
            w = get() & 0x7FFF
            if (w.bit_count() & 1) != odd:
                w |= 0x8000
            put(w)

        return step

    return build


def _parity_check(odd: bool) -> Builder:
    """C+1 = 1 (error) when the count of 1 bits in word[S] is not even (PRTOCH) / odd (PRTECH)."""

    def build(mem: Memory, fon: Fon) -> Step:
        get = word_get(mem, fon.s)
        b, c1 = mem.bits, fon.c + 1

        def step(ctx: FonContext) -> None:
            b[c1] = 1 if (get().bit_count() & 1) != odd else 0

        return step

    return build


# PRTE's description is a copy of PRTO's ("even"), but its example makes the parity odd: the
# example wins (docs/architecture.md section 6).
register(81, "PRTO", "M", "M")(built(_parity_set(odd=False)))
register(82, "PRTOCH", "M")(built(_parity_check(odd=False)))
register(83, "PRTE", "M", "M")(built(_parity_set(odd=True)))
register(84, "PRTECH", "M")(built(_parity_check(odd=True)))
