"""Guards the PySide6 pin: 6.12.0 loses a reference to None or True on every Python slot call or
signal emit, and on Python 3.11 (where they are not immortal) the process aborts after a few
minutes of a 100 ms refresh timer. This fails fast if such a binding is installed."""

import sys

import pytest
from PySide6.QtCore import QObject, Signal

pytestmark = pytest.mark.skipif(sys.version_info >= (3, 12), reason="None/True are immortal on 3.12+")


class _Emitter(QObject):
    changed = Signal(int)


def test_slot_calls_and_emits_keep_none_and_true_alive(qapp):
    emitter = _Emitter()
    seen: list[int] = []
    emitter.changed.connect(lambda v: seen.append(v))
    before = sys.getrefcount(None), sys.getrefcount(True)
    for i in range(500):
        emitter.changed.emit(i)
    after = sys.getrefcount(None), sys.getrefcount(True)
    assert len(seen) == 500
    assert after[0] - before[0] > -50, "the Qt binding leaks references to None"
    assert after[1] - before[1] > -50, "the Qt binding leaks references to True"
