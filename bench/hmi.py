"""HMI form update cost: a generated 300-element form driven by memory that changes every tick.

100 dials, 100 discrete colour labels, 50 bit graphs and 50 digital readouts, all bound to values
that change on every tick. One tick = FormView.refresh(snapshot) plus the repaint Qt does for it
(processEvents), under the offscreen platform. Prints milliseconds per update (mean, median, p95)
and the resident memory after warm-up and after all ticks (flat = no growth).

What is on screen stays current: gauges and labels repaint in the tick their text changes or a
pointer moves by a pixel; each plot is redrawn at most once per REDRAW_INTERVAL of the (fake,
100 ms a tick) clock, in staggered turns, so a plot lags its data by at most that interval.

    QT_QPA_PLATFORM=offscreen python bench/hmi.py [ticks]
"""

from __future__ import annotations

import ctypes
import json
import os
import resource
import statistics
import sys
import tempfile
import time
from array import array
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PySide6.QtWidgets import QApplication

from hmi_forms.elements.target import NullTarget
from hmi_forms.form import load_form
from hmi_forms.widgets.form_view import FormView
from hmi_forms.widgets.trend import REDRAW_INTERVAL
from netplc.engine import FakeClock
from netplc.memory import Memory

COLS = 20
TILE = 64


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() / 2**20


def rss_pair() -> tuple[float, float]:
    """Resident memory as it is, and after glibc has handed its free pages back: the second tells
    live memory (a leak) from heap the allocator keeps for reuse."""
    raw = rss_mb()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc: the raw figure is all there is
        return raw, raw
    return raw, rss_mb()


def generate(folder: Path) -> Path:
    elements = []
    tile = 0

    def place(w: int = TILE, h: int = TILE) -> dict[str, int]:
        nonlocal tile
        x, y = tile % COLS * TILE, tile // COLS * TILE
        tile += 1
        return {"x": x, "y": y, "w": w, "h": h}

    for i in range(100):
        elements.append({"type": "AnalogBase", "Name": f"D{i}", **place(), "InAddr": f"0{0o4000 + 2 * i:o}",
                         "Device": "Raw", "Units": "%", "Appearance": "dial", "PhyHigh": 90})
    for i in range(100):
        elements.append({"type": "DiscreteColorLabel", "Name": f"L{i}", **place(),
                         "InAddr": f"0{0o2000 + i:o}", "TextFalse": "OFF", "TextTrue": "ON",
                         "BackColorTrue": "#2e7d32", "ForeColorTrue": "#ffffff"})
    for i in range(50):
        elements.append({"type": "AnalogBase", "Name": f"N{i}", **place(), "InAddr": f"0{0o4400 + 2 * i:o}",
                         "Device": "Raw", "Units": "%", "Appearance": "digital"})
    for i in range(50):
        tile += (-tile) % 4  # graphs take four tiles in a row
        elements.append({"type": "Graph", "Name": f"G{i}", **place(4 * TILE, TILE),
                         "Address": f"0{0o2200 + i:o}", "Elements": 100})
        tile += 3
    rows = (tile + COLS - 1) // COLS
    doc = {"form": {"title": "bench", "width": COLS * TILE, "height": rows * TILE},
           "devices": [{"Name": "Raw", "AppMin": 0, "AppMax": 1000, "PhyMin": 0, "PhyMax": 100}],
           "elements": elements}
    path = folder / "bench.hmi"
    path.write_text(json.dumps(doc))
    return path


def drive(mem: Memory, tick: int) -> None:
    for i in range(100):
        mem.set_word(0o4000 + 2 * i, (tick * 7 + i * 13) % 1001)
        mem.set_bit(0o2000 + i, (tick + i) // 3 % 2)
    for i in range(50):
        mem.set_word(0o4400 + 2 * i, (tick * 3 + i) % 1001)
        mem.set_bit(0o2200 + i, (tick + i) // 5 % 2)


def main() -> None:
    ticks = int(sys.argv[1]) if len(sys.argv) > 1 else 10_000
    app = QApplication.instance() or QApplication([])
    with tempfile.TemporaryDirectory() as tmp:
        form = load_form(generate(Path(tmp)))
    clock = FakeClock()  # 100 ms ticks for the plot redraw pacing, however fast the replay runs
    view = FormView(form, NullTarget(), clock=clock)
    view.show()
    mem = Memory()
    # allocated up front, so that the measurement itself does not grow the memory it measures
    times = array("d", bytes(8 * ticks))
    models = array("d", bytes(8 * ticks))  # the refresh part: models, change detection, plot setData
    warm = min(500, ticks // 10)
    rss_warm = (0.0, 0.0)
    for tick in range(ticks):
        drive(mem, tick)
        snap = mem.snapshot(tick, tick * 0.1, 1.8e9 + tick * 0.1)
        clock.advance(0.1)
        t0 = time.perf_counter()
        view.refresh(snap)
        t1 = time.perf_counter()
        app.processEvents()
        t2 = time.perf_counter()
        times[tick] = (t2 - t0) * 1000
        models[tick] = (t1 - t0) * 1000
        if tick + 1 == warm:
            rss_warm = rss_pair()
    rss_end = rss_pair()
    steady = times[warm:]
    p95 = statistics.quantiles(steady, n=20)[-1]
    mean, refresh = statistics.mean(steady), statistics.mean(models[warm:])
    print(f"hmi form update, 300 elements: {mean:.2f} ms mean, {statistics.median(steady):.2f} ms median, "
          f"{p95:.2f} ms p95 over {len(steady)} ticks (target <= 10 ms); of it refresh {refresh:.2f} ms, "
          f"repaint {mean - refresh:.2f} ms; plots redrawn every {REDRAW_INTERVAL:g} s (together per form), "
          f"everything else in the tick it changes")
    for what, start, end in (("resident", rss_warm[0], rss_end[0]),
                             ("resident after malloc_trim", rss_warm[1], rss_end[1])):
        print(f"hmi {what} memory: {start:.1f} MB after {warm} ticks, {end:.1f} MB after {ticks} ticks "
              f"({end - start:+.2f} MB)")


if __name__ == "__main__":
    main()
