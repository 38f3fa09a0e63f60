import csv
import datetime as dt
import shutil
import sqlite3
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from netplc.records import Record
from registrar.catalog import Catalog, Message
from registrar.plant.forward import Forwarder
from registrar.query import Archive, Filter, SeriesKey
from registrar.store import Store

from .conftest import wait_for

DAY = dt.date(2026, 3, 5)
T0 = dt.datetime(2026, 3, 5, 8, 0).timestamp()
CATALOG = Catalog({1: Message(1, 1, 0, "Пуск нажат"), 3: Message(3, 1, 2, "Уровень выше 90 %"),
                   4: Message(4, 2, 1, "Связь с узлом 0 потеряна")})


def write(db, records):
    store = Store(db, catalog=CATALOG, wallclock=lambda: T0)
    for r in records:
        store.put(r)
    store.start()
    store.close()


@pytest.fixture(scope="module")
def journal(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The archive file the reading tests share: written once, none of them writes to it."""
    db = tmp_path_factory.mktemp("query") / "archive" / "journal.sqlite"
    records = []
    for i in range(300):
        records.append(Record(T0 + i, "data", 1, 1, "04010", value=float(i)))
        if i % 10 == 0:
            records.append(Record(T0 + i, "message", 1 if i % 20 else 2, 2 if i % 30 == 0 else 0,
                                  number=3 if i % 30 == 0 else 1))
    records.append(Record(T0 + 400, "operator", source="ivanov", number=0o4030, value=7.0,
                          text="write 04030: 0 -> 7"))
    records.append(Record(T0 - 86400, "system", source="app", text="station started"))
    write(db, records)
    return db


@pytest.fixture(scope="module", params=["sqlite", "postgresql"])
def journal_at(request: pytest.FixtureRequest, journal: Path) -> Path | str:
    """Where the reading tests open `journal`: the file itself, or the plant archive on PostgreSQL
    it was forwarded to once (a database of the module's: as `opened`, one test checks both)."""
    if request.param == "sqlite":
        return journal
    url = request.getfixturevalue("pg_cluster").create_database("query_reading")
    Forwarder(journal, url, "station").forward_all()
    return url


@pytest.fixture
def archive(journal_at: Path | str) -> Iterator[Archive]:
    with Archive(journal_at) as a:
        yield a


def test_days_newest_first(archive):
    assert archive.days() == [DAY, DAY - dt.timedelta(days=1)]


def test_pages_newest_first_with_offset(archive):
    first = archive.records(DAY, limit=5)
    assert [r.kind for r in first] == ["operator", "data", "data", "data", "data"]
    assert first[0].ts == T0 + 400 and first[0].source == "ivanov" and first[0].value == 7.0
    assert first[0].time == dt.datetime(2026, 3, 5, 8, 6, 40)
    second = archive.records(DAY, offset=5, limit=5)
    assert second[0].id == first[-1].id - 1
    oldest = archive.records(DAY, limit=2, newest_first=False)
    assert [(r.kind, r.value) for r in oldest] == [("data", 0.0), ("message", None)]


def test_filters_and_counts_agree(archive):
    cases = [
        (Filter(kinds={"message"}), 30),
        (Filter(kinds={"message"}, min_type=2), 10),
        (Filter(kinds={"message", "operator"}), 31),
        (Filter(kinds={"message"}, grp=2), 15),
        (Filter(kinds={"message"}, type=0), 20),
        (Filter(source="04010"), 300),
        (Filter(text="уровень"), 10),
        (Filter(text="ПУСК"), 20),
        (Filter(text="90 %"), 10),
        (Filter(text="100%"), 0),
        (Filter(kinds={"data"}, since=T0 + 100, until=T0 + 110), 10),
        (Filter(kinds=set()), 0),
        (Filter(), 331),
    ]
    for flt, n in cases:
        assert archive.count(DAY, flt) == n, flt
        got = archive.records(DAY, flt, limit=1000)
        assert len(got) == n, flt
    alarms = archive.records(DAY, Filter(kinds={"message"}, min_type=2))
    assert {(r.number, r.type, r.text) for r in alarms} == {(3, 2, "Уровень выше 90 %")}



def test_a_missing_day_is_empty(archive):
    other = dt.date(2020, 1, 1)
    assert archive.records(other) == []
    assert archive.count(other) == 0
    ts, values = archive.series(other, grp=1)
    assert len(ts) == len(values) == 0


def test_series_keys_and_small_series(archive):
    assert [key[:4] for key in archive.series_keys(DAY)] == [("data", 1, 1, "04010")]
    assert archive.series_keys(DAY - dt.timedelta(days=1)) == []
    ts, values = archive.series(DAY, grp=1, type=1, source="04010")
    assert np.array_equal(ts, T0 + np.arange(300)) and np.array_equal(values, np.arange(300.0))


def test_downsampling_keeps_peaks(db, opened):
    n = 5_000  # 25 records to a point: as many as 100 would prove it, 4 times the CPU
    values = np.sin(np.arange(n) / 125.0) * 100.0
    values[3_456] = 1000.0
    values[777] = -1000.0
    write(db, [Record(T0 + i * 0.1, "data", 3, 4, "04020", value=float(v)) for i, v in enumerate(values)])
    with opened(db) as a:
        ts, got = a.series(DAY, grp=3, type=4, points=200)
        _, full = a.series(DAY, grp=3, type=4, points=n)
    assert 100 <= len(ts) <= 200
    assert np.all(np.diff(ts) > 0)
    assert got.max() == 1000.0 and got.min() == -1000.0
    assert ts[np.argmax(got)] == pytest.approx(T0 + 345.6)
    assert ts[np.argmin(got)] == pytest.approx(T0 + 77.7)
    assert len(full) == n and np.array_equal(full, values)


def test_export_csv(archive, tmp_path):
    out = tmp_path / "alarms.csv"
    assert archive.export_csv(out, DAY, Filter(kinds={"message"}, min_type=2)) == 10
    with open(out, encoding="utf-8-sig", newline="") as f:
        table = list(csv.reader(f))
    assert table[0][:10] == ["id", "time", "ts", "kind", "grp", "type", "source", "number", "value", "text"]
    assert table[1][1] == "2026-03-05T08:00:00.000" and table[1][9] == "Уровень выше 90 %"
    assert len(table) == 11
    assert out.read_bytes().startswith(b"\xef\xbb\xbf")


def test_catalog_and_meta_travel_with_a_copied_archive(journal, tmp_path):
    copy = tmp_path / "elsewhere" / "copy.sqlite"
    copy.parent.mkdir()
    shutil.copyfile(journal, copy)
    with Archive(copy) as a:
        assert a.days()[0] == DAY
        assert a.count(DAY) == 331
        assert a.message_texts()[3] == "Уровень выше 90 %"
        assert a.meta()["ts_unit"].startswith("milliseconds")


def test_a_missing_file_is_not_created(tmp_path):
    with pytest.raises(FileNotFoundError):
        Archive(tmp_path / "none.sqlite")
    assert not (tmp_path / "none.sqlite").exists()


def test_reading_while_the_writer_writes(db):
    store = Store(db, flush_interval=0.01, wallclock=lambda: T0)
    store.start()
    store.put(Record(T0, "data", 1, 1, "04000", value=0.0))
    wait_for(lambda: store.committed == 1)
    stop = threading.Event()

    def produce() -> None:
        i = 0
        while not stop.is_set():
            store.put(Record(T0 + i / 1000, "data", 1, 1, "04000", value=float(i)))
            i += 1
            if i % 10 == 0:  # a writer paced as a station's: each read meets commits of its own
                stop.wait(0.001)  # (500 at once: a day growing faster than reads, seconds of CPU)

    producer = threading.Thread(target=produce)
    producer.start()
    counts = []
    with Archive(db) as a:
        while len(counts) < 50 or counts[-1] == counts[0]:
            counts.append(a.count(DAY))
            a.records(DAY, Filter(kinds={"data"}), limit=50)
            a.series(DAY, grp=1, type=1, source="04000", points=100)
        stop.set()
        producer.join()
        store.close()
        assert counts == sorted(counts)
        assert a.count(DAY) == store.committed
    assert store.stats.last_error == ""


def test_every_page_strategy_gives_the_reference_answer(db, opened, monkeypatch):
    """Small probe and index limits force all three ways of finding a page on a modest day."""
    import random

    import registrar.query as query

    monkeypatch.setattr(query, "PROBE_ROWS", 50)
    monkeypatch.setattr(query, "INDEX_ROWS", 100)
    rnd = random.Random(5)
    records = []
    for i in range(3000):
        if i < 40 or rnd.random() < 0.01:
            number = rnd.choice((1, 3, 4))
            records.append(Record(T0 + i, "message", rnd.randrange(3), rnd.randrange(4), number=number))
        elif i % 500 == 0:
            records.append(Record(T0 + i, "system", source="app", text="station started"))
        elif i % 37 == 0:  # an alarm's transition: grp = priority 1-4, type = new state 0-6
            records.append(Record(T0 + i, "alarm", rnd.randrange(1, 5), rnd.randrange(7), "LEVEL.H",
                                  rnd.randrange(7), text="LEVEL.H"))
        else:
            records.append(Record(T0 + i, "data", 1 + i % 2, 1, "04010", value=float(i)))
    write(db, records)
    filters = [
        Filter(kinds={"message"}), Filter(kinds={"message", "system"}), Filter(kinds={"message"}, grp=2),
        Filter(grp=0), Filter(grp=2, type=3), Filter(kinds={"data"}, grp=1), Filter(text="связь"),
        Filter(kinds={"message"}, min_type=2), Filter(kinds={"data"}, until=T0 + 100), Filter(grp=9),
        Filter(min_type=2), Filter(min_type=3), Filter(kinds={"alarm", "message"}, min_type=1),
        Filter(type=2), Filter(kinds={"alarm"}, type=3), Filter(kinds={"alarm"}, grp=2, type=2),
    ]
    with opened(db) as a:
        everything = a.records(DAY, limit=10_000, newest_first=False)
        assert len(everything) == 3000
        for flt in filters:
            expected = [r for r in everything if _matches(r, flt)]
            assert a.count(DAY, flt) == len(expected), flt
            for newest_first in (True, False):
                ordered = expected[::-1] if newest_first else expected
                for offset, limit in ((0, 10), (5, 30), (len(expected) - 3, 10)):
                    got = a.records(DAY, flt, offset=max(offset, 0), limit=limit, newest_first=newest_first)
                    assert got == ordered[max(offset, 0):max(offset, 0) + limit], (flt, newest_first, offset)


def _matches(r, flt: Filter) -> bool:
    return ((flt.kinds is None or r.kind in flt.kinds) and (flt.grp is None or r.grp == flt.grp)
            and (flt.type is None or (r.grp == 4 - flt.type if r.kind == "alarm" else r.type == flt.type))
            and (flt.min_type is None or (r.kind == "message" and r.type >= flt.min_type)
                 or (r.kind == "alarm" and r.grp <= 4 - flt.min_type))
            and (flt.until is None or r.ts < flt.until)
            and (flt.text is None or (r.text is not None and flt.text.lower() in r.text.lower())))


def test_a_file_that_is_no_archive_is_named_in_the_error(tmp_path):
    path = tmp_path / "notes.sqlite"
    path.write_bytes(b"plain text, not SQLite " * 100)
    with pytest.raises(sqlite3.DatabaseError, match=r"notes\.sqlite: cannot open the archive"):
        Archive(path)


def test_a_series_stays_in_time_order_when_the_clock_was_set_back(db):
    stamps = [T0 + 10, T0 + 11, T0 + 5, T0 + 12]  # the wall clock jumped back after the second
    write(db, [Record(t, "data", 1, 1, "04000", value=float(i)) for i, t in enumerate(stamps)])
    with Archive(db) as a:
        ts, values = a.series(DAY, grp=1, type=1, source="04000")
        assert list(ts) == sorted(stamps) and list(values) == [2.0, 0.0, 1.0, 3.0]
        assert [r.value for r in a.records(DAY, newest_first=False)] == [0.0, 1.0, 2.0, 3.0]


def _without_text_index_and_summary(db) -> None:
    """The file as an archive written before the trigram index and the per-minute summary."""
    con = sqlite3.connect(db)
    for (name,) in con.execute("SELECT name FROM sqlite_master WHERE type = 'table' "
                               "AND (name GLOB 'text_*' OR name GLOB 'minutes_*')").fetchall():
        if not name.endswith(("_data", "_idx", "_docsize", "_config", "_content")):
            con.execute(f'DROP TABLE "{name}"')
    con.commit()
    con.close()


def test_text_search_by_the_trigram_index_equals_the_scan(db):
    words = ["Авария насоса", "насос в работе", "Связь потеряна", "ПУСК нажат", 'кавычка "x"', "50%_done"]
    records = [Record(T0 + i, "operator" if i % 7 else "data", 1, 1, "04010", value=float(i),
                      text=words[i % len(words)] if i % 7 else None) for i in range(3000)]
    write(db, records)
    searches = ["авария", "НАСОС", "Насос", "связь", "пуск", '"x"', "0%_", "нет такого", "на", "ё",
                "a\x00b", "NEAR("]
    with Archive(db) as a:
        indexed = {t: (a.count(DAY, Filter(text=t)), a.records(DAY, Filter(text=t), limit=50, offset=3))
                   for t in searches}
    _without_text_index_and_summary(db)
    with Archive(db) as a:
        for t in searches:
            assert (a.count(DAY, Filter(text=t)), a.records(DAY, Filter(text=t), limit=50, offset=3)) \
                == indexed[t], t
    assert indexed["авария"][0] == 3000 * 6 // 7 // 6 and indexed["нет такого"][0] == 0


def test_a_long_series_is_read_from_the_minute_summary(db, monkeypatch):
    import registrar.query as query

    n = 6_000  # 10 records a second: 600 s, 10 minutes, 600 records to a minute's extremes
    values = np.cos(np.arange(n) / 210.0) * 50.0
    values[4_321] = 1000.0
    values[777] = -1000.0
    write(db, [Record(T0 + i * 0.1, "data", 3, 4, "04020", value=float(v)) for i, v in enumerate(values)])
    with Archive(db) as a:
        raw = a.series(DAY, grp=3, type=4, source="04020", points=200)
        monkeypatch.setattr(query, "SUMMARY_ABOVE", 1_000)
        ts, got = a.series(DAY, grp=3, type=4, source="04020", points=200)
        every, _ = a.series(DAY, grp=3, type=4, source="04020", points=100_000)
    assert 10 <= len(every) <= 2 * 10  # a minimum and a maximum per minute
    assert len(ts) <= 200 and np.all(np.diff(ts) > 0)
    assert got.max() == raw[1].max() == 1000.0 and got.min() == raw[1].min() == -1000.0
    assert ts[np.argmax(got)] == pytest.approx(T0 + 432.1)
    assert ts[np.argmin(got)] == pytest.approx(T0 + 77.7)
    _without_text_index_and_summary(db)  # an older archive: read from the records, same peaks
    with Archive(db) as a:
        old_ts, old = a.series(DAY, grp=3, type=4, source="04020", points=200)
    assert old.max() == 1000.0 and old_ts[np.argmax(old)] == pytest.approx(T0 + 432.1)


def test_a_day_written_before_the_index_gets_it_filled_when_written_again(db):
    write(db, [Record(T0 + i, "message", 1, 2, number=3) for i in range(10)])
    _without_text_index_and_summary(db)
    write(db, [Record(T0 + 20 + i, "data", 1, 1, "04010", value=float(i)) for i in range(5)])
    con = sqlite3.connect(db)
    try:
        fts = '"text_05_03_2026"'
        assert con.execute(f"SELECT count(*) FROM {fts} WHERE {fts} MATCH '\"уро\"'").fetchone() == (10,)
        assert con.execute('SELECT sum(n), max(hi) FROM "minutes_05_03_2026"').fetchone() == (5, 4.0)
    finally:
        con.close()


def _gappy() -> list[Record]:
    """A level stored every second; the node is down from 10 s (one mark without a value, then
    records of the frozen value with their quality), good again from 15 s; a forced value at 20 s."""
    out = [Record(T0 + i, "data", 1, 1, "04010", value=float(i)) for i in range(10)]
    out.append(Record(T0 + 10, "data", 1, 1, "04010", value=None, text="comm-fail"))
    out += [Record(T0 + 10.5 + i, "data", 1, 1, "04010", value=9.0, text="comm-fail") for i in range(5)]
    out += [Record(T0 + 15 + i, "data", 1, 1, "04010", value=float(15 + i)) for i in range(5)]
    out.append(Record(T0 + 20, "data", 1, 1, "04010", value=99.0, text="forced"))
    out.append(Record(T0 + 21, "data", 1, 1, "04010", value=None, text="not running"))
    return out


def test_a_series_breaks_over_records_whose_value_was_not_good(db, opened):
    write(db, _gappy())
    with opened(db) as a:
        ts, values = a.series(DAY, grp=1, type=1, source="04010")
        few_ts, few = a.series(DAY, grp=1, type=1, source="04010", points=8)
    gaps = ts[np.isnan(values)]
    assert list(gaps - T0) == [10.0, 21.0]  # the first record of each run that was not good
    assert list(values[~np.isnan(values)]) == [*map(float, range(10)), *map(float, range(15, 20)), 99.0]
    assert list(few_ts[np.isnan(few)] - T0) == [10.0, 21.0] and len(few) <= 8 + 2
    assert np.all(np.diff(few_ts) >= 0) and 99.0 in few


def test_a_long_series_from_the_minute_summary_keeps_its_gaps(db, monkeypatch):
    import registrar.query as query

    write(db, _gappy())
    monkeypatch.setattr(query, "SUMMARY_ABOVE", 5)
    with Archive(db) as a:
        ts, values = a.series(DAY, grp=1, type=1, source="04010")
    assert list(ts[np.isnan(values)] - T0) == [10.0, 21.0]
    assert list(values[~np.isnan(values)]) == [0.0, 99.0]  # the minute's extremes; frozen values none



def test_time_windows_by_bisection_over_ids(db):
    """first_at: the first id at or after a time; window: a series' or the journal's records of an
    id range, in id order either way, within times when given (Historical Access reads by them;
    the local archive only: the plant archive is not read that way)."""
    records = []
    for i in range(300):
        records.append(Record(T0 + i, "data", 1, 1, "04010", value=float(i)))
        if i % 10 == 0:
            records.append(Record(T0 + i, "message", 1, 0, number=1))
    records.append(Record(T0 + 400, "operator", source="ivanov", text="write 04030: 0 -> 7"))
    write(db, records)
    key = SeriesKey("data", 1, 1, "04010")
    with Archive(db) as archive:
        ids = [r.id for r in archive.window(DAY, (0, 1 << 40), key=key, limit=1000)]
        assert len(ids) == 300 and ids == sorted(ids)
        assert archive.first_at(DAY, round(T0 * 1000)) == ids[0]
        assert archive.first_at(DAY, round((T0 + 9.5) * 1000)) == ids[10]
        assert archive.first_at(DAY, round((T0 + 10) * 1000)) == ids[10]
        assert archive.first_at(DAY, round((T0 + 1000) * 1000)) == ids[-1] + 2  # past the operator's
        lo = archive.first_at(DAY, round((T0 + 100) * 1000))
        hi = archive.first_at(DAY, round((T0 + 110) * 1000))
        series = archive.window(DAY, (lo, hi), key=key, newest_first=True, limit=5)
        assert [r.value for r in series] == [109.0, 108.0, 107.0, 106.0, 105.0]
        journal = archive.window(DAY, (lo, hi), kinds=("message",), limit=10)
        assert [(r.kind, r.ts) for r in journal] == [("message", T0 + 100)]
        timed = archive.window(DAY, (0, 1 << 40), kinds=("message", "operator"), limit=100,
                               times=(round((T0 + 250) * 1000), round((T0 + 400) * 1000)))
        assert [r.ts - T0 for r in timed] == [250, 260, 270, 280, 290, 400]
        assert archive.first_at(DAY - dt.timedelta(days=3), 0) == 1  # no such day
