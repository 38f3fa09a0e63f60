"""Function behaviour beyond the manual's examples: error flags, indirect addresses, and the
decisions taken where the manual is silent (each function's docstring states them)."""

from __future__ import annotations

import pytest

from netplc.address import FERR1, FERR2
from netplc.engine import Engine, FakeClock
from netplc.program import parse
from netplc.records import ListSink

C = 0o3000


def engine_for(fon: str, rung: str = "$03760", **kw: object) -> Engine:
    """An engine running `TNA rung` + `FON C:$03000 <fon>` on a FakeClock."""
    program = parse(f"TNA {rung}\nFON C:$03000 {fon}\n", source="t.stl")
    return Engine(program, clock=FakeClock(0.0), wallclock=lambda: 0.0, sink=ListSink(), **kw)


def scan(engine: Engine, n: int = 1, dt: float = 0.1) -> None:
    for _ in range(n):
        engine.clock.advance(dt)  # type: ignore[attr-defined]
        engine.scan()


def data_unchanged(engine: Engine, before: bytes) -> bool:
    """Data memory is as before, apart from the RTC bytes the engine keeps current."""
    rtc = slice(len(before) - 0o100, len(before) - 0o70)  # 077700-077707 in the flat array
    now = bytearray(engine.mem.data)
    now[rtc] = before[rtc]
    return bytes(now) == before


# --- errors: FErr1 and nothing written -----------------------------------------------------------


@pytest.mark.parametrize(
    ("fon", "words"),
    [
        ("N:STM S:$04000 D:$04002", {0o4000: 0x1234, 0o4002: 0o10000}),  # pointer into a gap
        ("N:STM S:$04000 D:$04002", {0o4000: 0x1234, 0o4002: 0o7777}),  # word runs off its bank
        ("N:LDM S:$04002 D:$04000", {0o4002: 0o120000}),  # above 077777
        ("N:MVM S:$04000 D:$04002", {0o4000: 0o4010, 0o4002: 0o13776}),
        ("N:MVM S:$04000 D:$04002", {0o4000: 0o11000, 0o4002: 0o4010}),
        ("N:MVMBLK S:$04000 D:$04002 R:$04004", {0o4000: 0o4000, 0o4002: 0o7770, 0o4004: 16}),
        ("N:MVMBLK S:$04000 D:$04002 R:$04004", {0o4000: 0o4000, 0o4002: 0o4100, 0o4004: 257}),
        ("N:WBCD S:$04000 D:$04002", {0o4000: 10000}),
        ("N:BCDW S:$04000 D:$04002", {0o4000: 0x12A4}),
        ("N:ADDBCD S:$04000 D:$04002 R:$04004", {0o4000: 0x1234, 0o4002: 0x00F0}),
        ("N:SUBBCD S:$04000 D:$04002 R:$04004", {0o4000: 0xA000, 0o4002: 0x0001}),
        ("N:DIV S:$04000 D:$04002 R:$04004", {0o4000: 100, 0o4002: 0x0100}),  # divisor byte is 0
        ("N:SCALE S:$04000 D:$04010 R:0", {0o4000: 100, 0o4012: 3, 0o4014: 0}),  # B = 0
        ("N:SCALE S:$04000 D:$04010 R:2", {0o4000: 100, 0o4012: 3, 0o4014: 1}),  # R not 0/1
        ("N:MOV S:$07777 D:$04000", {0o4000: 0x5555}),  # a word on the last byte of a bank
        ("N:MOVBLK S:$04000 D:$04400 R:$05000", {}),  # 257 bytes
        ("N:MOVBLK S:$04010 D:$04000 R:$05000", {}),  # end before start
        ("N:PUSH S:$04000 D:$04100", {0o4000: 0x11}),  # 65 bytes
        ("N:PUSH S:$07770 D:$14007", {}),  # spans two banks
        ("N:POP S:$04010 D:$04000 R:$04020", {}),  # start above end
        ("N:SHFTBLK S:$04000 D:$04100", {}),  # 65 bytes
        ("N:BMASK S:$04000 D:400 R:0", {}),  # mask wider than a byte
        ("N:TGRP S:050", {}),  # more than 32 timers
        ("N:TGRP S:0", {}),
        ("N:MATH S:$04000 D:$04002 R:1", {0o4000: 5, 0o4002: 7}),
        ("N:NSYNC S:0 D:0", {}),
        ("N:PID S:1 D:5", {}),  # formula above 4
        ("N:ERCODE S:$04000 D:$02000", {0o4000: 3}),  # indicator must be an external bit
        ("N:NMOVW S:$07700 D:$04000 R:100", {}),  # 200 bytes run past the end of bank 0
        ("N:NMOVB S:$04000 D:$03770 R:2", {}),  # 16 bits from 03770 run past bit 03777
        ("N:NAVG S:$04000 D:$07776", {0o4000: 7}),  # the count word D+2 is outside the bank
    ],
)
def test_error_sets_ferr1_and_writes_nothing(fon: str, words: dict[int, int]) -> None:
    e = engine_for(fon)
    for a, v in words.items():
        e.mem.set_word(a, v)
    before = bytes(e.mem.data)
    scan(e, 2)
    assert e.mem.bits[FERR1] == 1
    assert data_unchanged(e, before)
    assert not any(e.mem.bits[C + 1 : C + 4])


def test_nstore_of_an_invalid_word_sets_ferr1_and_records_nothing() -> None:
    e = engine_for("N:NSTORE S:$07777 D:1 R:0")
    scan(e)
    assert e.mem.bits[FERR1] == 1
    assert e.sink.records == []  # type: ignore[attr-defined]


def test_ferr1_is_sticky_until_the_program_clears_it() -> None:
    e = engine_for("N:WBCD S:$04000 D:$04002")
    e.mem.set_word(0o4000, 10000)
    scan(e)
    e.mem.set_word(0o4000, 1234)
    scan(e)
    assert e.mem.get_word(0o4002) == 0x1234
    assert e.mem.bits[FERR1] == 1


def test_unsupported_hardware_function_loads_runs_and_sets_ferr1() -> None:
    text = (
        "TNA $02000\nFON C:$03000 N:READ S:17 D:$04000 R:$04010\n"
        "TNA $03760\nFON C:$03010 N:ADD S:$04020 D:$04022 R:$04024\n"
    )
    e = Engine(parse(text), clock=FakeClock(0.0), sink=ListSink())
    e.mem.set_word(0o4020, 2)
    e.mem.set_word(0o4022, 3)
    scan(e)
    assert e.mem.bits[FERR1] == 0  # READ's rung is off: it does not execute
    e.mem.bits[0o2000] = 1
    before = bytes(e.mem.data)
    scan(e, 3)
    assert e.mem.bits[FERR1] == 1
    assert e.mem.get_word(0o4024) == 5  # the rest of the program keeps running
    assert data_unchanged(e, before)
    assert e.state_text == "running"


@pytest.mark.parametrize("fn", ["WRITE S:$04000 D:17 R:3", "MVAMOD S:$04000 D:17 R:3",
                                "MVASET S:$04000 D:17", "MVARD S:17 D:$04000",
                                "ADCWR S:6315 D:3146 R:12336", "ADCRD S:$04030 D:17 R:176"])
def test_every_module_function_sets_ferr1(fn: str) -> None:
    e = engine_for("N:" + fn)
    scan(e)
    assert e.mem.bits[FERR1] == 1


# --- decisions where the manual is silent ------------------------------------------------------


def test_subbcd_negative_result_stores_the_tens_complement_with_borrow() -> None:
    e = engine_for("N:SUBBCD S:$04000 D:$04002 R:$04004")
    e.mem.set_word(0o4000, 0x1234)
    e.mem.set_word(0o4002, 0x5555)
    scan(e)
    assert e.mem.get_word(0o4004) == 0x5679
    assert (e.mem.bits[C + 1], e.mem.bits[C + 2]) == (1, 0)


def test_addbcd_zero_flag_follows_the_stored_digits() -> None:
    e = engine_for("N:ADDBCD S:$04000 D:$04002 R:$04004")
    e.mem.set_word(0o4000, 0x5000)
    e.mem.set_word(0o4002, 0x5000)
    scan(e)
    assert e.mem.get_word(0o4004) == 0
    assert (e.mem.bits[C + 1], e.mem.bits[C + 2]) == (1, 1)


def test_add_carry_and_zero() -> None:
    e = engine_for("N:ADD S:$04000 D:$04002 R:$04004")
    e.mem.set_word(0o4000, 0xFFFF)
    e.mem.set_word(0o4002, 1)
    scan(e)
    assert e.mem.get_word(0o4004) == 0
    assert (e.mem.bits[C + 1], e.mem.bits[C + 2]) == (1, 1)


def test_decod_of_zero_keeps_d_and_sets_z_and_takes_the_highest_bit() -> None:
    e = engine_for("N:DECOD S:$04000 D:$04002")
    e.mem.set_byte(0o4002, 0x77)
    scan(e)
    assert (e.mem.get_byte(0o4002), e.mem.bits[C + 1]) == (0x77, 1)
    e.mem.set_word(0o4000, 0x0104)
    scan(e)
    assert (e.mem.get_byte(0o4002), e.mem.bits[C + 1]) == (8, 0)


def test_push_of_a_zero_byte_does_nothing() -> None:
    e = engine_for("N:PUSH S:$04000 D:$04003")
    e.mem.write(0o4000, bytes([0, 1, 2, 3]))
    scan(e)
    assert e.mem.read(0o4000, 4) == bytes([0, 1, 2, 3])


def test_push_then_pop_is_last_in_first_out_and_level_triggered() -> None:
    e = engine_for("N:PUSH S:$04000 D:$04003", rung="$02000")
    e.mem.write(0o4000, bytes([0x44, 0, 0, 0]))
    e.mem.bits[0o2000] = 1
    scan(e)  # a second scan would push 0: nothing
    scan(e)
    assert e.mem.read(0o4000, 4) == bytes([0, 0, 0, 0x44])


def test_shftblk_towards_lower_addresses() -> None:
    e = engine_for("N:SHFTBLK S:$04003 D:$04000")
    e.mem.write(0o4000, bytes([1, 2, 3, 4, 5]))
    scan(e)
    assert e.mem.read(0o4000, 5) == bytes([2, 3, 4, 0, 5])


def test_scale_saturates_and_raises_ferr2() -> None:
    e = engine_for("N:SCALE S:$04000 D:$04010 R:1")
    e.mem.set_word(0o4000, 1)
    e.mem.set_word(0o4012, 1)
    e.mem.set_word(0o4014, 1)
    e.mem.set_word(0o4016, 5)
    scan(e)
    assert (e.mem.get_word(0o4010), e.mem.bits[FERR2], e.mem.bits[FERR1]) == (0, 1, 0)


def test_scale_keeps_precision_of_a_fraction() -> None:
    e = engine_for("N:SCALE S:$04000 D:$04010 R:0")
    for a, v in ((0o4000, 1000), (0o4012, 1), (0o4014, 3), (0o4016, 7)):
        e.mem.set_word(a, v)
    scan(e)
    assert e.mem.get_word(0o4010) == 333 + 7


def test_incw_overflow_flag_on_wrap() -> None:
    e = engine_for("N:INCW S:$04000 D:$04010")
    e.mem.set_word(0o4000, 5)
    e.mem.set_word(0o4010, 0xFFFF)
    scan(e)
    assert (e.mem.get_word(0o4010), e.mem.bits[C + 1], e.mem.bits[C + 2]) == (0, 1, 0)


def test_incw_is_level_triggered_like_every_fon() -> None:
    e = engine_for("N:INCW S:$04000 D:$04010")
    scan(e, 5)
    assert e.mem.get_word(0o4010) == 5


def test_timset_writes_n_setpoints_and_refuses_overflow() -> None:
    e = engine_for("N:TIMSET S:$04000 D:$07600 R:202")  # 1 s base, 3 timers
    e.mem.set_word(0o4004, 90)
    scan(e)
    assert [e.mem.get_word(0o7600 + 2 * k) for k in range(4)] == [90, 90, 90, 0]
    e2 = engine_for("N:TIMSET S:$04000 D:$07600 R:0")  # 0.01 s base: 1000 s does not fit
    e2.mem.set_word(0o4004, 1000)
    scan(e2)
    assert (e2.mem.get_word(0o7600), e2.mem.bits[FERR1]) == (0, 1)


def test_tgrp_pauses_when_disabled_early_and_resets_when_disabled_after_done() -> None:
    e = engine_for("N:TGRP S:010")
    e.mem.set_word(0o7660, 20)  # timer 0: 2.0 s
    e.mem.bits[0o3660] = 1
    scan(e, 11)  # first scan starts the clock, then 10 x 0.1 s
    assert e.mem.get_word(0o7760) == 10
    e.mem.bits[0o3660] = 0
    scan(e, 5)
    assert e.mem.get_word(0o7760) == 10  # paused
    e.mem.bits[0o3660] = 1
    scan(e, 12)
    assert (e.mem.get_word(0o7760), e.mem.bits[0o3661]) == (20, 1)  # never above the setpoint
    e.mem.set_word(0o7660, 30)  # raising the setpoint clears done and counting continues
    scan(e)
    assert (e.mem.get_word(0o7760), e.mem.bits[0o3661]) == (21, 0)
    scan(e, 9)
    e.mem.bits[0o3660] = 0
    scan(e)
    assert (e.mem.get_word(0o7760), e.mem.bits[0o3661]) == (0, 0)  # done and disabled: reset


def test_tgrp_group_sizes_round_up_to_eight() -> None:
    e = engine_for("N:TGRP S:011")  # 9 timers -> 16: timer 0 in slot 16
    e.mem.set_word(0o7640, 5)
    e.mem.bits[0o3640] = 1
    scan(e, 6)
    assert e.mem.get_word(0o7740) == 5


def test_tgrp2_base_stop_bits_and_current_values_above_setpoints() -> None:
    # 2 timers, 1 s base, with stop; setpoints 07400/07402, current 07500/07502, STOP bits 02100..
    e = engine_for("N:TGRP2 S:$07400 D:$02100 R:1201")
    e.mem.set_word(0o7400, 3)
    e.mem.set_word(0o7402, 3)
    e.mem.bits[0o2101] = 1  # timer 1 stopped
    scan(e, 1)
    scan(e, 2, dt=1.0)
    assert (e.mem.get_word(0o7500), e.mem.get_word(0o7502)) == (2, 0)
    scan(e, 5, dt=1.0)
    assert e.mem.get_word(0o7500) == 3  # stays at its setpoint
    e.mem.bits[0o2100] = 1  # stop after done: reset
    scan(e, 1, dt=1.0)
    assert e.mem.get_word(0o7500) == 0


def test_tgrp2_stop_bits_in_data_memory_and_timfix_reads_its_values() -> None:
    text = ("TNA $03760\nFON C:$03000 N:TGRP2 S:$07400 D:$04000 R:1100\n"
            "TNA $03760\nFON C:$03010 N:TIMFIX S:$07500 D:$04010 R:100\n")  # 0.1 s base, 1 timer
    e = Engine(parse(text), clock=FakeClock(0.0), sink=ListSink())
    e.mem.set_word(0o7400, 36015)  # 1 h 0 min 1.5 s
    scan(e, 1)
    scan(e, 1, dt=3601.5)
    assert [e.mem.get_word(0o4010 + 2 * k) for k in range(4)] == [1, 0, 1, 5]
    e.mem.set_byte(0o4000, 1)  # STOP bit 0 = bit 0 of byte 04000
    scan(e, 1)
    assert e.mem.get_word(0o7500) == 0


def test_ercode_goes_dark_when_the_code_clears() -> None:
    e = engine_for("N:ERCODE S:$04000 D:$01000")
    e.mem.set_byte(0o4000, 1)
    scan(e)
    assert e.mem.bits[0o1000] == 1
    e.mem.set_byte(0o4000, 0)
    scan(e)
    assert e.mem.bits[0o1000] == 0


# --- PID -------------------------------------------------------------------------------------------

PID0 = 0o74000


def pid_engine(formula: int, **words: int) -> Engine:
    e = engine_for(f"N:PID S:1 D:{formula:o}")
    defaults = {"KP": 2, "KP_DIV": 1, "TR": 10, "TR_DIV": 1, "TD": 0, "TD_DIV": 1, "XMIN": 0,
                "XMAX": 1000, "SV": 500, "PV": 400, "XOUT": 0}
    offsets = {"KP": 0, "KP_DIV": 2, "TR": 4, "TR_DIV": 6, "TD": 0o10, "TD_DIV": 0o12, "XMIN": 0o14,
               "XMAX": 0o16, "SV": 0o26, "PV": 0o30, "XOUT": 0o40, "FILTER": 0o34, "DEADZONE": 0o36}
    for name, v in {**defaults, **words}.items():
        e.mem.set_word(PID0 + offsets[name], v)
    return e


def test_pid_first_execution_initialises_then_pi_acts() -> None:
    e = pid_engine(3)
    scan(e)
    assert e.mem.get_word(PID0 + 0o42) == 100  # error = SV - PV
    assert e.mem.get_word(PID0 + 0o40) == 0  # no output on the initialising execution
    assert e.mem.bits[0o3740] == 1 and e.mem.bits[0o3720] == 0
    scan(e, 1, dt=1.0)  # ITERM += KP*e*dt/TR = 20; XOUT = KP*e + ITERM = 220
    assert (e.mem.get_word(PID0 + 0o40), e.mem.get_word(PID0 + 0o44)) == (220, 20)
    scan(e, 1, dt=1.0)
    assert e.mem.get_word(PID0 + 0o40) == 240


def test_pid_output_is_clamped_and_the_integral_does_not_wind_up() -> None:
    e = pid_engine(3, XMAX=210)
    scan(e)
    scan(e, 5, dt=1.0)
    assert e.mem.get_word(PID0 + 0o40) == 210
    iterm = e.mem.get_word(PID0 + 0o44)
    assert iterm <= 20


def test_pid_formula_2_is_incremental() -> None:
    e = pid_engine(2, TR=0)  # Q0 = KP, Q1 = -KP, Q2 = 0: XOUT = U1 + KP*(e - e1)
    e.mem.set_word(PID0 + 0o40, 100)
    scan(e)
    e.mem.set_word(PID0 + 0o30, 390)  # error 110
    scan(e, 1, dt=1.0)
    assert e.mem.get_word(PID0 + 0o40) == 100 + 2 * 110 - 2 * 100


def test_pid_k_bit_restarts_from_the_initial_iterm() -> None:
    e = pid_engine(3)
    scan(e)
    scan(e, 3, dt=1.0)
    e.mem.bits[0o3730] = 1
    scan(e, 1, dt=1.0)
    assert e.mem.bits[0o3730] == 0
    assert e.mem.get_word(PID0 + 0o44) == 0


def test_pid_setup_errors_are_reported_per_regulator() -> None:
    e = pid_engine(0, KP_DIV=0)
    scan(e)
    assert e.mem.get_word(PID0 + 0o50) == 1
    assert (e.mem.bits[0o3720], e.mem.bits[0o3740], e.mem.bits[FERR1]) == (1, 0, 1)
    pwm = pid_engine(0o100)
    scan(pwm)
    assert pwm.mem.get_word(PID0 + 0o50) == 8


def test_pid_disabled_regulators_are_untouched() -> None:
    e = pid_engine(3)
    e.mem.set_word(PID0 + 0o100 + 0o26, 900)  # regulator 1, not enabled by S=1
    scan(e, 3)
    assert e.mem.get_word(PID0 + 0o100 + 0o42) == 0
    assert e.mem.bits[0o3741] == 0


def test_pid_dead_zone_and_filter() -> None:
    e = pid_engine(3, DEADZONE=150)
    scan(e)
    assert e.mem.get_word(PID0 + 0o42) == 0
    f = pid_engine(3, FILTER=50)
    scan(f)
    f.mem.set_word(PID0 + 0o30, 300)  # raw error 200, filtered (200-100)*0.5+100 = 150
    scan(f, 1, dt=1.0)
    assert f.mem.get_word(PID0 + 0o42) == 150
