"""The archive's layout, shared by the writer (store.py) and the readers (query.py).

One table per local day named "DD_MM_YYYY" (the original registrar wrote one DD_MM_YYYY file a
day), so retention drops a whole table and a day's queries never touch other days.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import os
import sqlite3
import time
import zoneinfo
from pathlib import Path

from app.scada.series import GAP_WORDS
from app.scada.table import TagTable
from app.scada.tag import Scaling, Tag, TagType
from netplc.address import fmt_octal

SCHEMA_VERSION = "2"  # 2: `tags.source`, the key a tag's data records carry (docs/architecture.md section 8)
COLUMNS = ("id", "ts", "kind", "grp", "type", "source", "number", "value", "text")
DAY_GLOB = "[0-3][0-9]_[01][0-9]_[0-9][0-9][0-9][0-9]"

# ts is milliseconds since the epoch (UTC) so that sorting and ranges are integer comparisons.
DAY_COLUMNS_SQL = """(
    id     INTEGER PRIMARY KEY,
    ts     INTEGER NOT NULL,
    kind   TEXT    NOT NULL,
    grp    INTEGER,
    type   INTEGER,
    source TEXT,
    number INTEGER,
    value  REAL,
    text   TEXT,
    pid    INTEGER
)"""
# `pid`: a hot-standby pair's identity of a record its standby may archive too (netplc/records.py
# Record.pid), which the plant archive keys it by; NULL for every other record


def has_pid(con: sqlite3.Connection, table: str) -> bool:
    """Whether a day table has the `pid` column (a day written before it had none)."""
    return any(row[1] == "pid" for row in con.execute(f'PRAGMA table_info("{table}")'))

# Two indexes, both cheap while writing. The key index: its low-cardinality keys receive rows in
# id order, so each insert lands on the last page of its key range. It serves series (all four
# keys fixed: rows come out in id order), counts, and pages of rare kinds. The text index holds
# only rows with a text (messages, operator and system records, not NSTORE data), in id order
# with the text beside it, so a text search reads those alone and never the table's data rows.
KEY_INDEX_COLUMNS = "(kind, grp, type, source)"

# A data record's text is NULL while its value is good, else its quality word; one held by bad or
# not yet known quality (or one marking that its series turned so, without a value) is no point
# of its series: readers break the line there and the per-minute summary leaves it out
# (app/scada/series.py).
GAP_SQL = f"(text IS NOT NULL AND text IN ({', '.join(repr(w) for w in GAP_WORDS)}))"


def key_index(table: str) -> str:
    return f"{table}_key"


def text_index(table: str) -> str:
    return f"{table}_text"


def gap_index(table: str) -> str:
    return f"{table}_gaps"


def index_sql(table: str) -> list[str]:
    """The key and text indexes, and the gap index: the data records that are no point of their
    series only (few, so it costs nearly nothing), which a series read from the per-minute summary
    asks for its gaps."""
    return [f'CREATE INDEX IF NOT EXISTS "{key_index(table)}" ON "{table}" {KEY_INDEX_COLUMNS}',
            f'CREATE INDEX IF NOT EXISTS "{text_index(table)}" ON "{table}" (id, text) '
            "WHERE text IS NOT NULL",
            f'CREATE INDEX IF NOT EXISTS "{gap_index(table)}" ON "{table}" (grp, type, source, ts) '
            f"WHERE kind = 'data' AND {GAP_SQL}"]


# Beside each day table, two tables kept in the batch's transaction: a trigram full-text index of
# the texts (contentless, no positions: it names candidate rows, the LIKE filter decides, so a text
# search reads only rows holding the text's trigrams), and per series and minute the count, the
# minimum and the maximum at their own times (a day's series is read from 1,440 rows per key
# instead of every record). Days written before them have neither: readers fall back.
def fts_table(table: str) -> str:
    return f"text_{table}"


def minutes_table(table: str) -> str:
    return f"minutes_{table}"


def aux_sql(table: str) -> list[str]:
    return [f'CREATE VIRTUAL TABLE IF NOT EXISTS "{fts_table(table)}" USING fts5(text, content=\'\', '
            "detail=none, tokenize=trigram)",
            f'CREATE TABLE IF NOT EXISTS "{minutes_table(table)}" (grp INTEGER NOT NULL, '
            "type INTEGER NOT NULL, source TEXT NOT NULL, minute INTEGER NOT NULL, n INTEGER NOT NULL, "
            "lo REAL, lo_ts INTEGER, hi REAL, hi_ts INTEGER, PRIMARY KEY (grp, type, source, minute)) "
            "WITHOUT ROWID"]


def aux_fill_sql(table: str) -> list[str]:
    """Statements adding the rows with id > ? to the two tables (the min and the max each need a
    pass of their own: SQLite gives the ts of the row holding a lone min() or max())."""
    rows = (f'FROM "{table}" NOT INDEXED WHERE id > ? AND kind = \'data\' AND value IS NOT NULL '
            f"AND NOT {GAP_SQL} "
            "AND grp IS NOT NULL AND type IS NOT NULL AND source IS NOT NULL "
            "GROUP BY grp, type, source, ts / 60000")
    into = f'INSERT INTO "{minutes_table(table)}" (grp, type, source, minute, n, lo, lo_ts, hi, hi_ts)'
    return [
        f'INSERT INTO "{fts_table(table)}" (rowid, text) SELECT id, text FROM "{table}" '
        "WHERE id > ? AND text IS NOT NULL",
        f"{into} SELECT grp, type, source, ts / 60000, count(*), min(value), ts, NULL, NULL {rows} "
        "ON CONFLICT DO UPDATE SET n = n + excluded.n, "
        "lo_ts = CASE WHEN excluded.lo < lo THEN excluded.lo_ts ELSE lo_ts END, "
        "lo = CASE WHEN excluded.lo < lo THEN excluded.lo ELSE lo END",
        f"{into} SELECT grp, type, source, ts / 60000, 0, NULL, NULL, max(value), ts {rows} "
        "ON CONFLICT DO UPDATE SET "
        "hi_ts = CASE WHEN hi IS NULL OR excluded.hi > hi THEN excluded.hi_ts ELSE hi_ts END, "
        "hi = CASE WHEN hi IS NULL OR excluded.hi > hi THEN excluded.hi ELSE hi END",
    ]


META_SQL = "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT)"
MESSAGES_SQL = ("CREATE TABLE IF NOT EXISTS messages "
                "(number INTEGER PRIMARY KEY, grp INTEGER, type INTEGER, text TEXT)")
# The station's tags (tags.csv) as they were when the archive was last opened for writing, so the
# viewer and CSV show data series by tag name in physical units without the station's files.
# `source` is the address as the data records of the tag carry it (NSTORE's octal text,
# netplc.address.fmt_octal: "0" and at least four digits), so plain SQL joins a day table's records
# to their tags (`USING (source)`), while `address` stays the decimal number older readers know.
# It is a generated column: a writer that inserts the ten other columns (an older station) still
# fills it, and an archive written before it gets it by `add_tag_source`, losing nothing.
TAG_FIELDS = ("name", "address", "type", "unit", "app_min", "app_max", "phy_min", "phy_max", "decimals",
              "description")
TAG_SOURCE_SQL = "printf('0%04o', address)"
TAG_SOURCE_COLUMN = f"source TEXT GENERATED ALWAYS AS ({TAG_SOURCE_SQL}) VIRTUAL"
TAGS_SQL = ("CREATE TABLE IF NOT EXISTS tags (name TEXT PRIMARY KEY, address INTEGER, type TEXT, unit TEXT, "
            "app_min REAL, app_max REAL, phy_min REAL, phy_max REAL, decimals INTEGER, description TEXT, "
            f"{TAG_SOURCE_COLUMN})")
# The rows by name, and with their key: both read an archive of either layout (a reader never writes).
TAG_ROWS_SQL = f"SELECT {', '.join(TAG_FIELDS)} FROM tags ORDER BY name"
KEYED_TAG_ROWS_SQL = f"SELECT {', '.join(TAG_FIELDS)}, {TAG_SOURCE_SQL} FROM tags ORDER BY name"
ONE_WORD_TYPES = ("word", "int16", "bcd")  # the tags whose value one archived word holds whole


def add_tag_source(con: sqlite3.Connection) -> None:
    """Give a `tags` table written before the key its `source` column (inside the caller's
    transaction); the rows stay as they are."""
    columns = {row[1] for row in con.execute("PRAGMA table_xinfo(tags)")}
    if "source" not in columns:
        con.execute(f"ALTER TABLE tags ADD COLUMN {TAG_SOURCE_COLUMN}")


def tag_rows(table: TagTable) -> list[tuple]:
    """The tags as rows of the archive's `tags` table (TAG_FIELDS), by name."""
    def ranges(s: Scaling | None) -> tuple:
        return (s.AppMin, s.AppMax, s.PhyMin, s.PhyMax) if s is not None else (None,) * 4

    return sorted((t.name, t.address, str(t.type), t.unit, *ranges(t.scaling), t.decimals, t.description)
                  for t in table.tags)


def physical_sql(word: str, tag: str) -> str:
    """The physical value of a one-word tag's archived `word` as an SQL expression that SQLite and
    PostgreSQL both evaluate, `tag` naming the row of the tag (its `type` and ranges): the
    conversion of app/scada/tag.py (Tag.word_value, then Scaling.to_phy) with the same operations in
    the same order, so the same double. A BCD word with a digit above 9, NaN there, is NULL here,
    which SQL's aggregates skip."""
    w = f"CAST({word} AS INTEGER)"
    digits = [f"(({w} >> {shift}) & 15)" for shift in (12, 8, 4, 0)]
    bcd = (f"CASE WHEN {' OR '.join(f'{d} > 9' for d in digits)} THEN NULL "
           f"ELSE {digits[0]} * 1000 + {digits[1]} * 100 + {digits[2]} * 10 + {digits[3]} END")
    int16 = f"CASE WHEN {word} >= 32768 THEN {word} - 65536 ELSE {word} END"
    raw = f"(CASE {tag}.type WHEN 'int16' THEN {int16} WHEN 'bcd' THEN {bcd} ELSE {word} END)"
    a0, a1, p0, p1 = (f"{tag}.{c}" for c in ("app_min", "app_max", "phy_min", "phy_max"))
    return (f"CASE WHEN {a0} IS NULL OR {a1} IS NULL OR {p0} IS NULL OR {p1} IS NULL THEN {raw} "
            f"ELSE {p0} + ({raw} - {a0}) * ({p1} - {p0}) / NULLIF({a1} - {a0}, 0) END")


def tags_by_source(rows: list[tuple]) -> dict[str, Tag]:
    """The one-word tags of the `tags` table by the `source` their NSTORE data records carry."""
    out = {}
    for name, address, kind, unit, a0, a1, p0, p1, decimals, description in rows:
        scaling = Scaling(a0, a1, p0, p1) if None not in (a0, a1, p0, p1) else None
        tag = Tag(name, address, TagType(kind), unit or "", scaling, decimals or 0, description or "")
        if tag.type in (TagType.WORD, TagType.INT16, TagType.BCD):
            out[fmt_octal(address)] = tag
    return out


# The distinct data series of each day, kept by the writer so the viewer's picker is instant.
SERIES_SQL = ("CREATE TABLE IF NOT EXISTS series (day TEXT NOT NULL, kind TEXT NOT NULL, grp INTEGER, "
              "type INTEGER, source TEXT, UNIQUE (day, kind, grp, type, source))")


def table_name(day: dt.date) -> str:
    return f"{day.day:02d}_{day.month:02d}_{day.year:04d}"


def parse_table_name(name: str) -> dt.date | None:
    try:
        d, m, y = name.split("_")
        if len(d) != 2 or len(m) != 2 or len(y) != 4:
            return None
        return dt.date(int(y), int(m), int(d))
    except ValueError:
        return None


def quoted(day: dt.date) -> str:
    """The table name quoted for SQL (it starts with a digit)."""
    return f'"{table_name(day)}"'


def local_day_bounds(ts: float) -> tuple[dt.date, float, float]:
    """The local date of `ts` and the epoch seconds of its local midnight and the next one."""
    day = dt.date.fromtimestamp(ts)
    start = dt.datetime(day.year, day.month, day.day).timestamp()
    nxt = day + dt.timedelta(days=1)
    end = dt.datetime(nxt.year, nxt.month, nxt.day).timestamp()
    return day, start, end


def local_zone_key() -> str:
    """The IANA key of this machine's zone ("Europe/Moscow"), stored in `meta` so that a copy of the
    archive read in another zone still cuts days where the writer did; "" when it cannot be told."""
    candidates = [os.environ.get("TZ", "").lstrip(":")]
    try:
        target = os.path.realpath("/etc/localtime")
        if "/zoneinfo/" in target:
            candidates.append(target.split("/zoneinfo/", 1)[1])
    except OSError:
        pass
    with contextlib.suppress(OSError, UnicodeDecodeError):
        candidates.append(Path("/etc/timezone").read_text(encoding="ascii").strip())
    for key in candidates:
        if key and zone(key) is not None and _same_offsets(key):
            return key
    return ""


def zone(key: str) -> zoneinfo.ZoneInfo | None:
    try:
        return zoneinfo.ZoneInfo(key) if key else None
    except (zoneinfo.ZoneInfoNotFoundError, ValueError):
        return None


def _same_offsets(key: str) -> bool:
    """Whether the zone `key` agrees with what time.localtime says now (TZ may name a POSIX rule)."""
    tz = zone(key)
    now = time.time()
    return tz is not None and dt.datetime.fromtimestamp(now, tz).utcoffset() == dt.timedelta(
        seconds=time.localtime(now).tm_gmtoff)


def day_bounds_in(day: dt.date, tz: dt.tzinfo | None) -> tuple[float, float]:
    """The epoch seconds of `day`'s midnight and the next one in zone `tz` (None: this machine's)."""
    nxt = day + dt.timedelta(days=1)
    return (dt.datetime(day.year, day.month, day.day, tzinfo=tz).timestamp(),
            dt.datetime(nxt.year, nxt.month, nxt.day, tzinfo=tz).timestamp())
