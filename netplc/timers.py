"""TIM and CTR semantics, the timer time base and the square-wave generators (docs/architecture.md section 4).

Each TIM/CTR instruction gets one closure bound to its coil address and preset, which the reference
interpreter calls through the engine; the compiled program runs the same semantics written out as
source lines (`tim_lines`, `ctr_lines`, kept here beside the closures), and the equivalence tests
hold the two to identical memory and current values. Current values are
hidden state indexed by the coil address C (the manual exposes them nowhere), so they survive a
program reload and can be made retentive. They are lists over all 2048 coil addresses rather than
dicts of the coils in use: a list index costs a third of a dict look-up, once or twice per TIM/CTR.
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
    bits: list[int], ticks: list[float], c: int, n: int, clock: ScanClock
) -> Callable[[int], None]:
    """On-delay timer at C: C = RES; while RES the count advances by elapsed time-base ticks
    (the base read when the TIM runs), saturating at N; C+1 = count >= N."""
    c1 = c + 1
    done_at = n - _EPS

    def tim(res: int) -> None:
        if res:
            if bits[c]:
                t = ticks[c] + clock.dt / TIME_BASES[(bits[TIMEBASE_HI] << 1) | bits[TIMEBASE_LO]]
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


def make_ctr(bits: list[int], values: list[int], c: int, n: int) -> Callable[[int], None]:
    """Up-counter at C: C = RES; C+1 resets while 1; a rising edge of RES counts up to N; C+2 = done."""
    c1, c2 = c + 1, c + 2

    def ctr(res: int) -> None:
        rising = res and not bits[c]
        bits[c] = 1 if res else 0
        if bits[c1]:
            values[c] = 0
            bits[c2] = 0
            return
        cur = values[c]
        if rising and cur < n:
            cur += 1
            values[c] = cur
        bits[c2] = 1 if cur >= n else 0

    return ctr


# The same two instructions as source lines for the compiled program (netplc/compiler.py), which
# runs the first list when RES is 1 and the second when it is 0. They see the bit array as `b`, the
# current values as `tk` and `cv`, the engine (dt) as `eng`, TIME_BASES as `TB`, locals _t _v _q.
# A TIM's elapsed ticks `_q` are computed by QUOTIENT, which the compiler places before the TIM and
# reuses for later TIMs until something may have written a TIME_BASE_BITS bit (or called out).

TIME_BASE_BITS = (TIMEBASE_LO, TIMEBASE_HI)
QUOTIENT = f"_q = eng.dt / TB[(b[{TIMEBASE_HI}] << 1) | b[{TIMEBASE_LO}]]"


def tim_lines(c: int, n: int) -> tuple[list[str], list[str]]:
    """`make_tim`'s timer, written out (the same float operations: dt / base, then the sum).

    Bits hold 0 or 1, so where bit C is found 1 it is not stored again.
    """
    c1 = c + 1
    on = [f"if b[{c}]:",
          f"    _t = tk[{c}] + _q",
          f"    if _t > {float(n)!r}:",  # float to float: CPython compares these faster
          f"        _t = {float(n)!r}",
          f"    tk[{c}] = _t",
          f"    b[{c1}] = _t >= {n - _EPS!r}",
          "else:",  # the timer starts on this scan
          f"    tk[{c}] = 0.0",
          f"    b[{c1}] = {int(n - _EPS <= 0.0)}",
          f"    b[{c}] = 1"]
    return on, [f"tk[{c}] = 0.0", f"b[{c}] = 0", f"b[{c1}] = 0"]


def ctr_lines(c: int, n: int) -> tuple[list[str], list[str]]:
    """`make_ctr`'s counter, written out (a rising edge is RES 1 while bit C was 0)."""
    c1, c2 = c + 1, c + 2
    reset = [f"if b[{c1}]:", f"    cv[{c}] = 0", f"    b[{c2}] = 0", "else:"]
    on = [f"if b[{c}]:",  # no edge (bits hold 0 or 1: bit C stays 1)
          *("    " + line for line in reset),
          f"        b[{c2}] = cv[{c}] >= {n}",
          "else:",
          f"    b[{c}] = 1",
          *("    " + line for line in reset),
          f"        _v = cv[{c}]",
          f"        if _v < {n}:",
          "            _v += 1",
          f"            cv[{c}] = _v",
          f"        b[{c2}] = _v >= {n}"]
    return on, [f"b[{c}] = 0", *reset, f"    b[{c2}] = cv[{c}] >= {n}"]


def held(tim: list[float], ctr: list[int]) -> tuple[dict[int, float], dict[int, int]]:
    """The non-zero timer and counter current values by coil address: what a save needs to keep."""
    return {c: v for c, v in enumerate(tim) if v}, {c: v for c, v in enumerate(ctr) if v}


def update_generators(bits: list[int], elapsed: float) -> None:
    """03750-03757: square waves of period 0.1 s * 2**k, 50 % duty, from the engine clock."""
    halves = int(elapsed * 20 + _EPS)  # number of 0.05 s half-periods of the fastest generator
    for k in range(8):
        bits[GEN_BASE + k] = (halves >> k) & 1
