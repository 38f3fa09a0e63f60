"""The NetPlc group 303-316 (manual group 3.7, docs/architecture.md section 6): registration and processing.

NODE, NREAD and NWRITE (300-302) live in net.py with the exchange.

NMSG and NSTORE are level-triggered like every FON: while their rung is true they hand one record
to the registrar on *every scan*. A program therefore drives them from an edge - a CTR output, a
one-scan pulse, an NSYNC output - so that one event is one record (see
tests/netplc/test_functions_scada.py for the pulse pattern).
"""

from __future__ import annotations

from netplc.address import DATA_SIZE, fmt_octal
from netplc.functions._util import (
    FAIL_LINE,
    Builder,
    Step,
    at,
    block_get,
    block_set,
    built,
    constant_inline,
    copy_inline,
    data_at,
    fail,
    flag_bits,
    word_get,
    word_set,
    word_src,
    word_store,
)
from netplc.functions.registry import Fon, FonContext, Inline, register
from netplc.memory import Memory
from netplc.records import Record


@register(303, "NMSG", "D", "D", "D")
@built
def nmsg(mem: Memory, fon: Fon) -> Step:
    """Journal message number S, group D, type R; the registrar resolves the text from its catalog."""
    number, grp, typ = fon.s, fon.d, fon.r

    def step(ctx: FonContext) -> None:
        ctx.sink.put(Record(ctx.wall_time(), "message", grp=grp, type=typ, number=number, text=None))

    return step


@register(304, "NSTORE", "M", "D", "D")
@built
def nstore(mem: Memory, fon: Fon) -> Step:
    """Store the word at address S in the archive as data of group D, type R."""
    get, grp, typ = word_get(mem, fon.s), fon.d, fon.r
    source = fmt_octal(fon.s or 0)

    def step(ctx: FonContext) -> None:
        ctx.sink.put(Record(ctx.wall_time(), "data", grp=grp, type=typ, source=source, value=float(get())))

    return step


def _nsync_inline(fon: Fon) -> list[str] | None:
    flags = flag_bits(fon, 1)
    if flags is None:
        return None
    if not fon.s:
        return [f"b[{flags[0]}] = 0", FAIL_LINE]
    return [f"b[{flags[0]}] = eng.scan_counter % {fon.s} == {fon.d or 0}"]


@register(305, "NSYNC", "D", "D", inline=_nsync_inline)
@built
def nsync(mem: Memory, fon: Fon) -> Step:
    """C+1 = 1 on the scans whose number modulo the period S equals the phase D (else 0).

    A period of 0 raises FErr1 (C+1 = 0); a phase not below the period never fires.
    """
    period, phase = fon.s or 0, fon.d or 0
    b, c1 = mem.bits, fon.c + 1
    if period == 0:

        def bad(ctx: FonContext) -> None:
            b[c1] = 0
            fail(ctx)

        return bad

    def step(ctx: FonContext) -> None:
        b[c1] = 1 if ctx.scan_counter % period == phase else 0

    return step


def _compare(op: str, immediate: bool) -> Builder:
    """C+1 = word[S] <op> word[D] (or the decimal constant D), unsigned 16-bit."""

    def build(mem: Memory, fon: Fon) -> Step:
        gs = word_get(mem, fon.s)
        b, c1 = mem.bits, fon.c + 1
        if immediate:
            k = fon.d or 0
            if op == ">":
                return lambda ctx: b.__setitem__(c1, 1 if gs() > k else 0)
            return lambda ctx: b.__setitem__(c1, 1 if gs() < k else 0)
        gd = word_get(mem, fon.d)
        if op == ">":
            return lambda ctx: b.__setitem__(c1, 1 if gs() > gd() else 0)
        if op == "<":
            return lambda ctx: b.__setitem__(c1, 1 if gs() < gd() else 0)
        return lambda ctx: b.__setitem__(c1, 1 if gs() == gd() else 0)

    return build


def _compare_inline(op: str, immediate: bool) -> Inline:
    symbol = "==" if op == "=" else op

    def inline(fon: Fon) -> list[str] | None:
        i, flags = data_at(fon.s, 2), flag_bits(fon, 1)
        j = None if immediate else data_at(fon.d, 2)
        if i is None or flags is None or (j is None and not immediate):
            return None
        other = str(fon.d or 0) if j is None else word_src(j)
        return [f"b[{flags[0]}] = {word_src(i)} {symbol} {other}"]

    return inline


for _number, _name, _d, _op, _imm in (
    (306, "NGREAT", "M", ">", False),
    (307, "NLESS", "M", "<", False),
    (308, "NEQUAL", "M", "=", False),
    (315, "NLESSI", "D", "<", True),
    (316, "NGREATI", "D", ">", True),
):
    register(_number, _name, "M", _d, inline=_compare_inline(_op, _imm))(built(_compare(_op, _imm)))


@register(309, "NMEM", "M")
@built
def nmem(mem: Memory, fon: Fon) -> Step:
    """word[S] = the data-memory size in bytes (16384: eight banks of 2 KB)."""
    put = word_set(mem, fon.s)
    return lambda ctx: put(DATA_SIZE)


@register(310, "NAVG", "M", "M")
@built
def navg(mem: Memory, fon: Fon) -> Step:
    """Running mean of word[S] in word[D], sample count in word[D+2]; input C+1 = 1 resets.

    Each execution with C+1 = 0 takes one sample: mean = (mean*n + x)/(n+1) rounded half up,
    n+1 stored at D+2 (saturating at 65535, after which the mean keeps weighting new samples
    1/65536). While C+1 = 1 the mean and the count are 0 and no sample is taken. The exact sum is
    kept with the instruction, so rounding does not accumulate; if D or D+2 were changed by
    someone else, the sum restarts from what memory says (mean * n).
    """
    gx, gm, pm = word_get(mem, fon.s), word_get(mem, fon.d), word_set(mem, fon.d)
    gn, pn = word_get(mem, at(fon.d, 2)), word_set(mem, at(fon.d, 2))
    b, c1 = mem.bits, fon.c + 1
    kept = [0, 0, 0]  # mean and count as last stored, exact sum

    def step(ctx: FonContext) -> None:
        if b[c1]:
            pm(0)
            pn(0)
            kept[:] = [0, 0, 0]
            return
        mean, n = gm(), gn()
        total = kept[2] if kept[0] == mean and kept[1] == n else mean * n
        if n == 0xFFFF:
            total -= mean
        else:
            n += 1
        total += gx()
        mean = (2 * total + n) // (2 * n)
        pm(mean)
        pn(n)
        kept[:] = [mean, n, total]

    return step


@register(311, "NSETDI", "M", "D", inline=lambda fon: constant_inline(fon.s, fon.d or 0))
@built
def nsetdi(mem: Memory, fon: Fon) -> Step:
    """word[S] = the decimal constant D (S is the destination here)."""
    put, value = word_set(mem, fon.s), fon.d or 0
    return lambda ctx: put(value)


def _move(unit: int) -> Builder:
    """Copy R bytes (NMOVB) or R words (NMOVW) from S to D, any area to any area.

    A block that leaves addressable memory raises FErr1 and nothing is copied; R = 0 does nothing.
    """

    def build(mem: Memory, fon: Fon) -> Step:
        n = (fon.r or 0) * unit
        if n == 0:
            return lambda ctx: None
        get, put = block_get(mem, fon.s, n), block_set(mem, fon.d, n)
        return lambda ctx: put(get())

    return build


def _move_inline(unit: int) -> Inline:
    def inline(fon: Fon) -> list[str] | None:
        n = (fon.r or 0) * unit
        return [] if n == 0 else copy_inline(fon.s, fon.d, n)

    return inline


register(312, "NMOVB", "M", "M", "D", inline=_move_inline(1))(built(_move(1)))
register(313, "NMOVW", "M", "M", "D", inline=_move_inline(2))(built(_move(2)))


def _nmax_inline(fon: Fon) -> list[str] | None:
    i, k, flags = data_at(fon.s, 2), data_at(fon.d, 2), flag_bits(fon, 1)
    if i is None or k is None or flags is None:
        return None
    return [f"if b[{flags[0]}]:", f"    _x = {word_src(i)}", f"    if _x > {word_src(k)}:",
            *("        " + line for line in word_store(k, "_x")), "else:",
            *("    " + line for line in word_store(k, "0"))]


@register(314, "NMAX", "M", "M", inline=_nmax_inline)
@built
def nmax(mem: Memory, fon: Fon) -> Step:
    """Input C+1 = 0: word[D] = 0 ("reset by 0"); C+1 = 1: word[D] = max(word[D], word[S])."""
    gs, gd, pd = word_get(mem, fon.s), word_get(mem, fon.d), word_set(mem, fon.d)
    b, c1 = mem.bits, fon.c + 1

    def step(ctx: FonContext) -> None:
        if not b[c1]:
            pd(0)
            return
        x = gs()
        if x > gd():
            pd(x)

    return step
