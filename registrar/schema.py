"""The archive's layout, shared by the writer (store.py) and the readers (query.py).

One table per local day named "DD_MM_YYYY" (the original registrar wrote one DD_MM_YYYY file a
day), so retention drops a whole table and a day's queries never touch other days.
"""

from __future__ import annotations

import datetime as dt

from netplc.address import fmt_octal
from netplc.tags.table import TagTable
from netplc.tags.tag import Scaling, Tag, TagType

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
# The station's tags (tags.csv) as they were when the archive was last opened for writing, so the
# viewer and CSV show data series by tag name in physical units without the station's files.
TAGS_SQL = ("CREATE TABLE IF NOT EXISTS tags (name TEXT PRIMARY KEY, address INTEGER, type TEXT, unit TEXT, "
            "app_min REAL, app_max REAL, phy_min REAL, phy_max REAL, decimals INTEGER, description TEXT)")


def tag_rows(table: TagTable) -> list[tuple]:
    """The tags as rows of the archive's `tags` table."""
    def ranges(s: Scaling | None) -> tuple:
        return (s.AppMin, s.AppMax, s.PhyMin, s.PhyMax) if s is not None else (None,) * 4

    return [(t.name, t.address, str(t.type), t.unit, *ranges(t.scaling), t.decimals, t.description)
            for t in table.tags]


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
