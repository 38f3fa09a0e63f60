"""Appendix 1 of the manual: off-delay, pulse former, RS trigger and the divide-by-two T trigger,
wired as the spec digest reads them (section 3.1/3.2), under both engines."""

from __future__ import annotations

import pytest

from netplc.address import TIMEBASE_HI, TIMEBASE_LO
from tests.netplc.test_core_support import BOTH, ENGINE_IDS, Rig

engines = pytest.mark.parametrize("compiled", BOTH, ids=ENGINE_IDS)
TIME_BASES = pytest.mark.parametrize(
    "lo, hi, base", [(0, 0, 0.01), (1, 0, 0.1), (0, 1, 1.0), (1, 1, 10.0)], ids=["0.01s", "0.1s", "1s", "10s"]
)

OFF_DELAY = """
Dinput = $00000
Delay  = $03000
Dout   = $02000
; the timer runs while the input is off; its end-of-count bit Delay[1] drops the output
TFA Dinput
TIM Delay N:{n}
TNA Dinput
TNO Dout
TFA Delay[1]
YON Dout
"""


@engines
@TIME_BASES
def test_off_delay_drops_the_output_n_ticks_after_the_input(compiled, lo, hi, base):
    n = 4
    rig = Rig(OFF_DELAY.format(n=n), compiled)
    rig.bits[TIMEBASE_LO], rig.bits[TIMEBASE_HI] = lo, hi
    dout = 0o2000
    rig.step(base, scans=2)
    assert rig.bit(dout) == 0
    rig.step(base, b00000=1)
    assert rig.bit(dout) == 1  # on together with the input
    rig.step(base, scans=3)
    assert rig.bit(dout) == 1
    rig.step(base, b00000=0)  # the input falls: the delay starts
    held = 0
    while rig.bit(dout):
        held += 1
        assert held <= n
        rig.step(base)
    assert held == n  # off N time-base ticks after the fall
    rig.step(base, scans=3)
    assert rig.bit(dout) == 0


@engines
def test_off_delay_ignores_bounce_shorter_than_the_delay(compiled):
    rig = Rig(OFF_DELAY.format(n=5), compiled)
    rig.step(0.1, b00000=1)
    for _ in range(6):  # chatter: off for 3 ticks, on for 1, never 5 ticks off in a row
        rig.step(0.1, scans=3, b00000=0)
        assert rig.bit(0o2000) == 1
        rig.step(0.1, b00000=1)
        assert rig.bit(0o2000) == 1
    rig.step(0.1, b00000=0)  # the fall that lasts: the timer starts at 0 ...
    rig.step(0.1, scans=4)
    assert rig.bit(0o2000) == 1
    rig.step(0.1)  # ... and ends 5 ticks later
    assert rig.bit(0o2000) == 0


PULSE_FORMER = """
Sig     = $00000
Form    = $03010
Formout = $02001
; the timer is started by Sig and holds itself (Form) until its end of count Form[1];
; it resets only once Sig is off, so a long input gives one pulse
TNA Sig
TNO Form
TFA Form[1]
TNO Sig
TIM Form N:{n}
TNA Form
TFA Form[1]
YON Formout
"""


@engines
@pytest.mark.parametrize("length", [1, 2, 5, 12], ids=lambda n: f"input {n} scans")
def test_pulse_former_output_always_lasts_the_set_time(compiled, length):
    n = 5
    rig = Rig(PULSE_FORMER.format(n=n), compiled)
    for _ in range(2):  # two pulses in a row: the former re-arms
        out = []
        for k in range(length + n + 3):
            rig.step(0.1, b00000=1 if k < length else 0)
            out.append(rig.bit(0o2001))
        assert out[0] == 1  # rises together with the input
        assert sum(out) == n and out[:n] == [1] * n  # exactly N ticks, whatever the input length


RS_TRIGGER = """
Set   = $00000
Reset = $00001
Ctr   = $02003
TNA Reset
YON Ctr[1]
TNA Set
CTR Ctr N:1
"""


@engines
def test_rs_trigger_on_a_counter(compiled):
    rig = Rig(RS_TRIGGER, compiled)
    q = 0o2005  # Ctr[2], the end-of-count output (the digest's resolution of the manual's Ctr[1])
    rig.step()
    assert rig.bit(q) == 0
    rig.step(b00000=1)
    assert rig.bit(q) == 1 and rig.engine.ctr_values[0o2003] == 1
    rig.step(b00000=0, scans=3)
    assert rig.bit(q) == 1  # remembers the set
    rig.step(b00001=1)
    assert rig.bit(q) == 0 and rig.engine.ctr_values[0o2003] == 0
    rig.step(b00001=0, scans=2)
    assert rig.bit(q) == 0  # remembers the reset
    rig.step(b00000=1)
    assert rig.bit(q) == 1


T_TRIGGER = """
TTC = $02042
TA  = $02003
TB  = $02010
TNA TTC
CTR TA N:1
TNA TB[2]
YON TA[1]
TNA TTC
CTR TB N:2
TNA TB[2]
YON TB[1]
"""


@engines
@pytest.mark.parametrize("high, low", [(2, 3), (3, 3), (5, 2), (4, 7)])
def test_t_trigger_divides_its_input_by_two(compiled, high, low):
    rig = Rig(T_TRIGGER, compiled)
    out, tb2_scans = [], 0
    for _pulse in range(8):
        for k in range(high + low):
            rig.step(0.1, b02042=1 if k < high else 0)
            tb2_scans += rig.bit(0o2012)
        out.append(rig.bit(0o2005))  # TA[2], the T-trigger output
    assert out == [1, 0] * 4  # 1 after pulses 1, 3, 5, ...; 0 after 2, 4, ...
    assert tb2_scans == 4  # TB[2] lasts one scan per two pulses
