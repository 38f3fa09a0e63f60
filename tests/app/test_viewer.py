"""The offline viewer on an archive made by the headless run, copied elsewhere as from another PC;
its pages read off the GUI thread, and an unreadable archive said in the view (SQLite, and a plant
archive whose connection dropped)."""

from __future__ import annotations

import csv
import datetime as dt
import shutil
import time
from pathlib import Path

from PySide6.QtCore import Qt

from app.gui.viewer import PAGE, ViewerWindow, archive_of
from tests.app.held_archive import Ticks, archive_with, held

LEVEL = "LEVEL Уровень, % (group 1 / type 1 / 04010)"  # series are named by their tags
TEMP = "TEMP Температура, °C (group 1 / type 2 / 04012)"
WAIT = 10_000  # ms: a page is read in the pager's thread and shown through the event loop


def settled(qtbot, viewer: ViewerWindow) -> ViewerWindow:
    """The viewer once the page it asked for is shown."""
    qtbot.waitUntil(lambda: viewer.paging is None, timeout=WAIT)
    return viewer


def texts(viewer: ViewerWindow) -> list[str]:
    return [viewer.model.index(r, 7).data() for r in range(viewer.model.rowCount())]


def test_viewer_shows_rows_plots_and_exports(qtbot, headless_archive: tuple[Path, str],
                                             tmp_path: Path) -> None:
    source, _ = headless_archive
    copy = tmp_path / "copied" / "journal.sqlite"
    copy.parent.mkdir()
    shutil.copy(source, copy)  # a clean stop leaves no WAL behind: the file alone is the archive
    viewer = ViewerWindow(copy)
    qtbot.addWidget(viewer)
    viewer.show()

    assert viewer.day == dt.date.today()
    settled(qtbot, viewer)
    assert viewer.model.rowCount() > 20
    kinds = {viewer.model.index(r, 1).data() for r in range(viewer.model.rowCount())}
    assert kinds >= {"data", "message", "system"}
    shown = texts(viewer)
    assert "NetPlc запущен" in shown and shown[-1] == "станция остановлена"  # oldest first

    viewer.kind.setCurrentText("message")
    viewer.apply_filter()
    settled(qtbot, viewer)
    assert {viewer.model.index(r, 1).data() for r in range(viewer.model.rowCount())} == {"message"}
    assert viewer.page_label.text().startswith("records 1–")

    labels = [viewer.series_list.item(i).text() for i in range(viewer.series_list.count())]
    level = labels.index(LEVEL)
    viewer.check_series(level)
    viewer.check_series(labels.index(TEMP))
    assert len(viewer.loading) == 2  # read in the loader's thread, plotted when done
    qtbot.waitUntil(lambda: len(viewer.curves) == 2, timeout=10_000)
    assert not viewer.loading
    xs, ys = next(iter(viewer.curves.values())).getData()
    assert len(xs) >= 3 and ys[-1] > ys[0]  # the level rises after a start
    assert ys.min() >= 0 and ys.max() <= 100  # in %, not raw counts
    viewer.series_list.item(level).setCheckState(Qt.CheckState.Unchecked)
    assert len(viewer.curves) == 1

    out = tmp_path / "messages.csv"
    n = viewer.export_csv(out)
    with open(out, encoding="utf-8-sig", newline="") as f:
        rows = list(csv.DictReader(f))
    assert n == len(rows) == viewer.total
    assert {r["kind"] for r in rows} == {"message"}
    assert "NetPlc запущен" in {r["text"] for r in rows}

    viewer.kind.setCurrentText("data")
    viewer.apply_filter()
    settled(qtbot, viewer)
    viewer.export_csv(out)
    with open(out, encoding="utf-8-sig", newline="") as f:
        levels = [r for r in csv.DictReader(f) if r["source"] == "04010"]
    assert levels and all(r["tag"] == "LEVEL" and r["unit"] == "%" for r in levels)
    raw = float(levels[-1]["value"])  # the raw value is kept beside the physical one
    assert levels[-1]["physical"] == f"{raw * 100 / 4095:.1f}"


def test_a_series_unticked_while_it_loads_is_not_plotted_and_a_failed_read_is_said(
        qtbot, headless_archive: tuple[Path, str], tmp_path: Path) -> None:
    copy = tmp_path / "journal.sqlite"
    shutil.copy(headless_archive[0], copy)
    viewer = ViewerWindow(copy)
    qtbot.addWidget(viewer)
    labels = [viewer.series_list.item(i).text() for i in range(viewer.series_list.count())]
    first, second = labels.index(LEVEL), labels.index(TEMP)
    viewer.check_series(first)
    viewer.series_list.item(first).setCheckState(Qt.CheckState.Unchecked)  # before its answer arrives
    viewer.check_series(second)
    qtbot.waitUntil(lambda: not viewer.loading, timeout=10_000)  # one worker: first's answer came first
    assert [curve.name() for curve in viewer.curves.values()] == [TEMP]

    viewer.series_list.item(second).setCheckState(Qt.CheckState.Unchecked)
    copy.write_bytes(b"not an archive" * 100)
    viewer.check_series(first)
    qtbot.waitUntil(lambda: not viewer.loading, timeout=10_000)
    assert not viewer.curves
    assert viewer.statusBar().currentMessage().startswith(f"{LEVEL} could not be read: ")


def test_archive_argument(tmp_path: Path) -> None:
    assert archive_of(str(tmp_path / "a.sqlite")) == tmp_path / "a.sqlite"
    assert archive_of(None).name == "journal.sqlite"


def test_a_series_plot_breaks_over_records_whose_value_was_not_good(qtbot, tmp_path: Path) -> None:
    from netplc.records import Record
    from registrar.store import Store

    archive = tmp_path / "journal.sqlite"
    t0 = dt.datetime.combine(dt.date.today(), dt.time(0, 0, 1)).timestamp()
    store = Store(archive, wallclock=lambda: t0)
    for i in range(4):
        store.put(Record(t0 + i, "data", 1, 1, "04010", value=float(i)))
    store.put(Record(t0 + 4, "data", 1, 1, "04010", value=None, text="not running"))  # NetPlc stopped
    store.put(Record(t0 + 5, "data", 1, 1, "04010", value=3.0, text="initial"))  # no fresh data yet
    for i in range(6, 9):
        store.put(Record(t0 + i, "data", 1, 1, "04010", value=float(i)))
    store.start()
    store.close()
    viewer = ViewerWindow(archive)
    qtbot.addWidget(viewer)
    viewer.check_series(0)
    qtbot.waitUntil(lambda: len(viewer.curves) == 1, timeout=10_000)
    _, ys = next(iter(viewer.curves.values())).getData()
    assert [str(y) for y in ys] == ["0.0", "1.0", "2.0", "3.0", "nan", "6.0", "7.0", "8.0"]


def test_the_to_bound_is_exact_and_a_severity_keeps_the_worse_ones(qtbot, tmp_path: Path) -> None:
    from PySide6.QtCore import QTime

    from netplc.records import Record
    from registrar.store import Store

    day = dt.date.today()
    at = dt.datetime.combine(day, dt.time(10, 0, 5)).timestamp()
    store = Store(tmp_path / "journal.sqlite")
    store.start()
    for ts, typ, text in ((at + 0.5, 2, "alarm at :05.5"), (at + 0.999, 3, "critical at :05.999"),
                          (at + 1.2, 2, "alarm at :06.2"), (at - 1, 1, "warning at :04")):
        store.put(Record(ts, "message", grp=1, type=typ, text=text))
    store.close()
    viewer = ViewerWindow(tmp_path / "journal.sqlite")
    qtbot.addWidget(viewer)

    def shown() -> set[str]:
        viewer.apply_filter()
        return set(texts(settled(qtbot, viewer)))

    viewer.until.setTime(QTime(10, 0, 5))
    assert shown() == {"alarm at :05.5", "critical at :05.999", "warning at :04"}
    viewer.type.setCurrentText("2 alarm and above")
    assert shown() == {"alarm at :05.5", "critical at :05.999"}
    viewer.until.setTime(viewer.until.maximumTime())
    assert shown() == {"alarm at :05.5", "critical at :05.999", "alarm at :06.2"}


def test_pages_are_read_off_the_gui_thread_while_the_archive_is_locked(qtbot, tmp_path: Path) -> None:
    path = archive_with(tmp_path / "journal.sqlite", [f"m{i}" for i in range(PAGE + 10)])
    viewer = settled(qtbot, ViewerWindow(path))
    qtbot.addWidget(viewer)
    assert viewer.total == PAGE + 10 and texts(viewer)[:2] == ["m0", "m1"]
    ticks = Ticks()
    try:
        with held(path):
            started = time.monotonic()
            viewer.next.click()  # the count and the page wait for the lock, in the pager's thread
            assert time.monotonic() - started < 3  # a read waiting for the lock takes sqlite3's 5 s
            qtbot.waitUntil(lambda: ticks.count >= 5, timeout=3000)  # the GUI thread runs its timer
            assert viewer.paging is not None and viewer.page_label.text() == "reading…"
        settled(qtbot, viewer)
    finally:
        ticks.stop()
    assert texts(viewer) == [f"m{i}" for i in range(PAGE, PAGE + 10)]
    assert viewer.page_label.text() == f"records {PAGE + 1}–{PAGE + 10} of {PAGE + 10}"
    assert viewer.prev.isEnabled() and not viewer.next.isEnabled()


def test_an_unreadable_archive_is_said_in_the_view_and_the_viewer_goes_on(qtbot, tmp_path: Path) -> None:
    path = archive_with(tmp_path / "journal.sqlite", ["first", "second"])
    good = path.read_bytes()
    viewer = settled(qtbot, ViewerWindow(path))
    qtbot.addWidget(viewer)
    assert texts(viewer) == ["first", "second"]
    path.write_bytes(b"not an archive" * 1000)  # overwritten under the open viewer
    viewer.apply_filter()
    settled(qtbot, viewer)
    assert viewer.page_label.text().startswith("archive unreadable: ")
    assert viewer.model.rowCount() == 0 and viewer.total == 0 and not viewer.next.isEnabled()
    path.write_bytes(good)
    viewer.apply_filter()  # the failed connection was closed: the next page opens the file anew
    settled(qtbot, viewer)
    assert texts(viewer) == ["first", "second"] and viewer.page_label.text() == "records 1–2 of 2"


def test_a_dropped_plant_archive_connection_is_said_and_the_next_page_reconnects(
        qtbot, tmp_path: Path, pg_url: str) -> None:
    import psycopg

    from tests.app.test_plant_archive import plant_of_two

    plant_of_two(tmp_path, pg_url)
    viewer = settled(qtbot, ViewerWindow(pg_url))
    qtbot.addWidget(viewer)
    assert viewer.total == 202
    with psycopg.connect(pg_url, autocommit=True) as admin:  # as a restarted server does
        admin.execute("SELECT pg_terminate_backend(pid) FROM pg_stat_activity "
                      "WHERE datname = current_database() AND pid <> pg_backend_pid()")
    viewer.apply_filter()
    settled(qtbot, viewer)
    assert viewer.page_label.text().startswith(f"archive unreadable: {pg_url}: ")  # an ArchiveError
    assert viewer.model.rowCount() == 0
    viewer.apply_filter()
    settled(qtbot, viewer)
    assert viewer.total == 202 and viewer.page_label.text() == "records 1–202 of 202"


def restarted_archive(path: Path, t0: float) -> Path:
    """LEVEL (a tag) and 04020 (a symbol of the demo, no tag) every second from t0 to t0+9, the
    station stopped after t0+4 and started again at t0+6.5; an alarm of LEVEL at t0+2."""
    from app.scada.table import TagTable
    from app.scada.tag import Scaling, Tag, TagType
    from netplc.records import Record
    from registrar.store import Store

    level = Tag("LEVEL", 0o4010, TagType.WORD, "%", Scaling(0, 4095, 0, 100), 1, "Уровень")
    store = Store(path, wallclock=lambda: t0, tags=TagTable([level]))
    store.put(Record(t0 - 0.5, "system", source="station", text="station starting: here"))
    for i in (*range(5), *range(7, 10)):
        store.put(Record(t0 + i, "data", 1, 1, "04010", value=float(i * 409.5)))
        store.put(Record(t0 + i, "data", 1, 3, "04020", value=float(i)))
    store.put(Record(t0 + 2, "alarm", grp=2, type=1, source="LEVEL.H", number=0, value=91.25))
    store.put(Record(t0 + 4.5, "system", source="station", text="station stopped"))
    store.put(Record(t0 + 6.5, "system", source="station", text="station starting: here"))
    store.start()
    store.close()
    return path


def test_series_honour_from_to_and_break_at_a_restart(qtbot, demo_copy: Path) -> None:
    from PySide6.QtCore import QTime

    t0 = dt.datetime.combine(dt.date.today(), dt.time(10, 0, 0)).timestamp()
    path = restarted_archive(demo_copy / "archive" / "journal.sqlite", t0)
    viewer = settled(qtbot, ViewerWindow(path))  # finds the demo's symbols.csv beside the archive
    qtbot.addWidget(viewer)
    labels = [viewer.series_list.item(i).text() for i in range(viewer.series_list.count())]
    assert labels == ["LEVEL Уровень, % (group 1 / type 1 / 04010)", "LEVEL_AVG (group 1 / type 3 / 04020)"]
    viewer.check_series(1)
    qtbot.waitUntil(lambda: len(viewer.curves) == 1, timeout=WAIT)
    xs, ys = next(iter(viewer.curves.values())).getData()
    assert [str(y) for y in ys] == ["0.0", "1.0", "2.0", "3.0", "4.0", "nan", "7.0", "8.0", "9.0"]
    assert xs[5] == t0 + 6.5  # no line across the restart
    viewer.since.setTime(QTime(10, 0, 2))
    viewer.until.setTime(QTime(10, 0, 7))  # whole seconds: up to 10:00:07.999
    viewer.apply_filter()
    qtbot.waitUntil(lambda: not viewer.loading and len(viewer.curves) == 1, timeout=WAIT)
    xs, ys = next(iter(viewer.curves.values())).getData()
    assert [str(y) for y in ys] == ["2.0", "3.0", "4.0", "nan", "7.0"]
    assert xs.min() >= t0 + 2 and xs.max() < t0 + 8


def test_records_show_tag_names_and_physical_values_with_units_and_csv_rows_are_whole(
        qtbot, tmp_path: Path) -> None:
    t0 = dt.datetime.combine(dt.date.today(), dt.time(10, 0, 0)).timestamp()
    path = restarted_archive(tmp_path / "journal.sqlite", t0)
    viewer = settled(qtbot, ViewerWindow(path, symbols={0o4020: "LEVEL_AVG"}))
    qtbot.addWidget(viewer)
    rows = [[viewer.model.index(r, c).data() for c in (1, 4, 6)] for r in range(viewer.model.rowCount())]
    assert ["data", "LEVEL (04010)", "10.0 %"] in rows  # word 409 of 0..4095 -> 0..100 %
    assert ["data", "LEVEL_AVG (04020)", "1"] in rows  # no tag: the symbol, the value as stored
    assert ["alarm", "LEVEL.H", "91.2 %"] in rows
    out = tmp_path / "all.csv"
    viewer.export_csv(out)
    with open(out, encoding="utf-8-sig", newline="") as f:
        table = list(csv.reader(f))
    assert len(table) > 10 and {len(r) for r in table} == {len(table[0])}
