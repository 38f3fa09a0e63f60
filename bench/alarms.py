"""Alarm figures: the per-tick cost of 5,000 analog limit alarms, and a flood journaled completely.

1. 2,500 word tags with a conversion, each with an H and an L limit (deadband, on and off delay):
   5,000 analog limit alarms. Every 100 ms tick every value takes a random step (about 1 % of the
   alarms change state per tick), and `AlarmSystem.evaluate` runs on the tick's snapshot, as the
   runtime does on the engine thread. Yardstick from the same run: a plain Python loop comparing
   5,000 floats with 5,000 limits. Target: <= 1 ms per tick.
2. A flood: 10,000 discrete alarms all coming within one second (1,000 in each of 10 ticks of
   100 ms, paced in real time),
   journaled through the real registrar writer (SQLite file on disk) with the alarm state file
   saved by its thread; then every 'alarm' record in the archive is counted.
3. The workstation during that flood: the station's alarms (`StationAlarms`, 10,000 discrete
   alarms from a tags.csv) evaluated on a thread of their own as the engine thread does, 1,000
   new alarms per 100 ms tick for one second, while the alarm summary and the banner show them
   (offscreen Qt). A 10 ms QTimer stands for the operator, and the longest gap between its ticks
   is how long the window did not answer (as bench/viewer.py measures it). Yardstick from the
   same run: the same timer beside a plain QWidget with nothing else to do. Target: < 100 ms.

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/alarms.py [--ticks N]
"""

from __future__ import annotations

import argparse
import itertools
import os
import statistics
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from app.scada.alarms import AlarmSystem
from app.scada.table import TagAlarms, TagTable
from app.scada.tag import Scaling, Tag, TagType
from netplc.address import data_address
from netplc.memory import Memory
from registrar.alarm_state import AlarmStateFile
from registrar.query import Archive, Filter
from registrar.store import Store

TAGS = 2_500  # x 2 limits = 5,000 alarms
FLOOD = 10_000
TICK = 0.1


def limit_alarms(ticks: int) -> None:
    tags = [Tag(f"AI{i:04d}", data_address(2 * i), TagType.WORD, "%", Scaling(0, 4095, 0, 100), 1)
            for i in range(TAGS)]
    spec = TagAlarms(h=80, l=20, deadband=1, on_delay=0.3, off_delay=0.2, priority=3)
    system = AlarmSystem(TagTable(tags, {t.name: spec for t in tags}))
    assert len(system.alarms) == 2 * TAGS
    rng = np.random.default_rng(7)
    mem = Memory()
    raw = rng.uniform(0.3 * 4095, 0.7 * 4095, TAGS)  # in the normal band; the walk takes some out
    times, looped, changes = [], [], 0
    limits = [80.0] * (2 * TAGS)
    now = 1_800_000_000.0
    for _ in range(ticks):
        raw = np.clip(raw + rng.normal(0, 40, TAGS), 0, 4095)
        mem.data[0:2 * TAGS] = raw.astype("<u2").tobytes()  # flat data memory: tag i at index 2i
        snap = mem.snapshot()
        now += TICK
        t0 = time.perf_counter()
        changes += len(system.evaluate(snap, now))
        times.append(time.perf_counter() - t0)
        values = [float(v) for v in np.repeat(raw / 40.95, 2)]
        t0 = time.perf_counter()
        n = 0
        for v, lim in zip(values, limits, strict=True):  # the yardstick: 5,000 float comparisons
            if v > lim:
                n += 1
        looped.append(time.perf_counter() - t0)
    ms = [t * 1000 for t in times]
    yard = statistics.median(looped) * 1000
    median = statistics.median(ms)
    print(f"5,000 analog limit alarms, {ticks} ticks of {TICK * 1000:.0f} ms: evaluate median "
          f"{median:.3f} ms, mean {statistics.mean(ms):.3f} ms, p99 {np.percentile(ms, 99):.3f} ms, "
          f"max {max(ms):.3f} ms per tick ({median / (TICK * 1000) * 100:.2f} % of the tick); "
          f"{changes} transitions ({changes / ticks:.1f} per tick)")
    print(f"  yardstick, a plain Python loop comparing 5,000 floats: {yard:.3f} ms "
          f"-> evaluate = {median / yard:.2f}x the loop")


def flood(folder: Path) -> None:
    tags = [Tag(f"DI{i:05d}", 0o40000 + i, TagType.BIT) for i in range(FLOOD)]  # data bits 04000-...
    spec = TagAlarms(alarm_when=1, priority=2)
    store = Store(folder / "journal.sqlite")
    store.start()
    state = AlarmStateFile(folder / "alarms.sqlite", store)
    state.start()
    system = AlarmSystem(TagTable(tags, {t.name: spec for t in tags}), sink=store, on_change=state.update)
    mem = Memory()
    now = 1_800_000_000.0
    per_tick = FLOOD // 10
    t_start = time.perf_counter()
    ticks = []
    transitions = 0
    for k in range(10):
        for i in range(k * per_tick, (k + 1) * per_tick):
            mem.set_hmi_bit(0o40000 + i, 1)
        snap = mem.snapshot()
        now += TICK
        t0 = time.perf_counter()
        transitions += len(system.evaluate(snap, now))
        ticks.append((time.perf_counter() - t0) * 1000)
        time.sleep(max(0.0, t_start + (k + 1) * TICK - time.perf_counter()))  # the tick's pace
    produced = time.perf_counter() - t_start
    t0 = time.perf_counter()
    state.close()
    store.close()
    drained = time.perf_counter() - t0
    with Archive(folder / "journal.sqlite") as archive:
        day = archive.days()[0]
        journaled = archive.count(day, Filter(kinds=frozenset({"alarm"})))
    print(f"flood: {transitions} alarm transitions within {produced:.2f} s (10 ticks, evaluate "
          f"{statistics.mean(ticks):.1f} ms mean / {max(ticks):.1f} ms max per tick of 1,000 alarms); "
          f"journaled through the registrar writer: {journaled} of {transitions} 'alarm' records "
          f"({'complete' if journaled == transitions else 'INCOMPLETE'}), the rest written "
          f"{drained * 1000:.0f} ms after the last tick; {state.rows} alarm states saved in "
          f"{state.saves} transaction(s)")


def longest_gap(seconds: float, work: threading.Thread | None = None) -> float:
    """Run the Qt event loop for `seconds` (and until `work` has ended) with a 10 ms timer; the
    longest gap between two of its ticks, in seconds."""
    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication

    app = QApplication.instance()
    beats = [time.perf_counter()]
    timer = QTimer()
    timer.setInterval(10)
    timer.timeout.connect(lambda: beats.append(time.perf_counter()))
    timer.start()
    if work is not None:
        work.start()
    end = beats[0] + seconds
    while time.perf_counter() < end or (work is not None and work.is_alive()):
        app.processEvents()
        time.sleep(0.001)
    timer.stop()
    beats.append(time.perf_counter())
    return max(b - a for a, b in itertools.pairwise(beats))


def workstation_flood(folder: Path) -> None:
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide6.QtWidgets import QApplication, QWidget

    from app.authority import Commands, Source, Who
    from app.gui.alarm_summary import AlarmSummary
    from app.gui.alarms import AlarmBanner
    from app.scada.station import StationAlarms
    from netplc.engine import Engine
    from netplc.program import parse
    from netplc.records import ListSink

    if QApplication.instance() is None:
        QApplication([])
    plain = QWidget()
    plain.resize(1366, 300)
    plain.show()
    yard = longest_gap(1.5)
    plain.close()

    csv = folder / "tags.csv"
    csv.write_text("name,address,type,description,alarm_when,priority\n" + "".join(
        f"DI{i:05d},{0o40000 + i:o},bit,вход {i},1,{1 + i % 4}\n" for i in range(FLOOD)), encoding="utf-8")
    sink = ListSink()
    alarms = StationAlarms(csv, parse("JMP 0\n"), [], sink, folder / "alarms.sqlite")
    commands = Commands(Engine(parse("JMP 0\n")), sink, role_of=lambda _name: "operator", alarms=alarms)
    summary = AlarmSummary(alarms, commands, lambda: Who("operator", Source.CONSOLE), sound=False)
    banner = AlarmBanner()
    summary.changed.connect(lambda: banner.show_alarms(summary.unacknowledged()))
    summary.resize(1366, 300)
    summary.show()
    banner.show()
    mem = Memory()
    per_tick = FLOOD // 10

    def engine_thread() -> None:
        """Ten ticks of 1,000 new alarms each, then five quiet ticks, as the scan goes on."""
        t0 = time.perf_counter()
        for k in range(15):
            for i in range(k * per_tick, min(k + 1, 10) * per_tick):
                mem.set_hmi_bit(0o40000 + i, 1)
            alarms.on_scan(mem.snapshot(k + 1, k * TICK, 1_800_000_000.0 + k * TICK, "running"))
            time.sleep(max(0.0, t0 + (k + 1) * TICK - time.perf_counter()))

    gap = longest_gap(2.0, threading.Thread(target=engine_thread))
    summary.refresh()
    shown = len(summary.rows)
    summary.stop()
    alarms.close()
    transitions = sum(r.kind == "alarm" for r in sink.records)
    print(f"workstation during a flood of {transitions} alarm transitions in 1 s: the summary lists "
          f"{shown}, the banner shows P{banner.alarms[0].priority if banner.alarms else '-'}; longest the "
          f"window did not answer {gap * 1000:.0f} ms (a plain QWidget in the same run: "
          f"{yard * 1000:.0f} ms -> {gap / yard:.1f}x)  target < 100 ms")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ticks", type=int, default=600)
    args = parser.parse_args()
    limit_alarms(args.ticks)
    with tempfile.TemporaryDirectory() as tmp:
        flood(Path(tmp))
    with tempfile.TemporaryDirectory() as tmp:
        workstation_flood(Path(tmp))


if __name__ == "__main__":
    main()
