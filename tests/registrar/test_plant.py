"""The plant archive on a real PostgreSQL: stations writing at once, the forwarder across a server
restart and a SIGKILL of the station, retention, the lag alarm, `archive migrate`."""

from __future__ import annotations

import datetime as dt
import os
import re
import signal
import sqlite3
import threading
import time

import psycopg
import pytest

from app.cli import main as cli
from netplc.records import Record
from registrar.plant.forward import Forwarder
from registrar.query import Archive, Filter
from registrar.reading import ArchiveError
from registrar.store import Store

from .conftest import wait_for
from .test_crash import spawn

T0 = dt.datetime(2026, 3, 5, 8, 0).timestamp()
DAY = dt.date(2026, 3, 5)


def local_count(path) -> int:
    con = sqlite3.connect(path)
    try:
        tables = [n for (n,) in con.execute("SELECT name FROM sqlite_master WHERE type = 'table' "
                                            "AND name GLOB '[0-3][0-9]_*'")]
        return sum(con.execute(f'SELECT count(*) FROM "{t}"').fetchone()[0] for t in tables)
    finally:
        con.close()


def central(url: str, station: str) -> tuple[int, int]:
    """Rows of the station in the plant archive, and how many distinct (day, id) among them."""
    with psycopg.connect(url) as con:
        try:
            return con.execute("SELECT count(*), count(DISTINCT (day, id)) FROM records "
                               "WHERE station = %s", (station,)).fetchone()
        except psycopg.errors.UndefinedTable:  # no station has forwarded yet
            return 0, 0


def test_two_stations_write_at_once(tmp_path, pg_url):
    stations = {}
    for name in ("north", "south"):
        store = Store(tmp_path / name / "journal.sqlite", flush_interval=0.01)
        store.start()
        forwarder = Forwarder(store.path, pg_url, name, interval=0.01, batch=100)  # 10 batches each
        forwarder.start()
        stations[name] = (store, forwarder)

    def produce(name: str) -> None:
        store = stations[name][0]
        for i in range(1_000):
            store.put(Record(T0 + i / 10, "data", 1, 1, "04010", value=float(i)))
            if i % 250 == 0:
                store.put(Record(T0 + i / 10, "message", 1, 2, number=7, text=f"{name} alarm"))
                time.sleep(0.01)

    threads = [threading.Thread(target=produce, args=(n,)) for n in stations]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for name, (store, forwarder) in stations.items():
        store.close()
        wait_for(lambda f=forwarder, s=store: f.stats.backlog == 0 and f.stats.forwarded == s.committed)
        forwarder.close()
        assert central(pg_url, name) == (1_004, 1_004)
    with Archive(pg_url) as plant:
        assert plant.stations() == ["north", "south"]
        assert plant.days() == [DAY]
        assert plant.count(DAY) == 2_008
        alarms = plant.records(DAY, Filter(kinds={"message"}), limit=100, newest_first=False)
        assert [(r.station, r.text) for r in alarms[:2]] == [("north", "north alarm"),
                                                             ("south", "south alarm")]
        assert plant.count(DAY, Filter(stations={"south"}, kinds={"message"})) == 4
        assert len(plant.series_keys(DAY)) == 2
        ts, values = plant.series(DAY, grp=1, type=1, source="04010", station="north", points=100_000)
        assert len(ts) == 1_000 and values[-1] == 999.0


def test_forwarding_survives_a_server_restart(tmp_path, pg_cluster, pg_url):
    """The session's cluster is stopped and started again (on its port, with its other databases):
    no cluster of the test's own to make (an initdb) and to throw away."""
    url = pg_url
    store = Store(tmp_path / "journal.sqlite", flush_interval=0.01)
    store.start()
    forwarder = Forwarder(store.path, url, "st", interval=0.01, batch=40)
    forwarder.start()
    try:
        for i in range(200):
            store.put(Record(T0 + i, "data", 1, 1, "04010", value=float(i)))
        wait_for(lambda: forwarder.stats.forwarded == 200)
        pg_cluster.stop()
        for i in range(200, 600):
            store.put(Record(T0 + i, "data", 1, 1, "04010", value=float(i)))
        wait_for(lambda: store.committed == 600)
        wait_for(lambda: forwarder.stats.last_error != "" and not forwarder.stats.connected
                 and forwarder.stats.backlog == 400)
        pg_cluster.start()
        wait_for(lambda: forwarder.stats.backlog == 0, timeout=30)
    finally:
        store.close()
        forwarder.close()
        if pg_cluster.process is None:  # the next tests have their server back whatever failed here
            pg_cluster.start()
    assert central(url, "st") == (600, 600) and local_count(store.path) == 600


def test_a_sigkilled_station_loses_and_doubles_nothing(tmp_path, pg_url):
    db = tmp_path / "journal.sqlite"
    stations = spawn("plant_child.py", str(db), pg_url)  # forks each station run (plant_child.py)
    assert stations.stdin is not None and stations.stdout is not None
    try:
        for round_ in range(3):
            start = central(pg_url, "killed")[0]
            stations.stdin.write("start\n")
            stations.stdin.flush()
            pid = None
            for line in stations.stdout:  # forwarding is under way: kill it somewhere in a batch
                word = line.split()[0]
                if word == "pid":
                    pid = int(line.split()[1])
                elif pid is not None and int(word) > 400 + 100 * round_:  # (the killed run's last
                    break  # lines come before the pid of the next)
            assert pid is not None
            os.kill(pid, signal.SIGKILL)
            wait_for(lambda start=start: central(pg_url, "killed")[0] > start)
        stations.communicate(timeout=20)  # its stdin closed: it reaps the last station and ends
        assert stations.returncode == 0
    finally:
        if stations.poll() is None:
            stations.kill()
            stations.communicate(timeout=10)
    # The station starts again: its forwarder sends the rest from the committed position.
    assert Forwarder(db, pg_url, "killed").forward_all() >= 0
    total, distinct = central(pg_url, "killed")
    assert total == distinct == local_count(db)


def test_retention_drops_old_partitions(tmp_path, pg_url):
    clock = [T0]
    store = Store(tmp_path / "journal.sqlite", wallclock=lambda: clock[0])
    for day in range(4):
        store.put(Record(T0 + day * 86_400, "data", 1, 1, "04010", value=float(day)))
    store.start()
    store.close()
    Forwarder(store.path, pg_url, "st").forward_all()
    with Archive(pg_url) as plant:
        assert len(plant.days()) == 4
    clock[0] = T0 + 3 * 86_400
    Forwarder(store.path, pg_url, "st", keep_days=2, wallclock=lambda: clock[0]).forward_all()
    with Archive(pg_url) as plant:
        assert plant.days() == [DAY + dt.timedelta(days=3), DAY + dt.timedelta(days=2)]
        assert [k.station for k in plant.series_keys(DAY)] == []
    with psycopg.connect(pg_url) as con:  # detached and dropped, not left behind
        assert con.execute("SELECT count(*) FROM pg_tables WHERE tablename = '05_03_2026'").fetchone() == (0,)


def test_a_lag_over_a_minute_is_told_once_and_its_end_too(tmp_path, pg_cluster):
    clock = [T0]
    told: list[Record] = []
    store = Store(tmp_path / "journal.sqlite", wallclock=lambda: clock[0])
    store.put(Record(T0, "data", 1, 1, "04010", value=1.0))
    store.start()
    store.close()
    dead = "postgresql://postgres@127.0.0.1:9/none"  # nothing answers there
    forwarder = Forwarder(store.path, dead, "st", sink=told.append, wallclock=lambda: clock[0],
                          interval=0.01)
    forwarder.start()
    try:
        wait_for(lambda: forwarder.stats.last_error != "")
        clock[0] = T0 + 90
        wait_for(lambda: len(told) == 1)
        assert "lags by 90 s" in told[0].text and told[0].kind == "system"
        assert forwarder.stats.lag == pytest.approx(90, abs=1) and forwarder.stats.backlog == 1
        forwarder.url = pg_cluster.create_database("lagging")
        wait_for(lambda: len(told) == 2)
        assert "caught up" in told[1].text and "no records were lost" in told[1].text
    finally:
        forwarder.close()


def test_archive_migrate_is_idempotent(tmp_path, pg_url, capsys):
    db = tmp_path / "copies" / "journal.sqlite"
    store = Store(db, station="line1")  # the archive keeps its station's name
    for i in range(2_500):
        store.put(Record(T0 + i, "data", 1, 1, "04010", value=float(i)))
    store.start()
    store.close()
    assert cli(["archive", "migrate", str(db), pg_url]) == 0
    out = capsys.readouterr()
    assert "2,500 records copied" in out.out and "'line1'" in out.out and "2,500 / 2,500" in out.err
    assert cli(["archive", "migrate", str(db), pg_url]) == 0
    assert "0 records copied" in capsys.readouterr().out
    assert central(pg_url, "line1") == (2_500, 2_500)
    assert cli(["archive", "migrate", str(db), "postgresql://u:secret@127.0.0.1/plant"]) == 2
    assert "password must not be written" in capsys.readouterr().err


def test_a_replay_past_a_lost_position_doubles_nothing(tmp_path, pg_url):
    store = Store(tmp_path / "journal.sqlite")
    for i in range(1_000):
        store.put(Record(T0 + i, "data", 1, 1, "04010", value=float(i)))
    store.put(Record(T0 + 1_000, "operator", source="ivanov", text="NUL \x00 in a text"))
    store.start()
    store.close()
    assert Forwarder(store.path, pg_url, "st", batch=300).forward_all() == 1_001
    with psycopg.connect(pg_url) as con:
        con.execute("DELETE FROM forwarded")  # as if the position were lost
    assert Forwarder(store.path, pg_url, "st", batch=300).forward_all() == 1_001  # sent again...
    assert central(pg_url, "st") == (1_001, 1_001)  # ...and refused by the unique key
    with Archive(pg_url) as plant:
        assert plant.records(DAY, Filter(kinds={"operator"}))[0].text == "NUL \ufffd in a text"


def test_a_plant_archive_that_fails_says_so_as_an_archive_error(tmp_path, pg_url, capsys):
    """Its callers (the viewer, `archive migrate`) catch ArchiveError and know no psycopg."""
    dead = "postgresql://station@127.0.0.1:9/plant"  # nothing answers there
    with pytest.raises(ArchiveError, match="cannot open the plant archive"):
        Archive(dead)
    with pytest.raises(ArchiveError, match="no station has forwarded to it yet"):
        Archive(pg_url)
    store = Store(tmp_path / "journal.sqlite")
    store.put(Record(T0, "message", 1, 2, text="alarm"))
    store.start()
    store.close()
    Forwarder(store.path, pg_url, "st").forward_all()
    archive = Archive(pg_url)
    assert archive.days() == [DAY]
    with psycopg.connect(pg_url, autocommit=True) as con:  # the server drops the reader's session
        con.execute("SELECT pg_terminate_backend(pid) FROM pg_stat_activity "
                    "WHERE application_name = 'netplc-station' AND pid <> pg_backend_pid()")
    with pytest.raises(ArchiveError, match=re.escape(pg_url)):
        archive.records(DAY)
    archive.close()
    assert cli(["archive", "migrate", str(store.path), dead, "--station", "st"]) == 1
    assert f"{store.path} -> {dead}:" in capsys.readouterr().err
