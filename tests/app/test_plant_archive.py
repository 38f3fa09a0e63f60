"""A station whose Archive is a PostgreSQL URL, and the viewer on the plant archive."""

from __future__ import annotations

import csv
import datetime as dt
import sqlite3
import time
from collections import Counter
from pathlib import Path

import psycopg

from app.cli import main as cli
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
        runtime.put(Record(runtime.wallclock(), "system", source="station", text="hello plant"))
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


def run_station(folder: Path, values: range) -> Path:
    """The station started and stopped, NSTORE-like data of LEVEL put meanwhile: its local archive."""
    runtime = Runtime(load_station(folder))
    runtime.start()
    try:
        for v in values:
            runtime.put(Record(time.time(), "data", 1, 1, "04010", value=float(v)))
    finally:
        runtime.stop()  # the forwarder, if any, sends the rest
    return runtime.station.Archive


def local_keys(archive: Path, station: str) -> set[tuple]:
    con = sqlite3.connect(f"file:{archive}?mode=ro", uri=True)
    try:
        return {(station, day, i) for day in Archive(archive).days()
                for (i,) in con.execute(f'SELECT id FROM "{day:%d_%m_%Y}"')}
    finally:
        con.close()


def plant_keys(url: str) -> Counter:
    with psycopg.connect(url) as con:
        return Counter(con.execute("SELECT station, day, id FROM records").fetchall())


STATION = 'name = "Demo station"\nNetPlcLoad = false\n{archive}[modbus_server]\nport = 0\n'
TAGS = "name,address,type,unit,app_min,app_max,phy_min,phy_max\nLEVEL,04010,word,%,0,4095,0,100\n"


def test_forward_then_migrate_lands_every_record_once_under_the_stations_name(
        tmp_path: Path, pg_url: str, capsys) -> None:
    """The folder is `stpg`, the station's name "Demo station": the forwarder and `archive migrate`
    name it alike, so the unique key (station, day, id) keeps every record once, in either order."""
    toml = STATION.format(archive=f'Tags = "tags.csv"\nArchive = "{pg_url}"\n')
    folder = write_station(tmp_path / "stpg", toml, {"tags.csv": TAGS})
    archive = run_station(folder, range(500))
    keys = local_keys(archive, "Demo station")
    assert len(keys) >= 500 and plant_keys(pg_url) == Counter(keys)  # forwarded
    for source in (archive, folder, folder / "station.toml"):  # then migrated, and again
        assert cli(["archive", "migrate", str(source), pg_url]) == 0
        out = capsys.readouterr().out
        assert "0 records copied" in out
        assert f"as station 'Demo station' (the name in {folder / 'station.toml'}" in out
    assert plant_keys(pg_url) == Counter(keys)
    with psycopg.connect(pg_url) as con:
        assert con.execute("SELECT DISTINCT station FROM tags").fetchall() == [("Demo station",)]
        assert con.execute("SELECT count(*), min(unit) FROM tag_values").fetchone() == (500, "%")


def test_migrate_then_forward_lands_every_record_once(tmp_path: Path, pg_url: str, capsys) -> None:
    folder = write_station(tmp_path / "line2", STATION.format(archive=""))  # its own archive only
    archive = run_station(folder, range(300))
    before = local_keys(archive, "Demo station")
    assert cli(["archive", "migrate", str(folder), pg_url]) == 0
    assert f"{len(before):,} records copied" in capsys.readouterr().out
    (folder / "station.toml").write_text(STATION.format(archive=f'Archive = "{pg_url}"\n'), encoding="utf-8")
    assert run_station(folder, range(300, 400)) == archive  # now it forwards: the rest, not again
    keys = local_keys(archive, "Demo station")
    assert len(keys) > len(before) + 100 and plant_keys(pg_url) == Counter(keys)
    assert cli(["archive", "migrate", str(archive), pg_url]) == 0
    assert plant_keys(pg_url) == Counter(keys)


def test_migrate_says_why_it_cannot_name_the_station(tmp_path: Path, pg_url: str, capsys) -> None:
    loose = tmp_path / "copies" / "journal.sqlite"  # copied away from its station, written before names
    store = Store(loose)
    store.put(Record(T0, "data", 1, 1, "04010", value=1.0))
    store.start()
    store.close()
    assert cli(["archive", "migrate", str(loose), pg_url]) == 2
    err = capsys.readouterr().err
    assert f"{loose}: cannot tell whose archive it is" in err and "--station NAME" in err
    assert cli(["archive", "migrate", str(loose), pg_url, "--station", "line1"]) == 0
    assert "as station 'line1' (--station" in capsys.readouterr().out

    broken = write_station(tmp_path / "broken", 'name = 5\nNetPlcLoad = false\n')
    assert cli(["archive", "migrate", str(broken), pg_url]) == 2
    err = capsys.readouterr().err
    assert f"{broken / 'station.toml'}: name: expected" in err and "fix it" in err
    named = Store(tmp_path / "named.sqlite", station="line3")  # an archive keeps its station's name
    named.put(Record(T0, "data", 1, 1, "04010", value=1.0))
    named.start()
    named.close()
    assert cli(["archive", "migrate", str(named.path), pg_url]) == 0
    assert "as station 'line3' (the name the archive keeps" in capsys.readouterr().out
    assert plant_keys(pg_url) == Counter({("line1", DAY, 1): 1, ("line3", DAY, 1): 1})
