"""The one QApplication of a window of ours, and Python's cyclic garbage collected on its thread.

Python collects cycles in whichever thread allocates when a threshold is crossed, and the scan,
exchange, archive and OPC UA threads allocate all the time. When a cycle freed there holds a Qt
object with running timers (the widgets of a closed form or dialog), Qt deletes it on that thread,
its timers stay registered with the GUI thread's dispatcher, and the next timer event reaches
freed memory: the process crashes in QApplication::notify (seen in the suite, under load). So
while a window of ours runs, automatic collection is off and the GUI thread collects, generation by
generation, at the thresholds Python itself uses.
"""

from __future__ import annotations

import gc
import sys

from PySide6.QtCore import QObject, QTimer
from PySide6.QtWidgets import QApplication

from app.gui.style import apply_style


class MainThreadCollector(QObject):
    """Collects on the thread it lives on (the GUI thread) every `interval_ms`; `stop()` hands
    collection back to Python."""

    def __init__(self, interval_ms: int = 100, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._threshold = gc.get_threshold()
        self._was_enabled = gc.isenabled()
        gc.disable()
        self._timer = QTimer(self)
        self._timer.timeout.connect(self.collect)
        self._timer.start(interval_ms)

    def collect(self) -> None:
        young, middle, old = gc.get_count()
        if young > self._threshold[0]:
            generation = 0
            if middle > self._threshold[1]:
                generation = 2 if old > self._threshold[2] else 1
            gc.collect(generation)

    def stop(self) -> None:
        self._timer.stop()
        gc.collect()
        if self._was_enabled:
            gc.enable()


def application() -> QApplication:
    """The running QApplication (made when there is none), styled, collecting on its thread."""
    app = QApplication.instance() or QApplication(sys.argv[:1])
    assert isinstance(app, QApplication)
    apply_style(app)
    if app.findChild(MainThreadCollector) is None:
        MainThreadCollector(parent=app)
    return app
