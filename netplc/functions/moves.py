"""Data moves (manual group 3.1): MOV MVIBCD XCG MVID MVIO PUSH POP MOVBLK MVMBLK STM LDM MVM MOVB
SHFTBLK.

Indirect moves (MVMBLK STM LDM MVM) compute addresses from memory at run time, so they validate
each computed address on every execution: an invalid one raises FErr1 and nothing is written.
"""

from __future__ import annotations

from netplc.address import is_valid_operand
from netplc.functions._util import (
    Builder,
    Step,
    block_get,
    block_set,
    built,
    byte_get,
    byte_set,
    constant_inline,
    copy_inline,
    data_at,
    fail,
    span,
    valid_block,
    word_get,
    word_set,
    word_src,
    word_store,
)
from netplc.functions.registry import Fon, FonContext, register
from netplc.memory import Memory

STACK_MAX = 64  # PUSH/POP/SHFTBLK area limit in bytes
BLOCK_MAX = 256  # MOVBLK/MVMBLK length limit in bytes


@register(0, "MOV", "M", "M", inline=lambda fon: copy_inline(fon.s, fon.d, 2))
@built
def mov(mem: Memory, fon: Fon) -> Step:
    """word[D] = word[S]."""
    get, put = word_get(mem, fon.s), word_set(mem, fon.d)
    return lambda ctx: put(get())


def _store_constant(mem: Memory, fon: Fon) -> Step:
    put, value = word_set(mem, fon.d), fon.s or 0
    return lambda ctx: put(value)


# The parser has already turned the constant into the word to store (BCD digits as nibbles for
# MVIBCD, decimal for MVID, octal for MVIO), so the three differ only in how S is written.
def _store_constant_inline(fon: Fon) -> list[str] | None:
    return constant_inline(fon.d, fon.s or 0)


register(1, "MVIBCD", "B", "M", inline=_store_constant_inline)(built(_store_constant))
register(7, "MVID", "D", "M", inline=_store_constant_inline)(built(_store_constant))
register(8, "MVIO", "O", "M", inline=_store_constant_inline)(built(_store_constant))


def _xcg_inline(fon: Fon) -> list[str] | None:
    i, k = data_at(fon.s, 2), data_at(fon.d, 2)
    if i is None or k is None:
        return None
    return [f"_x = {word_src(i)}", f"_y = {word_src(k)}", *word_store(i, "_y"), *word_store(k, "_x")]


@register(2, "XCG", "M", "M", inline=_xcg_inline)
@built
def xcg(mem: Memory, fon: Fon) -> Step:
    """Swap word[S] and word[D]."""
    gs, ps = word_get(mem, fon.s), word_set(mem, fon.s)
    gd, pd = word_get(mem, fon.d), word_set(mem, fon.d)

    def step(ctx: FonContext) -> None:
        a, b = gs(), gd()
        ps(b)
        pd(a)

    return step


@register(90, "MOVB", "M", "M", inline=lambda fon: copy_inline(fon.s, fon.d, 1))
@built
def movb(mem: Memory, fon: Fon) -> Step:
    """byte[D] = byte[S]."""
    get, put = byte_get(mem, fon.s), byte_set(mem, fon.d)
    return lambda ctx: put(get())


def _stack(mem: Memory, fon: Fon) -> tuple[int, int] | None:
    """(bottom, length) of the PUSH/POP area S..D, or None when FErr1 is due.

    FErr1: start above end, more than 64 bytes, or an area that spans two banks (check_operand
    refuses a block that leaves its bank).
    """
    s = fon.s or 0
    n = span(s, fon.d)
    if n < 1 or n > STACK_MAX or not valid_block(s, n):
        return None
    return s, n


@register(68, "PUSH", "M", "M")
@built
def push(mem: Memory, fon: Fon) -> Step:
    """Push: v = byte[S]; bytes S+1..D shift down by one; byte[D] = v (the example's LIFO).

    The manual: "value 0 in the stack is treated as absence of data, so no shift is performed".
    Decided: when byte[S] is 0 the function does nothing.
    """
    area = _stack(mem, fon)
    if area is None:
        return fail
    get, put = block_get(mem, area[0], area[1]), block_set(mem, area[0], area[1])

    def step(ctx: FonContext) -> None:
        b = get()
        if b[0]:
            put(b[1:] + b[:1])

    return step


@register(69, "POP", "M", "M", "M")
@built
def pop(mem: Memory, fon: Fon) -> Step:
    """Pop: byte[R] = byte[D]; bytes S..D-1 shift up by one; byte[S] = 0."""
    area = _stack(mem, fon)
    if area is None:
        return fail
    get, put = block_get(mem, area[0], area[1]), block_set(mem, area[0], area[1])
    out = byte_set(mem, fon.r)

    def step(ctx: FonContext) -> None:
        b = get()
        out(b[-1])
        put(b"\0" + b[:-1])

    return step


@register(70, "MOVBLK", "M", "M", "M")
@built
def movblk(mem: Memory, fon: Fon) -> Step:
    """Copy the block S..D (inclusive) to the area starting at R.

    The manual gives three readings; its worked example says "the area D = 04000-04007 is copied
    to the area starting at R = 04010", and the example wins (docs/architecture.md section 6): S is the first
    source byte, D the last, R the first destination byte. FErr1 when D < S or the block is longer
    than 256 bytes (or runs off its bank).
    """
    s = fon.s or 0
    n = span(s, fon.d)
    if n < 1 or n > BLOCK_MAX:
        return fail
    get, put = block_get(mem, s, n), block_set(mem, fon.r, n)
    return lambda ctx: put(get())


@register(71, "MVMBLK", "M", "M", "M")
@built
def mvmblk(mem: Memory, fon: Fon) -> Step:
    """Copy word[R] bytes from address word[S] to address word[D] (pointers read every run).

    FErr1 (nothing copied): length above 256, or either block not wholly in addressable memory.
    Overlapping blocks copy as if through a buffer.
    """
    src, dst, cnt = word_get(mem, fon.s), word_get(mem, fon.d), word_get(mem, fon.r)

    def step(ctx: FonContext) -> None:
        s, d, n = src(), dst(), cnt()
        if n > BLOCK_MAX or not (valid_block(s, n) and valid_block(d, n)):
            fail(ctx)
        elif n:
            ctx.mem.write(d, ctx.mem.read(s, n))

    return step


def _indirect(src_pointer: bool, dst_pointer: bool) -> Builder:
    """Word move where S and/or D hold the address to use (read from memory on every execution).

    A computed address that is not a valid word raises FErr1 and nothing is written.
    """

    def build(mem: Memory, fon: Fon) -> Step:
        src, dst = word_get(mem, fon.s), word_get(mem, fon.d)
        s, d = fon.s or 0, fon.d or 0

        def step(ctx: FonContext) -> None:
            a = src() if src_pointer else s
            b = dst() if dst_pointer else d
            if is_valid_operand(a, 2) and is_valid_operand(b, 2):
                ctx.mem.set_word(b, ctx.mem.get_word(a))
            else:
                fail(ctx)

        return step

    return build


register(74, "STM", "M", "M")(built(_indirect(src_pointer=False, dst_pointer=True)))  # [[D]] = [S]
register(75, "LDM", "M", "M")(built(_indirect(src_pointer=True, dst_pointer=False)))  # [D] = [[S]]
register(76, "MVM", "M", "M")(built(_indirect(src_pointer=True, dst_pointer=True)))  # [[D]] = [[S]]


@register(91, "SHFTBLK", "M", "M")
@built
def shftblk(mem: Memory, fon: Fon) -> Step:
    """Shift the block between S and D by one byte, from S towards D; byte S becomes 0.

    S < D: towards higher addresses (old byte[D] is lost); S > D: towards lower addresses;
    S == D: nothing. FErr1 when the block is longer than 64 bytes.
    """
    s, d = fon.s or 0, fon.d or 0
    lo = min(s, d)
    n = span(lo, max(s, d))
    if n > STACK_MAX:
        return fail
    get, put = block_get(mem, lo, n), block_set(mem, lo, n)
    if s < d:
        return lambda ctx: put(b"\0" + get()[:-1])
    if s > d:
        return lambda ctx: put(get()[1:] + b"\0")
    return lambda ctx: None
