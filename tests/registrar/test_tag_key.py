"""The local archive's `tags` carry the key of their data records (`source`, octal text as NSTORE
writes it), so plain SQL joins a day's records to their tags; an archive written before the key
gets it when a station opens it, losing nothing, and older readers and writers keep working."""

from __future__ import annotations

import datetime as dt
import math
import sqlite3
from pathlib import Path

from app.scada.table import TagTable
from app.scada.tag import Tag, TagType
from netplc.address import fmt_octal
from netplc.records import Record
from registrar.query import Archive
from registrar.schema import ONE_WORD_TYPES, TAG_FIELDS, physical_sql
from registrar.store import Store

from .test_plant_tags import WORDS, demo_tags

T0 = dt.datetime(2026, 3, 5, 8, 0).timestamp()
OLD_TAGS_SQL = ("CREATE TABLE tags (name TEXT PRIMARY KEY, address INTEGER, type TEXT, unit TEXT, "
                "app_min REAL, app_max REAL, phy_min REAL, phy_max REAL, decimals INTEGER, description TEXT)")


def query(path: Path, sql: str) -> list[tuple]:
    con = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    try:
        return con.execute(sql).fetchall()
    finally:
        con.close()


def test_the_key_is_the_source_nstore_writes(tmp_path):
    addresses = [0, 7, 0o3777, 0o4000, 0o4010, 0o77776, 0o40005, 0o777777]
    tags = TagTable([Tag(f"T{a}", a, TagType.BIT if a >= 0o40000 else TagType.WORD) for a in addresses])
    store = Store(tmp_path / "journal.sqlite", tags=tags)
    store.start()
    store.close()
    keys = dict(query(store.path, "SELECT address, source FROM tags"))
    assert keys == {a: fmt_octal(a) for a in addresses}


def older_archive(path: Path, table: TagTable) -> Path:
    """An archive as a station wrote it before the key: the ten-column `tags` and a day of NSTORE data."""
    store = Store(path)
    words = [t for t in table.tags if t.type.value in ONE_WORD_TYPES]
    for i, (tag, word) in enumerate((t, w) for t in words for w in WORDS):
        store.put(Record(T0 + i, "data", 1, 1, fmt_octal(tag.address), value=float(word)))
    store.start()
    store.close()
    con = sqlite3.connect(path, isolation_level=None)
    try:
        con.execute("DROP TABLE tags")
        con.execute(OLD_TAGS_SQL)
        con.executemany("INSERT INTO tags VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",  # as the older writer did
                        [(t.name, t.address, str(t.type), t.unit,
                          *((t.scaling.AppMin, t.scaling.AppMax, t.scaling.PhyMin, t.scaling.PhyMax)
                            if t.scaling else (None,) * 4), t.decimals, t.description) for t in table.tags])
        con.execute("DELETE FROM meta WHERE key = 'tags_since'")
    finally:
        con.close()
    return path


def test_an_older_archive_gets_the_key_and_joins_its_records_by_tag(tmp_path):
    table = demo_tags()
    db = older_archive(tmp_path / "journal.sqlite", table)
    before = query(db, f"SELECT {', '.join(TAG_FIELDS)} FROM tags ORDER BY name")
    with Archive(db) as archive:  # read before it is migrated (a reader never writes)
        assert archive.tags()["04010"].name == "LEVEL"

    store = Store(db, tags=table, wallclock=lambda: T0 + 3600)  # the station opens it: migrated
    store.start()
    store.close()
    assert query(db, f"SELECT {', '.join(TAG_FIELDS)} FROM tags ORDER BY name") == before  # nothing lost
    assert ("tags_since",) not in query(db, "SELECT key FROM meta")  # the same tags: no change
    day = '"05_03_2026"'
    joined = query(db, f"SELECT t.name, d.value, {physical_sql('d.value', 't')}, t.unit "
                       f"FROM {day} d JOIN tags t ON t.source = d.source "
                       f"WHERE d.kind = 'data' AND t.type IN ('word', 'int16', 'bcd') ORDER BY d.id")
    assert len(joined) == query(db, f"SELECT count(*) FROM {day}")[0][0] == 5 * len(WORDS)
    for name, raw, value, unit in joined:
        tag = table.get(name)
        assert tag is not None and unit == tag.unit
        expected = tag.word_value(int(raw))  # the station's conversion, the same double
        assert (value is None and math.isnan(expected)) or value == expected, (name, raw, value, expected)

    con = sqlite3.connect(db, isolation_level=None)  # an older station opens it again: its writes work
    try:
        con.execute("DELETE FROM tags")
        con.execute("INSERT INTO tags VALUES ('LEVEL', 2056, 'word', '%', 0, 4095, 0, 100, 1, '')")
        assert con.execute("SELECT name, address, source FROM tags").fetchall() == [("LEVEL", 2056, "04010")]
    finally:
        con.close()


def test_a_changed_tag_set_says_since_when(tmp_path):
    db = tmp_path / "journal.sqlite"
    v1 = demo_tags()
    v2 = TagTable([Tag("LEVEL", 0o4010, TagType.WORD, "m"), *v1.tags[1:]])

    def since(tags: TagTable, at: float) -> str | None:
        store = Store(db, tags=tags, wallclock=lambda: at)
        store.start()
        store.close()
        return dict(query(db, "SELECT key, value FROM meta")).get("tags_since")

    assert since(v1, T0) == str(round(T0 * 1000))
    assert since(v1, T0 + 60) == str(round(T0 * 1000))  # a restart with the same tags.csv
    assert since(TagTable(), T0 + 90) == str(round(T0 * 1000))  # no tags.csv: the file keeps its own
    assert since(v2, T0 + 120) == str(round((T0 + 120) * 1000))
    assert query(db, "SELECT unit FROM tags WHERE source = '04010'") == [("m",)]
