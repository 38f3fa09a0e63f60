"""Timers and counters (manual group 3.5): TIMSET TIMFIX INCW DECW TGRP TGRP2.

TGRP and TGRP2 keep their timers in data memory (setpoints and current values, in time-base
ticks) so that the program, the HMI and other stations can read and change them at any time. On a
CPU-165 the firmware advances them at the end of every scan once the group is configured; here each
execution of the function adds the time elapsed since its previous execution (engine clock), which
is the same for a group executed every scan (the manual's recommended use, e.g. behind 03760).
"""

from __future__ import annotations

from netplc.functions._util import (
    Step,
    at,
    bit_get,
    built,
    data_at,
    fail,
    flag_bits,
    operand_bit,
    word_get,
    word_set,
    word_src,
    word_store,
)
from netplc.functions.registry import Fon, FonContext, register
from netplc.memory import Memory

BASE_HUNDREDTHS = (1, 10, 100, 1000)  # the `aa` time-base code: 0.01 s, 0.1 s, 1 s, 10 s
TGRP_SETPOINTS = 0o7600
TGRP_CURRENT = 0o7700
TGRP_BITS = 0o3600
TGRP_SLOTS = 32
CURRENT_OFFSET = 0o100  # TGRP2: current values 0100 bytes above the setpoints (074xx -> 075xx)


def _time_code(r: int) -> tuple[int, int]:
    """(hundredths of a second per tick, number of timers) from R = ...0aa.0bb.bbb (TIMSET/TIMFIX)."""
    return BASE_HUNDREDTHS[(r >> 6) & 3], (r & 0o37) + 1


@register(56, "TIMSET", "M", "M", "O")
@built
def timset(mem: Memory, fon: Fon) -> Step:
    """Setpoint = hours S+0, minutes S+2, seconds S+4, tenths S+6, in ticks of R's base, to D.

    With R's count field bbbbb = n-1 the same setpoint goes to the n words D, D+2, ... Decided where
    the manual is silent: the time is truncated to whole ticks (0.05 s at a 0.1 s base is 0); a
    setpoint above 65535 ticks raises FErr1 and writes nothing.
    """
    base, count = _time_code(fon.r or 0)
    s, d = fon.s or 0, fon.d or 0
    h, m, sec, t = (word_get(mem, at(s, 2 * k)) for k in range(4))
    puts = [word_set(mem, at(d, 2 * k)) for k in range(count)]

    def step(ctx: FonContext) -> None:
        hundredths = ((h() * 3600 + m() * 60 + sec()) * 10 + t()) * 10
        value = hundredths // base
        if value > 0xFFFF:
            fail(ctx)
            return
        for put in puts:
            put(value)

    return step


@register(57, "TIMFIX", "M", "M", "O")
@built
def timfix(mem: Memory, fon: Fon) -> Step:
    """Timer value at S (ticks of R's base) -> hours, minutes, seconds, tenths at D+0..D+6.

    With R's count field bbbbb = n-1, n timers S, S+2, ... go to n structures D, D+010, ...
    Hundredths (0.01 s base) are truncated to tenths.
    """
    base, count = _time_code(fon.r or 0)
    s, d = fon.s or 0, fon.d or 0
    timers = []
    for k in range(count):
        out = at(d, 8 * k)
        timers.append((word_get(mem, at(s, 2 * k)), [word_set(mem, at(out, 2 * j)) for j in range(4)]))

    def step(ctx: FonContext) -> None:
        for get, (ph, pm, ps, pt) in timers:
            tenths = get() * base // 10
            ph(tenths // 36000)
            pm(tenths // 600 % 60)
            ps(tenths // 10 % 60)
            pt(tenths % 10)

    return step


def _incw_inline(fon: Fon) -> list[str] | None:
    i, k, flags = data_at(fon.s, 2), data_at(fon.d, 2), flag_bits(fon, 2)
    if i is None or k is None or flags is None:
        return None
    c1, c2 = flags  # the setpoint is read after the store, as the step reads it
    return [f"_v = {word_src(k)} + 1 & 65535", *word_store(k, "_v"),
            f"b[{c1}] = _v == 0", f"b[{c2}] = _v == {word_src(i)}"]


@register(63, "INCW", "M", "M", inline=_incw_inline)
@built
def incw(mem: Memory, fon: Fon) -> Step:
    """Counter: word[D] += 1 (wrapping); C+1 ">" = it wrapped past FFFF; C+2 "=" = word[D] == word[S].

    The manual's prose swaps S and D; the parameter table and the example win (D counts, S is the
    setpoint). ">" is read as overflow, by symmetry with DECW's "<"; counting continues past the
    setpoint and the program resets the counter by writing 0.
    """
    gs, gd, pd = word_get(mem, fon.s), word_get(mem, fon.d), word_set(mem, fon.d)
    b, c1, c2 = mem.bits, fon.c + 1, fon.c + 2

    def step(ctx: FonContext) -> None:
        v = (gd() + 1) & 0xFFFF
        pd(v)
        b[c1] = 1 if v == 0 else 0
        b[c2] = 1 if v == gs() else 0

    return step


def _decw_inline(fon: Fon) -> list[str] | None:
    k, flags = data_at(fon.s, 2), flag_bits(fon, 2)
    if k is None or flags is None:
        return None
    c1, c2 = flags
    return [f"_x = {word_src(k)}", "_v = _x - 1 & 65535", *word_store(k, "_v"),
            f"b[{c1}] = _x == 0", f"b[{c2}] = _v == 0"]


@register(64, "DECW", "M", inline=_decw_inline)
@built
def decw(mem: Memory, fon: Fon) -> Step:
    """word[S] -= 1 (wrapping); C+1 "<" = it passed through 0000; C+2 Z = the new value is 0."""
    get, put = word_get(mem, fon.s), word_set(mem, fon.s)
    b, c1, c2 = mem.bits, fon.c + 1, fon.c + 2

    def step(ctx: FonContext) -> None:
        old = get()
        v = (old - 1) & 0xFFFF
        put(v)
        b[c1] = 1 if old == 0 else 0
        b[c2] = 1 if v == 0 else 0

    return step


class _Ticker:
    """Whole time-base ticks elapsed between executions; the fraction carries over."""

    def __init__(self, seconds_per_tick: float) -> None:
        self.per_tick = seconds_per_tick
        self.last: float | None = None
        self.frac = 0.0

    def ticks(self, now: float) -> int:
        if self.last is None:
            self.last = now
            return 0
        self.frac += (now - self.last) / self.per_tick
        self.last = now
        whole = int(self.frac + 1e-6)
        self.frac = max(0.0, self.frac - whole)
        return whole


@register(65, "TGRP", "O")
@built
def tgrp(mem: Memory, fon: Fon) -> Step:
    """A group of S timers (S octal: 010, 020, 030, 040; others round up to a multiple of 010).

    Timer k uses slot j = 32 - n + k: setpoint 07600+2j, current value 07700+2j (0.1 s ticks),
    enable ("instantaneous coil") bit 03600+2j, done bit 03601+2j = setpoint <= current.
    More than 040 timers (or 0) is a setup error: FErr1, nothing configured.
    The manual says both "coil off -> current = 0" and "disabled before the setpoint: counting
    pauses, and resumes when re-enabled", and "the counter resets when the setpoint has been reached
    and the enable bit is off". Decided, reconciling all three: enable on counts up to the setpoint;
    enable off before the setpoint pauses; enable off at or past the setpoint resets to 0.
    """
    n = -(-(fon.s or 0) // 8) * 8
    if not 0 < n <= TGRP_SLOTS:
        return fail
    slots = range(TGRP_SLOTS - n, TGRP_SLOTS)
    timers = [
        (word_get(mem, TGRP_SETPOINTS + 2 * j), word_get(mem, TGRP_CURRENT + 2 * j),
         word_set(mem, TGRP_CURRENT + 2 * j), TGRP_BITS + 2 * j)
        for j in slots
    ]
    b = mem.bits
    ticker = _Ticker(0.1)

    def step(ctx: FonContext) -> None:
        dt = ticker.ticks(ctx.now)
        for setpoint, current, put, enable in timers:
            sp, cur = setpoint(), current()
            if b[enable]:
                if cur < sp and dt:
                    cur = min(sp, cur + dt)
                    put(cur)
            elif cur >= sp and cur:
                cur = 0
                put(0)
            b[enable + 1] = 1 if sp <= cur else 0

    return step


@register(66, "TGRP2", "M", "M", "O")
@built
def tgrp2(mem: Memory, fon: Fon) -> Step:
    """Timer group 2: setpoints from S, current values at S+0100, STOP bits from D.

    The manual gives only the parameters: S = setpoints (074xx or 076xx), D = STOP bits (data or
    I/O), R = 0.000.00a.0bb.0cc.ccc with a = "with stop", bb = time base (as TIMSET), ccccc = number
    of timers. Decided, as TGRP with these differences:
    - ccccc counts as in TIMSET (00000 = 1 timer, 11111 = 32);
    - current values are 0100 bytes above the setpoints (074xx -> 075xx, 076xx -> 077xx, which is
      where TIMFIX reads them), in ticks of the selected base;
    - there are no enable or done bits: timer k counts up to its setpoint unless (a = 1) its STOP
      bit k is 1 (bit D+k in the I/O area, bit k%8 of byte D+k//8 in data memory); a stopped timer
      that has reached its setpoint resets to 0, a stopped one still counting pauses (the TGRP rule
      with STOP = not enable); without stop (a = 0) a timer stays at its setpoint until the program
      writes 0 to its current value. Done is `current >= setpoint` (e.g. NLESS/CMP).
    """
    r = fon.r or 0
    base, count = _time_code(r)
    with_stop = bool(r & 0o1000)
    s, d = fon.s or 0, fon.d or 0
    timers = []
    for k in range(count):
        stop = bit_get(mem, operand_bit(d, k)) if with_stop else None
        timers.append((word_get(mem, at(s, 2 * k)), word_get(mem, at(s, CURRENT_OFFSET + 2 * k)),
                       word_set(mem, at(s, CURRENT_OFFSET + 2 * k)), stop))
    ticker = _Ticker(base / 100)

    def step(ctx: FonContext) -> None:
        dt = ticker.ticks(ctx.now)
        for setpoint, current, put, stop in timers:
            sp, cur = setpoint(), current()
            if stop is not None and stop():
                if cur >= sp and cur:
                    put(0)
            elif cur < sp and dt:
                put(min(sp, cur + dt))

    return step

