"""The archive's layout, shared by the writer (store.py) and the readers (query.py).

One table per local day named "DD_MM_YYYY" (the original registrar wrote one DD_MM_YYYY file a
day), so retention drops a whole table and a day's queries never touch other days.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import os
import time
import zoneinfo
from pathlib import Path

SCHEMA_VERSION = "1"
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
    text   TEXT
)"""

# Two indexes, both cheap while writing. The key index: its low-cardinality keys receive rows in
# id order, so each insert lands on the last page of its key range. It serves series (all four
# keys fixed: rows come out in id order), counts, and pages of rare kinds. The text index holds
# only rows with a text (messages, operator and system records, not NSTORE data), in id order
# with the text beside it, so a text search reads those alone and never the table's data rows.
KEY_INDEX_COLUMNS = "(kind, grp, type, source)"


def key_index(table: str) -> str:
    return f"{table}_key"


def text_index(table: str) -> str:
    return f"{table}_text"


def index_sql(table: str) -> list[str]:
    return [f'CREATE INDEX IF NOT EXISTS "{key_index(table)}" ON "{table}" {KEY_INDEX_COLUMNS}',
            f'CREATE INDEX IF NOT EXISTS "{text_index(table)}" ON "{table}" (id, text) '
            "WHERE text IS NOT NULL"]


META_SQL = "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT)"
MESSAGES_SQL = ("CREATE TABLE IF NOT EXISTS messages "
                "(number INTEGER PRIMARY KEY, grp INTEGER, type INTEGER, text TEXT)")
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
