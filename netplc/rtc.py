"""The CPU-165 real-time clock in data bytes 077700-077707 (BCD).

The program sets the clock by the documented sequence: write non-zero to 077700, write the new
time to 077701-077707, write 0 to 077700. NetPlc never touches the PC's clock: it keeps the
difference as an offset and shows wall time plus offset from then on. The control byte is watched
after each queued operator write and after the program, so the sequence may be spread over scans
or sent as one batch of operator writes; the new time is taken at the start of the scan after the
control byte returns to 0.
"""

from __future__ import annotations

import datetime as dt
import logging
import math

from netplc.address import RTC_CONTROL, RTC_FIRST, data_index
from netplc.memory import Memory

logger = logging.getLogger(__name__)

_CTRL = data_index(RTC_CONTROL)
_FIRST = data_index(RTC_FIRST)


def to_bcd(v: int) -> int:
    return ((v // 10) << 4) | (v % 10)


def from_bcd(b: int) -> int:
    return (b >> 4) * 10 + (b & 0x0F)


class Rtc:
    def __init__(self) -> None:
        self.offset = 0.0  # seconds added to the wall clock
        self._setting = False
        # The BCD bytes of the current second: the clock shows seconds, so the calendar is worked
        # out once a second rather than every scan (it costs more than the rest of the scan set-up).
        self._second: int | None = None
        self._bcd = b""

    def update(self, mem: Memory, wall: float) -> None:
        """Called once per scan before the program runs."""
        data = mem.data
        if data[_CTRL]:
            self._setting = True
            return
        if self._setting:
            self._setting = False
            self._take_setting(data, wall)
        shown = wall + self.offset
        second = math.floor(shown)
        if second != self._second:
            self._second = second
            t = dt.datetime.fromtimestamp(shown)
            fields = (t.second, t.minute, t.hour, t.day, t.month, t.year % 100, (t.weekday() + 1) % 7)
            self._bcd = bytes(to_bcd(v) for v in fields)
        data[_FIRST:_FIRST + len(self._bcd)] = self._bcd

    def watch(self, mem: Memory) -> None:
        """Note a setting in progress (control byte non-zero) between the points update() runs."""
        if mem.data[_CTRL]:
            self._setting = True

    def now(self, wall: float) -> dt.datetime:
        return dt.datetime.fromtimestamp(wall + self.offset)

    def _take_setting(self, data: bytearray, wall: float) -> None:
        s, mi, h, d, mo, y = (from_bcd(data[_FIRST + i]) for i in range(6))
        try:
            wanted = dt.datetime(2000 + y, mo, d, h, mi, s)
        except ValueError as e:  # an impossible date: keep the clock as it was
            logger.warning("RTC setting ignored: 20%02d-%02d-%02d %02d:%02d:%02d: %s", y, mo, d, h, mi, s, e)
            return
        self.offset = wanted.timestamp() - wall
