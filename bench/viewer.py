"""Viewer: how long the window stops answering while a big series is ticked.

One day of a 10 Hz NSTORE of one source (864,000 records) goes into an archive through the real
Store. The viewer opens it offscreen and the series is ticked, as an operator's click does; a 10 ms
QTimer stands for the operator, and the longest gap between its ticks is how long the window did
not answer (repaint, a click). Printed beside it: the time to the curve, and what the same read
takes on the GUI thread (the stall if it were read there).

    QT_QPA_PLATFORM=offscreen python bench/viewer.py [records]
"""

from __future__ import annotations

import datetime as dt
import itertools
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from archive import DAY, write
from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QApplication

from app.gui.viewer import SERIES_POINTS, ViewerWindow
from netplc.records import Record
from registrar.query import Archive

RUNS = 3


def records(n: int) -> list[Record]:
    start = dt.datetime(DAY.year, DAY.month, DAY.day).timestamp()
    step = 86_000 / n
    return [Record(start + i * step, "data", 1, 1, "04010", value=float(i % 4096)) for i in range(n)]


def tick_and_wait(app: QApplication, viewer: ViewerWindow) -> tuple[float, float]:
    """Seconds from the tick to the curve, and the longest gap between two 10 ms timer ticks."""
    viewer.series_list.item(0).setCheckState(Qt.CheckState.Unchecked)  # start from no curve
    beats: list[float] = []
    timer = QTimer()
    timer.setInterval(10)
    timer.timeout.connect(lambda: beats.append(time.perf_counter()))
    timer.start()
    t0 = time.perf_counter()
    beats.append(t0)
    viewer.check_series(0)
    deadline = t0 + 60
    while (viewer.loading or not viewer.curves) and time.perf_counter() < deadline:
        app.processEvents()
        time.sleep(0.001)
    done = time.perf_counter()
    timer.stop()
    if not viewer.curves:
        raise SystemExit(f"the series did not arrive within a minute: {viewer.statusBar().currentMessage()}")
    beats.append(done)
    return done - t0, max(b - a for a, b in itertools.pairwise(beats))


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 864_000
    app = QApplication.instance() or QApplication([])
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "journal.sqlite"
        write(path, records(n))
        with Archive(path) as archive:
            t0 = time.perf_counter()
            ts, _ = archive.series(DAY, grp=1, type=1, source="04010", points=SERIES_POINTS)
            direct = time.perf_counter() - t0
        viewer = ViewerWindow(path)
        viewer.show()
        for row in range(viewer.days.count()):
            if viewer.days.item(row).data(Qt.ItemDataRole.UserRole) == DAY:
                viewer.days.setCurrentRow(row)
        viewer.tabs.setCurrentIndex(1)
        runs = [tick_and_wait(app, viewer) for _ in range(RUNS)]
        viewer.close()
    print(f"viewer series of {n:,} records -> {len(ts):,} points: read on the GUI thread it would "
          f"stall the window {direct * 1000:.0f} ms")
    curve, stall = statistics.median(r[0] for r in runs), max(r[1] for r in runs)
    print(f"viewer series, read by the loader thread: curve after {curve * 1000:.0f} ms; longest the "
          f"window did not answer {stall * 1000:.0f} ms (worst of {RUNS})  target < 100 ms")


if __name__ == "__main__":
    main()
