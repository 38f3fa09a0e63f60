"""Keep PySide6 6.12.0 from crashing a long-running window on Python 3.11.

PySide6 6.12.0 drops one reference to None on every Python slot call (timers, clicks, any
signal) and one to True on every `Signal.emit()` from Python. Python 3.12 made these singletons
immortal, so the stray decrefs are harmless there; on 3.11 None's count (a few thousand) runs
out after a few minutes of a 100 ms timer and the process dies with "Fatal Python error:
none_dealloc". Giving the three singletons the huge reference count that 3.12 gives them makes
3.11 behave like 3.12: they are never deallocated in either case, so nothing else changes.
"""

from __future__ import annotations

import ctypes
import sys

IMMORTAL = 1 << 60


def make_singletons_immortal() -> None:
    if sys.version_info >= (3, 12) or sys.implementation.name != "cpython":
        return
    for obj in (None, True, False):
        count = ctypes.c_ssize_t.from_address(id(obj))
        if abs(count.value - sys.getrefcount(obj)) > 2:  # not the layout assumed: leave it alone
            return
        count.value = IMMORTAL
