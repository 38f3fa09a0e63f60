"""HMI form update cost at plant size, against plain QLabels with setText in the same run.

A generated form of N elements (`--elements`, default 300) laid out in a square grid of 64 px tiles
(3,000 elements make a 3,520 x 3,520 px form, inside the 10,000 px limit): per six elements two
dials, two discrete colour labels, one digital readout and one bar, every one bound to a value that
changes on every tick. One tick = what the workstation does with a snapshot: FormView.refresh
(models, change detection, repaint scheduling) and the paint that follows (processEvents). The
yardstick is N plain QLabels, one in each element's rectangle, given per tick with setText the
text the element shows of the same operand (a gauge's value as its model formats it, with " %"
where a bar writes its units beside it; a lamp's ON or OFF), in the font and alignment the element
draws that text with, and painted the same way. So both do the same work for the operator: the
same number of texts, the same characters at the same size in boxes of the same size, all
changing every tick; the labels draw nothing else and keep no picture. That is the least a
changing text costs in Qt, so a form at or below it costs nothing for its dials, bars and colours.

The values are a plant's (`--workload full`, the default): each word anywhere in 0..65535 (a
transmitter's full range, shown scaled to 0..10000 with one decimal), every word a new value at
every tick, so a cache of pictures per value never warms up and the memory figures show whether
every cache is bounded. `--workload demo` is the old one: 1,001 values of 0..1000 (scaled to
0..100), which a per-value cache holds after a few hundred ticks.

Ticks of the form and the yardstick alternate, so both see the same machine load. Prints per tick
the mean, median, p95 and worst of the form, the yardstick beside it and the ratio of the medians,
the median thread CPU time of each and its ratio (on a loaded machine a tick's wall time is mostly
waiting for a core, its CPU time is the work), and the resident memory after warm-up and after
all ticks (flat = no growth).

`--readings` refreshes as the workstation does, with the runtime's Readings of each scan: the
words come from NREADs of one node (64 words each, link up), so every element's data quality is
judged on every refresh as well.

`--plots` makes every sixth element a bit trend plot of 100 samples (four tiles wide) instead of a
bar, every bit toggling at every tick (a square wave over the bit's whole range, so every redraw
draws new points). The plots are redrawn once per REDRAW_INTERVAL of the (fake, 100 ms a tick)
clock, all plots of the form in the same tick on their shared time axis, so every tenth tick
carries the redraws. The bench times the redraw of the 50 plots on its own in those ticks (the
form's `redraw_trends` and the paint that follows, after the tick's refresh and paint of the other
elements) and quotes its worst and median, and the whole redraw tick (the median of all ticks
hides them). The plots' yardstick, in the same ticks, interleaved, is 50 plain widgets of the size
of the plots' drawing area at their places, each drawing by hand with QPainter a background fill
and one polyline of the same 100 samples in the same steps the plot shows (199 points), read from
the same trend buffers, mapped with numpy to the same time window and value range and written
straight into the QPolygonF's memory (no point objects): the least a trend costs in Qt done the
plain way. It is fair to the yardstick: it draws no axes, grid, labels, limit lines or gaps, all of
which the plots do; a plot at or below it costs nothing for them.

    QT_QPA_PLATFORM=offscreen python bench/hmi.py [--elements N] [--ticks T] [--plots] [--readings]
        [--workload full|demo]
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

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtGui import QFont, QPainter, QPaintEvent, QPen, QPolygonF
from PySide6.QtWidgets import QApplication, QLabel, QWidget

from app.scada.quality import LinkView, QualityMap
from app.scada.readings import Readings
from app.station import heap
from hmi_forms.elements.target import NullTarget
from hmi_forms.form import load_form
from hmi_forms.widgets import theme
from hmi_forms.widgets.form_view import FormView
from hmi_forms.widgets.gauges import GaugeWidget
from hmi_forms.widgets.trend import REDRAW_INTERVAL, TrendWidget, polygon
from netplc.engine import FakeClock
from netplc.memory import Memory, Snapshot
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


def places(n: int, plots: bool) -> tuple[int, int, list[tuple[str, int, int, int]]]:
    """Each element's kind and place (x, y, width in tiles) on the grid, its columns and rows."""
    tiles = sum(4 if k == "graph" else 1 for k in kinds(n, plots))
    cols = columns(tiles)
    tile = 0
    out = []
    for kind in kinds(n, plots):
        span = 4 if kind == "graph" else 1
        if tile % cols + span > cols:  # a plot does not wrap around the row's end
            tile += cols - tile % cols
        out.append((kind, tile % cols * TILE, tile // cols * TILE, span))
        tile += span
    return cols, (tile + cols - 1) // cols, out


# (AppMax, PhyMax, the word of element i at a tick) of each workload
WORKLOADS = {
    "full": (65535, 10000, lambda tick, i: (tick * 40503 + i * 9973) & 0xFFFF),
    "demo": (1000, 100, lambda tick, i: (tick * 7 + i * 13) % 1001),
}


def generate(folder: Path, n: int, plots: bool, workload: str = "full") -> Path:
    cols, rows, placed = places(n, plots)
    app_max, phy_max, _ = WORKLOADS[workload]
    elements = []
    for i, (kind, x, y, span) in enumerate(placed):
        word, bit = f"0{word_addr(i):o}", f"0{bit_addr(i):o}"
        place = {"x": x, "y": y, "w": span * TILE, "h": TILE}
        if kind == "label":
            elements.append({"type": "DiscreteColorLabel", "Name": f"L{i}", **place, "InAddr": bit,
                             "TextFalse": "OFF", "TextTrue": "ON", "BackColorTrue": "#2e7d32",
                             "ForeColorTrue": "#ffffff"})
        elif kind == "graph":
            elements.append({"type": "Graph", "Name": f"G{i}", **place, "Address": bit, "Elements": 100})
        else:
            elements.append({"type": "AnalogBase", "Name": f"A{i}", **place, "InAddr": word,
                             "Device": "Raw", "Units": "%", "Appearance": kind, "PhyHigh": 0.9 * phy_max})
    doc = {"form": {"title": "bench", "width": cols * TILE, "height": rows * TILE},
           "devices": [{"Name": "Raw", "AppMin": 0, "AppMax": app_max, "PhyMin": 0, "PhyMax": phy_max}],
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


def drive(mem: Memory, n: int, tick: int, workload: str = "full") -> None:
    """Every element's value changes on every tick (words as `WORKLOADS` says), bits toggle."""
    word = WORKLOADS[workload][2]
    for i in range(n):
        mem.set_word(word_addr(i), word(tick, i))
    for i in range(min(n, 0o1700)):
        mem.set_bit(0o2000 + i, (tick + i) % 2)


class Polyline(QWidget):
    """The yardstick of a trend plot: the samples it shows, drawn by hand as one polyline."""

    def __init__(self, plot: TrendWidget, parent: QWidget) -> None:
        super().__init__(parent)
        self.plot = plot
        self.points = QPolygonF()
        self.pen = QPen(Qt.GlobalColor.darkBlue, 1)

    def redraw(self) -> None:
        """The plot's samples in its time window, with the steps its curve draws between them."""
        t, y = self.plot.trend.times(), self.plot.trend.values()
        keep = ~np.isnan(t) & ~np.isnan(y)
        t0, t1 = self.plot.window()
        x = (t[keep] - t0) * (self.width() / (t1 - t0))
        y = (self.plot.hi - y[keep]) * (self.height() / (self.plot.hi - self.plot.lo))
        self.points, xy = polygon(2 * len(x) - 1)
        xy[0::2, 0], xy[1::2, 0], xy[0::2, 1], xy[1::2, 1] = x, x[1:], y, y[:-1]
        self.update()

    def paintEvent(self, _event: QPaintEvent) -> None:
        p = QPainter(self)
        p.fillRect(self.rect(), Qt.GlobalColor.white)
        p.setPen(self.pen)
        p.drawPolyline(self.points)
        p.end()


Plain = tuple[QLabel, str, int]  # a yardstick label, the kind of element it stands for, its operand


def text_look(widget: QWidget) -> tuple[QFont, Qt.AlignmentFlag]:
    """The font and alignment an element draws the text it shows with."""
    if isinstance(widget, GaugeWidget):
        widget._layout()
        assert widget._value is not None
        return widget._value.font, widget._value.align
    model = widget.model  # a lamp
    return theme.qfont(model.Font, bold=model.Enabled), theme.alignment(model.TextAlign) | theme.WRAP


def yardstick(n: int, view: FormView) -> tuple[QWidget, list[Plain], list[Polyline]]:
    """The form's yardstick on the same grid: for each element that is not a plot a plain QLabel
    in its rectangle, with the font and alignment of its text; a Polyline for each plot."""
    cols, rows, placed = places(n, bool(view.trends))
    window = QWidget()
    window.setFixedSize(cols * TILE, rows * TILE)
    texts: list[Plain] = []
    lines: list[Polyline] = []
    for i, ((kind, x, y, span), (_, element)) in enumerate(zip(placed, view.pairs, strict=True)):
        if kind == "graph":  # the plot's drawing area, under its header
            plot = view.trends[len(lines)]
            widget: QWidget = Polyline(plot, window)
            lines.append(widget)
            widget.setGeometry(plot.plot.geometry().translated(x, y))
        else:
            label = widget = QLabel("---", window)
            font, align = text_look(element)
            label.setFont(font)
            label.setAlignment(align)
            texts.append((label, kind, bit_addr(i) if kind == "label" else word_addr(i)))
            widget.setGeometry(x, y, span * TILE, TILE)
    return window, texts, lines


def show_texts(plain: list[Plain], snap: Snapshot, workload: str) -> None:
    """A yardstick tick: each label given the text its element shows of the snapshot (a gauge's
    value converted as `Scaling.to_phy` does, PhyMin and AppMin 0: the same number, the same text)."""
    app_max, phy_max, _ = WORKLOADS[workload]
    for label, kind, addr in plain:
        if kind == "label":
            label.setText("ON" if snap.get_bit(addr) else "OFF")
        elif kind == "hbar":
            label.setText(f"{snap.get_word(addr) * phy_max / app_max:.1f} %")
        else:
            label.setText(f"{snap.get_word(addr) * phy_max / app_max:.1f}")


def stats(values: array) -> tuple[float, float, float, float]:
    return (statistics.mean(values), statistics.median(values), statistics.quantiles(values, n=20)[-1],
            max(values))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--elements", type=int, default=300, help="elements on the form (default 300)")
    parser.add_argument("--ticks", type=int, default=1000, help="ticks measured (default 1000)")
    parser.add_argument("--plots", action="store_true", help="every sixth element a trend plot, not a bar")
    parser.add_argument("--readings", action="store_true", help="judge data quality as the workstation does")
    parser.add_argument("--workload", choices=sorted(WORKLOADS), default="full",
                        help="full: words over 0..65535, a new value each tick (default); demo: 1,001 values")
    args = parser.parse_args()
    n, ticks = args.elements, args.ticks
    app = QApplication.instance() or QApplication([])
    with tempfile.TemporaryDirectory() as tmp:
        form = load_form(generate(Path(tmp), n, args.plots, args.workload))
    clock = FakeClock()  # stands still: the bench redraws the plots itself, every REDRAW_INTERVAL
    view = FormView(form, NullTarget(), clock=clock)
    view.show()
    window, plain, lines = yardstick(n, view)
    window.show()
    mem = Memory()
    qmap, links = station(n), LinkView(links={0: True})
    app.processEvents()
    heap.settle()  # as the workstation does once its window is shown (app/station/heap.py)
    # allocated up front, so that the measurement itself does not grow the memory it measures
    times = array("d", bytes(8 * ticks))
    models = array("d", bytes(8 * ticks))  # the refresh part: models, change detection, scheduling
    yard = array("d", bytes(8 * ticks))
    cpu, y_cpu = array("d", bytes(8 * ticks)), array("d", bytes(8 * ticks))  # thread CPU time of each
    plots, polylines = array("d"), array("d")  # the redraws of the plots, of the yardstick's polylines
    redraws: list[int] = []  # the ticks that redrew the plots
    every = round(REDRAW_INTERVAL * 1000 / TICK_MS)
    warm = min(200, ticks // 10)
    rss_warm = (0.0, 0.0)
    for tick in range(ticks):
        drive(mem, n, tick, args.workload)
        snap = mem.snapshot(tick, tick * 0.1, 1.8e9 + tick * 0.1)
        readings = Readings(snap, qmap, links, qmap.evaluate(snap, links)) if args.readings else None
        c0, t0 = time.thread_time(), time.perf_counter()
        view.refresh(snap, readings)
        t1 = time.perf_counter()
        app.processEvents()
        t2, c1 = time.perf_counter(), time.thread_time()
        times[tick] = (t2 - t0) * 1000
        models[tick] = (t1 - t0) * 1000
        cpu[tick] = (c1 - c0) * 1000
        c0, t0 = time.thread_time(), time.perf_counter()
        show_texts(plain, snap, args.workload)
        app.processEvents()
        yard[tick] = (time.perf_counter() - t0) * 1000
        y_cpu[tick] = (time.thread_time() - c0) * 1000
        if lines and tick % every == 0:  # the plots, then their yardstick (in the plots' new window)
            t0 = time.perf_counter()
            view.redraw_trends(snap.wall)
            app.processEvents()
            t1 = time.perf_counter()
            for line in lines:
                line.redraw()
            app.processEvents()
            t2 = time.perf_counter()
            if tick >= warm:
                redraws.append(tick)
                plots.append((t1 - t0) * 1000)
                polylines.append((t2 - t1) * 1000)
        if tick + 1 == warm:
            rss_warm = rss_pair()
    rss_end = rss_pair()
    mean, median, p95, worst = stats(times[warm:])
    y_mean, y_median, y_p95, y_worst = stats(yard[warm:])
    refresh = statistics.mean(models[warm:])
    what = "plots apart, " if args.plots else ""
    what += f"quality judged against {len(qmap.feeds)} NREADs, " if args.readings else ""
    print(f"hmi form update, {n} elements all changing every tick ({args.workload} workload), "
          f"{form.width}x{form.height} px: "
          f"{mean:.2f} ms mean, {median:.2f} ms median, {p95:.2f} ms p95, {worst:.2f} ms worst over "
          f"{ticks - warm} ticks (of it refresh {refresh:.2f} ms, paint {mean - refresh:.2f} ms); {what}"
          f"target <= {TICK_MS / 2:g} ms")
    print(f"  yardstick, {len(plain)} QLabels with setText: "
          f"{y_mean:.2f} ms mean, {y_median:.2f} ms median, {y_p95:.2f} ms p95, {y_worst:.2f} ms worst; "
          f"form / yardstick (medians) {median / y_median:.2f}x (target <= 1.00x)")
    f_cpu, f_y_cpu = statistics.median(cpu[warm:]), statistics.median(y_cpu[warm:])
    print(f"  thread CPU time per tick (medians): form {f_cpu:.2f} ms, yardstick {f_y_cpu:.2f} ms, "
          f"form / yardstick {f_cpu / f_y_cpu:.2f}x; load average {os.getloadavg()[0]:.1f}")
    if redraws:
        f_median, f_worst = statistics.median(plots), max(plots)
        y_median, y_worst = statistics.median(polylines), max(polylines)
        print(f"hmi plots: {len(redraws)} redraws of the {len(lines)} plots, every {REDRAW_INTERVAL:g} s "
              f"of the replayed clock: {f_median:.2f} ms median, {f_worst:.2f} ms worst; yardstick "
              f"({len(lines)} hand-drawn polylines of the same samples, interleaved): {y_median:.2f} ms "
              f"median, {y_worst:.2f} ms worst; plots / yardstick: worst {f_worst / y_worst:.2f}x, "
              f"median {f_median / y_median:.2f}x (target <= 1.00x)")
        whole = array("d", (times[i] + f for i, f in zip(redraws, plots, strict=True)))
        y_whole = array("d", (yard[i] + y for i, y in zip(redraws, polylines, strict=True)))
        print(f"  whole ticks that redrew them (the tick's refresh and paint, then the plots): "
              f"{statistics.median(whole):.2f} ms median, {max(whole):.2f} ms worst; yardstick "
              f"{statistics.median(y_whole):.2f} ms median, {max(y_whole):.2f} ms worst; form / "
              f"yardstick: worst {max(whole) / max(y_whole):.2f}x, median "
              f"{statistics.median(whole) / statistics.median(y_whole):.2f}x")
    for name, start, end in (("resident", rss_warm[0], rss_end[0]),
                             ("resident after malloc_trim", rss_warm[1], rss_end[1])):
        print(f"hmi {name} memory: {start:.1f} MB after {warm} ticks, {end:.1f} MB after {ticks} ticks "
              f"({end - start:+.2f} MB)")


if __name__ == "__main__":
    main()
