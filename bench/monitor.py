"""Scan time with the Program view open on a full 8 K-word program, against the same station with
the view closed, in the same run (the yardstick).

The station runs for real: bench/scan.py's generated 8 K-word program (about 5,000 lines) as its
NetPlc program, scanned by the runtime's scan thread on a 10 ms tick, while the GUI thread either
idles in the Qt event loop (closed) or shows the Program view at 1366x768 (offscreen) with five
watched words, refreshing at its 10 Hz and painting the visible lines of a FON-rich part of the
listing. The two phases alternate in short rounds, so both see the same load on a shared machine;
every scan's own time is recorded (the engine's `scan()`, as ScanStats times it) and the figure is
the median per phase, which a neighbour's burst of load does not move. Target: open <= 1.05 x closed.

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/monitor.py [--seconds S] [--rounds N]
"""

from __future__ import annotations

import argparse
import random
import statistics
import tempfile
import time
from pathlib import Path

from PySide6.QtWidgets import QApplication
from scan import generate, pick_functions  # bench/scan.py: the 8 K-word program

from app.gui.application import application
from app.gui.monitor.source import LocalSource
from app.gui.monitor.window import ProgramWindow
from app.station.config import load_station
from app.station.runtime import Runtime
from netplc.engine import Engine
from netplc.memory import Snapshot


def station(folder: Path, seed: int) -> Path:
    text, _ = generate(random.Random(seed), pick_functions())
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "big.stl").write_text(text, encoding="utf-8")
    (folder / "station.toml").write_text('NetPlcProgram = "big.stl"\nNetSyncTime = 10\n'
                                         "[modbus_server]\nenabled = false\n", encoding="utf-8")
    return folder


def record_scans(engine: Engine) -> list[float]:
    """Every scan's duration in us from now on (the scan thread calls engine.scan)."""
    times: list[float] = []
    scan = engine.scan

    def timed() -> Snapshot:
        t0 = time.perf_counter()
        try:
            return scan()
        finally:
            times.append((time.perf_counter() - t0) * 1e6)

    engine.scan = timed  # type: ignore[method-assign]
    return times


def phase(app: QApplication, times: list[float], seconds: float) -> list[float]:
    """The scans' durations over `seconds` of the GUI thread's event loop running."""
    first = len(times)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        app.processEvents()
        time.sleep(0.005)
    return times[first:]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=1.0, help="per phase")
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--seed", type=int, default=165)
    args = ap.parse_args()
    app = application()
    with tempfile.TemporaryDirectory() as tmp:
        runtime = Runtime(load_station(station(Path(tmp) / "st", args.seed)))
        runtime.start()
        try:
            lines = len(Path(runtime.program.source).read_text(encoding="utf-8").splitlines())
            print(f"program: {runtime.program.words} words, {len(runtime.program.instrs)} instructions, "
                  f"{lines} listing lines; tick 10 ms")
            assert runtime.engine is not None
            times = record_scans(runtime.engine)
            window = ProgramWindow(LocalSource(runtime), lambda: "bench")
            monitor = window.monitor
            for addr in ("05000", "05002", "05004", "05006", "05010"):
                monitor.add_watch(addr)
            closed: list[float] = []
            opened: list[float] = []
            refreshes = 0
            for _ in range(args.rounds):
                monitor.timer.stop()
                window.hide()
                closed += phase(app, times, args.seconds)
                window.show()
                monitor.view.go_to(lines // 2)
                monitor.timer.start()
                before = monitor.refreshes
                opened += phase(app, times, args.seconds)
                refreshes += monitor.refreshes - before
            painted = monitor.view.painted_rows
            window.close()
        finally:
            runtime.stop()
    c, o = statistics.median(closed), statistics.median(opened)
    per_s = refreshes / (args.rounds * args.seconds)
    print(f"view closed (yardstick): {c:.0f} us/scan median, mean {statistics.fmean(closed):.0f} "
          f"({len(closed)} scans in {args.rounds} phases)")
    print(f"view open: {o:.0f} us/scan median, mean {statistics.fmean(opened):.0f} ({len(opened)} scans); "
          f"{per_s:.1f} refreshes/s, {painted} lines painted per refresh")
    print(f"open / closed: {o / c:.3f} (median), {statistics.fmean(opened) / statistics.fmean(closed):.3f} "
          "(mean); target <= 1.05")


if __name__ == "__main__":
    main()
