"""A station whose Archive is a PostgreSQL URL, and the viewer on the plant archive."""

from __future__ import annotations

import csv
import datetime as dt
from pathlib import Path

from app.gui.viewer import ViewerWindow
from app.station.config import load_station
from app.station.runtime import Runtime
from netplc.records import Record
from registrar.plant.forward import Forwarder
from registrar.query import Archive
from registrar.store import Store
from tests.registrar.conftest import wait_for

from .conftest import write_station

T0 = dt.datetime(2026, 3, 5, 8, 0).timestamp()
DAY = dt.date(2026, 3, 5)


def test_a_station_forwards_its_archive_to_the_plant_archive(tmp_path: Path, pg_url: str) -> None:
    write_station(tmp_path / "line1", f'NetPlcLoad = false\nArchive = "{pg_url}"\n'
                                      "[modbus_server]\nport = 0\n")
    station = load_station(tmp_path / "line1")
    assert station.plant_archive == pg_url
    assert station.Archive == tmp_path / "line1" / "archive" / "journal.sqlite"  # written first
    runtime = Runtime(station)
    runtime.start()
    try:
        runtime.system("hello plant")
        assert runtime.forwarder is not None
        wait_for(lambda: runtime.forwarder.stats.forwarded >= 2)
        assert not any("plant archive" in p for p in runtime.status().problems)
    finally:
        runtime.stop()
    with Archive(station.Archive) as local, Archive(pg_url) as plant:
        day = local.days()[0]
        assert plant.stations() == ["line1"]
        assert plant.count(day) == local.count(day) >= 3  # "station stopped" went too
        assert [r.text for r in plant.records(day, limit=1)] == ["station stopped"]


def plant_of_two(tmp_path: Path, url: str) -> None:
    for k, name in enumerate(("north", "south")):
        store = Store(tmp_path / name / "journal.sqlite")
        for i in range(100):
            store.put(Record(T0 + i, "data", 1, 1, "04010", value=float(i * (k + 1))))
        store.put(Record(T0 + 50, "message", 1, 2, number=1, text=f"alarm at {name}"))
        store.start()
        store.close()
        Forwarder(store.path, url, name).forward_all()


def test_the_viewer_reads_the_plant_archive(qtbot, tmp_path: Path, pg_url: str) -> None:
    plant_of_two(tmp_path, pg_url)
    viewer = ViewerWindow(pg_url)
    qtbot.addWidget(viewer)
    viewer.show()
    assert viewer.day == DAY and viewer.stations.isVisible()
    assert [viewer.stations.item(i).text() for i in range(viewer.stations.count())] == ["north", "south"]
    qtbot.waitUntil(lambda: viewer.paging is None)  # pages are read in the viewer's worker thread
    assert viewer.total == 202
    viewer.kind.setCurrentText("message")
    viewer.apply_filter()
    qtbot.waitUntil(lambda: viewer.paging is None)
    assert viewer.total == 2
    viewer.stations.item(0).setCheckState(viewer.stations.item(0).checkState().Unchecked)
    qtbot.waitUntil(lambda: viewer.paging is None)
    assert viewer.total == 1 and viewer.current_filter().stations == {"south"}
    assert viewer.model.index(0, 7).data() == "alarm at south"
    assert viewer.model.index(0, 8).data() == "south" and not viewer.table.isColumnHidden(8)
    out = tmp_path / "south.csv"
    assert viewer.export_csv(out) == 1
    with open(out, encoding="utf-8-sig", newline="") as f:
        assert list(csv.reader(f))[1][-1] == "south"

    labels = [viewer.series_list.item(i).text() for i in range(viewer.series_list.count())]
    assert labels == ["north: group 1 / type 1 / 04010", "south: group 1 / type 1 / 04010"]
    viewer.check_series(0)
    viewer.check_series(1)
    qtbot.waitUntil(lambda: len(viewer.curves) == 2, timeout=10_000)
    peaks = sorted(curve.getData()[1].max() for curve in viewer.curves.values())
    assert peaks == [99.0, 198.0]  # each station's own series, on one plot
    viewer.close()


def test_the_health_strip_says_when_forwarding_lags(tmp_path: Path) -> None:
    clock = [T0]
    dead = "postgresql://station@127.0.0.1:9/plant"  # nothing answers there
    write_station(tmp_path, f'NetPlcLoad = false\nArchive = "{dead}"\n[modbus_server]\nport = 0\n')
    runtime = Runtime(load_station(tmp_path), wallclock=lambda: clock[0])
    runtime.start()
    try:
        assert runtime.forwarder is not None
        wait_for(lambda: runtime.forwarder.stats.last_error != "")
        assert not [p for p in runtime.status().problems if "plant archive" in p]
        clock[0] = T0 + 75
        wait_for(lambda: any("lags by" in p for p in runtime.status().problems))
        problem = next(p for p in runtime.status().problems if "lags by" in p)
        assert problem.startswith("archive: forwarding to the plant archive lags by 75 s")
    finally:
        runtime.stop()
    with Archive(tmp_path / "archive" / "journal.sqlite") as local:
        texts = [r.text for r in local.records(local.days()[0], limit=100)]
    assert any("lags by 75 s" in (t or "") for t in texts)  # the 'system' record


def test_the_plant_archive_keeps_its_own_days_not_the_stations(tmp_path: Path) -> None:
    """The plant's day partitions hold every station's records: a station keeping its own archive
    for a week must not drop the others' older records there (`plant_keep_days`, default all)."""
    dead = "postgresql://station@127.0.0.1:9/plant"
    for name, extra, kept in (("short", "", 0), ("plant", "plant_keep_days = 400\n", 400)):
        write_station(tmp_path / name, f'NetPlcLoad = false\nArchive = "{dead}"\nkeep_days = 7\n{extra}'
                                       "[modbus_server]\nport = 0\n")
        station = load_station(tmp_path / name)
        assert (station.keep_days, station.plant_keep_days) == (7, kept)
        runtime = Runtime(station)
        runtime.start()
        try:
            assert runtime.forwarder is not None and runtime.forwarder.keep_days == kept
        finally:
            runtime.stop()
