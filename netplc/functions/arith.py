"""Arithmetic (manual group 3.4): ADDBCD SUBBCD CMP ROR ROL SCALE MATH ADD SUB MUL DIV.

Words are unsigned 16-bit. Output flags at C+1.. are written (1 or 0) every time the function
executes; an error sets FErr1 and leaves memory and flags as they were.
"""

from __future__ import annotations

from netplc.address import FERR2
from netplc.functions._util import (
    FAIL_LINE,
    Builder,
    Step,
    at,
    bcd_to_bin,
    bin_to_bcd,
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


def _bcd_arith(subtract: bool) -> Builder:
    """word[R] = S + D or S - D on 4-digit BCD words; C+1 carry/borrow; C+2 Z (stored value 0).

    FErr1 and nothing done when an operand is not valid BCD (stated for ADDBCD; decided for SUBBCD
    the same way). Z follows the stored 4 digits (5000 + 5000 stores 0000: carry 1, Z 1). The
    manual does not say what SUBBCD stores on a negative result; decided: the 10000's complement
    (1234 - 5555 stores 5679 with the borrow set), as a 4-digit BCD subtractor leaves it.
    """

    def build(mem: Memory, fon: Fon) -> Step:
        gs, gd, put = word_get(mem, fon.s), word_get(mem, fon.d), word_set(mem, fon.r)
        b, c1, c2 = mem.bits, fon.c + 1, fon.c + 2

        def step(ctx: FonContext) -> None:
            x, y = bcd_to_bin(gs()), bcd_to_bin(gd())
            if x is None or y is None:
                fail(ctx)
                return
            total = x - y if subtract else x + y
            value = total % 10000
            put(bin_to_bcd(value))
            b[c1] = 1 if total < 0 or total > 9999 else 0
            b[c2] = 1 if value == 0 else 0

        return step

    return build


register(10, "ADDBCD", "M", "M", "M")(built(_bcd_arith(subtract=False)))
register(11, "SUBBCD", "M", "M", "M")(built(_bcd_arith(subtract=True)))


def _cmp_inline(fon: Fon) -> list[str] | None:
    i, j, flags = data_at(fon.s, 2), data_at(fon.d, 2), flag_bits(fon, 3)
    if i is None or j is None or flags is None:
        return None
    c1, c2, c3 = flags
    return [f"_x = {word_src(i)}", f"_y = {word_src(j)}",
            f"b[{c1}] = _x > _y", f"b[{c2}] = _x == _y", f"b[{c3}] = _x < _y"]


@register(12, "CMP", "M", "M", inline=_cmp_inline)
@built
def cmp(mem: Memory, fon: Fon) -> Step:
    """C+1 = S > D, C+2 = S == D, C+3 = S < D (unsigned 16-bit; the table and values, not the prose)."""
    gs, gd = word_get(mem, fon.s), word_get(mem, fon.d)
    b, c1, c2, c3 = mem.bits, fon.c + 1, fon.c + 2, fon.c + 3

    def step(ctx: FonContext) -> None:
        x, y = gs(), gd()
        b[c1] = 1 if x > y else 0
        b[c2] = 1 if x == y else 0
        b[c3] = 1 if x < y else 0

    return step


def _rotate(left: bool) -> Builder:
    """Rotate word[S] by one through the input bit C+1, reporting two bits of the old word.

    ROR: bit 15 <- C+1; C+2 <- old bit 0; C+3 <- old bit 8 (the table and example, not the prose).
    ROL: bit 0 <- C+1; C+2 <- old bit 15; C+3 <- old bit 7 (the dump 0080 -> 0101, not the prose).
    """
    out_bit, mid_bit = (15, 7) if left else (0, 8)

    def build(mem: Memory, fon: Fon) -> Step:
        get, put = word_get(mem, fon.s), word_set(mem, fon.s)
        b, c1, c2, c3 = mem.bits, fon.c + 1, fon.c + 2, fon.c + 3

        def step(ctx: FonContext) -> None:
            w = get()
            put(((w << 1) & 0xFFFF) | b[c1] if left else (w >> 1) | (b[c1] << 15))
            b[c2] = (w >> out_bit) & 1
            b[c3] = (w >> mid_bit) & 1

        return step

    return build


register(36, "ROR", "M")(built(_rotate(left=False)))
register(37, "ROL", "M")(built(_rotate(left=True)))


def _scale_inline(fon: Fon) -> list[str] | None:
    d = fon.d or 0
    x, y = data_at(fon.s, 2), data_at(d, 2)
    a, b, c = (data_at(at(d, k), 2) for k in (2, 4, 6))
    if x is None or y is None or a is None or b is None or c is None:
        return None
    if fon.r not in (0, 1):
        return [FAIL_LINE]
    return [f"_y = {word_src(b)}", "if _y:",
            f"    _t = {word_src(a)} * {word_src(x)} // _y {'-' if fon.r else '+'} {word_src(c)}",
            "    if _t < 0:", "        _t = 0", f"        b[{FERR2}] = 1",
            "    elif _t > 65535:", "        _t = 65535", f"        b[{FERR2}] = 1",
            *("    " + line for line in word_store(y, "_t")), "else:", f"    {FAIL_LINE}"]


@register(54, "SCALE", "M", "M", "O", inline=_scale_inline)
@built
def scale(mem: Memory, fon: Fon) -> Step:
    """Y = (A/B)*X + s*C with X = word[S], Y = word[D], A, B, C = words D+2, D+4, D+6; R 0: s=+1, 1: s=-1.

    Decided where the manual is silent: evaluated as floor(A*X / B) with an exact intermediate, so
    A/B < 1 keeps its precision; B = 0 or R other than 0/1 raises FErr1 and writes nothing; a result
    outside 0..65535 is saturated to the nearest end and raises FErr2 (the output stays usable, the
    program can see the overflow).
    """
    d = fon.d or 0
    gx, put = word_get(mem, fon.s), word_set(mem, d)
    ga, gb, gc = word_get(mem, at(d, 2)), word_get(mem, at(d, 4)), word_get(mem, at(d, 6))
    if fon.r not in (0, 1):
        return fail
    sign = -1 if fon.r else 1
    b = mem.bits

    def step(ctx: FonContext) -> None:
        div = gb()
        if div == 0:
            fail(ctx)
            return
        y = ga() * gx() // div + sign * gc()
        if not 0 <= y <= 0xFFFF:
            y = 0 if y < 0 else 0xFFFF
            b[FERR2] = 1
        put(y)

    return step


@register(55, "MATH", "M", "M", "D")
@built
def math(mem: Memory, fon: Fon) -> Step:
    """Special math functions: the manual lists only the parameters and the outputs < = >.

    Decided: with no operation defined anywhere, any computation would be a guess that a ported
    CPU-165 program would silently rely on; MATH loads (so such programs run) and raises FErr1 each
    time it executes, touching nothing else, so the program can detect it.
    """
    return fail


def _bin_arith(subtract: bool) -> Builder:
    """word[R] = S + D or S - D (16 bits, wrapping); C+1 carry out of 16 bits / borrow (S < D); C+2 Z."""

    def build(mem: Memory, fon: Fon) -> Step:
        gs, gd, put = word_get(mem, fon.s), word_get(mem, fon.d), word_set(mem, fon.r)
        b, c1, c2 = mem.bits, fon.c + 1, fon.c + 2

        def step(ctx: FonContext) -> None:
            total = gs() - gd() if subtract else gs() + gd()
            value = total & 0xFFFF
            put(value)
            b[c1] = 1 if total != value else 0
            b[c2] = 1 if value == 0 else 0

        return step

    return build


def _bin_arith_inline(subtract: bool) -> Inline:
    def inline(fon: Fon) -> list[str] | None:
        ops = sdr_data_at(fon, 2, 2)
        if ops is None:
            return None
        i, j, k, flags = ops
        c1, c2 = flags
        return [f"_t = {word_src(i)} {'-' if subtract else '+'} {word_src(j)}", "_v = _t & 65535",
                *word_store(k, "_v"), f"b[{c1}] = _t != _v", f"b[{c2}] = _v == 0"]

    return inline


for _number, _name, _subtract in ((92, "ADD", False), (93, "SUB", True)):
    register(_number, _name, "M", "M", "M", inline=_bin_arith_inline(_subtract))(built(_bin_arith(_subtract)))


def _mul_inline(fon: Fon) -> list[str] | None:
    i, j = data_at(fon.s, 2), data_at(fon.d, 2)
    lo, hi = data_at(fon.r, 2), data_at(at(fon.r, 2), 2)
    if i is None or j is None or lo is None or hi is None:
        return None
    return [f"_t = {word_src(i)} * {word_src(j)}", "_v = _t & 65535", *word_store(lo, "_v"),
            "_v = _t >> 16", *word_store(hi, "_v")]


@register(94, "MUL", "M", "M", "M", inline=_mul_inline)
@built
def mul(mem: Memory, fon: Fon) -> Step:
    """32-bit product of the unsigned words S and D: low word at R, high word at R+2."""
    r = fon.r or 0
    gs, gd = word_get(mem, fon.s), word_get(mem, fon.d)
    lo, hi = word_set(mem, r), word_set(mem, at(r, 2))

    def step(ctx: FonContext) -> None:
        p = gs() * gd()
        lo(p)
        hi(p >> 16)

    return step


def _div_inline(fon: Fon) -> list[str] | None:
    i, j = data_at(fon.s, 2), data_at(fon.d, 1)
    q, m = data_at(fon.r, 2), data_at(at(fon.r, 2), 1)
    if i is None or j is None or q is None or m is None:
        return None
    return [f"_y = d[{j}]", "if _y:", f"    _x = {word_src(i)}", "    _v = _x // _y",
            *("    " + line for line in word_store(q, "_v")), f"    d[{m}] = _x % _y", "else:",
            f"    {FAIL_LINE}"]


@register(95, "DIV", "M", "M", "M", inline=_div_inline)
@built
def div(mem: Memory, fon: Fon) -> Step:
    """word[S] / byte[D]: 16-bit quotient at R, 8-bit remainder in byte R+2 (the "24-bit result").

    The manual gives the divisor as "8-bit data" and the result as 24 bits, which fits exactly a
    16-bit quotient and a remainder below 256; so the divisor is the byte at D (the low byte of the
    word) and exactly three bytes are written. A zero divisor raises FErr1 and writes nothing.
    """
    r = fon.r or 0
    gs, gd = word_get(mem, fon.s), byte_get(mem, fon.d)
    quot, rem = word_set(mem, r), byte_set(mem, at(r, 2))

    def step(ctx: FonContext) -> None:
        divisor = gd()
        if divisor == 0:
            fail(ctx)
            return
        q, m = divmod(gs(), divisor)
        quot(q)
        rem(m)

    return step
