"""TIM and CTR semantics, the timer time base and the square-wave generators (DESIGN section 4).

Both the compiled engine and the reference interpreter call these, so the two can differ only in
how they evaluate contacts and jumps. Current values are hidden state keyed by the coil address C
(the manual exposes them nowhere), so they survive a program reload and can be made retentive.
"""

from __future__ import annotations

from netplc.address import GEN_BASE, TIMEBASE_HI, TIMEBASE_LO

TIME_BASES = (0.01, 0.1, 1.0, 10.0)  # indexed by (03774 << 1) | 03773
_EPS = 1e-6


def time_base(bits: bytearray) -> float:
    return TIME_BASES[(bits[TIMEBASE_HI] << 1) | bits[TIMEBASE_LO]]


def run_tim(bits: bytearray, ticks: dict[int, float], c: int, n: int, res: int, dt: float) -> None:
    """On-delay timer: C = RES; while RES the count advances by elapsed time-base ticks; C+1 = done."""
    if res:
        if bits[c]:
            t = ticks.get(c, 0.0) + dt / time_base(bits)
            ticks[c] = t if t < n else float(n)
        else:
            ticks[c] = 0.0  # the timer starts on this scan
        bits[c + 1] = 1 if ticks[c] + _EPS >= n else 0
        bits[c] = 1
    else:
        ticks[c] = 0.0
        bits[c] = 0
        bits[c + 1] = 0


def run_ctr(bits: bytearray, values: dict[int, int], c: int, n: int, res: int) -> None:
    """Up-counter: C = RES; C+1 resets while 1; a rising edge of RES counts up to N; C+2 = done."""
    rising = res and not bits[c]
    bits[c] = res
    if bits[c + 1]:
        values[c] = 0
        bits[c + 2] = 0
        return
    cur = values.get(c, 0)
    if rising and cur < n:
        cur += 1
        values[c] = cur
    bits[c + 2] = 1 if cur >= n else 0


def update_generators(bits: bytearray, elapsed: float) -> None:
    """03750-03757: square waves of period 0.1 s * 2**k, 50 % duty, from the engine clock."""
    halves = int(elapsed * 20 + _EPS)  # number of 0.05 s half-periods of the fastest generator
    for k in range(8):
        bits[GEN_BASE + k] = (halves >> k) & 1
