"""The run-time trend of the console: tags picked into pens, the archive's known series under the
cursors and in the statistics of the range shown, a trend saved per user, the CSV of the range."""

from __future__ import annotations

import csv
import datetime as dt
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from PySide6.QtCore import Qt

from app.gui.main_window import MainWindow
from app.gui.trend_window import TrendWindow
from app.scada.trends import TrendBook
from app.station.config import load_station
from app.station.runtime import Runtime
from netplc.records import Record
from registrar.store import Store
from tests.app.conftest import copy_demo
from tests.app.test_console import close_shared

WAIT = 15_000


def archived(path: Path, t0: float) -> None:
    """LEVEL (0..4095 raw = 0..100 %) at 0, 10, ... 90 % and TEMP (0..1000 raw = -50..150 °C) at
    0, 20, ... 180 raw = -50..-14 °C, a sample a minute from t0; and an hour of TEMP_SP (0..4095
    raw = -50..150 °C) every half second from t0, raw 0, 1, 2 ... (7200 samples, more than a day's
    read keeps)."""
    store = Store(path, wallclock=lambda: t0)
    for i in range(7200):
        if i % 120 == 0 and i < 1200:
            store.put(Record(t0 + 60 * (i // 120), "data", 1, 1, "04010", value=i // 120 * 409.5))
            store.put(Record(t0 + 60 * (i // 120), "data", 1, 1, "04012", value=i // 120 * 20.0))
        store.put(Record(t0 + 0.5 * i, "data", 1, 5, "04030", value=float(i % 4096)))
    store.start()
    store.close()


@pytest.fixture(scope="module")
def trended(qapp, tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[MainWindow, float]]:
    """The demo's console, its archive holding the `archived` samples from two hours ago: one for
    the module's tests that open trends on it (`station` closes them after each)."""
    demo_copy = copy_demo(tmp_path_factory.mktemp("trends") / "station")
    t0 = float(int(time.time()) - 7200)  # two hours ago, whole seconds (the archive keeps ms)
    archived(demo_copy / "archive" / "journal.sqlite", t0)
    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    window = MainWindow(runtime)
    window.resize(1366, 768)
    try:
        yield window, t0
    finally:
        close_shared(qapp, window)


@pytest.fixture
def station(trended: tuple[MainWindow, float]) -> Iterator[tuple[MainWindow, float]]:
    """The module's console for one test: its trend windows closed after it, the viewer on duty."""
    yield trended
    window = trended[0]
    for opened in window.viewers:
        opened.close()
    window.viewers.clear()
    window.log_out()


def test_two_tags_picked_give_pens_cursors_and_statistics_of_the_archive(
        qtbot, station, tmp_path: Path) -> None:
    window, t0 = station
    trend = window.open_trends()
    assert isinstance(trend, TrendWindow)
    trend.search.setText("уровень")  # the picker searches descriptions too
    listed = [trend.tag_list.item(i).data(Qt.ItemDataRole.UserRole) for i in range(trend.tag_list.count())]
    assert listed == ["LEVEL"]
    trend.tag_list.setCurrentRow(0)
    trend._add_current()
    trend.add_pen("TEMP")
    assert list(trend.pens) == ["LEVEL", "TEMP"]
    assert trend.pens["LEVEL"].colour != trend.pens["TEMP"].colour
    label = trend.plot.getAxis("left").labelText
    assert "%" in label and "°C" in label
    legend = [item[1].text for item in trend.legend.items]
    assert legend == ["LEVEL, %", "TEMP, °C"]
    qtbot.waitUntil(lambda: len(trend.pens["TEMP"].live_t) >= 2, timeout=WAIT)  # live goes on

    trend.set_range(t0 - 30, t0 + 9 * 60 + 30)  # pan and zoom back into the archive
    qtbot.waitUntil(lambda: not trend.loading() and len(trend.pens["LEVEL"].days) > 0, timeout=WAIT)
    trend.set_cursors(t0 + 60 * 2 + 5, t0 + 60 * 7 + 5)
    trend.dirty = True
    trend.redraw()
    assert [trend.cell("LEVEL", c) for c in ("A", "B", "B − A")] == ["20.0", "70.0", "50.0"]
    assert [trend.cell("TEMP", c) for c in ("A", "B", "B − A")] == ["-42.0", "-22.0", "20.0"]
    assert "B − A 300.0 s" in trend.cursor_text.text()
    assert [trend.cell("LEVEL", c) for c in ("Min", "Max", "Mean")] == ["0.0", "90.0", "45.0"]
    assert [trend.cell("TEMP", c) for c in ("Min", "Max", "Mean")] == ["-50.0", "-14.0", "-32.0"]
    assert not trend.grab().isNull()

    out = tmp_path / "trend.csv"
    trend.set_range(t0 + 60 * 3 - 1, t0 + 60 * 5 + 1)
    trend.export_csv(out)
    rows = list(csv.reader(out.open(encoding="utf-8")))
    assert rows[0] == ["time", "LEVEL, %", "TEMP, °C"]
    assert [r[1:] for r in rows[1:]] == [["30", "-38"], ["40", "-34"], ["50", "-30"]]
    assert rows[1][0] == dt.datetime.fromtimestamp(t0 + 180).isoformat(sep=" ", timespec="milliseconds")
    png = tmp_path / "trend.png"
    trend.export_png(png)
    assert png.stat().st_size > 1000


def test_a_saved_trend_reopens_with_its_pens_for_the_same_user_only(qtbot, station) -> None:
    window, _t0 = station
    window.login("operator", "operator")
    trend = window.open_trends()
    trend.add_pen("TEMP")
    trend.add_pen("LEVEL", "#123456")
    trend.span.setCurrentIndex(0)
    trend.save_as("Печь")
    trend.close()
    assert TrendBook(window.runtime.station.Archive.parent).names("operator") == ["Печь"]

    again = window.open_trends()
    assert [again.saved.itemText(i) for i in range(again.saved.count())] == ["Печь"]
    assert again.open_trend("Печь")
    assert [(p.tag.name, p.colour) for p in again.pens.values()] == [
        ("TEMP", trend.pens["TEMP"].colour), ("LEVEL", "#123456")]
    assert again.span.currentData() == 600.0 and "Печь" in again.windowTitle()
    assert not again.grab().isNull()
    again.close()

    window.login("engineer", "engineer")
    other = window.open_trends()
    assert other.saved.count() == 0 and not other.open_trend("Печь")
    assert "Печь" in other.message.text()


def test_a_range_zoomed_into_is_read_at_its_own_detail(qtbot, station) -> None:
    """A day of TEMP_SP every half second (the archive's hour of it, more than a day's read keeps):
    zoomed into 20 s, every sample of them is drawn, not the day's bucket extremes."""
    window, t0 = station
    trend = window.open_trends()
    trend.add_pen("TEMP_SP")
    a, b = t0 + 600 - 0.25, t0 + 620 - 0.25  # 600 s .. 619.5 s: samples 1200 .. 1239
    trend.set_range(a, b)

    def inside() -> int:
        ts, _ = trend.pens["TEMP_SP"].samples()
        return int(((ts >= a) & (ts < b)).sum())

    qtbot.waitUntil(lambda: trend.pens["TEMP_SP"].detail is not None and not trend.loading(), timeout=WAIT)
    assert inside() == 40
    trend.dirty = True
    trend.redraw()
    assert trend.cell("TEMP_SP", "Min") == f"{1200 / 4095 * 200 - 50:.1f}"
    assert trend.cell("TEMP_SP", "Max") == f"{1239 / 4095 * 200 - 50:.1f}"
