"""TIM and CTR semantics, the timer time base and the square-wave generators (DESIGN section 4).

Each TIM/CTR instruction gets one closure bound to its coil address and preset; the compiled
program calls it directly and the reference interpreter reaches the same closure through the
engine, so the two can differ only in how they evaluate contacts and jumps. Current values are
hidden state keyed by the coil address C (the manual exposes them nowhere), so they survive a
program reload and can be made retentive.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from netplc.address import GEN_BASE, TIMEBASE_HI, TIMEBASE_LO

TIME_BASES = (0.01, 0.1, 1.0, 10.0)  # indexed by (03774 << 1) | 03773
_EPS = 1e-6  # absorbs float error of a clock stepped in 0.1 s increments


class ScanClock(Protocol):
    dt: float  # seconds since the previous scan


def make_tim(
    bits: bytearray, ticks: dict[int, float], c: int, n: int, clock: ScanClock
) -> Callable[[int], None]:
    """On-delay timer at C: C = RES; while RES the count advances by elapsed time-base ticks
    (the base read when the TIM runs), saturating at N; C+1 = count >= N."""
    c1 = c + 1
    done_at = n - _EPS

    def tim(res: int) -> None:
        if res:
            if bits[c]:
                t = ticks.get(c, 0.0) + clock.dt / TIME_BASES[(bits[TIMEBASE_HI] << 1) | bits[TIMEBASE_LO]]
                if t > n:
                    t = float(n)
            else:
                t = 0.0  # the timer starts on this scan
            ticks[c] = t
            bits[c1] = 1 if t >= done_at else 0
            bits[c] = 1
        else:
            ticks[c] = 0.0
            bits[c] = 0
            bits[c1] = 0

    return tim


def make_ctr(bits: bytearray, values: dict[int, int], c: int, n: int) -> Callable[[int], None]:
    """Up-counter at C: C = RES; C+1 resets while 1; a rising edge of RES counts up to N; C+2 = done."""
    c1, c2 = c + 1, c + 2

    def ctr(res: int) -> None:
        rising = res and not bits[c]
        bits[c] = 1 if res else 0
        if bits[c1]:
            values[c] = 0
            bits[c2] = 0
            return
        cur = values.get(c, 0)
        if rising and cur < n:
            cur += 1
            values[c] = cur
        bits[c2] = 1 if cur >= n else 0

    return ctr


def update_generators(bits: bytearray, elapsed: float) -> None:
    """03750-03757: square waves of period 0.1 s * 2**k, 50 % duty, from the engine clock."""
    halves = int(elapsed * 20 + _EPS)  # number of 0.05 s half-periods of the fastest generator
    for k in range(8):
        bits[GEN_BASE + k] = (halves >> k) & 1
