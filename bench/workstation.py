"""The workstation on the demo station: CPU and memory over a run at 100 ms ticks, and the time
from start to the first drawn form.

Everything runs for real in this process (offscreen Qt at 1366x768): the runtime with its scan,
exchange, archive and the embedded node, and the window drawing the demo's forms. CPU is the
process's CPU time (all threads) over wall time, in % of one core; memory is the resident set,
sampled after a warm-up and at the end. Yardsticks from the same run: the headless runtime alone
for the same time (what the window adds is the difference), and a bare QMainWindow with a label
shown (what the first drawn form costs beyond Qt's own start).

Then each of the demo's forms is shown in turn (`--form-seconds` each) and every turn of the event
loop is timed: one turn holds a tick's refresh of the forms, or the paint that follows it, or the
trends' redraw once a second, so the longest turn is the longest the console stalls (target: no
turn over 50 ms, half a tick). On a loaded machine a turn's wall time is mostly waiting for a
core, so the GUI thread's CPU time in each turn is printed beside it: the work the console did.

The start is measured twice: in this process (station loaded, started, window built and drawn),
and from launching a fresh Python process to its first drawn form (imports included, as the
operator waits for them), beside a fresh process that shows a bare QMainWindow.

    QT_QPA_PLATFORM=offscreen python bench/workstation.py [--seconds 60 | --minutes 10]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PySide6.QtCore import QEvent, QObject
from PySide6.QtWidgets import QApplication, QLabel, QMainWindow

from app.gui.application import application
from app.gui.main_window import MainWindow
from app.gui.screenshots import copy_station
from app.station.config import load_station
from app.station.runtime import Runtime

SIZE = (1366, 768)
WARMUP = 10.0  # seconds before the memory baseline: caches, pixmaps and the trend buffers fill


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() / 1e6


def pump(app: QApplication, seconds: float, turns: list[tuple[float, float]] | None = None) -> None:
    """Run the event loop for `seconds`; each of its turns, wall time and the GUI thread's CPU time
    (ms), goes to `turns`."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        t0, c0 = time.perf_counter(), time.thread_time()
        app.processEvents()
        if turns is not None:
            turns.append(((time.perf_counter() - t0) * 1000, (time.thread_time() - c0) * 1000))
        time.sleep(0.005)


class FirstPaint(QObject):
    """When a widget was first painted."""

    def __init__(self) -> None:
        super().__init__()
        self.at: float | None = None

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.Paint and self.at is None:
            self.at = time.perf_counter()
        return False


def first_form(app: QApplication, folder: Path) -> tuple[float, Runtime, MainWindow]:
    """Seconds from nothing to the first form drawn with live data (station loaded and started,
    window built, a snapshot shown)."""
    t0 = time.perf_counter()
    runtime = Runtime(load_station(folder))
    runtime.start()
    window = MainWindow(runtime)
    window.resize(*SIZE)
    painted = FirstPaint()
    view = window.views[0]
    window.show()
    while view._last is None:  # the first snapshot has reached the form
        app.processEvents()
    view.installEventFilter(painted)
    view.update()
    while painted.at is None:
        app.processEvents()
    return painted.at - t0, runtime, window


def bare_window(app: QApplication) -> float:
    t0 = time.perf_counter()
    window = QMainWindow()
    label = QLabel("yardstick")
    window.setCentralWidget(label)
    window.resize(*SIZE)
    painted = FirstPaint()
    label.installEventFilter(painted)
    window.show()
    while painted.at is None:
        app.processEvents()
    window.close()
    return painted.at - t0


def launched(mode: str) -> float:
    """Seconds from launching a Python process to its first drawn window (`--child MODE T0`)."""
    t0 = time.time()
    out = subprocess.run([sys.executable, __file__, "--child", mode, repr(t0)], capture_output=True,
                         text=True, timeout=120, check=True).stdout
    return float(out.split()[-1])


def child(mode: str, t0: float) -> None:
    app = application()
    if mode == "bare":
        bare_window(app)
        print(time.time() - t0)
        return
    with tempfile.TemporaryDirectory() as tmp:
        _, runtime, window = first_form(app, copy_station(Path(tmp) / "station"))
        print(time.time() - t0, flush=True)
        window.close()
        runtime.stop()


def cpu_over(app: QApplication, seconds: float, samples: list[float] | None = None) -> float:
    """% of one core used by the whole process over `seconds` of the event loop; the resident
    memory at ten even steps of it goes to `samples` (is it flat, or still growing at the end?)."""
    c0, w0 = time.process_time(), time.monotonic()
    for _ in range(10):
        pump(app, seconds / 10)
        if samples is not None:
            samples.append(rss_mb())
    return 100 * (time.process_time() - c0) / (time.monotonic() - w0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="length of each measured run (default 60)")
    ap.add_argument("--minutes", type=float, help="the long run: length in minutes (10 for the acceptance)")
    ap.add_argument("--form-seconds", type=float, default=20.0, help="each form shown this long (default 20)")
    ap.add_argument("--child", nargs=2, metavar=("MODE", "T0"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        child(args.child[0], float(args.child[1]))
        return 0
    cold, cold_bare = launched("form"), launched("bare")
    seconds = args.minutes * 60 if args.minutes else args.seconds
    app = application()
    bare = bare_window(app)
    with tempfile.TemporaryDirectory() as tmp:
        headless = Runtime(load_station(copy_station(Path(tmp) / "headless")))
        headless.start()
        pump(app, WARMUP)
        base_cpu = cpu_over(app, min(seconds, 60.0))
        headless.stop()

        start, runtime, window = first_form(app, copy_station(Path(tmp) / "station"))
        try:
            pump(app, WARMUP)
            mem0 = rss_mb()
            samples: list[float] = []
            cpu = cpu_over(app, seconds, samples)
            mem1 = samples[-1]
            status = runtime.status()
            forms = []
            for i in range(window.tabs.count()):
                window.tabs.setCurrentIndex(i)
                pump(app, 1.0)
                turns: list[tuple[float, float]] = []
                pump(app, args.form_seconds, turns)
                forms.append((window.tabs.tabText(i), turns))
        finally:
            window.close()
            runtime.stop()
    print(f"launch of a fresh process to the first drawn form: {cold:.2f} s (to a bare QMainWindow: "
          f"{cold_bare:.2f} s, {cold / cold_bare:.1f}x)")
    print(f"in a running process, station start to the first drawn form: {start:.2f} s (a bare "
          f"QMainWindow: {bare:.3f} s)")
    print(f"workstation on the demo, {SIZE[0]}x{SIZE[1]}, {status.tick_ms} ms ticks, {seconds:.0f} s: "
          f"{cpu:.1f} % of one core (the headless runtime alone: {base_cpu:.1f} %, the window adds "
          f"{cpu - base_cpu:.1f} %); {status.scans} scans, {status.overruns} overruns")
    print(f"resident memory after {WARMUP:.0f} s warm-up {mem0:.1f} MB, after the run {mem1:.1f} MB "
          f"({mem1 - mem0:+.1f} MB); at each tenth of the run: "
          + " ".join(f"{m:.1f}" for m in samples))
    for name, turns in forms:
        walls, cpus = [w for w, _ in turns], [c for _, c in turns]
        print(f"form {name!r} shown {args.form_seconds:.0f} s, {len(turns)} turns of the event loop: "
              f"longest {max(walls):.1f} ms wall ({sum(w > 50 for w in walls)} over 50 ms), p99 "
              f"{statistics.quantiles(walls, n=100)[-1]:.1f} ms; GUI thread CPU in a turn: longest "
              f"{max(cpus):.1f} ms ({sum(c > 50 for c in cpus)} over 50 ms), p99 "
              f"{statistics.quantiles(cpus, n=100)[-1]:.1f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
