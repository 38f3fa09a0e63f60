"""The plant archive read by tag in plain SQL: the stations' tags versioned per change, and the view
`tag_values` giving every data record of a tag in physical units as the station converts it."""

from __future__ import annotations

import datetime as dt
import math
import shutil
from pathlib import Path

import psycopg

from app.scada.table import TagTable, load_tags
from app.scada.tag import Scaling, Tag, TagType
from app.station.config import DEMO_STATION
from netplc.address import fmt_octal
from netplc.program import load_symbols
from netplc.records import Record
from registrar.plant.forward import Forwarder
from registrar.query import Archive
from registrar.store import Store

DEMO = DEMO_STATION
T0 = dt.datetime(2026, 3, 5, 8, 0).timestamp()
WORDS = (0, 1, 100, 2047, 2048, 4095, 9999, 0x1234, 0x7FFF, 0x8000, 0x8001, 0xFFFF)


def demo_tags() -> TagTable:
    """The demo's tags, and an int16 and a BCD tag for the conversions the demo does not use."""
    demo = load_tags(DEMO / "tags.csv", load_symbols(DEMO / "symbols.csv"))
    extra = [Tag("DELTA", 0o4100, TagType.INT16, "kPa", Scaling(-1000, 1000, -10, 10), 2),
             Tag("COUNT", 0o4102, TagType.BCD, "pcs")]
    return TagTable([*demo.tags, *extra])


def archive_of(path: Path, tags: TagTable, start: float, records: list[Record], station: str = "") -> Path:
    """The station's archive after one run from `start`: the tags it was given, the records."""
    store = Store(path, tags=tags, wallclock=lambda: start, station=station)
    for record in records:
        store.put(record)
    store.start()
    store.close()
    return path


def tag_values(url: str, station: str) -> list[tuple]:
    with psycopg.connect(url) as con:
        return con.execute("SELECT tag, raw, value, unit, quality, version, time, ts FROM tag_values "
                           "WHERE station = %s ORDER BY ts, tag", (station,)).fetchall()


def test_the_view_gives_the_stations_physical_values_and_units(tmp_path, pg_url):
    table = demo_tags()
    words = [t for t in table.tags if t.type in (TagType.WORD, TagType.INT16, TagType.BCD)]
    assert {t.name for t in words} == {"LEVEL", "TEMP", "TEMP_SP", "DELTA", "COUNT"}
    records, i = [], 0
    for tag in words:
        for word in WORDS:
            records.append(Record(T0 + i, "data", 1, 1, fmt_octal(tag.address), value=float(word)))
            i += 1
    records.append(Record(T0 + i, "data", 1, 1, "04010", value=None, text="comm-fail"))  # a held series
    records.append(Record(T0 + i + 1, "data", 1, 1, "04010", value=7.0, text="forced"))
    records.append(Record(T0 + i + 2, "data", 1, 1, "07000", value=7.0))  # no tag there
    db = archive_of(tmp_path / "journal.sqlite", table, T0, records)
    assert Forwarder(db, pg_url, "Demo station").forward_all() == len(records)

    rows = tag_values(pg_url, "Demo station")
    assert len(rows) == len(words) * len(WORDS) + 2
    for name, raw, value, unit, quality, version, time, ts in rows[:-2]:
        tag = table.get(name)
        assert tag is not None and unit == tag.unit and quality == "good" and version == 1
        expected = tag.word_value(int(raw))  # the station's own conversion, to the last bit
        assert (value is None and math.isnan(expected)) or value == expected, (name, raw, value, expected)
        assert time == dt.datetime.fromtimestamp(ts / 1000, dt.UTC)
    assert [r[0:5] for r in rows[-2:]] == [("LEVEL", None, None, "%", "comm-fail"),
                                           ("LEVEL", 7.0, table.get("LEVEL").word_value(7), "%", "forced")]
    level = next(r for r in rows if r[0] == "LEVEL" and r[1] == 2048)
    assert level[2] == 2048 * 100 / 4095 and level[3] == "%"
    count = [r[2] for r in rows if r[0] == "COUNT"]
    assert count[WORDS.index(0x1234)] == 1234 and count[WORDS.index(9999)] is None  # 0x270F: not BCD

    with psycopg.connect(pg_url) as con:  # Grafana's PostgreSQL data source reads these types
        types = dict(con.execute("SELECT attname, format_type(atttypid, atttypmod) FROM pg_attribute "
                                 "WHERE attrelid = 'tag_values'::regclass AND attnum > 0").fetchall())
        assert (types["time"], types["metric"], types["value"]) == (
            "timestamp with time zone", "text", "double precision")
        by_source = con.execute("SELECT name, unit FROM tags WHERE station = %s AND source = '04010'",
                                ("Demo station",)).fetchall()
        assert by_source == [("LEVEL", "%")]
    with Archive(pg_url) as plant:  # the plant archive's reader has them too, as the SQLite one
        assert plant.tags() == Archive(db).tags() and plant.tags()["04012"].name == "TEMP"


def test_a_tags_change_makes_a_new_version_and_older_rows_keep_theirs(tmp_path, pg_url):
    v1 = demo_tags()
    level = v1.get("LEVEL")
    assert level is not None and level.scaling is not None
    v2 = TagTable([Tag("LEVEL", level.address, TagType.WORD, "m", Scaling(0, 4095, 0, 5), 2), *v1.tags[1:]])
    db = tmp_path / "journal.sqlite"

    def run(start: float, tags: TagTable) -> None:
        archive_of(db, tags, start, [Record(start + k, "data", 1, 1, "04010", value=4095.0)
                                     for k in range(3)])
        Forwarder(db, pg_url, "st").forward_all()  # the station's start publishes its tags

    run(T0, v1)
    run(T0 + 100, v1)  # a restart with the same tags.csv: no new version
    run(T0 + 200, v2)  # tags.csv changed: LEVEL is now 0..5 m
    run(T0 + 300, v2)
    Forwarder(db, pg_url, "st").forward_all()  # and again, as `archive migrate` would
    rows = tag_values(pg_url, "st")
    assert [(r[2], r[3], r[5]) for r in rows] == [(100.0, "%", 1)] * 6 + [(5.0, "m", 2)] * 6
    with psycopg.connect(pg_url) as con:
        versions = con.execute("SELECT version, valid_from::text, valid_to::text, count(*) FROM tags "
                               "WHERE station = 'st' GROUP BY 1, 2, 3 ORDER BY 1").fetchall()
        change = con.execute("SELECT (timestamptz 'epoch' + %s * interval '1 millisecond')::text",
                             (round((T0 + 200) * 1000),)).fetchone()[0]
        hashes = con.execute("SELECT count(DISTINCT hash) FROM tags WHERE station = 'st'").fetchone()[0]
    assert versions == [(1, "-infinity", change, len(v1.tags)), (2, change, "infinity", len(v2.tags))]
    assert hashes == 2
    with Archive(pg_url) as plant:  # the current version
        assert plant.tags()["04010"].unit == "m"


def test_an_older_tag_set_published_late_takes_the_time_before_the_change(tmp_path, pg_url):
    """A copy of the station's archive taken before a change, migrated after the station forwarded
    the new tags: its tags convert the records before the change, and nothing after it."""
    v1 = demo_tags()
    v2 = TagTable([replace_unit(t, "m") if t.name == "LEVEL" else t for t in v1.tags])
    db = archive_of(tmp_path / "journal.sqlite", v1, T0, [Record(T0 + 1, "data", 1, 1, "04010", value=1.0)])
    copy = tmp_path / "copy.sqlite"
    shutil.copy(db, copy)
    archive_of(db, v2, T0 + 50, [Record(T0 + 60, "data", 1, 1, "04010", value=1.0)])
    Forwarder(db, pg_url, "st").forward_all()
    assert [(r[3], r[5]) for r in tag_values(pg_url, "st")] == [("m", 1), ("m", 1)]  # nothing older known
    Forwarder(copy, pg_url, "st").forward_all()
    assert [(r[3], r[5]) for r in tag_values(pg_url, "st")] == [("%", 2), ("m", 1)]
    Forwarder(db, pg_url, "st").forward_all()
    Forwarder(copy, pg_url, "st").forward_all()
    assert [(r[3], r[5]) for r in tag_values(pg_url, "st")] == [("%", 2), ("m", 1)]


def replace_unit(tag: Tag, unit: str) -> Tag:
    return Tag(tag.name, tag.address, tag.type, unit, tag.scaling, tag.decimals, tag.description)


def test_a_plant_archive_of_an_older_version_gets_tags_and_the_view(tmp_path, pg_url):
    db = archive_of(tmp_path / "journal.sqlite", demo_tags(), T0,
                    [Record(T0, "data", 1, 1, "04010", value=4095.0)])
    Forwarder(db, pg_url, "st").forward_all()
    with psycopg.connect(pg_url) as con:  # as the older version left it
        con.execute("DROP VIEW tag_values")
        con.execute("DROP TABLE tags")
        con.execute("UPDATE meta SET value = '1' WHERE key = 'schema_version'")
    with Archive(pg_url) as plant:
        assert plant.tags() == {}  # read as before
    assert Forwarder(db, pg_url, "st").forward_all() == 0  # the next start of a station of this version
    with psycopg.connect(pg_url) as con:
        assert con.execute("SELECT tag, value FROM tag_values").fetchall() == [("LEVEL", 100.0)]
        assert con.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone() == ("2",)
