"""HMI form update cost at plant size, against plain QLabels with setText in the same run.

A generated form of N elements (`--elements`, default 300) laid out in a square grid of 64 px tiles
(3,000 elements make a 3,520 x 3,520 px form, inside the 10,000 px limit): per six elements two
dials, two discrete colour labels, one digital readout and one bar, every one bound to a value that
changes on every tick. One tick = what the workstation does with a snapshot: FormView.refresh
(models, change detection, repaint scheduling) and the paint that follows (processEvents). The
yardstick is N plain QLabels on the same grid, each given a new text per tick with setText and
painted the same way. Ticks of the two alternate, so both see the same machine load. Prints per
tick the mean, median and p95 of the form, the yardstick beside it and the ratio of the medians,
and the resident memory after warm-up and after all ticks (flat = no growth).

`--readings` refreshes as the workstation does, with the runtime's Readings of each scan: the
words come from NREADs of one node (64 words each, link up), so every element's data quality is
judged on every refresh as well.

`--plots` makes every sixth element a trend plot (four tiles wide) instead of a bar, as the
300-element bench of the first releases did: the plots are redrawn once per REDRAW_INTERVAL of the
(fake, 100 ms a tick) clock, all plots of the form in the same tick (they share one clock-time
axis), so a plot lags its data by at most that interval and every tenth tick carries the redraws.

    QT_QPA_PLATFORM=offscreen python bench/hmi.py [--elements N] [--ticks T] [--plots] [--readings]
"""

from __future__ import annotations

import argparse
import ctypes
import json
import math
import os
import resource
import statistics
import tempfile
import time
from array import array
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PySide6.QtWidgets import QApplication, QLabel, QWidget

from app.scada.quality import LinkView, QualityMap
from app.scada.readings import Readings
from hmi_forms.elements.target import NullTarget
from hmi_forms.form import load_form
from hmi_forms.widgets.form_view import FormView
from hmi_forms.widgets.trend import REDRAW_INTERVAL
from netplc.engine import FakeClock
from netplc.memory import Memory
from netplc.program import parse

TILE = 64
TICK_MS = 100.0


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


def columns(tiles: int) -> int:
    """A square grid: 3,000 tiles make 55 x 55, far inside the 10,000 px form limit."""
    return max(10, math.ceil(math.sqrt(tiles)))


def word_addr(i: int) -> int:
    """The word of element i: 1,024 words per data bank, banks 0-7 (k*010000 + 04000)."""
    bank, k = divmod(i, 1024)
    return bank * 0o10000 + 0o4000 + 2 * k


def bit_addr(i: int) -> int:
    """The bit of element i: internal I/O bits 02000-03677, clear of the special bits 03700-03777."""
    return 0o2000 + i % 0o1700


def kinds(n: int, plots: bool) -> list[str]:
    pattern = ("dial", "label", "dial", "label", "digital", "graph" if plots else "hbar")
    return [pattern[i % len(pattern)] for i in range(n)]


def generate(folder: Path, n: int, plots: bool) -> Path:
    tiles = sum(4 if k == "graph" else 1 for k in kinds(n, plots))
    cols = columns(tiles)
    tile = 0
    elements = []

    def place(span: int = 1) -> dict[str, int]:
        nonlocal tile
        if tile % cols + span > cols:  # a plot does not wrap around the row's end
            tile += cols - tile % cols
        x, y = tile % cols * TILE, tile // cols * TILE
        tile += span
        return {"x": x, "y": y, "w": span * TILE, "h": TILE}

    for i, kind in enumerate(kinds(n, plots)):
        word, bit = f"0{word_addr(i):o}", f"0{bit_addr(i):o}"
        if kind == "label":
            elements.append({"type": "DiscreteColorLabel", "Name": f"L{i}", **place(), "InAddr": bit,
                             "TextFalse": "OFF", "TextTrue": "ON", "BackColorTrue": "#2e7d32",
                             "ForeColorTrue": "#ffffff"})
        elif kind == "graph":
            elements.append({"type": "Graph", "Name": f"G{i}", **place(4), "Address": bit, "Elements": 100})
        else:
            elements.append({"type": "AnalogBase", "Name": f"A{i}", **place(), "InAddr": word,
                             "Device": "Raw", "Units": "%", "Appearance": kind, "PhyHigh": 90})
    rows = (tile + cols - 1) // cols
    doc = {"form": {"title": "bench", "width": cols * TILE, "height": rows * TILE},
           "devices": [{"Name": "Raw", "AppMin": 0, "AppMax": 1000, "PhyMin": 0, "PhyMax": 100}],
           "elements": elements}
    path = folder / "bench.hmi"
    path.write_text(json.dumps(doc))
    return path


BLOCK = 64  # words per NREAD of `--readings`


def station(n: int) -> QualityMap:
    """The NREADs that fill the words of n elements, coils in the external bits (clear of the
    bits the lamps show)."""
    lines = []
    for b in range(math.ceil(n / BLOCK)):
        coil, target = 0o1000 + 4 * b, word_addr(b * BLOCK)
        lines += ["TNA $03760", f"FON C:$0{coil:o} N:NREAD S:4000 D:$0{target:o} R:{2 * BLOCK}"]
    return QualityMap(parse("\n".join([*lines, "JMP 0", ""])), [])


def drive(mem: Memory, n: int, tick: int) -> None:
    """Every element's value changes on every tick: words step by at least 0.7 % of the range,
    bits toggle."""
    for i in range(n):
        mem.set_word(word_addr(i), (tick * 7 + i * 13) % 1001)
    for i in range(min(n, 0o1700)):
        mem.set_bit(0o2000 + i, (tick + i) % 2)


def labels(n: int) -> tuple[QWidget, list[QLabel]]:
    """The yardstick: n plain QLabels on the same grid of tiles."""
    cols = columns(n)
    window = QWidget()
    window.setFixedSize(cols * TILE, (n + cols - 1) // cols * TILE)
    out = []
    for i in range(n):
        label = QLabel("---", window)
        label.setGeometry(i % cols * TILE, i // cols * TILE, TILE, TILE)
        out.append(label)
    return window, out


def stats(values: array) -> tuple[float, float, float]:
    return statistics.mean(values), statistics.median(values), statistics.quantiles(values, n=20)[-1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--elements", type=int, default=300, help="elements on the form (default 300)")
    parser.add_argument("--ticks", type=int, default=1000, help="ticks measured (default 1000)")
    parser.add_argument("--plots", action="store_true", help="every sixth element a trend plot, not a bar")
    parser.add_argument("--readings", action="store_true", help="judge data quality as the workstation does")
    args = parser.parse_args()
    n, ticks = args.elements, args.ticks
    app = QApplication.instance() or QApplication([])
    with tempfile.TemporaryDirectory() as tmp:
        form = load_form(generate(Path(tmp), n, args.plots))
    clock = FakeClock()  # 100 ms ticks for the plot redraw pacing, however fast the replay runs
    view = FormView(form, NullTarget(), clock=clock)
    view.show()
    window, plain = labels(n)
    window.show()
    mem = Memory()
    qmap, links = station(n), LinkView(links={0: True})
    app.processEvents()
    # allocated up front, so that the measurement itself does not grow the memory it measures
    times = array("d", bytes(8 * ticks))
    models = array("d", bytes(8 * ticks))  # the refresh part: models, change detection, scheduling
    yard = array("d", bytes(8 * ticks))
    warm = min(200, ticks // 10)
    rss_warm = (0.0, 0.0)
    for tick in range(ticks):
        drive(mem, n, tick)
        snap = mem.snapshot(tick, tick * 0.1, 1.8e9 + tick * 0.1)
        readings = Readings(snap, qmap, links, qmap.evaluate(snap, links)) if args.readings else None
        clock.advance(0.1)
        t0 = time.perf_counter()
        view.refresh(snap, readings)
        t1 = time.perf_counter()
        app.processEvents()
        t2 = time.perf_counter()
        times[tick] = (t2 - t0) * 1000
        models[tick] = (t1 - t0) * 1000
        t0 = time.perf_counter()
        for i, label in enumerate(plain):  # the text a model would make of the same word
            label.setText(f"{snap.get_word(word_addr(i)) / 10:.1f}")
        app.processEvents()
        yard[tick] = (time.perf_counter() - t0) * 1000
        if tick + 1 == warm:
            rss_warm = rss_pair()
    rss_end = rss_pair()
    mean, median, p95 = stats(times[warm:])
    y_mean, y_median, y_p95 = stats(yard[warm:])
    refresh = statistics.mean(models[warm:])
    what = f"plots redrawn together every {REDRAW_INTERVAL:g} s, " if args.plots else ""
    what += f"quality judged against {len(qmap.feeds)} NREADs, " if args.readings else ""
    print(f"hmi form update, {n} elements all changing every tick, {form.width}x{form.height} px: "
          f"{mean:.2f} ms mean, {median:.2f} ms median, {p95:.2f} ms p95 over {ticks - warm} ticks "
          f"(of it refresh {refresh:.2f} ms, paint {mean - refresh:.2f} ms); {what}"
          f"target <= {TICK_MS / 2:g} ms")
    print(f"  yardstick, {n} QLabels with setText: {y_mean:.2f} ms mean, {y_median:.2f} ms median, "
          f"{y_p95:.2f} ms p95; form / yardstick (medians) {median / y_median:.2f}x "
          f"(target <= 1.00x)")
    for name, start, end in (("resident", rss_warm[0], rss_end[0]),
                             ("resident after malloc_trim", rss_warm[1], rss_end[1])):
        print(f"hmi {name} memory: {start:.1f} MB after {warm} ticks, {end:.1f} MB after {ticks} ticks "
              f"({end - start:+.2f} MB)")


if __name__ == "__main__":
    main()
