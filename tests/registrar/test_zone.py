"""Archives across time zones: days are cut where the writer's zone cuts them, wherever read."""

from __future__ import annotations

import datetime as dt
import os
import time
import zoneinfo

import pytest

from netplc.records import Record
from registrar.query import Archive
from registrar.schema import local_zone_key
from registrar.store import Store

WRITER = "Asia/Vladivostok"  # UTC+10, no daylight saving


@pytest.fixture
def zone_of():
    """Switch this process's local zone (TZ) and restore it."""
    before = os.environ.get("TZ")

    def switch(key: str) -> None:
        os.environ["TZ"] = key
        time.tzset()

    yield switch
    if before is None:
        os.environ.pop("TZ", None)
    else:
        os.environ["TZ"] = before
    time.tzset()


def test_an_archive_read_in_another_zone_keeps_the_writers_days(db, zone_of):
    zone_of(WRITER)
    assert local_zone_key() == WRITER
    tz = zoneinfo.ZoneInfo(WRITER)
    late = dt.datetime(2026, 3, 5, 23, 30, tzinfo=tz).timestamp()  # 13:30 UTC
    store = Store(db)
    store.put(Record(late, "data", 1, 1, "04010", value=1.0))
    store.start()
    store.close()
    zone_of("UTC")
    with Archive(db) as a:
        assert a.meta()["timezone_key"] == WRITER and a.tz == tz
        assert a.days() == [dt.date(2026, 3, 5)]
        row = a.records(dt.date(2026, 3, 5))[0]
        assert row.time == dt.datetime(2026, 3, 5, 23, 30)  # the writer's wall time, not 13:30


def test_an_archive_without_a_zone_key_reads_in_the_local_zone(db, zone_of):
    import sqlite3

    store = Store(db)
    store.put(Record(dt.datetime(2026, 3, 5, 8).timestamp(), "data", 1, 1, "04010", value=1.0))
    store.start()
    store.close()
    con = sqlite3.connect(db)
    con.execute("DELETE FROM meta WHERE key = 'timezone_key'")  # as archives before the key
    con.commit()
    con.close()
    with Archive(db) as a:
        assert a.tz is None and a.records(dt.date(2026, 3, 5))[0].time == dt.datetime(2026, 3, 5, 8)


def test_the_viewer_cuts_from_and_to_in_the_writers_zone(qtbot, db, zone_of):
    from PySide6.QtCore import QTime

    from app.gui.viewer import ViewerWindow

    zone_of(WRITER)
    tz = zoneinfo.ZoneInfo(WRITER)
    store = Store(db)
    for hour in (1, 12, 23):
        store.put(Record(dt.datetime(2026, 3, 5, hour, 30, tzinfo=tz).timestamp(), "data", 1, 1, "04010",
                         value=float(hour)))
    store.start()
    store.close()
    zone_of("America/New_York")  # 15 hours behind the writer
    viewer = ViewerWindow(db)
    qtbot.addWidget(viewer)
    qtbot.waitUntil(lambda: viewer.paging is None)  # pages are read in the viewer's worker thread
    assert viewer.day == dt.date(2026, 3, 5) and viewer.total == 3
    viewer.since.setTime(QTime(12, 0))
    viewer.until.setTime(QTime(23, 59, 59))
    viewer.apply_filter()
    qtbot.waitUntil(lambda: viewer.paging is None)
    assert viewer.total == 2
    assert [viewer.model.index(r, 0).data() for r in range(2)] == ["12:30:00.000", "23:30:00.000"]
    viewer.close()
