"""The RTC bytes 077700-077707: BCD time from the wall clock, and the documented setting sequence
(write 1 to 077700, the new time to 077701-077707, then 0 to 077700)."""

from __future__ import annotations

import datetime as dt

import pytest

from netplc.functions.registry import lookup
from netplc.rtc import from_bcd, to_bcd
from tests.netplc.test_core_support import BOTH, ENGINE_IDS, Rig

WALL = dt.datetime(2026, 3, 14, 15, 9, 26).timestamp()  # a Saturday, local time
NEW_TIME = bytes([0x30, 0x45, 0x07, 0x01, 0x12, 0x25, 0x01])  # 07:45:30 on 1 Dec 2025 (a Monday)


def rtc(rig: Rig) -> bytes:
    return rig.engine.mem.read(0o77701, 7)


def test_bcd_conversion():
    assert to_bcd(59) == 0x59 and to_bcd(0) == 0 and from_bcd(0x23) == 23
    assert all(from_bcd(to_bcd(v)) == v for v in range(100))


@pytest.mark.parametrize("compiled", BOTH, ids=ENGINE_IDS)
def test_rtc_bytes_follow_the_wall_clock_in_bcd(compiled):
    rig = Rig("NOP", compiled, wall=WALL)
    rig.step(1.0)  # the wall clock moves with the step: 15:09:27
    assert rtc(rig) == bytes([0x27, 0x09, 0x15, 0x14, 0x03, 0x26, 0x06])  # Sunday = 0, Saturday = 6
    assert rig.engine.mem.get_byte(0o77700) == 0
    rig.step(34.0)
    assert rtc(rig)[:3] == bytes([0x01, 0x10, 0x15])


def test_rtc_bytes_change_on_the_second_and_a_program_overwrite_lasts_one_scan():
    rig = Rig("NOP", wall=WALL + 0.5)  # 15:09:26.5
    rig.step(0.4)
    assert rtc(rig)[0] == 0x26
    rig.engine.mem.set_byte(0o77701, 0x99)  # a program or operator scribbling on the seconds
    rig.step(0.05)  # 15:09:26.95: the same second, the bytes are rewritten all the same
    assert rtc(rig)[0] == 0x26
    rig.step(0.1)  # 15:09:27.05
    assert rtc(rig)[0] == 0x27


def test_setting_over_several_scans_as_documented():
    rig = Rig("NOP", wall=WALL)
    mem = rig.engine.mem
    rig.step(1.0)
    mem.set_byte(0o77700, 1)
    rig.step(1.0)
    mem.write(0o77701, NEW_TIME)
    rig.step(1.0)
    assert rtc(rig) == NEW_TIME  # frozen while the control byte is set
    mem.set_byte(0o77700, 0)
    rig.step(1.0)  # taken at the start of this scan, one second has passed since
    assert rtc(rig) == NEW_TIME  # the new time, as written
    rig.step(10.0)
    assert rtc(rig)[:3] == bytes([0x40, 0x45, 0x07])  # and it runs on from there
    assert rtc(rig)[3:] == NEW_TIME[3:]


def test_setting_with_one_batch_of_operator_writes():
    rig = Rig("NOP", wall=WALL)
    rig.step(1.0)
    rig.engine.write_bytes(0o77700, b"\x01")
    rig.engine.write_bytes(0o77701, NEW_TIME)
    rig.engine.write_bytes(0o77700, b"\x00")
    rig.step(1.0)
    assert rtc(rig) == NEW_TIME


SET_CLOCK = """
TNA $00000
FON C:$03000 N:MOVB S:$04001 D:$077700   ; control byte = 1
TNA $00001
FON C:$03004 N:MVIBCD S:4530 D:$077701   ; seconds, minutes
TNA $00001
FON C:$03010 N:MVIBCD S:0107 D:$077703   ; hours, day
TNA $00001
FON C:$03014 N:MVIBCD S:2512 D:$077705   ; month, year
TNA $00001
FON C:$03020 N:MOVB S:$04001 D:$077707   ; weekday
TNA $00002
FON C:$03024 N:MOVB S:$04000 D:$077700   ; control byte = 0
"""


@pytest.mark.parametrize("compiled", BOTH, ids=ENGINE_IDS)
def test_setting_by_the_program_across_scans(compiled):
    assert lookup("MOVB") is not None and lookup("MVIBCD") is not None  # a failed import must show
    rig = Rig(SET_CLOCK, compiled, wall=WALL)
    rig.engine.mem.set_byte(0o4001, 1)
    rig.step(1.0, b00000=1)
    rig.step(1.0, b00000=0, b00001=1)
    assert rtc(rig) == NEW_TIME
    rig.step(1.0, b00001=0, b00002=1)
    rig.step(1.0, b00002=0)
    assert rtc(rig) == NEW_TIME  # taken at the start of the scan after the control byte fell
    rig.step(5.0)
    assert rtc(rig)[0] == 0x35


def test_an_impossible_date_keeps_the_clock():
    rig = Rig("NOP", wall=WALL)
    rig.step(1.0)
    rig.engine.write_bytes(0o77700, b"\x01")
    rig.engine.write_bytes(0o77701, bytes([0x00, 0x00, 0x00, 0x31, 0x02, 0x26, 0x00]))  # 31 February
    rig.engine.write_bytes(0o77700, b"\x00")
    rig.step(1.0)
    assert rtc(rig)[:3] == bytes([0x28, 0x09, 0x15])
